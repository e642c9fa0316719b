"""A first ``fit`` and ``diagnose`` of the FEATS sample with an empty cache (a fresh install).

    python benchmarks/bench_first_use.py [--repeats N]

Each run gets a new, empty cache folder (``$TACTILEVISION_CACHE``), so nothing computed
before is read: what a user's first command costs. Prints the wall time of ``python -c
"import tactilevision"`` (the reference of the same run; it loads no NumPy), of importing
the modules the commands load (NumPy, SciPy, the mechanics and the diagnosis), then of
``tactilevision fit`` and ``tactilevision diagnose`` of
``sample_frames/feats/force_depth.csv``, each as a fresh process, the median over the
repeats, and the ratio to the import. The ball on
the FEATS gel's finite pad is one FEM sweep per law and contact; they ship in
``models/sphere_pad_sweeps.npz`` (``tactilevision fem tables --what pad``).
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "sample_frames" / "feats" / "force_depth.csv"
#: The second reference: the modules ``fit`` and ``diagnose`` load (NumPy, SciPy, the
#: mechanics and the diagnosis), where ``import tactilevision`` loads none of them.
IMPORT_WORK = "import tactilevision.mechanics, tactilevision.diagnosis"


def _timed(argv: list[str], cache: Path) -> float:
    env = dict(os.environ, TACTILEVISION_CACHE=str(cache))
    t0 = time.perf_counter()
    done = subprocess.run(argv, cwd=ROOT, env=env, capture_output=True, text=True)
    dt = time.perf_counter() - t0
    if done.returncode not in (0, 3):
        raise SystemExit(f"{' '.join(argv)} failed ({done.returncode}): {done.stderr}")
    return dt


def measure(repeats: int = 3) -> dict[str, list[float]]:
    """Wall times, s, of the import, of the modules the two commands load
    (:data:`IMPORT_WORK`), of the first ``fit`` and the first ``diagnose`` of the sample,
    each a fresh process with a new, empty cache, ``repeats`` times each (the four
    interleaved): ``{"import": [...], "import work": [...], "fit": [...],
    "diagnose": [...]}``."""
    exe = [sys.executable, "-m", "tactilevision"]
    runs: dict[str, list[float]] = {"import": [], "import work": [], "fit": [],
                                    "diagnose": []}
    for _ in range(repeats):
        for what, argv in (("import", [sys.executable, "-c", "import tactilevision"]),
                           ("import work", [sys.executable, "-c", IMPORT_WORK]),
                           ("fit", [*exe, "fit", str(SAMPLE)]),
                           ("diagnose", [*exe, "diagnose", str(SAMPLE)])):
            with tempfile.TemporaryDirectory() as cache:   # empty: a fresh install
                runs[what].append(_timed(argv, Path(cache)))
    return runs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    runs = measure(args.repeats)
    ref = statistics.median(runs["import"])
    print(f"{SAMPLE.relative_to(ROOT)}, empty cache each run, {args.repeats} runs "
          f"(median, range):")
    for what, t in runs.items():
        print(f"  {what:11s} {statistics.median(t):6.2f} s  [{min(t):.2f}, {max(t):.2f}]"
              + ("" if what == "import" else f"  {statistics.median(t) / ref:5.1f} x import"))


if __name__ == "__main__":
    main()
