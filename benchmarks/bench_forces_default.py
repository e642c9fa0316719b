"""`tactilevision forces` with its default options against the sample session's F/T log.

    python benchmarks/bench_forces_default.py [--fit FIT.json] [--every N]
        [--variants default,shipped,field,before]

Runs the command on every N-th frame of ``sample_frames/gelsight_session``
(default 3) once per variant and compares each frame's total Fz with the F/T
log's at the frame's time (the fit's clock offset):

- **hold frames** of presses at least 0.3 mm deep (issue 16's target: within
  5 %), and of the 0.15 mm presses; hold times from ``truth.json``, used only
  to group frames; the misaligned and the pad-edge press are left out;
- **no-contact frames** (outside every hold, |F/T| under 50 mN; target under
  20 mN).

Variants: ``default`` (no options but ``--fit``); ``shipped`` (``--sensor
gelsight``: the shipped calibration, fitted on real GelSight frames, instead
of the session's own optics); ``field`` (``--contact field --level
far_field``: the height field trusted everywhere); ``before`` (the defaults
before issue 16: ``--sensor gelsight --contact field --level far_field
--beta 0``). ``--fit`` defaults to ``out/calibration/fit.json`` (the README's
first command), else the truth (E, nu, clock offset; beta 0.82).
"""

from __future__ import annotations

import argparse
import csv
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from tactilevision.cli import main as cli

ROOT = Path(__file__).resolve().parents[1]
SESSION = ROOT / "sample_frames" / "gelsight_session"
VARIANTS = {
    "default": [],
    "shipped": ["--sensor", "gelsight"],
    "field": ["--contact", "field", "--level", "far_field"],
    "before": ["--sensor", "gelsight", "--contact", "field", "--level", "far_field",
               "--beta", "0"],
}


def evaluate(rows: list[dict], truth: dict) -> dict:
    """Fz / F_T on hold frames by indenter depth, |Fz| on no-contact frames."""
    hold, free = [], []
    for r in rows:
        t, fz, ft = float(r["t_s"]), float(r["fz_n"]), float(r["ft_fz_n"])
        press = next((p for p in truth["presses"]
                      if p["hold_from_s"] + 0.05 <= t <= p["hold_from_s"] + 0.45), None)
        if press is None:
            if abs(ft) < 0.05:
                free.append(abs(fz))
        elif not (press["edge"] or press["misaligned"]):
            hold.append((press["w0_mm"], fz / ft))
    h = np.array(hold)
    out = {}
    for name, sel in (("deep", h[:, 0] >= 0.3), ("shallow", h[:, 0] < 0.3)):
        r = h[sel, 1]
        out[name] = dict(n=int(r.size), median=float(np.median(r)), lo=float(r.min()),
                         hi=float(r.max()), within5=float(np.mean(np.abs(r - 1) <= 0.05)))
    out["free"] = dict(n=len(free), median_mn=1e3 * float(np.median(free)),
                       max_mn=1e3 * float(np.max(free)))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fit", type=Path, default=ROOT / "out" / "calibration" / "fit.json")
    ap.add_argument("--every", type=int, default=3)
    ap.add_argument("--variants", default="default,shipped,field,before")
    args = ap.parse_args()
    truth = json.loads((SESSION / "truth.json").read_text())
    with tempfile.TemporaryDirectory() as tmp:
        fit = args.fit
        if not fit.is_file():
            fit = Path(tmp) / "fit.json"
            fit.write_text(json.dumps({"E_mpa": truth["E_mpa"], "nu": truth["nu"],
                                       "beta": 0.82,
                                       "clock_offset_s": truth["clock_offset_s"]}))
        print(f"Command: python benchmarks/bench_forces_default.py --fit {args.fit} "
              f"--every {args.every}\nfit: {fit}\n")
        print("| variant | options | frames | s per frame | presses >= 0.3 mm: hold frames, "
              "median Fz/F_T (range), within 5 % | 0.15 mm: median (range) | "
              "no-contact frames: median, max |Fz| |")
        print("|---|---|---|---|---|---|---|")
        for name in args.variants.split(","):
            out = Path(tmp) / name
            t0 = time.perf_counter()
            rc = cli(["forces", str(SESSION), "--fit", str(fit), "--every", str(args.every),
                      "--out", str(out), "--no-images", "--no-progress", *VARIANTS[name]])
            dt = time.perf_counter() - t0
            if rc != 0:
                print(f"| {name} | failed with status {rc} |")
                continue
            rows = list(csv.DictReader((out / "forces.csv").open()))
            e = evaluate(rows, truth)
            d, s, f = e["deep"], e["shallow"], e["free"]
            print(f"| {name} | `{' '.join(VARIANTS[name]) or '(none)'}` | {len(rows)} | "
                  f"{dt / len(rows):.2f} | {d['n']}, {d['median']:.3f} ({d['lo']:.3f} to "
                  f"{d['hi']:.3f}), {d['within5']:.0%} | {s['median']:.3f} ({s['lo']:.3f} to "
                  f"{s['hi']:.3f}) | {f['median_mn']:.1f}, {f['max_mn']:.1f} mN |", flush=True)


if __name__ == "__main__":
    main()
