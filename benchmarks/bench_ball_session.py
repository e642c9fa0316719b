"""Calibrate of a 50-press ball session: its time beside the decode of its frames.

Draws a ball's session folder (:func:`tactilevision.sim.make_ball_session`: Sneddon's
closed form, the Taxim authors' GelSight shading, 20 frames/s, F/T at 1 kHz; 5 contact
radii x 10 presses), then in the same run times

1. decoding every frame (``Session.frame``, PNG through OpenCV), the floor any
   calibrate of these frames pays, and
2. ``calibrate_ball_session`` (presses found, clock synchronised, holds, circles,
   depths, fit),

and prints both, their ratio, and the calibration's E against the truth.

Usage: python benchmarks/bench_ball_session.py [--presses-per-depth 10] [--law linear]
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
from pathlib import Path

import numpy as np

from tactilevision.io import read_session
from tactilevision.pipeline import calibrate_ball_session
from tactilevision.sim import make_ball_session


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--presses-per-depth", type=int, default=10)
    ap.add_argument("--law", choices=("linear", "neo_hookean"), default="linear")
    args = ap.parse_args()
    E = 1.0
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "ball"
        t = time.perf_counter()
        sched = make_ball_session(folder, E_mpa=E, contact_radii_mm=(0.6, 0.75, 0.9, 1.05, 1.2),
                                  repeats=args.presses_per_depth, progress=True)
        t_make = time.perf_counter() - t
        session = read_session(folder)
        t = time.perf_counter()
        for i in range(session.n_frames):
            session.frame(i)
        t_decode = time.perf_counter() - t
        t = time.perf_counter()
        cal = calibrate_ball_session(session, nu=0.5, law=args.law)
        t_cal = time.perf_counter() - t
    fit = cal.fit
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores; "
          f"session drawn in {t_make:.0f} s")
    print(f"{sched.n_presses} presses, {session.n_frames} frames "
          f"({session.shape[1]} x {session.shape[0]} px)")
    print(f"decode every frame:      {t_decode:6.2f} s")
    print(f"calibrate_ball_session:  {t_cal:6.2f} s  ({t_cal / t_decode:.2f} x the decode)")
    print(f"presses fitted {len(cal.used)}, rejected {len(cal.rejected)}; E = {fit.E_mpa:.4f} "
          f"MPa, 95 % CI [{fit.E_ci95_mpa[0]:.4f}, {fit.E_ci95_mpa[1]:.4f}] (truth {E:g}, "
          f"{'inside' if fit.E_ci95_mpa[0] <= E <= fit.E_ci95_mpa[1] else 'OUTSIDE'}); "
          f"depth error mean {1e3 * _depth_error(cal, sched):.1f} um")


def _depth_error(cal, sched) -> float:
    """Mean of the certified depths less the schedule's (presses in time order)."""
    order = np.argsort([cal.presses.presses[i].t_frame_s for i in cal.used])
    press = np.array([cal.presses.presses[i].press for i in cal.used])[order]
    return float(np.mean(cal.depths.depth_mm[order] - sched.depth_mm[press]))


if __name__ == "__main__":
    main()
