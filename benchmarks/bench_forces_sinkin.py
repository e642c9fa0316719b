"""Why the shallow presses' forces read low: the punch face's height against its true depth,
and the total force against the press's, as the contact mask grows.

    python benchmarks/bench_forces_sinkin.py [--fit FIT.json] [--grow 6,12,20]

On every press of ``sample_frames/gelsight_session`` (not at the image's edge, not
misaligned; one frame 0.25 s into its hold, the press's true depth and force from
``truth.json``): the default force path's pieces, the session's own optics with the height
pinned to zero outside the frame's contact mask (``DepthReconstructor(boundary='contact')``)
and the spectral 'footprint' estimator (height above 0.02 mm) with E, nu and beta from
``--fit`` (``tactilevision calibrate sample_frames/gelsight_session --out out/calibration``
writes it). The contact mask is the colour change above the frame's threshold, grown by
``--grow`` px (6 px is the library's default, ``DepthReconstructor``'s dilation).

Printed per growth: for the 0.15 mm presses and the deeper ones, the median (range) of the
face's height (median within 0.6 punch radii) over the true depth, and of the total force
over the true force, and how many presses lie within 5 %.

The pinned boundary is the point: the gel round a punch sinks in far beyond the punch's
edge, and where its slope falls under the colour threshold the mask ends with the surface
still below zero; pinning it there lifts the whole face by that sink-in.

``--sinkin``: instead of growing the mask, the boundary's own sink-in from the elastic
model of the force found: the heights inside the mask raised by delta, delta the median
over the ring of pixels just outside the mask of the layer's surface displacement under
the (linear, beta 0) traction the raised heights give on the first footprint (a fixed
point, iterated to 0.01 um); the force then read with beta on that footprint. Printed as
the rows above, with the median delta.
"""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

import cv2
import numpy as np

from tactilevision.fem import ForceEstimator
from tactilevision.optics import DepthReconstructor, PhotometricCalibration

ROOT = Path(__file__).resolve().parents[1]
SESSION = ROOT / "sample_frames" / "gelsight_session"


def _hold_frames(truth: dict):
    """(press, its frame 0.25 s into the hold) for every press not at the pad's edge nor
    misaligned."""
    with (SESSION / "frames.csv").open() as fh:
        times = {r["frame"]: float(r["t_s"]) for r in csv.DictReader(fh)}
    for p in truth["presses"]:
        if p["edge"] or p["misaligned"]:
            continue
        t = p["hold_from_s"] + 0.25
        name = min(times, key=lambda k: abs(times[k] - t))
        yield p, cv2.imread(str(SESSION / "frames" / name))


def _face(z: np.ndarray, p: dict, truth: dict) -> float:
    """The punch face's height (median within 0.6 punch radii) over the press's depth."""
    mm = float(truth["mm_per_px"])
    h, w = z.shape
    yy, xx = np.indices(z.shape)
    d = np.hypot(xx - (w / 2 + p["x_mm"] / mm), yy - (h / 2 + p["y_mm"] / mm)) * mm
    return float(np.median(z[d < 0.6 * truth["radius_mm"]])) / p["depth_mm"]


def _setup(fit: dict, truth: dict, beta: float | None = None):
    """The session's optics with the contact-pinned height, and the footprint estimator."""
    cal = PhotometricCalibration.load(SESSION / "optics.npz")
    ref = cv2.imread(str(SESSION / "reference.png"))
    recon = DepthReconstructor(cal, reference=ref, boundary="contact", level="median")
    est = ForceEstimator(cal.shape, float(truth["mm_per_px"]),
                         thickness_mm=float(truth["thickness_mm"]), E_mpa=fit["E_mpa"],
                         nu=fit["nu"], contact="footprint", threshold_mm=0.02,
                         beta=fit.get("beta", 0.0) if beta is None else beta)
    return cal, recon, est


def run(grow: int, fit: dict, truth: dict) -> list[tuple[float, float, float]]:
    """(w0, face / depth, Fz / force) per press at a mask growth of `grow` px."""
    _, recon, est = _setup(fit, truth)
    recon._dilate = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * grow + 1, 2 * grow + 1))
    out = []
    for p, frame in _hold_frames(truth):
        z = recon(frame)
        out.append((p["w0_mm"], _face(z, p, truth), float(est(z).total_n[2]) / p["force_n"]))
    return out


def run_sinkin(fit: dict, truth: dict) -> list[tuple[float, float, float, float]]:
    """(w0, face / depth, Fz / force, delta mm) per press with the boundary's own sink-in
    (``--sinkin``)."""
    cal, recon, est = _setup(fit, truth)
    _, _, lin = _setup(fit, truth, beta=0.0)
    mm = float(truth["mm_per_px"])
    op, (H, W) = lin._op, cal.shape
    ring_kernel = np.ones((3, 3), np.uint8)
    out = []
    for p, frame in _hold_frames(truth):
        z0 = recon(frame)
        mask = recon.contact_mask(frame, threshold="frame", fill_holes=True)
        ring = cv2.dilate(mask.astype(np.uint8), ring_kernel).astype(bool) & ~mask
        first = z0 > 0.02
        delta = 0.0
        for _ in range(20):
            traction = lin(z0 + delta * mask, contact_mask=first).forces_n[..., 2] / mm**2
            u = np.zeros((*op.fshape, 1), np.float32)
            u[:H, :W, 0] = traction
            new = float(np.median(op._apply32(op.C32, u)[:H, :W, 0][ring]))
            done, delta = abs(new - delta) < 1e-5, new
            if done:
                break
        z = z0 + delta * mask
        fz = float(est(z, contact_mask=first).total_n[2])
        out.append((p["w0_mm"], _face(z, p, truth), fz / p["force_n"], delta))
    return out


def _print_rows(head: str, rows: np.ndarray) -> None:
    """A table row for the 0.15 mm presses and one for the deeper ones."""
    for label, sel in (("0.15 mm", rows[:, 0] < 0.3), (">= 0.3 mm", rows[:, 0] >= 0.3)):
        r = rows[sel]
        face, force = r[:, 1], r[:, 2]
        extra = f" (delta {1e3 * np.median(r[:, 3]):.1f} um)" if rows.shape[1] > 3 else ""
        print(f"| {head}{extra} | {label} ({sel.sum()}) | {np.median(face):.3f} "
              f"({face.min():.3f} to {face.max():.3f}) | {np.median(force):.3f} "
              f"({force.min():.3f} to {force.max():.3f}) | "
              f"{int(np.sum(np.abs(force - 1) <= 0.05))} of {sel.sum()} |", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fit", type=Path, default=ROOT / "out" / "calibration" / "fit.json")
    ap.add_argument("--grow", default="6,12,20")
    ap.add_argument("--sinkin", action="store_true",
                    help="also the boundary's own sink-in from the force found (docstring)")
    args = ap.parse_args()
    truth = json.loads((SESSION / "truth.json").read_text())
    if not args.fit.is_file():
        raise SystemExit(f"{args.fit}: no fit.json (run tactilevision calibrate "
                         "sample_frames/gelsight_session --out out/calibration first)")
    fit = json.loads(args.fit.read_text())
    print(f"fit: {args.fit} (E {fit['E_mpa']:.4g} MPa, nu {fit['nu']:.4g}, "
          f"beta {fit.get('beta', 0.0):.3g})")
    print("| mask grown | presses | face / depth: median (range) | force / F: median (range) "
          "| force within 5 % |")
    print("|---|---|---|---|---|")
    for grow in (int(g) for g in args.grow.split(",")):
        _print_rows(f"{grow} px", np.array(run(grow, fit, truth)))
    if args.sinkin:
        _print_rows("sink-in", np.array(run_sinkin(fit, truth)))

if __name__ == "__main__":
    main()
