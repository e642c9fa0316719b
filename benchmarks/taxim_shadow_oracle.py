"""How much of the absolute-depth error on Taxim's shadowed frames could a shadow detector remove?

    python benchmarks/taxim_shadow_oracle.py [--presses 48]

Renders, with Taxim's own renderer (``bench_absolute_depth.render_taxim``), the
test presses (a 2 mm ball and a 2.5 mm flat punch at 0.1 to 0.6 mm) and
``--presses`` calibration presses of a 3 mm ball, each twice: with Taxim's
shadows and without (same seed, same camera noise). A LUT with 4 x 3 position
cells is calibrated on the shadowed calibration presses (the optics a rig would
make from frames that show shadows), and every shadowed test frame is
reconstructed with the contact zero (``integrate_poisson_masked`` on the frame's
contact region) three ways:

- as it is;
- with an oracle: the gradient set to zero on the pixels where the shadowed
  and the unshadowed render differ by more than 8 grey levels (the exact
  shadow, which no detector of ours knows);
- the unshadowed frame itself, with the same optics.

Printed: the shadow's pixels and how many of them have a colour change in a
cell of the calibration's colour table that no calibration pixel filled (which
a detector of unsupported colours could flag), and the deepest-point error
(within 0.9 a) of each reconstruction, um. If the oracle
left the error near the unshadowed frame's, a shadow detector would be worth
building; where it does not, the shadows fall on the contact itself (Taxim
casts them from the contact's rim onto the deeper gel) and a per-pixel
photometric model cannot read the slope under them.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_absolute_depth as B

from tactilevision.optics import DepthReconstructor, PhotometricCalibration
from tactilevision.optics._poisson import integrate_poisson_masked


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--presses", type=int, default=48)
    a = ap.parse_args(argv)
    t0 = time.perf_counter()
    ref, sh, balls = B.render_taxim(shadow=True, calibration_presses=a.presses)
    _, nosh = B.render_taxim(shadow=False)
    print(f"{len(sh) + len(nosh) + a.presses + 1} Taxim renders in "
          f"{time.perf_counter() - t0:.0f} s")
    cal = PhotometricCalibration.from_ball_presses(
        ref, balls["frames"], balls["centers_px"], balls["radii_px"],
        ball_radius_mm=B.CAL_BALL_MM, mm_per_px=B.MM_PER_PX, model="lut",
        lut_cells=B.OWN_LUT_CELLS)
    rec = DepthReconstructor(cal, reference=ref, boundary="contact")
    mm = B.MM_PER_PX
    centre = ((B.SHAPE[1] - 1) / 2, (B.SHAPE[0] - 1) / 2)
    r_mm = B._grid_r_px(B.SHAPE, centre) * mm
    from tactilevision.optics._features import blur_frames, colour_change

    empty = (cal.lut.counts == 0).ravel()
    print("| press | shadow pixels | of them in empty colour cells | as it is | gradient zeroed "
          "on the exact shadow | the unshadowed frame |")
    print("|---|---|---|---|---|---|")
    for p, q in zip(sh, nosh, strict=True):
        f, f0 = p["frame"], q["frame"]
        d, rad = p["depth_mm"], p["contact_radius_mm"]
        truth = (B._ball_truth(r_mm, B.BALL_MM, rad) if p["kind"] == "ball"
                 else np.where(r_mm < rad, d, 0.0))
        shadow = np.abs(f.astype(int) - f0.astype(int)).max(-1) > 8
        fb = blur_frames(f, cal.blur_sigma) if cal.blur_sigma > 0 else f
        cells = cal.lut.index(colour_change(fb, rec._ref_inv).astype(np.float32))
        unsupported = int(np.count_nonzero(shadow & empty[cells]))
        gx, gy = rec.gradients(f)
        m = rec.contact_mask(f, threshold="frame", fill_holes=True)
        z_as = integrate_poisson_masked(gx, gy, m) * mm
        z_or = integrate_poisson_masked(np.where(shadow, 0, gx).astype(np.float32),
                                        np.where(shadow, 0, gy).astype(np.float32), m) * mm
        z_no = rec(f0)
        inner = r_mm < B.DISC * rad
        top = truth[inner].max()

        def err(z: np.ndarray, top: float = top, inner: np.ndarray = inner) -> str:
            return f"{1000 * (z[inner].max() - top):+.0f}"

        print(f"| {p['kind']} {d:g} mm | {int(shadow.sum())} | {unsupported} | {err(z_as)} | "
              f"{err(z_or)} | {err(z_no)} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
