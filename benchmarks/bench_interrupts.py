"""Ctrl-C at random moments: exit status, time to exit, traceback, staging left behind.

    python benchmarks/bench_interrupts.py [--n 5] [--commands reconstruct forces calibrate batch]
                                          [--window 1.0 6.0]

Each command runs on the sample session (sample_frames/gelsight_session, 777 frames) into
a fresh folder and gets SIGINT at a moment uniform in the window (default 1 to 6 s after
its start; ``--window 0.93 1.13`` hits batch's imports, where an interrupt caught inside
code ``exec``'d from text once ended ``python -m`` by the signal); printed per command: how
many of n exited 130, within 1 s of the signal, without a traceback, with no
``.tactilevision-tmp-*`` folder left (issue 54, item 5's target: all of them).
"""

from __future__ import annotations

import argparse
import platform
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SESSION = ROOT / "sample_frames" / "gelsight_session"


def argv_for(command: str, out: Path) -> list[str]:
    cal = ["--calibration", str(SESSION / "optics.npz")]
    if command == "reconstruct":
        return ["reconstruct", str(SESSION / "frames"), *cal, "--out", str(out), "--no-progress"]
    if command == "forces":
        return ["forces", str(SESSION), "--out", str(out), "--E-mpa", "0.2", "--nu", "0.48",
                "--no-progress"]
    if command == "calibrate":
        return ["calibrate", str(SESSION), "--out", str(out), "--no-progress"]
    return ["batch", "reconstruct", str(SESSION / "frames"), *cal, "--out", str(out),
            "--workers", "2", "--no-progress"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=5)
    ap.add_argument("--commands", nargs="+",
                    default=["reconstruct", "forces", "calibrate", "batch"])
    ap.add_argument("--window", nargs=2, type=float, default=(1.0, 6.0), metavar=("FROM", "TO"),
                    help="seconds after the start between which the signal is sent")
    args = ap.parse_args()
    print(f"machine: {platform.machine()}, python {platform.python_version()}")
    rng = np.random.default_rng(0)
    for command in args.commands:
        ok = {"130": 0, "1 s": 0, "no traceback": 0, "nothing left": 0}
        waits, shown, codes = [], False, {}
        for _ in range(args.n):
            with tempfile.TemporaryDirectory() as tmp:
                out = Path(tmp) / "out"
                proc = subprocess.Popen([sys.executable, "-m", "tactilevision",
                                         *argv_for(command, out)],
                                        stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                        text=True)
                time.sleep(float(rng.uniform(*args.window)))
                t0 = time.perf_counter()
                proc.send_signal(signal.SIGINT)
                proc.wait(timeout=120)             # the command's own exit (the prompt back)
                took = time.perf_counter() - t0
                _, err = proc.communicate(timeout=120)  # its workers may hold the pipes
                waits.append(took)
                ok["130"] += proc.returncode == 130
                codes[proc.returncode] = codes.get(proc.returncode, 0) + 1
                ok["1 s"] += took <= 1.0
                ok["no traceback"] += "Traceback" not in err
                ok["nothing left"] += not list(Path(tmp).rglob(".tactilevision-tmp-*"))
                if (proc.returncode != 130 or "Traceback" in err) and not shown:
                    shown = True        # the first failure, as it ended
                    print(f"  {command}: exit {proc.returncode}; stderr ends: "
                          + " | ".join(err.strip().splitlines()[-4:]))
        print(f"{command}: of {args.n}: " + ", ".join(f"{k} {v}" for k, v in ok.items())
              + f"; time to exit {min(waits):.2f} to {max(waits):.2f} s; statuses {codes}")


if __name__ == "__main__":
    main()
