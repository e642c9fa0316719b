"""``tactilevision fem tables``: rebuild the FEM kappa and beta tables of ``models/``."""

from __future__ import annotations

import argparse
from pathlib import Path

from .. import InputError
from ..fem import build_beta_table, build_kappa_table, build_sphere_table, write_table
from ..mechanics import PAD_SWEEPS_FILE, SHIPPED_PAD_SWEEPS, build_pad_sweeps, pad_sweep_result

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
    """Run ``fem tables``."""
    what = {w.strip() for w in args.what.split(",") if w.strip()}
    if not what or not what <= {"kappa", "beta", "sphere", "pad"}:
        raise InputError(f"--what must name kappa, beta, sphere and/or pad, got "
                         f"'{args.what}'")
    if args.jobs < 1:
        raise InputError(f"--jobs must be at least 1, got {args.jobs}")
    command = "tactilevision " + " ".join(args.argv)
    grid = {}
    if args.quick:
        grid = {"nu": [0.3, 0.45, 0.49], "a_over_h": [0.4, 0.8, 1.2]}
    if "kappa" in what:
        mesh = {"cell": 0.25, "edge_refinements": 6} if args.quick else {}
        table = build_kappa_table(**grid, **mesh, jobs=args.jobs, progress=not args.no_progress)
        path = write_table(args.out_dir / "kappa_fem.npz", table, command=command)
        print(f"wrote {path}")
    if "beta" in what:
        mesh = {"cell": 0.5, "edge_refinements": 4, "steps": 4} if args.quick else {}
        table = build_beta_table(**grid, **mesh, jobs=args.jobs, progress=not args.no_progress)
        path = write_table(args.out_dir / "beta_fem.npz", table, command=command)
        print(f"wrote {path}")
    if "sphere" in what:
        sgrid = ({"radius_over_h": [1.0, 4.0], "nu": [0.4, 0.5], "w_over_h": [0.02, 0.1]}
                 if args.quick else {})
        table = build_sphere_table(**sgrid, jobs=args.jobs, progress=not args.no_progress)
        path = write_table(args.out_dir / "sphere_fem.npz", table, command=command)
        print(f"wrote {path}")
    if "pad" in what:
        def say(key: str) -> None:
            if not args.no_progress:
                print(f"pad sweep {key}", flush=True)

        table = build_pad_sweeps(SHIPPED_PAD_SWEEPS, pad_sweep_result, progress=say)
        path = write_table(args.out_dir / PAD_SWEEPS_FILE, table, command=command)
        print(f"wrote {path}")
    return 0
