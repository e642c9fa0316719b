"""Time and accuracy of the main job on the bundled sample session.

    python benchmarks/bench_calibrate.py [SESSION_DIR]

Prints the wall time of reading, certification (per frame) and the fit, beside the
time to decode every frame once in the same run (a reference operation), and,
when the session has a truth.json, the errors of the certified depths and
forces and of E and nu.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

from tactilevision import calibrate_session
from tactilevision.io import read_session

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    path = Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "sample_frames" / "gelsight_session"
    t0 = time.perf_counter()
    session = read_session(path)
    t1 = time.perf_counter()
    cal = calibrate_session(session)
    t2 = time.perf_counter()
    c = cal.certification
    print(f"{path}: {session.n_frames} frames {session.shape[1]} x {session.shape[0]}, "
          f"{len(c.presses)} certified, {len(c.rejected)} rejected")
    # the same run's reference operation: every frame decoded once, in one thread
    t3 = time.perf_counter()
    for i in range(session.n_frames):
        session.frame(i)
    decode = time.perf_counter() - t3
    print(f"read {t1 - t0:.2f} s, certify + fit {t2 - t1:.1f} s "
          f"({1e3 * (t2 - t1) / session.n_frames:.1f} ms per frame); decoding every frame "
          f"once took {decode:.2f} s in the same run (certify + fit "
          f"{(t2 - t1) / decode:.0f} times that)")
    f = cal.fit
    print(f"E = {f.E_mpa:.4f} MPa {f.E_ci95_mpa}, nu = {f.nu:.4f} {f.nu_ci95}, "
          f"clock offset {c.clock_offset_s:.4f} s ({c.clock_source})")
    truth_path = path / "truth.json"
    if truth_path.is_file():
        truth = json.loads(truth_path.read_text())
        tp = {p["press"]: p for p in truth["presses"]}
        dd = np.array([d - tp[p.press]["depth_mm"] for p, d in zip(c.presses, cal.depth_mm,
                                                                    strict=True)])
        df = np.array([p.force_n - tp[p.press]["force_n"] for p in c.presses])
        print(f"depth error max {1e3 * np.abs(dd).max():.2f} um; force error mean "
              f"{1e3 * df.mean():.2f} mN, sd {1e3 * df.std():.2f} mN, max "
              f"{1e3 * np.abs(df).max():.2f} mN")
        print(f"E error {100 * (f.E_mpa / truth['E_mpa'] - 1):+.2f}%, nu error "
              f"{f.nu - truth['nu']:+.4f}, clock error "
              f"{1e3 * (c.clock_offset_s - truth['clock_offset_s']):+.1f} ms")
        for r in c.rejected:
            print(f"  rejected press {r.press}: {r.reason} ({r.detail})")


if __name__ == "__main__":
    main()
