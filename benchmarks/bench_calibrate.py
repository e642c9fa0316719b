"""Time and accuracy of the main job on the bundled sample session.

    python benchmarks/bench_calibrate.py [SESSION_DIR]

Prints the wall time of reading, certification (per frame) and the fit, beside the
time to decode every frame once in the same run (a reference operation), and,
when the session has a truth.json, the errors of the certified depths and
forces and of E and nu. :func:`measure` returns the same figures (the validation
report's ``calibrate_sample``, ``benchmarks/report.py``).
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
SESSION = ROOT / "sample_frames" / "gelsight_session"


def measure(path: Path = SESSION) -> dict:
    """Calibrate the session at `path` once and decode its frames once: the times (s),
    the certification's counts and rejections, E, nu and the clock, and, when the session
    has a truth.json, the errors against it (``"truth"``, else None)."""
    t0 = time.perf_counter()
    session = read_session(path)
    t1 = time.perf_counter()
    cal = calibrate_session(session)
    t2 = time.perf_counter()
    c = cal.certification
    # the same run's reference operation: every frame decoded once, in one thread
    t3 = time.perf_counter()
    for i in range(session.n_frames):
        session.frame(i)
    decode = time.perf_counter() - t3
    f = cal.fit
    out = {"path": str(path), "n_frames": session.n_frames,
           "width": session.shape[1], "height": session.shape[0],
           "certified": len(c.presses), "rejected": [(r.press, r.reason, r.detail)
                                                     for r in c.rejected],
           "read_s": t1 - t0, "certify_fit_s": t2 - t1, "decode_s": decode,
           "E_mpa": f.E_mpa, "E_ci95_mpa": tuple(f.E_ci95_mpa), "nu": f.nu,
           "nu_ci95": tuple(f.nu_ci95), "clock_offset_s": c.clock_offset_s,
           "clock_source": c.clock_source, "truth": None}
    truth_path = path / "truth.json"
    if truth_path.is_file():
        truth = json.loads(truth_path.read_text())
        tp = {p["press"]: p for p in truth["presses"]}
        dd = np.array([d - tp[p.press]["depth_mm"] for p, d in zip(c.presses, cal.depth_mm,
                                                                    strict=True)])
        df = np.array([p.force_n - tp[p.press]["force_n"] for p in c.presses])
        out["truth"] = {"E_mpa": truth["E_mpa"], "nu": truth["nu"],
                        "clock_offset_s": truth["clock_offset_s"],
                        "depth_err_max_mm": float(np.abs(dd).max()),
                        "depth_err_mean_mm": float(dd.mean()),
                        "depth_err_sd_mm": float(dd.std()),
                        "force_err_mean_n": float(df.mean()), "force_err_sd_n": float(df.std()),
                        "force_err_max_n": float(np.abs(df).max())}
    return out


def main() -> None:
    path = Path(sys.argv[1]) if len(sys.argv) > 1 else SESSION
    m = measure(path)
    print(f"{path}: {m['n_frames']} frames {m['width']} x {m['height']}, "
          f"{m['certified']} certified, {len(m['rejected'])} rejected")
    fit_s, decode = m["certify_fit_s"], m["decode_s"]
    print(f"read {m['read_s']:.2f} s, certify + fit {fit_s:.1f} s "
          f"({1e3 * fit_s / m['n_frames']:.1f} ms per frame); decoding every frame "
          f"once took {decode:.2f} s in the same run (certify + fit "
          f"{fit_s / decode:.0f} times that)")
    print(f"E = {m['E_mpa']:.4f} MPa {m['E_ci95_mpa']}, nu = {m['nu']:.4f} {m['nu_ci95']}, "
          f"clock offset {m['clock_offset_s']:.4f} s ({m['clock_source']})")
    t = m["truth"]
    if t is not None:
        print(f"depth error max {1e3 * t['depth_err_max_mm']:.2f} um; force error mean "
              f"{1e3 * t['force_err_mean_n']:.2f} mN, sd {1e3 * t['force_err_sd_n']:.2f} mN, "
              f"max {1e3 * t['force_err_max_n']:.2f} mN")
        print(f"E error {100 * (m['E_mpa'] / t['E_mpa'] - 1):+.2f}%, nu error "
              f"{m['nu'] - t['nu']:+.4f}, clock error "
              f"{1e3 * (m['clock_offset_s'] - t['clock_offset_s']):+.1f} ms")
        for press, reason, detail in m["rejected"]:
            print(f"  rejected press {press}: {reason} ({detail})")


if __name__ == "__main__":
    main()
