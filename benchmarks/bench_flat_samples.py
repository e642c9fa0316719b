"""Flat samples: what `flat_fraction` trades, on the real GelSight presses and Taxim renders.

For each flat fraction, a calibration from detected circles is trained on the even
presses of the first ball and scored held out. On taxim's real GelSight presses
(annotated circles as truth), it reports the normal angle and the deepest point
(``calibration_accuracy``, ``level='far_field'``), and the radial slope within 0.2 of
the contact radius against the ball's. It also reports the flat gel beyond twice that
radius, whose true tilt is 0: its mean tilt and its height rms, under both levels.
Optionally (``--taxim-npz``, renders saved by ``--save-taxim`` or drawn with
``--render-taxim``) it scores Taxim renders without shadows against Taxim's own gel
(``bench_contact_edge.score``): odd presses, and the unseen second ball.
With ``--zero-background both`` every calibration is also scored with
``DepthReconstructor(zero_background=True)`` (gradients outside each frame's contact
region set to zero before integrating); the angle and the background tilt are the
gradients' and do not change with it.

    python benchmarks/bench_flat_samples.py [--models lut mlp] [--fractions 0.03 0.01 0.003]
        [--zero-background {off,both}]
        [--render-taxim 40 20 --save-taxim renders.npz | --taxim-npz renders.npz]
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "2")
sys.path.insert(0, str(Path(__file__).parent))

import numpy as np

from tactilevision.io import read_ball_presses, taxim_datapack
from tactilevision.optics import (
    DepthReconstructor,
    PhotometricCalibration,
    ball_gradients,
    calibration_accuracy,
)

MM = 0.0295


def _real_row(cal, model: str, ff: float, zb: bool, t_cal: float, ps, train, ball_px) -> str:
    """One table line: a calibration scored on the held-out real presses."""
    ref, frames, centres, radii = ps.reference, ps.frames, ps.centers_px, ps.radii_px
    h, w = ref.shape[:2]
    yy, xx = np.mgrid[0:h, 0:w]
    recs = {lv: DepthReconstructor(cal, level=lv, zero_background=zb)
            for lv in ("far_field", "median")}
    ball = calibration_accuracy(recs["far_field"], frames, centres, radii,
                                np.full(len(frames), ball_px), trained=train,
                                label_fraction=1.0)["balls"][0]
    centre, tilt, rms = [], [], {lv: [] for lv in recs}
    for i in np.flatnonzero(~train):
        gx, gy = recs["far_field"].gradients(frames[i])
        tgx, tgy, _ = ball_gradients((h, w), centres[i], radii[i], ball_px)
        dx, dy = xx - centres[i][0], yy - centres[i][1]
        d = np.hypot(dx, dy)
        m = d < 0.2 * radii[i]
        centre.append((gx * dx + gy * dy)[m].sum() / (tgx * dx + tgy * dy)[m].sum())
        far = d > 2 * radii[i]
        tilt.append(np.degrees(np.arctan(np.hypot(gx[far], gy[far]))).mean())
        for lv, rec in recs.items():
            hp = rec(frames[i]) * 1000.0
            rms[lv].append(np.sqrt(np.mean((hp[far] - np.median(hp[far])) ** 2)))
    return (f"| real GelSight | {model} | {ff:g}{' + zero_background' if zb else ''} | "
            f"{ball['normal_angle_deg']:.2f} deg, "
            f"{100 * ball['deepest_point']:+.1f} % | {np.median(centre):.2f} | "
            f"{np.median(tilt):.2f} deg | {np.median(rms['far_field']):.0f} / "
            f"{np.median(rms['median']):.0f} um | {t_cal:.0f} s |")


def real_rows(models, fractions, zero_backgrounds=(False,)) -> list[str]:
    """One line per (model, flat fraction) on the real GelSight presses."""
    ps = read_ball_presses(taxim_datapack("gelsight"))
    ref, frames = ps.reference, ps.frames
    ball_px = 2.0 / MM
    train = np.arange(len(frames)) % 2 == 0
    lines = []
    for model in models:
        for ff in fractions:
            t0 = time.perf_counter()
            cal = PhotometricCalibration.from_ball_presses(
                ref, frames[train], ball_radius_mm=2.0, mm_per_px=MM, model=model,
                flat_fraction=ff)
            t_cal = time.perf_counter() - t0
            for zb in zero_backgrounds:
                lines.append(_real_row(cal, model, ff, zb, t_cal, ps, train, ball_px))
                print(lines[-1], flush=True)
    return lines


def taxim_rows(data: dict, models, fractions, label: str,
               zero_backgrounds=(False,)) -> list[str]:
    """One line per (model, flat fraction) on Taxim renders, against Taxim's own gel."""
    from bench_contact_edge import score

    ref, frames, ball_mm = data["reference"], data["frames"], data["ball_mm"]
    n = len(frames)
    train = (ball_mm == ball_mm[0]) & (np.arange(n) % 2 == 0)
    lines = []
    for model in models:
        for ff in fractions:
            cal = PhotometricCalibration.from_ball_presses(
                ref, frames[train], ball_radius_mm=ball_mm[train], mm_per_px=MM, model=model,
                flat_fraction=ff)
            for zb in zero_backgrounds:
                recon = DepthReconstructor(cal, reference=ref, zero_background=zb)
                cells = []
                for b in np.unique(ball_mm):
                    idx = np.flatnonzero((ball_mm == b) & ~train)
                    s = score(recon, frames, idx, data["centres"], data["radii"], ball_mm / MM,
                              gel=data["gel"])
                    cells.append(f"{s['angle_deg']:.2f} deg, {100 * s['deepest']:+.1f} % "
                                 f"(n={s['n']})")
                lines.append(f"| {label} | {model} | {ff:g}"
                             f"{' + zero_background' if zb else ''} | " + " | ".join(cells) + " |")
                print(lines[-1], flush=True)
    return lines


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--models", nargs="+", default=["lut", "mlp"], choices=["lut", "mlp"])
    p.add_argument("--fractions", nargs="+", type=float, default=[0.03, 0.01, 0.003])
    p.add_argument("--skip-real", action="store_true")
    p.add_argument("--render-taxim", nargs=2, type=int, metavar=("FIRST", "SECOND"),
                   default=None, help="draw this many presses of a 2 mm and a 3 mm ball")
    p.add_argument("--save-taxim", type=Path, default=None)
    p.add_argument("--taxim-npz", type=Path, default=None,
                   help="renders saved by --save-taxim")
    p.add_argument("--taxim-label", default="Taxim, no shadows",
                   help="what the renders are, for the table (e.g. 'Taxim, shadows')")
    p.add_argument("--zero-background", choices=("off", "both"), default="off",
                   help="'both': also score every calibration with zero_background=True")
    a = p.parse_args(argv)
    zbs = (False, True) if a.zero_background == "both" else (False,)
    print(f"# bench_flat_samples: {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} cores, {time.strftime('%Y-%m-%d %H:%M')}")
    if not a.skip_real:
        print("| data | model | flat_fraction | angle, deepest point | centre slope / ball's "
              "| background tilt | background rms far_field / median | calibration |")
        print("|---|---|---|---|---|---|---|---|")
        real_rows(a.models, a.fractions, zbs)
    data = None
    if a.taxim_npz is not None:
        data = dict(np.load(a.taxim_npz))
        for old, new in (("centers_px", "centres"), ("radii_px", "radii"),
                         ("ball_radius_mm", "ball_mm"), ("gel_mm", "gel")):
            if old in data:                    # renders saved under the session's names
                data[new] = data.pop(old)
    elif a.render_taxim is not None:
        from bench_contact_edge import render_taxim

        data = render_taxim(*a.render_taxim, shadow=False)
        if a.save_taxim is not None:
            np.savez_compressed(a.save_taxim, **data)
    if data is not None:
        print("| data | model | flat_fraction | odd presses: angle, deepest | unseen ball |")
        print("|---|---|---|---|---|")
        taxim_rows(data, a.models, a.fractions, a.taxim_label, zbs)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
