"""Does strain stiffening close the gap to the paper's beta? Yeoh C20 against beta.

The paper's presses (a = 2.5 mm, h = 3 mm, a/h = 0.833; depths 0.15, 0.30,
0.40, 0.50, 0.60 mm) give beta = 1.5071 (line 6). A bonded compressible
Neo-Hookean layer gives at most about 0.8 there (models/beta_fem.npz). This
adds Yeoh's strain-stiffening term C20 (I1bar - 3)^2 to the isochoric energy
and prints, for nu = 0.45, 0.48 and 0.499, the secant beta of eq. (5) at the
paper's five depths against C20 / C10, then the C20 / C10 that reproduces
1.5071 (root of beta(C20) = 1.5071 by Brent's method).

Run: ``python benchmarks/bench_material_law.py`` (about 5 minutes).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from tactilevision.fem import neo_hookean_indentation

A_OVER_H = 2.5 / 3.0
PAPER_BETA = 5.2662 / 3.4943
PAPER_W = np.array([3, 6, 8, 10, 12]) / 60.0  # 0.15 ... 0.60 mm over h = 3 mm


def beta_at_paper_depths(nu: float, ratio: float) -> float:
    res = neo_hookean_indentation(A_OVER_H, nu, contact="bonded", steps=12,
                                  c20_over_c10=ratio)
    if not res.complete:
        return float("nan")
    idx = [int(np.argmin(np.abs(res.w_over_h - w))) for w in PAPER_W]
    slope, icpt = np.polyfit(res.w_over_h[idx], res.kappa_n[idx], 1)
    return slope / icpt


def main() -> None:
    ratios = (0.0, 0.05, 0.1, 0.2, 0.3, 0.5)
    print("secant beta at the paper's depths, a/h = 0.833, bonded punch")
    print("  nu     " + "  ".join(f"C20/C10={r:<5g}" for r in ratios))
    for nu in (0.45, 0.48, 0.499):
        row = [beta_at_paper_depths(nu, r) for r in ratios]
        print(f"  {nu:5.3f}  " + "  ".join(f"{b:13.4f}" for b in row))
        root = brentq(lambda r, nu=nu: beta_at_paper_depths(nu, r) - PAPER_BETA, 0.0, 0.5,
                      xtol=1e-3)
        print(f"         beta = {PAPER_BETA:.4f} at C20/C10 = {root:.3f}")


if __name__ == "__main__":
    main()
