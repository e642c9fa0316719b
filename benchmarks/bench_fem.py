"""Timing of the indentation FEM: one linear solve, one finite-strain sweep, the table builds.

Prints, on this machine (one thread):

- one small-strain solve (``linear_indentation``) at a/h = 0.8, nu = 0.45 on the
  kappa table's mesh (cell 0.125, 10 edge refinements): dofs, seconds;
- one finite-strain depth sweep (``neo_hookean_indentation``, bonded punch, ten
  increments to w/h = 0.2) on the beta table's mesh (cell 0.25, 7 edge
  refinements) and on a finer one: dofs, seconds, Newton iterations;
- the full table builds: the wall time and per-sweep times recorded in the
  provenance of ``models/kappa_fem.npz`` and ``models/beta_fem.npz``; with
  ``--rebuild`` the beta table is rebuilt into a temporary folder and timed
  (about 15 minutes with ``--jobs 2``).

Run: ``python benchmarks/bench_fem.py [--rebuild] [--jobs N]`` (about a minute
without --rebuild).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np

from tactilevision.fem import linear_indentation, neo_hookean_indentation
from tactilevision.mechanics._fem_tables import fem_table_meta


def linear() -> None:
    t0 = time.perf_counter()
    res = linear_indentation(0.8, 0.45)
    dt = time.perf_counter() - t0
    print(f"linear solve, a/h 0.8, nu 0.45, frictionless: {res.n_dofs} dofs, {dt:.2f} s "
          f"(mesh, assembly and solve), kappa = {res.kappa:.4f}")


def finite() -> None:
    for cell, er in ((0.25, 7), (0.25, 8), (0.125, 8)):
        res = neo_hookean_indentation(0.8, 0.45, contact="bonded", cell=cell,
                                      edge_refinements=er)
        print(f"finite-strain sweep, a/h 0.8, nu 0.45, bonded, cell {cell}, {er} edge "
              f"refinements: {res.n_dofs} dofs, {res.seconds:.1f} s, "
              f"{int(res.newton_iterations.sum())} Newton iterations for {len(res.w_over_h)} "
              f"depths ({res.seconds / res.newton_iterations.sum():.2f} s each), "
              f"beta = {res.beta_secant:.4f}, complete {res.complete}")


def tables() -> None:
    for name in ("kappa_fem.npz", "beta_fem.npz"):
        try:
            meta = fem_table_meta(name)
        except ValueError as exc:
            print(f"{name}: {exc}")
            continue
        per = meta.get("seconds_per_sweep")
        extra = (f", per sweep min {per['min']} / median {per['median']} / max {per['max']} s "
                 f"with {meta.get('jobs', 1)} worker(s)") if per else ""
        print(f"{name}: built in {meta['seconds']:.0f} s{extra}; command '{meta['command']}', "
              f"created {meta['created']}")


def rebuild(jobs: int) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-m", "tactilevision", "fem", "tables", "--what", "beta",
                        "--jobs", str(jobs), "--out-dir", tmp], check=True)
        dt = time.perf_counter() - t0
        with np.load(Path(tmp) / "beta_fem.npz") as z:
            n = z["complete"].size
        print(f"beta table rebuilt: {n} sweeps in {dt:.0f} s with {jobs} worker(s)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rebuild", action="store_true", help="rebuild and time the beta table")
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()
    linear()
    finite()
    tables()
    if args.rebuild:
        rebuild(args.jobs)


if __name__ == "__main__":
    main()
