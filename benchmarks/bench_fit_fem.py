"""Fit with the FEM tables on presses made by the finite-strain FEM: bias, scatter, coverage.

Presses of a bonded Neo-Hookean layer (E = 0.15 MPa, nu = 0.47, h = 2.5 mm,
a = 3.0 mm, a/h = 1.2) at five depths (w/h = 0.06 ... 0.2), simulated on a finer
mesh (8 edge refinements) than the tables (7); ten presses per depth with
Gaussian force noise. Prints the noise-free fit, then for three noise levels
over 40 seeds the sd and largest error of E and nu, and how often the 95%
interval of E holds the truth.

Run: ``python benchmarks/bench_fit_fem.py`` (about a minute).
"""

from __future__ import annotations

import numpy as np

from tactilevision.fem import neo_hookean_indentation
from tactilevision.mechanics import fit_indentation

H, A, E, NU = 2.5, 3.0, 0.15, 0.47
W = np.array([0.06, 0.10, 0.14, 0.17, 0.20])


def main() -> None:
    t = neo_hookean_indentation(A / H, NU, contact="bonded", steps=20, edge_refinements=8)
    idx = [int(np.argmin(abs(t.w_over_h - x))) for x in W]
    force = E * H * H * t.force[idx]
    fit = fit_indentation(W * H, force, thickness_mm=H, radius_mm=A)
    print(f"noise-free: E = {fit.E_mpa:.5f} MPa ({100 * (fit.E_mpa / E - 1):+.2f}%), "
          f"nu = {fit.nu:.4f} ({fit.nu - NU:+.4f}), beta = {fit.beta:.4f}")
    for noise in (1 / 80, 0.005, 0.002):
        e_err, nu_err, cover = [], [], 0
        for seed in range(40):
            rng = np.random.default_rng(seed)
            w = np.repeat(W * H, 10)
            p = np.repeat(force, 10) + rng.normal(0, noise, w.size)
            f = fit_indentation(w, p, thickness_mm=H, radius_mm=A)
            if f.out_of_table:
                e_err.append(np.nan)
                nu_err.append(np.nan)
                continue
            e_err.append(f.E_mpa / E - 1)
            nu_err.append(f.nu - NU)
            cover += f.E_ci95_mpa[0] < E < f.E_ci95_mpa[1]
        e, n = np.array(e_err), np.array(nu_err)
        print(f"noise {noise:.4f} N per press: E error sd {100 * np.nanstd(e):.2f}%, largest "
              f"{100 * np.nanmax(abs(e)):.2f}%; nu error sd {np.nanstd(n):.4f}, largest "
              f"{np.nanmax(abs(n)):.4f}; out of table {int(np.isnan(e).sum())}/40; "
              f"95% interval of E holds the truth {cover}/40")


if __name__ == "__main__":
    main()
