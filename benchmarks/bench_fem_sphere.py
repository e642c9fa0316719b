"""The sphere FEM against truth that is not our code, and its mesh convergence.

Prints:

1. Hertz's half-space: a thick layer (R/h = 0.1, chi = sqrt(R w)/h = 0.003 and
   0.005), paraboloid, linear: P / P_Hertz and a / sqrt(R w).
2. Dimitriadis et al. (Biophys. J. 82:2798, 2002) eq. (12), an incompressible
   layer bonded to a rigid base under a paraboloid: FEM over the series at
   chi = 0.1 ... 0.5.
3. Mesh convergence: force and contact radius on two surface cells (the
   default and half of it), linear and Neo-Hookean, frictionless and tied.
4. The sphere table's interpolation (models/sphere_fem.npz) against direct
   sweeps off its grid.

Usage: python benchmarks/bench_fem_sphere.py [--quick]
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np

from tactilevision.fem import sphere_indentation
from tactilevision.mechanics import sphere_contact_ratio, sphere_force_ratio

DIM12 = (1.133, 1.283, 0.769, 0.0975)


def dimitriadis(chi):
    c = DIM12
    return 1 + c[0] * chi + c[1] * chi**2 + c[2] * chi**3 + c[3] * chi**4


def hertz_limit() -> None:
    R, w = 0.1, np.array([1e-4, 2.5e-4])
    t = time.perf_counter()
    r = sphere_indentation(R, 0.5, w, model="linear", profile="paraboloid", cache=False)
    chi = np.sqrt(R * w)
    print(f"1. Hertz limit (R/h = {R}, paraboloid, linear, nu = 0.5; {r.n_dofs} dofs, "
          f"{time.perf_counter() - t:.1f} s)")
    for k in range(w.size):
        print(f"   chi = {chi[k]:.4f}: P/P_Hertz = {r.hertz_ratio[k]:.5f} (layer's first order "
              f"1 + 1.133 chi = {1 + 1.133 * chi[k]:.5f}), a/sqrt(Rw) = "
              f"{r.contact_radius[k] / np.sqrt(R * w[k]):.5f}")


def dimitriadis_check(quick: bool) -> None:
    chi = np.array([0.1, 0.2, 0.3] if quick else [0.1, 0.15, 0.2, 0.25, 0.3, 0.4, 0.5])
    t = time.perf_counter()
    r = sphere_indentation(1.0, 0.5, chi**2, model="linear", profile="paraboloid", cache=False)
    print(f"2. Dimitriadis eq. (12) (R/h = 1, paraboloid, linear, nu = 0.5, bonded base; "
          f"{r.n_dofs} dofs, {time.perf_counter() - t:.1f} s)")
    for k in range(chi.size):
        print(f"   chi = {chi[k]:.2f}: FEM {r.hertz_ratio[k]:.4f}, eq. (12) "
              f"{dimitriadis(chi[k]):.4f}, ratio {r.hertz_ratio[k] / dimitriadis(chi[k]):.4f}")


def convergence(quick: bool) -> None:
    w = np.array([0.01, 0.04] if quick else [0.01, 0.04, 0.16])
    print("3. Mesh convergence (R/h = 2, nu = 0.45): surface cell a_first/12 and half of it")
    for model in ("linear", "neo_hookean"):
        for contact in ("frictionless", "tied"):
            t = time.perf_counter()
            a = sphere_indentation(2.0, 0.45, w, model=model, contact=contact, cache=False)
            b = sphere_indentation(2.0, 0.45, w, model=model, contact=contact, cache=False,
                                   surface_cell=0.5 * a.surface_cell)
            dp = 100 * (a.force / b.force - 1)
            da = 100 * (a.contact_radius / b.contact_radius - 1)
            print(f"   {model:11s} {contact:12s} dofs {a.n_dofs}/{b.n_dofs}: force "
                  + " ".join(f"{v:+.2f}%" for v in dp) + "; contact radius "
                  + " ".join(f"{v:+.2f}%" for v in da)
                  + f"  ({time.perf_counter() - t:.0f} s)")


def table_check() -> None:
    print("4. Sphere table interpolation against direct sweeps off its grid")
    for R, nu, model, contact in ((1.4, 0.47, "neo_hookean", "tied"),
                                  (3.0, 0.42, "linear", "frictionless"),
                                  (6.0, 0.49, "neo_hookean", "frictionless")):
        w = np.array([0.03, 0.15, 0.33])
        r = sphere_indentation(R, nu, w, model=model, contact=contact)
        f = sphere_force_ratio(R, nu, w, model=model, contact=contact)
        a = sphere_contact_ratio(R, nu, w, model=model, contact=contact)
        df = 100 * (f / r.hertz_ratio - 1)
        da = 100 * (a / (r.contact_radius / np.sqrt(R * w)) - 1)
        print(f"   R/h {R}, nu {nu}, {model}, {contact}: force " + " ".join(
            f"{v:+.2f}%" for v in df) + "; contact radius " + " ".join(f"{v:+.2f}%" for v in da))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer depths")
    ap.add_argument("--no-table", action="store_true", help="skip the table check")
    args = ap.parse_args()
    print(f"machine: {platform.machine()}, {platform.processor() or '?'}; "
          f"python {platform.python_version()}")
    hertz_limit()
    dimitriadis_check(args.quick)
    convergence(args.quick)
    if not args.no_table:
        table_check()


if __name__ == "__main__":
    main()
