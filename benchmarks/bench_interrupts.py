"""Ctrl-C at random moments: exit status, time to exit, traceback, what is left behind.

    python benchmarks/bench_interrupts.py [--n 5] [--commands reconstruct forces calibrate batch]
                                          [--window 1.0 6.0] [--seed 0]

Each command runs on the sample session (sample_frames/gelsight_session, 777 frames) into
a fresh folder and gets SIGINT at a moment uniform in the window (default 1 to 6 s after
its start; ``--window 0 2`` includes the interpreter's start and the imports, issue 86's
"20 of 20 interrupts at random moments from 0 to 2 s": ``--n 20 --window 0 2``;
``--window 0.93 1.13`` hits batch's imports, where an interrupt caught inside code
``exec``'d from text once ended ``python -m`` by the signal). Printed per command: how
many of n exited 130; how many a shell reports as 130 (a process the signal itself ended,
before Python's own handler was installed, is -2 to ``subprocess`` and 130 in ``$?``);
how many within 1 s of the signal, without a traceback, with no ``.tactilevision-tmp-*``
folder and no empty folder left (issue 54, item 5's target and issue 86's: all of them).
A run that had ended before its signal was sent is counted apart ("ended first") and left
out of the others; a failure while the interpreter itself started, before any of
tactilevision's code ran (killed before Python's own handler was installed, or in its
``site`` module), is marked as such.
"""

from __future__ import annotations

import argparse
import os
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


def empty_folders(tmp: Path) -> list[Path]:
    """The folders under `tmp` with nothing in them (an output folder made and left)."""
    return [p for p in Path(tmp).rglob("*") if p.is_dir() and not any(p.iterdir())]


def interpreters_start(status: int, err: str) -> bool:
    """Whether the signal landed while the interpreter itself started, before any of
    tactilevision's code ran: killed before Python's own handler was installed (status
    -2, nothing printed), or in its ``site`` module ("init_import_site")."""
    return (status == -signal.SIGINT and not err.strip()) or "init_import_site" in err


def shell_status(status: int) -> int:
    """The exit status a POSIX shell reports (``$?``): 128 + N for a process the signal N
    ended (``subprocess`` gives -N), the status itself otherwise."""
    return 128 - status if status < 0 else status


def interrupt_once(command: str, after_s: float) -> dict:
    """Run `command` into a fresh folder, send SIGINT `after_s` seconds after its start;
    how it ended."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        proc = subprocess.Popen([sys.executable, "-m", "tactilevision",
                                 *argv_for(command, out)],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        time.sleep(after_s)
        if proc.poll() is not None:              # it ended before the signal
            proc.communicate()
            return {"ended first": True, "status": proc.returncode}
        t0 = time.perf_counter()
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=120)                   # the command's own exit (the prompt back)
        took = time.perf_counter() - t0
        _, err = proc.communicate(timeout=120)   # its workers may hold the pipes
        return {"ended first": False, "status": proc.returncode, "took": took, "err": err,
                "staging": list(Path(tmp).rglob(".tactilevision-tmp-*")),
                "empty": empty_folders(Path(tmp))}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=5)
    ap.add_argument("--commands", nargs="+",
                    default=["reconstruct", "forces", "calibrate", "batch"])
    ap.add_argument("--window", nargs=2, type=float, default=(1.0, 6.0), metavar=("FROM", "TO"),
                    help="seconds after the start between which the signal is sent")
    ap.add_argument("--seed", type=int, default=0, help="seed of the moments (default 0)")
    args = ap.parse_args()
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, python "
          f"{platform.python_version()}; load average {os.getloadavg()[0]:.2f}; window "
          f"{args.window[0]:g} to {args.window[1]:g} s, seed {args.seed}")
    rng = np.random.default_rng(args.seed)
    for command in args.commands:
        ok = {"130": 0, "130 in a shell": 0, "1 s": 0, "no traceback": 0, "no staging": 0,
              "no empty folder": 0}
        waits, codes, first, runs, starts = [], {}, 0, 0, 0
        for _ in range(args.n):
            after = float(rng.uniform(*args.window))
            r = interrupt_once(command, after)
            if r["ended first"]:
                first += 1
                continue
            runs += 1
            waits.append(r["took"])
            codes[r["status"]] = codes.get(r["status"], 0) + 1
            ok["130"] += r["status"] == 130
            ok["130 in a shell"] += shell_status(r["status"]) == 130
            ok["1 s"] += r["took"] <= 1.0
            ok["no traceback"] += "Traceback" not in r["err"]
            ok["no staging"] += not r["staging"]
            ok["no empty folder"] += not r["empty"]
            if r["status"] != 130 or "Traceback" in r["err"] or r["staging"] or r["empty"]:
                start = interpreters_start(r["status"], r["err"])
                starts += start
                print(f"  {command} at {after:.3f} s"
                      + (" (in the interpreter's start)" if start else "")
                      + f": exit {r['status']}; left "
                      f"{[str(p.name) for p in r['staging'] + r['empty']]}; stderr ends: "
                      + " | ".join(r["err"].strip().splitlines()[-3:]))
        span = f"{min(waits):.2f} to {max(waits):.2f} s" if waits else "-"
        print(f"{command}: of {runs} interrupted ({first} ended first): "
              + ", ".join(f"{k} {v}" for k, v in ok.items())
              + f"; time to exit {span}; statuses {codes}; failures in the interpreter's "
              f"start {starts}")


if __name__ == "__main__":
    main()
