"""How far the detected contact circles lie from truths no code of ours drew.

    python benchmarks/bench_circle_uncertainty.py [--renders N] [--json PATH]

The accuracy report of ``optics calibrate`` scores held-out presses against detected
circles (``detect_contact_circles(edge='contact')``); the circles' own error enters the
score. This benchmark measures that error, as fractions of the true contact radius r
(so that it carries over between sensors of other pixel sizes):

- the 48 real GelSight presses of ``taxim`` against their hand-annotated circles;
- with ``--renders N`` (default 30; 0 skips), presses drawn by Taxim's own renderer
  (shadows on, 1.5 grey levels of noise, balls of 2 and 3 mm, 0.15 to 1.2 mm deep)
  against the circle where Taxim's own gel leaves the ball (its tilt's largest, as in
  ``benchmarks/bench_contact_edge.py``), presses whose rim leaves the image left out.

Printed per data set: the centre's offset (mean and sd per axis, and the sd of one
axis pooled), the radius ratio (mean and sd). ``tactilevision.optics.CIRCLE_ERROR``
holds the figures the report propagates.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from tactilevision.io import read_ball_presses, taxim_datapack
from tactilevision.optics import detect_contact_circles


def stats(centres: np.ndarray, radii: np.ndarray, true_c: np.ndarray, true_r: np.ndarray
          ) -> dict:
    ok = np.isfinite(true_r) & np.all(np.isfinite(true_c), axis=1)
    off = (centres[ok] - true_c[ok]) / true_r[ok, None]        # fractions of r
    q = radii[ok] / true_r[ok]
    return {"n": int(ok.sum()), "centre_mean": off.mean(0).round(4).tolist(),
            "centre_sd": off.std(0, ddof=1).round(4).tolist(),
            "centre_sd_pooled": float(np.sqrt(np.mean(off.var(0, ddof=1)))),
            "centre_bias": float(np.hypot(*off.mean(0))),
            "radius_mean": float(q.mean()), "radius_sd": float(q.std(ddof=1))}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--renders", type=int, default=30)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    out = {"machine": f"{platform.machine()}, {os.cpu_count()} cores",
           "command": "python benchmarks/bench_circle_uncertainty.py "
                      + " ".join(argv if argv is not None else sys.argv[1:])}
    ps = read_ball_presses(taxim_datapack("gelsight"))
    c, r = detect_contact_circles(ps.frames, ps.reference, edge="contact")
    out["real GelSight, hand-annotated circles"] = stats(c, r, ps.centers_px, ps.radii_px)
    if args.renders > 0:
        try:
            from bench_contact_edge import render_taxim

            n1 = args.renders * 2 // 3
            tx = render_taxim(n1, args.renders - n1, shadow=True)
            c, r = detect_contact_circles(tx["frames"], tx["reference"], edge="contact")
            out["Taxim renders, its gel's edge"] = stats(c, r, tx["centres"], tx["gel_edge"])
        except (ImportError, RuntimeError) as exc:
            out["Taxim renders, its gel's edge"] = {"skipped": str(exc)}
    out["seconds"] = time.perf_counter() - t0
    print(f"Machine: {out['machine']}. Command: {out['command']}. {out['seconds']:.0f} s.\n")
    print("| data | presses | centre offset / r: mean (x, y) | sd (x, y) | radius / true: "
          "mean, sd |")
    print("|---|---|---|---|---|")
    for name, s in out.items():
        if not isinstance(s, dict):
            continue
        if "skipped" in s:
            print(f"| {name} | skipped: {s['skipped']} | | | |")
            continue
        print(f"| {name} | {s['n']} | {s['centre_mean'][0]:+.4f}, {s['centre_mean'][1]:+.4f} "
              f"| {s['centre_sd'][0]:.4f}, {s['centre_sd'][1]:.4f} | {s['radius_mean']:.4f}, "
              f"{s['radius_sd']:.4f} |")
    if args.json:
        args.json.write_text(json.dumps(out, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
