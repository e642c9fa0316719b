"""How long ``optics calibrate`` takes on a 67-press GelSight Mini folder, against
decoding that folder once, in the same run (one calibration through the library, and
the command with its default held-out report: the engine's choice, whose network is
scored, then the calibration saved, its network started from the scored one's).

The folder is the shared GelSight Mini calibration (gs_sdk's layout, 22 presses of a
6.31 mm ball, 320 x 240) with its presses repeated to 67, so that it holds as many
labelled pixels as a 67-press folder of that sensor (the held-back presses are not
here); it is written to a temporary folder. Timed: ``read_ball_presses`` of the folder
(the reference: decoding its PNGs once) and the calibration with the command's
defaults (``PhotometricCalibration.from_ball_presses``: circles detected at the
contact edge, centres refined by a first round, a position-aware network), once with
the default step budget and once with ``max_steps=None`` (every epoch in full, the
behaviour before the budget) unless ``--skip-full``.

    python benchmarks/bench_optics_calibration_time.py [--folder DIR] [--presses 67]
                                                       [--skip-full]

The folder defaults to ``$TACTILEVISION_GELSIGHT_MINI`` or ``../shared/real/gelsight_mini``
beside the repository.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import platform
import shutil
import tempfile
import time
from pathlib import Path

from tactilevision.cli import main as cli_main
from tactilevision.io import read_ball_presses
from tactilevision.optics import PhotometricCalibration

MM_PER_PX = 0.0634


def repeated_folder(src: Path, dst: Path, n: int) -> None:
    """gs_sdk's layout with the source's presses repeated to `n`."""
    presses = sorted((src / "6.310mm").iterdir(), key=lambda p: int(p.name))
    shutil.copy(src / "background.png", dst / "background.png")
    rows = ["experiment_reldir,diameter(mm)"]
    for i in range(n):
        d = dst / "6.310mm" / str(i)
        d.mkdir(parents=True)
        shutil.copy(presses[i % len(presses)] / "gelsight.png", d / "gelsight.png")
        rows.append(f"6.310mm/{i},6.31")
    (dst / "catalog.csv").write_text("\n".join(rows) + "\n")


def main() -> int:
    root = Path(__file__).resolve().parents[1]
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--folder", type=Path, default=Path(os.environ.get(
        "TACTILEVISION_GELSIGHT_MINI", root.parent / "shared" / "real" / "gelsight_mini")))
    ap.add_argument("--presses", type=int, default=67)
    ap.add_argument("--skip-full", action="store_true")
    args = ap.parse_args()
    if not (args.folder / "catalog.csv").is_file():
        print(f"no GelSight Mini folder at {args.folder}: nothing to time")
        return 0
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        repeated_folder(args.folder, folder, args.presses)
        t0 = time.perf_counter()
        ps = read_ball_presses(folder)
        t_read = time.perf_counter() - t0
        print(f"decode {len(ps.frames)} presses once: {t_read:.2f} s")
        runs = [("default step budget", {})]
        if not args.skip_full:
            runs.append(("every epoch in full (max_steps=None)", {"max_steps": None}))
        for label, kw in runs:
            t0 = time.perf_counter()
            PhotometricCalibration.from_ball_presses(
                ps.reference, ps.frames, ball_radius_mm=ps.ball_radius_mm,
                mm_per_px=MM_PER_PX, **kw)
            t = time.perf_counter() - t0
            print(f"one calibration, {label}: {t:.1f} s, {t / t_read:.0f} x the decode")
        # the command as a user runs it: the engine's choice (the network scored on the
        # first fold), then the one saved, trained on every press from that network
        t0 = time.perf_counter()
        with contextlib.redirect_stdout(io.StringIO()) as out:
            rc = cli_main(["optics", "calibrate", str(folder), "--mm-per-px", str(MM_PER_PX),
                       "--out", str(folder / "out" / "optics.npz"), "--no-progress"])
        t = time.perf_counter() - t0
        held = next((line for line in out.getvalue().splitlines()
                     if line.startswith("held out")), "")
        print(f"tactilevision optics calibrate (exit {rc}): {t:.1f} s, {t / t_read:.0f} x the "
              f"decode; {held.split(';')[0]}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
