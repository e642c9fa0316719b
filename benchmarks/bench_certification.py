"""Figures behind the certification of a session (issue 4's note).

    python benchmarks/bench_certification.py [--skip-bevel]

1. The bulge: crest height (fraction of w) and radius of a bonded gel at
   a/h = 2.5/3 for nu = 0.45, 0.48, 0.49, and the depth at which a flat land
   meets it for the gauge block's w0.
2. How exact the depths must be: eq. (5) with the FEM tables fitted to exact
   FEM presses (E 0.20 MPa, nu 0.48, ten per indenter) whose certified depths
   are short of the truth by d.
3. The bulge at the machined bevel's crest (9 mm = 3 h out), the correction a
   vernier reading needs (benchmarks/bench_vernier.py measures the reading).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from scipy.interpolate import PchipInterpolator

from tactilevision.contact import bulge_at, bulge_height, land_contact_depth
from tactilevision.mechanics import fit_indentation
from tactilevision.sim import press_profile

ROOT = Path(__file__).resolve().parents[1]
H, A = 3.0, 2.5
W0 = (0.15, 0.30, 0.40, 0.50, 0.60)


def bulge() -> None:
    print("1. bulge crest of a bonded layer, a/h = 0.8333 (finite-strain FEM)")
    for nu in (0.45, 0.48, 0.49):
        p = press_profile(A / H, nu)
        crest = [bulge_height(p, w) for w in (0.05, 0.1, 0.2)]
        wc = [land_contact_depth(w / H, p) * H for w in W0]
        print(f"  nu {nu}: crest/w at w/h 0.05, 0.1, 0.2 = "
              + ", ".join(f"{c / w:.4f} (r/h {r:.2f})" for (c, r), w in zip(crest, (0.05, 0.1, 0.2),
                                                                           strict=True))
              + "; land meets it at w = " + ", ".join(f"{v:.4f}" for v in wc) + " mm")


#: The shared depth errors :func:`sensitivity_rows` tries, mm (every press short by d).
SHORT_MM = (0.0, 0.00025, 0.001)


def sensitivity_rows(shorts_mm: tuple[float, ...] = SHORT_MM) -> list[tuple[float, float, float,
                                                                          float]]:
    """E and nu fitted to exact FEM presses (E 0.20 MPa, nu 0.48, ten per indenter) whose
    certified depths are all short of the truth by d: ``(d_um, E error %, nu error,
    beta)`` per d."""
    p = press_profile(A / H, 0.48, w_over_h_max=0.22, steps=11)
    w = np.repeat(W0, 10)
    force = 0.20 * H * H * PchipInterpolator(p.w_over_h, p.force)(w / H)
    rows = []
    for d in shorts_mm:
        f = fit_indentation(w - d, force, thickness_mm=H, radius_mm=A)
        rows.append((1e3 * d, 100 * (f.E_mpa / 0.2 - 1), f.nu - 0.48, f.beta))
    return rows


def sensitivity() -> None:
    print("2. E and nu when every certified depth is short of the truth by d")
    for d, e, nu, beta in sensitivity_rows():
        print(f"  d = {d:.2f} um: E {e:+.2f}%, nu {nu:+.4f}, beta {beta:.4f}")


def bevel_bulge() -> None:
    print("3. the bulge at the bevel's crest, fraction of w (bulge_at; the vernier's correction)")
    for r in (6.0, 7.5, 9.0, 10.5, 12.0):
        fr = [float(bulge_at(r, [0.3], thickness_mm=H, radius_mm=A, nu=nu)[0]) / 0.3
              for nu in (0.45, 0.48, 0.49)]
        print(f"  {r:4.1f} mm ({r / H:.1f} h): nu 0.45 {100 * fr[0]:.2f}%, "
              f"0.48 {100 * fr[1]:.2f}%, 0.49 {100 * fr[2]:.2f}%")


if __name__ == "__main__":
    bulge()
    sensitivity()
    if "--skip-bevel" not in sys.argv:
        bevel_bulge()
