"""Frames -> height maps -> total force against the F/T log, on the sample session.

    python benchmarks/bench_forces_session.py [EVERY]

Every EVERY-th frame (default 7) of ``sample_frames/gelsight_session`` whose
F/T force (at the frame's time, the true clock offset) exceeds 0.5 N goes
through the shipped GelSight calibration and ``ForceEstimator`` with the true
E, nu and h of ``truth.json``, in 'field' and in 'footprint' (height above
0.02 mm) contact. Prints per frame the F/T force, both totals, the height
map's maximum and the area above 0.02 mm, then the median ratio: issue 6's
end-to-end check (5 % at the deeper presses), not met yet.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from tactilevision.cli._calibrate import _reconstructor
from tactilevision.fem import ForceEstimator
from tactilevision.io import read_session

SESSION = Path(__file__).resolve().parents[1] / "sample_frames" / "gelsight_session"


def main() -> None:
    every = int(sys.argv[1]) if len(sys.argv) > 1 else 7
    s = read_session(SESSION)
    truth = json.loads((SESSION / "truth.json").read_text())
    rec = _reconstructor(s)
    ft_t = s.force_times_s - truth["clock_offset_s"]
    kw = dict(thickness_mm=truth["thickness_mm"], E_mpa=truth["E_mpa"], nu=truth["nu"])
    field = ForceEstimator(s.shape, s.config.mm_per_px, **kw)
    foot = ForceEstimator(s.shape, s.config.mm_per_px, contact="footprint", threshold_mm=0.02,
                          **kw)
    print(f"{'frame':>6s} {'F/T N':>7s} {'field N':>8s} {'footprint N':>11s} "
          f"{'max h mm':>9s} {'area>0.02 mm2':>13s}")
    ratios = []
    for i in range(0, s.n_frames, every):
        ft = float(np.interp(s.frame_times_s[i], ft_t, s.forces_n[:, 2]))
        if ft < 0.5:
            continue
        h = rec(s.frame(i))
        a, b = field(h).total_n[2], foot(h).total_n[2]
        ratios.append((a / ft, b / ft))
        print(f"{i:6d} {ft:7.3f} {a:8.3f} {b:11.3f} {float(h.max()):9.3f} "
              f"{float((h > 0.02).sum()) * s.config.mm_per_px**2:13.1f}")
    r = np.array(ratios)
    print(f"{len(r)} frames: median total / F/T: field {np.median(r[:, 0]):.2f} (range "
          f"{r[:, 0].min():.2f} to {r[:, 0].max():.2f}), footprint {np.median(r[:, 1]):.2f} "
          f"({r[:, 1].min():.2f} to {r[:, 1].max():.2f}); image area "
          f"{s.shape[0] * s.shape[1] * s.config.mm_per_px**2:.0f} mm^2")


if __name__ == "__main__":
    main()
