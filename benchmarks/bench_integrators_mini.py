"""Three integrators of the same gradients on a real GelSight Mini, against the ball.

``gs_sdk_reference.npz`` (in the shared GelSight Mini folder) holds what gs_sdk itself
computed on six of the folder's presses: its gradients G and its heights H (its own DCT
Poisson solve of G). This benchmark integrates the same G with this project's
:class:`~tactilevision.optics.PoissonSolver` (Neumann, DCT-II), reads the heights this
project's default pipeline gives with gs_sdk's own network imported
(``PhotometricCalibration.from_gs_sdk``, default table engine), and compares each with
the 6.31 mm ball in the contact circle detected on the frame
(:func:`~tactilevision.optics.detect_contact_circles`, the contact edge; no integrator
is used to find it):

- inner cap: the height at the centre above the median on the circle at 0.8 of the
  contact radius, against the sphere's drop there, R - sqrt(R^2 - (0.8 r)^2): inside
  the contact, where the ball surely touches;
- full cap: the deepest point inside the circle above the median on the circle, against
  R - sqrt(R^2 - r^2): the rim, whose shape the ball does not set, included.

    python benchmarks/bench_integrators_mini.py [--folder DIR]
"""

from __future__ import annotations

import argparse
import math
import os
from pathlib import Path

import cv2
import numpy as np

from tactilevision.optics import (
    DepthReconstructor,
    PhotometricCalibration,
    PoissonSolver,
    detect_contact_circles,
)

MM_PER_PX = 0.0634
BALL_RADIUS_MM = 6.31 / 2


def caps(height_um: np.ndarray, centre: np.ndarray, radius: float) -> tuple[float, float]:
    """(inner cap, full cap), um: centre over the 0.8 r circle, deepest point over the rim."""
    hh, ww = height_um.shape
    yy, xx = np.mgrid[0:hh, 0:ww]
    d = np.hypot(xx - centre[0], yy - centre[1])
    inner = height_um[d <= 1.5].mean() - np.median(height_um[np.abs(d - 0.8 * radius) <= 1.0])
    full = height_um[d <= radius].max() - np.median(height_um[np.abs(d - radius) <= 1.0])
    return float(inner), float(full)


def sphere(radius_px: float) -> tuple[float, float]:
    """The ball's inner and full caps for a contact radius, um."""
    big = BALL_RADIUS_MM / MM_PER_PX
    drop = [big - math.sqrt(big * big - (f * radius_px) ** 2) for f in (0.8, 1.0)]
    return drop[0] * MM_PER_PX * 1000, drop[1] * MM_PER_PX * 1000


def main() -> int:
    root = Path(__file__).resolve().parents[1]
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--folder", type=Path, default=Path(os.environ.get(
        "TACTILEVISION_GELSIGHT_MINI", root.parent / "shared" / "real" / "gelsight_mini")))
    args = ap.parse_args()
    ref_path = args.folder / "gs_sdk_reference.npz"
    if not ref_path.is_file():
        print(f"no gs_sdk_reference.npz in {args.folder}: nothing to compare")
        return 0
    ref = np.load(ref_path)
    background = cv2.imread(str(args.folder / "background.png"))
    cal = PhotometricCalibration.from_gs_sdk(args.folder / "model" / "nnmodel.pth",
                                             background, mm_per_px=MM_PER_PX)
    pipeline = DepthReconstructor(cal)
    solver = PoissonSolver(background.shape[:2])
    frames = np.stack([cv2.imread(str(args.folder / str(n) / "gelsight.png"))
                       for n in ref["presses"]])
    centres, radii = detect_contact_circles(frames, background)
    print("| press | contact r (px) | sphere inner / full (um) | gs_sdk's solve | this "
          "project's solve, same G | this project's pipeline |")
    print("|---|---|---|---|---|---|")
    rel = {"gs_sdk": [], "ours": [], "pipeline": []}
    for k, name in enumerate(ref["presses"]):
        G = ref["gradients"][k].astype(np.float64)
        heights = {
            # gs_sdk's H is the height towards the camera in px: the depth is -H
            "gs_sdk": -ref["heights_px"][k] * MM_PER_PX * 1000,
            # our depth slope is -G
            "ours": solver(-G[..., 0], -G[..., 1]) * MM_PER_PX * 1000,
            "pipeline": pipeline(frames[k]) * 1000,
        }
        s_in, s_full = sphere(radii[k])
        cells = []
        for key, h in heights.items():
            c_in, c_full = caps(h, centres[k], radii[k])
            rel[key].append((c_in / s_in - 1, c_full / s_full - 1))
            cells.append(f"{c_in:.0f} / {c_full:.0f} ({100 * (c_in / s_in - 1):+.0f} %, "
                         f"{100 * (c_full / s_full - 1):+.0f} %)")
        print(f"| {name} | {radii[k]:.1f} | {s_in:.0f} / {s_full:.0f} | " + " | ".join(cells)
              + " |")
    for key, label in (("gs_sdk", "gs_sdk's solve"), ("ours", "this project's solve"),
                       ("pipeline", "this project's pipeline")):
        r = np.array(rel[key])
        print(f"{label}: inner cap {100 * np.median(r[:, 0]):+.1f} % (median), full cap "
              f"{100 * np.median(r[:, 1]):+.1f} % against the sphere")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
