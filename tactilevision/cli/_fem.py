"""``tactilevision fem tables``: rebuild the FEM kappa and beta tables of ``models/``."""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path

__all__ = ["add_parser", "run_tables"]


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Register ``fem`` and its ``tables`` sub-command."""
    p = sub.add_parser("fem", help="finite-element tables of the gel layer",
                       description="Finite elements of the gel layer.")
    fsub = p.add_subparsers(dest="fem_command", metavar="SUBCOMMAND", required=True)
    t = fsub.add_parser(
        "tables", help="rebuild models/kappa_fem.npz, beta_fem.npz and sphere_fem.npz",
        description="Compute kappa(nu, a/h) (small strain) and kappa_n(nu, a/h, w/h), "
        "beta(nu, a/h) (finite-strain Neo-Hookean) for a frictionless and a bonded punch on "
        "the grids of tactilevision.fem.NU_GRID and A_OVER_H_GRID, and write them with their "
        "provenance. kappa takes about 10 minutes on 2 cores; beta (bonded punch only: a "
        "frictionless sharp punch does not converge at finite strain) about 15 minutes with "
        "--jobs 2. sphere: a ball's P(w) and a(w) over R/h 0.5 to 20, nu 0.30 to 0.50 and w/h "
        "to 0.5, linear and Neo-Hookean, frictionless and tied (about 90 minutes with --jobs 2). "
        "pad: the ball-on-a-finite-pad sweeps the bundled FEATS sample reads "
        "(models/sphere_pad_sweeps.npz; from the disk cache where they are there, else about "
        "15 minutes).")
    t.add_argument("--what", default="kappa,beta",
                   help="comma-separated: kappa, beta, sphere, pad (default kappa,beta)")
    t.add_argument("--out-dir", type=Path, default=Path("models"),
                   help="folder for kappa_fem.npz and beta_fem.npz (default models/)")
    t.add_argument("--jobs", type=int, default=1, metavar="N",
                   help="worker processes for the kappa and beta sweeps (default 1)")
    t.add_argument("--quick", action="store_true",
                   help="a 3 x 3 grid on coarse meshes, for a smoke test (not for use)")
    t.add_argument("--no-progress", action="store_true", help="no progress bars")
    t.set_defaults(func=run_tables)


def run_tables(args: argparse.Namespace) -> int:
    """Run ``fem tables``: :func:`~tactilevision.cli._fem_run.run_tables`, imported only now
    (``--help`` reads the options without the command's stack)."""
    return importlib.import_module("._fem_run", __package__).run_tables(args)
