"""``tactilevision COMMAND --help`` of every command, timed beside the interpreter's start.

    python benchmarks/bench_cli_help.py [--n 7] [--max 0.5]

Each line is the median wall time of n runs (fresh processes, ``python -m tactilevision``)
and its ratio to ``python -c pass`` timed in the same run; ``import tactilevision`` and
``tactilevision --help`` are timed the same way. Issue 86's target: every command's
``--help`` under 0.5 s at rest (exit status 1 when a median exceeds --max). The machine's
load is printed first: on a loaded machine every figure, the interpreter's start included,
grows with it; the ratios move less.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

from tactilevision.cli import build_parser

ROOT = Path(__file__).resolve().parents[1]


def command_lines() -> list[list[str]]:
    """Every command line with options of its own (``optics calibrate`` for the groups)."""
    sub = next(a for a in build_parser()._actions
               if isinstance(a, argparse._SubParsersAction))
    out = []
    for name, parser in sub.choices.items():
        inner = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        out += [[name, child] for child in inner[0].choices] if inner else [[name]]
    return out


def median_s(argv: list[str], n: int) -> float:
    """The median wall time of `n` runs of `argv` (output discarded), seconds."""
    times = []
    for _ in range(n):
        t0 = time.perf_counter()
        subprocess.run(argv, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                       check=True)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=7, help="runs per command (default 7)")
    ap.add_argument("--max", type=float, default=0.5,
                    help="seconds a median may take (default 0.5; exit status 1 beyond)")
    args = ap.parse_args()
    py = sys.executable
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, python "
          f"{platform.python_version()}; load average {os.getloadavg()[0]:.2f} at the start")
    base = median_s([py, "-c", "pass"], args.n)
    rows = [("python -c pass", base),
            ("python -c 'import tactilevision'", median_s([py, "-c", "import tactilevision"],
                                                          args.n)),
            ("tactilevision --help", median_s([py, "-m", "tactilevision", "--help"], args.n))]
    for words in command_lines():
        rows.append((f"tactilevision {' '.join(words)} --help",
                     median_s([py, "-m", "tactilevision", *words, "--help"], args.n)))
    print(f"median of {args.n} runs; ratio to python -c pass")
    worst = 0.0
    for label, t in rows:
        print(f"  {label:42s} {1e3 * t:7.0f} ms  x{t / base:4.1f}")
        if label.startswith("tactilevision"):
            worst = max(worst, t)
    print(f"load average {os.getloadavg()[0]:.2f} at the end; slowest --help "
          f"{1e3 * worst:.0f} ms ({'over' if worst > args.max else 'within'} {args.max} s)")
    return 1 if worst > args.max else 0


if __name__ == "__main__":
    sys.exit(main())
