"""Where the true crossing force lies in each press's bracket, on null sessions of bench_loop.

    python benchmarks/bench_bracket_truth.py SESSION:OUT [SESSION:OUT ...]

SESSION is a Taxim gauge-block session (``benchmarks/taxim_gauge_session.py``; its
``truth.json`` gives each press's w0), OUT a ``benchmarks/bench_loop.py SESSION --kinds
null --out OUT`` folder (``OUT/null/truth.json`` gives the law its F/T log was drawn
with, P = c w (1 + beta w / h), and ``OUT/null/calibration/measurements.csv`` the
certified crossing forces). The certification states each crossing force as uniform over
its bracket ``force_w0_n -+ sqrt(3) force_w0_sem_n``; for each press this prints where
the true P(w0) lies in it (u: 0 at the low edge, 1 at the high one), per session and
over all: the mean u (uniform: 0.5), the presses outside, the share in the middle half
(uniform: 50 %), the median bracket width and the midpoints' mean error (% of the true
force), and the certified depths' mean error against the renderer's (um); then the same
split by the bracket's length in frame periods (the stage's mean approach speed to the
press's depth, truth's ``t_start_s`` to ``hold_from_s``, times the law's dP/dw at w0)
and by whether Taxim drew its shadows.
"""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

import numpy as np


def bracket_places(session: Path, out: Path) -> np.ndarray:
    """(N, 5): u, width / P, (midpoint - P) / P, the depth error (mm) and the bracket's
    length in frame periods, per press."""
    truth = json.loads((session / "truth.json").read_text())
    law = json.loads((out / "null" / "truth.json").read_text())
    c, beta, h = law["c"], law["beta"], truth["thickness_mm"]
    presses = {p["press"]: p for p in truth["presses"]}
    with open(out / "null" / "calibration" / "measurements.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    got = []
    for r in rows:
        p = presses[int(r["press"])]
        w0 = p["w0_mm"]
        force = c * w0 * (1 + beta * w0 / h)
        speed = p["depth_mm"] / (p["hold_from_s"] - p["t_start_s"])
        per_frame = c * (1 + 2 * beta * w0 / h) * speed / truth["fps"]
        mid, half = float(r["force_w0_n"]), np.sqrt(3) * float(r["force_w0_sem_n"])
        got.append(((force - (mid - half)) / (2 * half), 2 * half / force,
                    (mid - force) / force, float(r["depth_mm"]) - p["depth_mm"],
                    2 * half / per_frame))
    return np.array(got)


def _row(name: str, a: np.ndarray) -> str:
    u = a[:, 0]
    return (f"| {name} | {len(a)} | {u.mean():.3f} | {int(np.sum((u < 0) | (u > 1)))} | "
            f"{100 * np.mean((u >= 0.25) & (u <= 0.75)):.0f} | "
            f"{100 * np.median(a[:, 1]):.1f} | {100 * a[:, 2].mean():+.2f} | "
            f"{1e3 * a[:, 3].mean():+.1f} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("pairs", nargs="+", help="SESSION:OUT")
    args = ap.parse_args()
    print("| session | presses | mean u | outside | middle half (%) | width (% of P) | "
          "midpoint error (%) | depth error (um) |")
    print("|---|---|---|---|---|---|---|---|")
    every, shadow = [], []
    for pair in args.pairs:
        session, out = (Path(s) for s in pair.split(":", 1))
        a = bracket_places(session, out)
        every.append(a)
        taxim = json.loads((session / "truth.json").read_text()).get("taxim", {})
        shadow.append(np.full(len(a), bool(taxim.get("with_shadow", False))))
        print(_row(session.name, a))
    a, shadow = np.concatenate(every), np.concatenate(shadow)
    print(_row("all", a))
    for drawn in (False, True):
        for name, lo, hi in (("one period", 0.0, 1.5), ("two periods or more", 1.5, np.inf)):
            m = (shadow == drawn) & (a[:, 4] >= lo) & (a[:, 4] < hi)
            if m.any():
                print(_row(f"{name}, shadows {'on' if drawn else 'off'}", a[m]))
    q = np.histogram(np.clip(a[:, 0], -0.5, 1.5), bins=[-0.5, 0, 0.25, 0.5, 0.75, 1, 1.5])[0]
    print(f"u below 0, in each quarter, above 1: {', '.join(map(str, q))}; uniform's mean "
          f"0.5 +- {0.2887 / np.sqrt(len(a)):.3f}")


if __name__ == "__main__":
    main()
