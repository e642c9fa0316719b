"""``tactilevision diagnose``: model against measurement (formats.md §3, §4)."""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path

from ._options import add_dome_argument
from ._out import add_overwrite_argument

__all__ = ["add_parser", "run"]

_DESCRIPTION = """\
Compare the indentation model with a measurements table: residuals against
every covariate column (a test with a p-value and the fraction of residual
variance explained), the replicate noise floor, the model plus each
applicable catalogue effect compared by BIC and cross-validated RMSE, the
verdict (missing effect, equivalent effects, unexplained covariate) and the
error ladder with E and nu at each step. Columns the depth rule computed
(overshoot_mm) are tested apart as the certification's, never as physics. A
verdict that names nothing says what it rules out: per catalogue effect, the
smallest size this table would have named (its presses replayed at its noise).
A table certified by the mark rule ([certification] depth_rule in its
session.toml) is told to read force effects within an indenter as depth.
The force over each press's hold (calibrate's holds.csv, read from beside the
table unless --holds names another or --no-holds) is tested for a relaxing gel,
which a table read at one time of every hold cannot show. --report DIR writes
the figures and report.html. Exit status 2 on bad input.

A ball's table ([indenter] shape = "sphere"): the ladder starts from the
small-strain law with the stated contact and tries large_deformation (finite
strain), contact_slip (the other contact condition), force_offset and
depth_offset, taking the change that lowers the BIC most until none does; each
rung shows every press's apparent E (flat when the model is right). As fit does,
it weighs the presses by depth_std_mm and force_sem_n and fits the circles'
shared error (depth_shared_mm) within its bound in every rung."""


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Register the ``diagnose`` sub-command."""
    p = sub.add_parser("diagnose", help="find where the model fails and which effect is missing",
                       description=_DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("measurements", metavar="MEASUREMENTS.csv", type=Path)
    p.add_argument("--effects", default="", metavar="E1,E2",
                   help="effects already in the model diagnosed: catalogue names, or an "
                        "Effect subclass of your own as package.module:ClassName or "
                        "path/to/file.py:ClassName (a module not on the Python path is looked "
                        "for in the working directory; docs/custom_effects.md)")
    p.add_argument("--candidates", default="", metavar="E1,E2",
                   help="effects of your own tried beside the catalogue's, as candidates for "
                        "the missing effect (package.module:ClassName or "
                        "path/to/file.py:ClassName; docs/custom_effects.md)")
    p.add_argument("--scan", default="", metavar="COL1,COL2",
                   help="response columns (fx_n, fy_n, force_std_n: they follow the force) to "
                        "scan as covariates all the same; by default they are not, and the "
                        "output names the columns scanned")
    p.add_argument("--base", choices=("paper", "layer", "fem"), default="paper",
                   help="paper: eq. (5), the layer with large_deformation (default); "
                        "layer: the small-strain layer alone; fem: the FEM's finite-strain "
                        "law (E and nu its own parameters; docs/diagnose_power.md)")
    holds = p.add_mutually_exclusive_group()
    holds.add_argument("--holds", metavar="HOLDS.csv", type=Path,
                       help="the force over each press's hold, tested for a relaxing gel "
                            "(default: holds.csv beside the table, where there is one)")
    holds.add_argument("--no-holds", action="store_true",
                       help="do not read the holds (not even holds.csv beside the table)")
    p.add_argument("--thickness-mm", type=float, metavar="H")
    p.add_argument("--radius-mm", type=float, metavar="A")
    p.add_argument("--beta-table", choices=("fem", "paper"), default="fem",
                   help="table for E and nu at each step (the diagnosis does not depend on it)")
    p.add_argument("--json", metavar="FILE", help="write the result as JSON ('-': stdout)")
    p.add_argument("--report", metavar="DIR", type=Path,
                   help="write residuals_by_covariate.png, error_ladder.png, report.html")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--shape", choices=("flat_punch", "sphere"),
                   help="indenter shape (default: session.toml [indenter] shape)")
    p.add_argument("--contact", choices=("frictionless", "tied"),
                   help="a ball's stated contact (default: session.toml [indenter] contact)")
    p.add_argument("--nu", type=float, default=0.5, metavar="NU",
                   help="a ball's models are fitted at this nu (default 0.5)")
    p.add_argument("--pad-radius-mm", type=float, metavar="R",
                   help="a ball's gel pad radius (default: session.toml [sensor] "
                        "gel_radius_mm, else the infinite layer)")
    add_dome_argument(p)
    add_overwrite_argument(p, "report folder")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run ``diagnose``: :func:`~tactilevision.cli._diagnose_run.run`, imported only now
    (``--help`` reads the options without the command's stack)."""
    return importlib.import_module("._diagnose_run", __package__).run(args)
