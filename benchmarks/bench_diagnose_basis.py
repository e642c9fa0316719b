"""Two facts behind diagnose's rules, printed.

    python benchmarks/bench_diagnose_basis.py

1. depth_offset and force_offset give the same BIC on every table: in eq. (5)
   both are a constant plus a quadratic in w, so they are always reported as
   equivalent.
2. eq. (5) misfits the FEM's own P(w) by about 0.1 % of the deepest force,
   which low-noise repeated presses resolve: depth effects must beat a
   (w/h)^2 curvature of the law before they are reported.
"""

from __future__ import annotations

import warnings

import numpy as np

from tactilevision.mechanics import IndentationModel
from tactilevision.sim import make_measurement_table
from tactilevision.sim._tables import _fem_force


def main() -> None:
    warnings.simplefilter("ignore")
    model = IndentationModel()
    gaps = []
    for seed in range(20):
        t = make_measurement_table(None, seed)
        bic = [model.with_effect(e).fit(t.columns, thickness_mm=t.thickness_mm).bic
               for e in ("depth_offset", "force_offset")]
        gaps.append(abs(bic[0] - bic[1]))
    print(f"max |BIC(depth_offset) - BIC(force_offset)| over 20 null tables: {max(gaps):.3f}")
    for seed in range(3):
        t = make_measurement_table(None, seed)
        tr = t.truth
        w = np.unique(t.columns["depth_mm"])
        P = _fem_force(tr["E_mpa"], tr["nu"], t.radius_mm, t.thickness_mm, w)
        f = model.fit({"depth_mm": w, "force_n": P}, thickness_mm=t.thickness_mm, loss="linear")
        worst = np.max(np.abs(f.residuals_n)) / P.max()
        print(f"table {seed}: eq. (5) fitted to the FEM's P(w) at a/h "
              f"{t.radius_mm / t.thickness_mm:.2f}, nu {tr['nu']:.3f}: residuals "
              f"{np.round(f.residuals_n * 1e3, 2)} mN, max {worst:.2%} of Pmax {P.max():.3f} N")


if __name__ == "__main__":
    main()
