"""``tactilevision validate``: the paper's FEA check of a calibration (formats.md §3)."""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path

from ._out import add_overwrite_argument

__all__ = ["add_parser", "run"]

_DESCRIPTION = """\
Simulate every press of a measurements table with the finite-strain
Neo-Hookean FEM at E and nu, and compare the simulated depth at the measured
force with the measured depth (the paper's section V.A, Fig. 8). Without
--E-mpa and --nu the table is fitted first ('tactilevision fit', default
options) and its E and nu are simulated. h and a come from the options or the
session.toml next to the table; the pad radius from its [sensor] gel_radius_mm
(default 20 h). Exit status 2 on bad input."""


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Register the ``validate`` sub-command."""
    p = sub.add_parser("validate", help="simulated against measured depths (FEM check)",
                       description=_DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("measurements", metavar="MEASUREMENTS.csv", type=Path)
    p.add_argument("--E-mpa", dest="E_mpa", type=float, metavar="E",
                   help="Young's modulus to simulate, MPa (default: fitted)")
    p.add_argument("--nu", type=float, metavar="NU",
                   help="Poisson's ratio to simulate (default: fitted)")
    p.add_argument("--thickness-mm", type=float, metavar="H")
    p.add_argument("--radius-mm", type=float, metavar="A")
    p.add_argument("--pad-radius-mm", type=float, metavar="R",
                   help="gel pad radius, mm (default: session.toml, else 20 h)")
    p.add_argument("--contact", choices=("bonded", "frictionless", "tied"),
                   help="punch condition of the simulation (default bonded, as the FEM tables; "
                        "a frictionless sharp punch often stops converging before w/h = 0.1); "
                        "a ball's: frictionless or tied (default: session.toml [indenter] "
                        "contact, else frictionless)")
    p.add_argument("--shape", choices=("flat_punch", "sphere"),
                   help="indenter shape (default: session.toml [indenter] shape)")
    p.add_argument("--law", choices=("auto", "neo_hookean", "linear"), default="auto",
                   help="a ball's material law (default auto: the one fit selects)")
    p.add_argument("--json", metavar="FILE", help="write the result as JSON ('-': stdout)")
    p.add_argument("--report", metavar="DIR", type=Path,
                   help="write validation.png (force against depth) and validation.csv")
    add_overwrite_argument(p, "report folder")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run ``validate``: :func:`~tactilevision.cli._validate_run.run`, imported only now
    (``--help`` reads the options without the command's stack)."""
    return importlib.import_module("._validate_run", __package__).run(args)
