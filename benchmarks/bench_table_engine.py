"""The default (table) engine against the exact network on held-out real presses.

For the GelSight Mini (``$TACTILEVISION_GELSIGHT_MINI``, contact circles detected), the
GelSlim 3.0 (``$TACTILEVISION_GELSLIM``, set_2020_11, detected) and the GelSight of
``taxim`` (annotated circles): holds out presses by the accuracy report's own split
(:func:`holdout_presses`, one in four), trains a network on the rest in both forms (every
pixel's own position and reference, ``position_cell_px=0``, and the default position
cells), and prints, per form and engine, the median and 95th percentile of the normal
angle against the ball's sphere inside 0.8 of the contact radius over the held-out
presses' pixels, and the table engine against the exact one.

Run: ``python benchmarks/bench_table_engine.py`` (about 5 minutes on 2 cores; needs
torch).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np

from tactilevision.io import read_ball_presses, taxim_datapack
from tactilevision.optics import (
    DepthReconstructor,
    PhotometricCalibration,
    ball_gradients,
    detect_contact_circles,
    holdout_presses,
    normal_angle_deg,
)
from tactilevision.optics._reconstructor import table_domain

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "real"
GELSLIM = Path(os.environ.get("TACTILEVISION_GELSLIM", SHARED / "gelslim3"))
MINI = Path(os.environ.get("TACTILEVISION_GELSIGHT_MINI", SHARED / "gelsight_mini"))


def sensors():
    if (MINI / "background.png").is_file():
        ps = read_ball_presses(MINI)
        yield "GelSight Mini", ps, 0.0634, np.asarray(ps.ball_radius_mm), None
    if (GELSLIM / "set_2020_11").is_dir():
        ps = read_ball_presses(GELSLIM / "set_2020_11")
        yield "GelSlim 3.0", ps, 0.0806, np.full(len(ps.frames), 3.8), None
    ps = read_ball_presses(taxim_datapack())
    yield "GelSight (taxim)", ps, 0.0295, np.full(len(ps.frames), 2.0), (ps.centers_px,
                                                                          ps.radii_px)


def angles(gx, gy, tgx, tgy, inside):
    return normal_angle_deg(gx[inside], gy[inside], tgx[inside], tgy[inside])


def rows():
    """Per sensor and network form, the held-out presses' angles: yields dicts with
    ``sensor``, ``held`` (presses held out), ``form``, ``cell`` (the network's position
    cells, None for every pixel's own), ``table_cell_px``, ``exact`` and ``table`` (median
    and 95th percentile, degrees, against the ball) and ``diff`` (the table against the
    exact engine, the same two)."""
    for name, ps, mm, ball_mm, given in sensors():
        centres, radii = given if given else detect_contact_circles(ps.frames, ps.reference)
        ball_px = ball_mm / mm
        held = holdout_presses(centres, radii, ball_px, ps.reference.shape[:2], 0.25)
        train = np.flatnonzero(~held)
        for form, cell in (("own pixel", 0), ("position cells", None)):
            cal = PhotometricCalibration.from_ball_presses(
                ps.reference, ps.frames[train], centres[train] if given else None,
                radii[train] if given else None, ball_radius_mm=ball_mm[train], mm_per_px=mm,
                position_cell_px=cell)
            got = {"table": [], "onnx": [], "diff": []}
            engines = {e: DepthReconstructor(cal, engine=e) for e in ("table", "onnx")}
            for i in np.flatnonzero(held):
                tgx, tgy, inside = ball_gradients(cal.shape, centres[i], 0.8 * radii[i],
                                                  ball_px[i])
                g = {e: r.gradients(ps.frames[i]) for e, r in engines.items()}
                for e in engines:
                    got[e].append(angles(*g[e], tgx, tgy, inside))
                got["diff"].append(angles(*g["table"], *g["onnx"], inside))
            med_p95 = {k: (float(np.median(np.concatenate(v))),
                           float(np.percentile(np.concatenate(v), 95)))
                       for k, v in got.items()}
            yield {"sensor": name, "held": int(np.count_nonzero(held)), "form": form,
                   "cell": cal.position_cell_px or None, "table_cell_px": table_domain(cal)[2],
                   "exact": med_p95["onnx"], "table": med_p95["table"],
                   "diff": med_p95["diff"]}


def main() -> int:
    print("| sensor | network (position cells) | engine | median deg | p95 deg "
          "| table vs exact median / p95 |")
    print("|---|---|---|---|---|---|")
    for r in rows():
        head = (f"| {r['sensor']} ({r['held']} held out) | {r['form']} "
                f"({r['cell'] or 'none'}; table cells {r['table_cell_px']} px)")
        print(f"{head} | exact | {r['exact'][0]:.2f} | {r['exact'][1]:.2f} |  |")
        print(f"{head} | table (default) | {r['table'][0]:.2f} | {r['table'][1]:.2f} | "
              f"{r['diff'][0]:.2f} / {r['diff'][1]:.2f} |", flush=True)
    return 0

if __name__ == "__main__":
    sys.exit(main())
