"""The F/T's zero read from the log: a session with a known zero added to its F/T log.

The frames do not depend on the F/T's zero, so one rendered session serves every
variant: its ``forces.csv`` is rewritten with fz + z0 + d (t - t0) / (t1 - t0) (a
constant zero z0, e.g. the gauge block's weight on a sensor tared before the block
was mounted, and a linear drift d over the log), the frames linked. Each variant is
calibrated with the default ``ft_zero='auto'`` (the line when the zero drifts, else
its mean), with ``'constant'``, ``'drift'`` and ``'off'``; printed: the zero measured
against the truth (at each press's force window), E against the same session without
a zero (the reference run, same command), and the drift's test.

    python benchmarks/bench_ft_zero.py [SESSION_DIR] [--zeros 0.05 0.3 0.5]
                                       [--drifts 0 0.1 -0.1] [--modes auto ...]

SESSION_DIR defaults to the bundled sample session (sample_frames/gelsight_session).
"""

from __future__ import annotations

import argparse
import os
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from tactilevision import calibrate_session

ROOT = Path(__file__).resolve().parents[1]


def variant(session: Path, folder: Path, zero_n: float, drift_n: float) -> Path:
    """A copy of `session` in `folder` whose fz reads `zero_n` plus a linear `drift_n`."""
    folder.mkdir(parents=True)
    for p in session.iterdir():
        if p.name in ("forces.csv", "calibration"):
            continue
        os.symlink(p.resolve(), folder / p.name)
    data = np.loadtxt(session / "forces.csv", delimiter=",", skiprows=1)
    header = (session / "forces.csv").read_text().splitlines()[0]
    t = data[:, 0]
    data[:, 3] += zero_n + drift_n * (t - t[0]) / (t[-1] - t[0])
    np.savetxt(folder / "forces.csv", data, delimiter=",", header=header, comments="",
               fmt="%.6g")
    return folder


def true_zero(session: Path, cal, zero_n: float, drift_n: float) -> np.ndarray:
    """The added zero at each certified press's force window."""
    t0, t1 = (float(v) for v in np.loadtxt(session / "forces.csv", delimiter=",", skiprows=1,
                                           usecols=0)[[0, -1]])
    off = cal.certification.clock_offset_s
    t = np.array([p.t_frame_s + off + p.hold_s for p in cal.certification.presses])
    return zero_n + drift_n * (t - t0) / (t1 - t0)


#: The table's columns (:func:`run`'s ``rows``).
COLUMNS = ["zero (N)", "drift (N)", "mode", "zero read at the presses, error (mN): mean, max",
           "drift read (mN) [p]", "E (MPa)", "E vs reference"]


def run(session: Path, zeros=(0.05, 0.3, 0.5), drifts=(0.0, 0.1, -0.1),
        modes=("auto", "constant", "drift", "off"), *, echo: bool = False) -> dict:
    """The reference calibration of `session` and, for each zero, drift and mode, the
    variant's calibration: ``reference`` (E, nu, presses, its own zero in mN, seconds) and
    ``rows`` (:data:`COLUMNS`; the error of the zero read against the one added plus the
    reference's own, at each press's force window)."""
    t = time.perf_counter()
    ref = calibrate_session(session)
    out = {"reference": dict(E=ref.fit.E_mpa, nu=ref.fit.nu,
                             presses=len(ref.certification.presses),
                             zero_mn=1e3 * ref.ft_zero.zero_n, s=time.perf_counter() - t),
           "rows": []}
    if echo:
        r = out["reference"]
        print(f"reference (no zero added): E = {r['E']:.4f} MPa, nu = {r['nu']:.4f}, "
              f"{r['presses']} presses, {r['s']:.1f} s; its own zero read {r['zero_mn']:+.2f} mN")
        print("| " + " | ".join(COLUMNS) + " |")
        print("|" + "---|" * len(COLUMNS))
    with tempfile.TemporaryDirectory() as tmp:
        for z0 in zeros:
            for d in drifts:
                folder = variant(session, Path(tmp) / f"z{z0}_d{d}", z0, d)
                for mode in modes:
                    cal = calibrate_session(folder, ft_zero=mode)
                    zt = true_zero(folder, cal, z0, d) + ref.ft_zero.zero_n
                    off = cal.certification.clock_offset_s
                    tw = np.array([p.t_frame_s + off + p.hold_s
                                   for p in cal.certification.presses])
                    err = 1e3 * (cal.ft_zero.at(tw) - zt)
                    e = cal.fit.E_mpa
                    row = [f"{z0:g}", f"{d:+g}", mode,
                           f"{err.mean():+.2f}, {np.abs(err).max():.2f}",
                           f"{1e3 * cal.ft_zero.drift_n:+.1f} [{cal.ft_zero.drift_p_value:.2g}]",
                           f"{e:.4f}", f"{100 * (e / ref.fit.E_mpa - 1):+.1f} %"]
                    out["rows"].append(row)
                    if echo:
                        print("| " + " | ".join(row) + " |", flush=True)
                shutil.rmtree(folder)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("session", nargs="?", type=Path,
                    default=ROOT / "sample_frames" / "gelsight_session")
    ap.add_argument("--zeros", type=float, nargs="+", default=[0.05, 0.3, 0.5])
    ap.add_argument("--drifts", type=float, nargs="+", default=[0.0, 0.1, -0.1])
    ap.add_argument("--modes", nargs="+", default=["auto", "constant", "drift", "off"],
                    choices=("auto", "constant", "drift", "off"))
    args = ap.parse_args()
    run(args.session, args.zeros, args.drifts, args.modes, echo=True)


if __name__ == "__main__":
    main()
