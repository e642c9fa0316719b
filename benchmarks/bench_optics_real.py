"""Photometric stereo on real sensor frames: accuracy and frame rate.

Prints, for the GelSight ball presses of ``taxim`` (annotated circles) and the
GelSlim 3.0 ball presses of ``$TACTILEVISION_GELSLIM`` (circles detected),
calibrating on the even-numbered presses and evaluating on the odd ones:

- mean angle between reconstructed and true normals inside the contact disc,
- RMS shape error after fitting the unknown offset (and with the ball's
  position fitted too, which removes the error of the given circle centre),
- the ball radius fitted to the reconstructed height, mean and spread,
- milliseconds per frame on one core (OpenCV, onnxruntime and scipy.fft on
  one thread).

Models: the baseline of the issue (binned colour-difference LUT, no
reference normalisation, Dirichlet DST Poisson), our colour-only LUT, the
LUT with 4 x 3 position cells (``lut_cells``), the
MLP without position inputs (ablation), the position-aware MLP run through
onnxruntime, and the same MLP tabulated over colour and position cells.

Run: ``python benchmarks/bench_optics_real.py`` (about 5 minutes on 2 cores;
``--sensors gelsight`` for the GelSight part only).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import cv2
import numpy as np

from tactilevision.io import read_ball_presses, taxim_datapack
from tactilevision.optics import (
    DepthReconstructor,
    PhotometricCalibration,
    ball_gradients,
    ball_press_metrics,
    detect_contact_circles,
    evaluate_ball_presses,
    fit_colour_lut,
    gradients_from_normals,
    integrate_poisson,
    normals_from_gradients,
)

cv2.setNumThreads(1)
GELSLIM = Path(os.environ.get("TACTILEVISION_GELSLIM",
                              Path(__file__).resolve().parents[1].parent / "shared" / "real"
                              / "gelslim3"))

# GelSlim 3.0: the release's calibration script names a 7.6 mm ball and two
# scales, 0.10577 mm/px and "0.0806 x 1.5". Only 0.0806 mm/px makes the ball
# (47.1 px) larger than every detected contact circle (up to 47 px, 40 px
# after the 0.85 label fraction); 0.10577 (35.9 px) is impossible.
GELSLIM_MM_PER_PX = 0.0806
GELSLIM_BALL_MM = 3.8


def datasets(which: list[str]) -> list[dict]:
    out = []
    if "gelsight" in which:
        ps = read_ball_presses(taxim_datapack())
        out.append(dict(name="GelSight (taxim)", ps=ps, centres=ps.centers_px, radii=ps.radii_px,
                        mm=0.0295, ball_mm=2.0, given=True, units="um"))
    for sub in ("set_2020_11", "set_2020_09"):
        if "gelslim" in which and (GELSLIM / sub).is_dir():
            ps = read_ball_presses(GELSLIM / sub)
            c, r = detect_contact_circles(ps.frames, ps.reference)
            tag = " (markers)" if sub.endswith("09") else ""
            out.append(dict(name=f"GelSlim 3.0 {sub}{tag}",
                            ps=ps, centres=c, radii=0.85 * r, mm=GELSLIM_MM_PER_PX,
                            ball_mm=GELSLIM_BALL_MM, given=False, units="px"))
    return out


def baseline(ps, cal_i, ev_i, centres, radii, ball_px) -> tuple[dict, float]:
    """Plain binned colour-difference LUT + DST Poisson (the issue's reference)."""
    ref = ps.reference.astype(np.float32)
    h, w = ref.shape[:2]
    feats, labels = [], []
    rng = np.random.default_rng(0)
    for i in cal_i:
        gx, gy, inside = ball_gradients((h, w), centres[i], radii[i], ball_px)
        d = ps.frames[i].astype(np.float32) - ref
        yy, xx = np.mgrid[0:h, 0:w]
        far = (xx - centres[i][0]) ** 2 + (yy - centres[i][1]) ** 2 > (2 * radii[i]) ** 2
        sel = inside | (far & (rng.random((h, w)) < 0.03))
        feats.append(d[sel] / 255.0)
        labels.append(normals_from_gradients(gx[sel], gy[sel])[:, :2])
    lut = fit_colour_lut(np.concatenate(feats), np.concatenate(labels), bins=32, smooth_sigma=0)
    per = []
    t = 0.0
    for i in ev_i:
        t0 = time.perf_counter()
        nxy = lut.normals((ps.frames[i].astype(np.float32) - ref) / 255.0)
        gx, gy = gradients_from_normals(nxy[..., 0], nxy[..., 1])
        z = integrate_poisson(gx, gy, boundary="dirichlet")
        t += time.perf_counter() - t0
        per.append(ball_press_metrics(gx, gy, z, centres[i], radii[i], ball_px))
    return summary(per), 1000 * t / len(ev_i)


def summary(per) -> dict:
    r = np.array([p.fitted_radius_px for p in per])
    return dict(angle=float(np.mean([p.normal_angle_deg for p in per])),
                rms=float(np.mean([p.shape_rms_px for p in per])),
                placed=float(np.mean([p.shape_rms_placed_px for p in per])),
                radius=float(r.mean()), radius_std=float(r.std()))


def time_frames(recon: DepthReconstructor, frames: np.ndarray, repeat: int = 3) -> float:
    recon(frames[0])
    t0 = time.perf_counter()
    n = 0
    for _ in range(repeat):
        for f in frames:
            recon(f)
            n += 1
    return 1000 * (time.perf_counter() - t0) / n


def rows_for(sensors: list[str], skip_mlp: bool = False) -> list[dict]:
    """The table's rows for the named sensors ('gelsight', 'gelslim'): per sensor and
    model, ``angle`` (deg), ``rms`` and ``placed`` (shape RMS, px), ``radius`` and
    ``radius_std`` (the fitted ball radius, px), ``ms`` (per frame, one core), ``scale``
    (um a px, or 1 where ``units`` is 'px')."""
    rows = []
    for ds in datasets(sensors):
        ps = ds["ps"]
        n = len(ps.frames)
        cal_i, ev_i = np.arange(0, n, 2), np.arange(1, n, 2)
        ball_px = ds["ball_mm"] / ds["mm"]
        scale = ds["mm"] * 1000 if ds["units"] == "um" else 1.0
        frames_ev = ps.frames[ev_i]
        res, ms = baseline(ps, cal_i, ev_i, ds["centres"], ds["radii"], ball_px)
        rows.append(dict(sensor=ds["name"], model="baseline LUT (diff, DST)", ms=ms, **res,
                         scale=scale, units=ds["units"]))
        configs = [("LUT (ours, colour only)", "lut", {}, "table"),
                   ("LUT, 4 x 3 position cells", "lut", {"lut_cells": (4, 3)}, "table"),
                   ("MLP, no position (onnx)", "mlp", {"use_position": False}, "onnx"),
                   ("MLP, position-aware (onnx)", "mlp", {}, "onnx"),
                   ("MLP, position-aware (table)", "mlp", {}, "table")]
        cals = {}
        if skip_mlp:
            configs = [c for c in configs if c[1] == "lut"]
        for label, model, kw, engine in configs:
            key = (model, tuple(kw.items()))
            if key not in cals:
                t0 = time.perf_counter()
                cals[key] = PhotometricCalibration.from_ball_presses(
                    ps.reference, ps.frames[cal_i],
                    ds["centres"][cal_i] if ds["given"] else None,
                    ds["radii"][cal_i] if ds["given"] else None,
                    ball_radius_mm=ds["ball_mm"], mm_per_px=ds["mm"], model=model, **kw)
                print(f"[{ds['name']}] calibrated {model} {kw} in "
                      f"{time.perf_counter() - t0:.1f} s", file=sys.stderr)
            recon = DepthReconstructor(cals[key], engine=engine)
            rep = evaluate_ball_presses(recon, frames_ev, ds["centres"][ev_i], ds["radii"][ev_i],
                                        ball_px)
            ms = time_frames(recon, frames_ev[:8], repeat=1 if engine == "onnx" else 5)
            rows.append(dict(sensor=ds["name"], model=label, ms=ms,
                             angle=rep.normal_angle_deg, rms=rep.shape_rms_px,
                             placed=rep.shape_rms_placed_px, radius=rep.fitted_radius_px,
                             radius_std=rep.fitted_radius_std_px, scale=scale,
                             units=ds["units"]))
        rows[-1]["ball_px"] = ball_px
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sensors", default="gelsight,gelslim")
    ap.add_argument("--json", type=Path, default=None, help="also write the rows as JSON")
    ap.add_argument("--skip-mlp", action="store_true", help="the LUT rows only (no torch)")
    args = ap.parse_args(argv)
    rows = rows_for(args.sensors.split(","), args.skip_mlp)
    print("\n| sensor | model | normal angle (deg) | shape RMS | shape RMS, ball placed | "
          "fitted ball radius | ms/frame (1 core) | frames/s |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        s, u = r["scale"], r["units"]
        rad = (f"{r['radius'] * s / 1000:.3f} +- {r['radius_std'] * s / 1000:.3f} mm" if u == "um"
               else f"{r['radius']:.1f} +- {r['radius_std']:.1f} px")
        print(f"| {r['sensor']} | {r['model']} | {r['angle']:.2f} | {r['rms'] * s:.1f} {u} | "
              f"{r['placed'] * s:.1f} {u} | {rad} | {r['ms']:.1f} | {1000 / r['ms']:.0f} |")
    print("\nGelSight: ball radius 2.0 mm at 0.0295 mm/px, 24 presses calibrate, 24 evaluate, "
          "annotated circles. GelSlim 3.0: ball radius 3.8 mm at an assumed "
          f"{GELSLIM_MM_PER_PX} mm/px ({GELSLIM_BALL_MM / GELSLIM_MM_PER_PX:.1f} px), circles "
          "detected, discs of 0.85 x the detected radius; frames 427 x 320.")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
