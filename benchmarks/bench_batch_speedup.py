"""``batch`` on N local workers against one ``reconstruct`` / ``forces`` process, same video.

    python benchmarks/bench_batch_speedup.py [--frames 1200] [--workers 2]
        [--kinds reconstruct forces] [--chunk-frames 32] [--repeats 1]

A 640 x 480 MJPG video of ``--frames`` frames is written from the real GelSight ball
presses of ``sample_frames/gelsight_ball`` (moved a pixel a frame, a third of them
the reference), with its ``<stem>_reference.png``. Then, as a user runs them, each
command as its own process (``python -m tactilevision ...``, default options, the
shipped GelSight calibration ``--sensor gelsight``; forces with E 0.2 MPa, nu 0.48, a
3 mm gel), timed from start to exit, set-up included:

- one ``reconstruct`` (or ``forces``) process over the video;
- ``batch reconstruct`` (or ``batch forces``) on ``--workers`` local worker processes.

Prints both rates, frames/s, and their ratio (issue target: at least 0.8 N times one
process), and the CPU seconds (user + system) each used, the batch's workers included:
on N cores the batch cannot run faster than its CPU seconds / N, which bounds the ratio
at N x (one process's wall time) / (the batch's CPU seconds).
Both do the same work a frame: the height map, its deepest point, the contact
area and ``out_of_range_px`` (for ``reconstruct``; until 2026-11-27 the one process also
computed a second colour change a frame and the batch no ``out_of_range_px``), and the
batch also rounds, compresses and writes the heights to Zarr. The optics table's disk
cache is warmed first, so neither run pays for tabulating the network.
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
BALL = ROOT / "sample_frames" / "gelsight_ball"
MATERIAL = ["--E-mpa", "0.2", "--nu", "0.48", "--thickness-mm", "3.0"]


def make_video(folder: Path, n: int) -> Path:
    """The video (n frames, 640 x 480, MJPG at 30 frames/s) and its reference beside it."""
    ref = cv2.imread(str(BALL / "reference.png"))
    presses = [cv2.imread(str(p)) for p in sorted((BALL / "frames").glob("press_*.png"))]
    video = folder / "presses.avi"
    cv2.imwrite(str(folder / "presses_reference.png"), ref)
    h, w = ref.shape[:2]
    vw = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 30.0, (w, h))
    rng = np.random.default_rng(0)
    # a press moved sideways: its colour change against the reference rolled, not the frame
    # (whose rolled edge would read as contact beside the press)
    change = [p.astype(np.int16) - ref for p in presses]
    for i in range(n):
        moved = np.roll(change[i % len(change)], (i % 60) - 30, axis=1)
        vw.write(ref if rng.random() < 0.3 else np.clip(ref + moved, 0, 255).astype(np.uint8))
    vw.release()
    return video


def timed(cmd: list[str]) -> tuple[float, float]:
    """Wall seconds of one command run to its end, and the CPU seconds (user + system) it
    and the processes it waited for (the batch's workers) used; its output kept quiet
    unless it fails."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    run = subprocess.run(cmd, capture_output=True, text=True)
    seconds = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if run.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} exited {run.returncode}:\n{run.stderr[-2000:]}")
    return seconds, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def speedup_rows(frames: int = 1200, workers: int = 2, chunk_frames: int = 32,
                 kinds: tuple[str, ...] = ("reconstruct", "forces"), repeats: int = 1,
                 log=print) -> dict:
    """Each kind's one process and batch, timed as a user runs them, `repeats` times in
    turn: ``{"rows": [{"kind", "one_s", "batch_s", "ratio", "one_cpu_s", "batch_cpu_s",
    "bound"}], "frames", "workers", "cores", "video_mib"}``."""
    work = Path(tempfile.mkdtemp(prefix="bench_batch_speedup_"))
    py = [sys.executable, "-m", "tactilevision"]
    rows = []
    try:
        video = make_video(work, frames)
        mib = video.stat().st_size / 2**20
        log(f"machine: {os.cpu_count()} cores; video {frames} frames 640 x 480 MJPG "
            f"({mib:.0f} MiB)")
        # the network's table into the disk cache: neither timed run tabulates it
        timed([*py, "reconstruct", str(BALL / "frames"), "--sensor", "gelsight", "--out",
               str(work / "warm"), "--no-progress"])
        cores = min(workers, os.cpu_count() or 1)
        for r in range(repeats):
            for kind in kinds:
                extra = MATERIAL if kind == "forces" else []
                one, one_cpu = timed([*py, kind, str(video), "--sensor", "gelsight", "--out",
                                      str(work / f"{kind}_one_{r}"), "--no-progress", *extra])
                many, many_cpu = timed([*py, "batch", kind, str(video), "--sensor",
                                        "gelsight", "--out", str(work / f"{kind}_batch_{r}"),
                                        "--workers", str(workers), "--chunk-frames",
                                        str(chunk_frames), "--no-progress", *extra])
                # the batch's own work bounds it: on `cores` cores it cannot finish before
                # many_cpu / cores seconds, however well the frames are spread
                row = {"kind": kind, "one_s": one, "batch_s": many, "ratio": one / many,
                       "one_cpu_s": one_cpu, "batch_cpu_s": many_cpu,
                       "bound": cores * one / many_cpu}
                rows.append(row)
                log(f"{kind}: one process {one:.1f} s ({frames / one:.1f} frames/s); batch "
                    f"on {workers} workers {many:.1f} s ({frames / many:.1f} frames/s): "
                    f"{one / many:.2f} x one process (target {0.8 * workers:.1f})")
                log(f"  CPU (user + system): one process {one_cpu:.1f} s, batch "
                    f"{many_cpu:.1f} s ({many_cpu / one_cpu:.2f} x); on {cores} cores the "
                    f"batch can be at most {row['bound']:.2f} x one process")
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return {"rows": rows, "frames": frames, "workers": workers, "cores": cores,
            "video_mib": mib}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=1200)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--chunk-frames", type=int, default=32)
    ap.add_argument("--kinds", nargs="+", default=["reconstruct", "forces"],
                    choices=("reconstruct", "forces"))
    ap.add_argument("--repeats", type=int, default=1,
                    help="run each kind's pair this many times, in turn")
    args = ap.parse_args()
    speedup_rows(args.frames, args.workers, args.chunk_frames, tuple(args.kinds),
                 args.repeats)
    return 0


if __name__ == "__main__":
    sys.exit(main())
