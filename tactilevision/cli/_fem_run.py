"""What ``tactilevision fem tables`` does once its options are parsed
(:mod:`tactilevision.cli._fem`): rebuild the FEM kappa and beta tables of ``models/``.

Imported only when the command runs, so that its ``--help`` does not load this stack.
"""

from __future__ import annotations

import argparse

from .. import InputError
from ..fem import build_beta_table, build_kappa_table, build_sphere_table, write_table
from ..mechanics import PAD_SWEEPS_FILE, SHIPPED_PAD_SWEEPS, build_pad_sweeps, pad_sweep_result

__all__ = ["run_tables"]


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
