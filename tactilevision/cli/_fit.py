"""``tactilevision fit``: E and nu from a measurements table (formats.md §3)."""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path

from ._options import add_dome_argument

__all__ = ["EFFECT_NAMES", "LAW_CHOICES", "add_indenter_arguments", "add_parser", "run"]

#: The effect catalogue's names as ``--effects``'s help lists them: a copy of
#: :data:`tactilevision.mechanics.EFFECT_NAMES`, which is read from the catalogue's classes
#: (importing the mechanics and SciPy: seconds that ``fit --help`` does without);
#: tests/test_cli_help_imports.py keeps the two equal.
EFFECT_NAMES = ("large_deformation", "depth_offset", "force_offset", "force_drift",
                "viscoelastic_relaxation", "incomplete_recovery", "aging",
                "spatial_nonuniformity", "force_crosstalk", "stiffness_trend:<column>",
                "stiffness_step:<column>", "force_trend:<column>")

#: ``--law`` choices: a material law, or ``auto`` (both fitted, the better one reported).
LAW_CHOICES = ("auto", "neo_hookean", "linear")

_DESCRIPTION = """\
Fit the paper's law P/w = c beta (w/h) + c (eq. 5) to a measurements table
(one row per certified press: depth_mm, force_n, ...), then nu from the beta
table and E from kappa (eq. 4). h and a come from the options or from
session.toml next to the table ([sensor] gel_thickness_mm, [indenter] radius_mm).
--beta-table fem (default): beta and kappa of our finite-strain Neo-Hookean
and small-strain FEM (models/, bonded punch, at the exact a/h). --beta-table
paper: the paper's relation (7) (a/h = 0.8) and Hayes' kappa, as in the paper.
A depth_std_mm column (standard uncertainty of each certified depth, mm) with a
value in every row is carried into the fit of eq. (5) (errors in both
variables, effective variance); if any of its cells is empty, the fit goes on
without it and says so on stderr. --ignore-depth-std fits without it.
Exit status 2 on bad input; 3 when the model's parameters are not all identified
by the table (e.g. viscoelastic_relaxation on a constant hold_s): the fit is
printed and written, with "identified": false in the JSON.

A ball ([indenter] shape = "sphere" in session.toml, or --shape sphere; radius_mm
its radius R): the force of our FEM's sphere table (or, with a pad radius, one FEM
sweep per nu), E at the nu the presses identify or at a stated nu (--nu, default
0.5) with "nu not identified", each material law fitted (--law auto) and the
apparent E of every press (flat when the law fits, drifting with depth when an
effect is missing)."""


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Register the ``fit`` sub-command.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The sub-parsers of the ``tactilevision`` parser.
    """
    p = sub.add_parser("fit", help="fit E and nu to a measurements table",
                       description=_DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("measurements", metavar="MEASUREMENTS.csv", type=Path, nargs="+",
                   help="table of certified presses (formats.md section 2); several tables "
                        "(or ramps, with --ramp), or a table with a specimen column: each "
                        "specimen fitted on its own, then the batch's E with the spread "
                        "between them (a random effect of the specimen)")
    p.add_argument("--thickness-mm", type=float, metavar="H",
                   help="gel thickness h in mm (default: session.toml [sensor] gel_thickness_mm)")
    p.add_argument("--radius-mm", type=float, metavar="A",
                   help="indenter radius a in mm (default: session.toml [indenter] radius_mm)")
    p.add_argument("--beta-table", choices=("fem", "paper"), default="fem",
                   help="source of nu(beta) and kappa: our FEM tables (default) or the "
                        "paper's relation (7) with Hayes 1972")
    p.add_argument("--effects", default="large_deformation", metavar="E1,E2",
                   help="comma-separated effects added to the base model (large_deformation); "
                        "with any, the whole model is fitted by robust least squares "
                        f"(catalogue: {', '.join(EFFECT_NAMES)}; or an Effect subclass of "
                        "your own as package.module:ClassName or path/to/file.py:ClassName, "
                        "a module not on the Python path looked for in the working "
                        "directory: docs/custom_effects.md)")
    p.add_argument("--a-over-h", type=float, metavar="X",
                   help="a/h at which kappa is read (default: the exact a/h; 0.8 reproduces "
                        "the paper)")
    p.add_argument("--ignore-depth-std", action="store_true",
                   help="fit without the table's depth_std_mm column (depths taken as exact)")
    p.add_argument("--holds", metavar="HOLDS.csv", type=Path,
                   help="the force over each press's hold (calibrate's holds.csv): fit a "
                        "standard linear solid to it, take each row's force back to the "
                        "instant of loading (the table's force0_n where calibrate wrote it, "
                        "else force_n over what is left of it at hold_s), and report E as the "
                        "instantaneous E_0 with the relaxed E_inf = (1 - g) E_0 beside it "
                        "(needs the table's hold_s; press matches rows to holds)")
    p.add_argument("--crossings", action="store_true",
                   help="fit the crossing forces instead of the force windows: each press's "
                        "force where it crossed its indenter's w0 (a table certified by the "
                        "mark rule: force_w0_n at depth_mm - overshoot_mm), a depth the "
                        "frames certify apart from the force, weighted by force_w0_sem_n; "
                        "for an effect the mark's depths absorbed (diagnose says when)")
    p.add_argument("--json", metavar="FILE",
                   help="write the result as JSON to FILE ('-' for standard output)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace --json FILE even when tactilevision did not write it")
    add_indenter_arguments(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run ``fit``: :func:`~tactilevision.cli._fit_run.run`, imported only now (``--help`` reads
    the options without the command's stack)."""
    return importlib.import_module("._fit_run", __package__).run(args)



def add_indenter_arguments(p: argparse.ArgumentParser) -> None:
    """The options of ``fit`` that an indenter other than the flat punch reads."""
    g = p.add_argument_group("indenter (a ball: [indenter] shape = \"sphere\")")
    g.add_argument("--shape", choices=("flat_punch", "sphere"),
                   help="indenter shape (default: session.toml [indenter] shape, else "
                        "flat_punch)")
    g.add_argument("--contact", choices=("frictionless", "tied", "coulomb"),
                   help="ball-gel contact (default: session.toml [indenter] contact, else "
                        "frictionless); coulomb: friction --friction between them (the "
                        "small-strain law only, one FEM sweep per nu)")
    g.add_argument("--friction", type=float, metavar="MU",
                   help="Coulomb's friction coefficient between ball and gel, with "
                        "--contact coulomb")
    g.add_argument("--law", choices=LAW_CHOICES, default="auto",
                   help="material law of a ball's force: auto (default: both fitted, the one "
                        "with the smaller residuals reported, the other beside it), "
                        "neo_hookean (finite strain) or linear")
    g.add_argument("--nu", type=float, metavar="NU",
                   help="Poisson's ratio at which E is reported when the presses do not "
                        "identify nu (default 0.5)")
    g.add_argument("--ramp", action="store_true",
                   help="the table is a force-depth ramp (displacement_mm, force_n[, time_s]: "
                        "an Instron's or a robot's loading curve, the contact point not "
                        "marked): fit its contact point, baseline and E (docs/guide/ramps.md)")
    g.add_argument("--pad-radius-mm", type=float, metavar="R",
                   help="lateral radius of the gel pad, mm, when it is small enough to "
                        "matter (default: session.toml [sensor] gel_radius_mm, else the "
                        "infinite layer); each nu is then one FEM sweep")
    add_dome_argument(g)
