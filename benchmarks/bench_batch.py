"""Throughput of ``tactilevision batch reconstruct`` on a local Dask cluster.

A recorded sequence of GelSlim-size frames (320 rows x 428 columns: GelSlim 3.0's
427 x 320, padded to the even width the video codecs need) is written as an MJPG
video from the real GelSight presses of ``sample_frames/gelsight_ball`` (resized,
shifted a pixel a frame), with a LUT calibration fitted to them at that size. Then:

1. the single-process loop (decode, height map, no storage) over the first
   ``--loop`` frames: the reference cost per frame;
2. the batch on 1 worker and on 2 workers over all ``--frames`` frames (height maps
   to Zarr, rows to Parquet): frames/s, scaling efficiency, cost per frame against
   the loop's;
3. the peak memory (``ru_maxrss``) of each worker after a batch of ``--short``
   frames and after the full one: flat when the memory does not grow with the
   sequence;
4. on paper: 100 sensors x 1 hour at 90 frames/s, and the cores it needs.

Run: ``python benchmarks/bench_batch.py`` (about 10 minutes here);
``--frames 2000 --short 500 --loop 500`` for a quick look.
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
BALL = ROOT / "sample_frames" / "gelsight_ball"
W, H = 428, 320


def make_inputs(folder: Path, n: int) -> tuple[Path, Path]:
    """The video (n frames), its reference and a LUT calibration at W x H."""
    from tactilevision.optics import PhotometricCalibration

    def small(img):
        return cv2.resize(img, (W, H), interpolation=cv2.INTER_AREA)

    ref = small(cv2.imread(str(BALL / "reference.png")))
    presses = [small(cv2.imread(str(p))) for p in sorted((BALL / "frames").glob("press_*.png"))]
    cal = PhotometricCalibration.from_ball_presses(
        ref, np.stack(presses), ball_radius_mm=2.0, mm_per_px=0.0295 * 640 / W, model="lut")
    cal.save(folder / "optics.npz")
    video = folder / "gelslim_size.avi"
    cv2.imwrite(str(folder / "gelslim_size_reference.png"), ref)
    vw = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 90.0, (W, H))
    rng = np.random.default_rng(0)
    for i in range(n):
        f = ref if rng.random() < 0.3 else np.roll(presses[i % 4], (i % 60) - 30, axis=1)
        vw.write(f)
    vw.release()
    return video, folder / "optics.npz"


def single_loop(video: Path, optics: Path, n: int) -> tuple[float, float]:
    """Seconds per frame of the single-process loop, one core (OpenCV on one thread, as
    in a worker): the bare height map, and the batch's own per-frame work (height map,
    its maximum, the contact area, as ``reconstruct`` does), nothing stored."""
    from tactilevision.io import VideoFrames
    from tactilevision.optics import DepthReconstructor, PhotometricCalibration

    cv2.setNumThreads(1)
    recon = DepthReconstructor(PhotometricCalibration.load(optics),
                               reference=cv2.imread(str(video.with_name(
                                   "gelslim_size_reference.png"))))
    frames = VideoFrames(video)
    t0 = time.perf_counter()
    for f in frames.iter(0, n):
        recon(f)
    bare = (time.perf_counter() - t0) / n
    t0 = time.perf_counter()
    for f in frames.iter(0, n):
        h = recon(f)
        float(h.max())
        int(recon.contact_mask(f).sum())
    return bare, (time.perf_counter() - t0) / n


def batch(video: Path, optics: Path, n_workers: int, out: Path, n: int | None = None
          ) -> tuple[float, list[float]]:
    """(seconds, peak RSS of each worker in MiB) of one batch on a fresh local cluster."""
    import dask
    from distributed import Client, LocalCluster

    from tactilevision.batch import WORKER_ENVIRON, BatchSettings, run_batch

    src = video
    if n is not None:                      # a shorter recording: the first n frames
        src = out.parent / f"first_{n}.avi"
        src.with_name(f"first_{n}_reference.png").write_bytes(
            video.with_name("gelslim_size_reference.png").read_bytes())
        if not src.is_file():
            from tactilevision.io import VideoFrames

            vw = cv2.VideoWriter(str(src), cv2.VideoWriter_fourcc(*"MJPG"), 90.0, (W, H))
            for f in VideoFrames(video).iter(0, n):
                vw.write(f)
            vw.release()
    with dask.config.set(WORKER_ENVIRON):       # as run_batch's own cluster
        cluster = LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                               dashboard_address=":0")
    client = Client(cluster)
    try:
        client.run(lambda: None)            # workers up before the clock starts
        settings = BatchSettings(kind="reconstruct", calibration=str(optics), chunk_frames=64)
        t0 = time.perf_counter()
        rep = run_batch("reconstruct", [src], out, settings=settings, client=client,
                        progress=False)
        seconds = time.perf_counter() - t0
        assert rep.inputs[0].status == "done", rep.inputs[0].error
        peaks = client.run(lambda: resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
    finally:
        client.close()
        cluster.close()
    return seconds, sorted(peaks.values())


def scaling_rows(frames: int, short: int, loop: int, log=print) -> dict:
    """Steps 1 to 4 of the module docstring on a new video of `frames` frames: ``{"frames",
    "video_mib", "bare_ms", "loop_ms" (with the batch's rows), "batch": {workers:
    (seconds, peaks MiB)}, "short": (frames, seconds, peaks), "scaling", "efficiency",
    "cost": {workers: the batch's worker-ms a frame over the loop's}, "core_hours",
    "cores"}``; `log` prints each step's line."""
    work = Path(tempfile.mkdtemp(prefix="bench_batch_"))
    try:
        t0 = time.perf_counter()
        video, optics = make_inputs(work, frames)
        size = video.stat().st_size / 2**20
        log(f"video: {frames} frames, MJPG, {size:.0f} MiB, written in "
            f"{time.perf_counter() - t0:.1f} s")
        bare, per_frame = single_loop(video, optics, loop)
        log(f"single-process loop, one core, {loop} frames: decode + height map "
            f"{1e3 * bare:.2f} ms/frame ({1 / bare:.0f} frames/s); with the batch's "
            f"per-frame rows (maximum, contact area), nothing stored: {1e3 * per_frame:.2f} "
            f"ms/frame ({1 / per_frame:.0f} frames/s)")
        res, cost = {}, {}
        for nw in (1, 2):
            s, peaks = batch(video, optics, nw, work / f"out{nw}")
            res[nw] = (s, peaks)
            cost[nw] = s * nw / frames / per_frame
            log(f"batch, {nw} worker(s), {frames} frames: {s:.1f} s = {frames / s:.0f} "
                f"frames/s; {1e3 * s * nw / frames:.2f} worker-ms/frame = "
                f"{cost[nw]:.2f} x the loop's with the same rows; peak RSS per worker "
                f"{', '.join(f'{p:.0f}' for p in peaks)} MiB")
        eff = res[1][0] / (2 * res[2][0])
        log(f"scaling 1 -> 2 workers: {res[1][0] / res[2][0]:.2f} x, efficiency "
            f"{100 * eff:.0f} %")
        s_short, peaks_short = batch(video, optics, 2, work / "out_short", n=short)
        log(f"batch, 2 workers, first {short} frames: {s_short:.1f} s; peak RSS per "
            f"worker {', '.join(f'{p:.0f}' for p in peaks_short)} MiB (against the "
            f"{frames}-frame run above: flat if equal within noise)")
        need = 100 * 3600 * 90                  # frames: 100 sensors x 1 hour x 90 frames/s
        core_s = need * res[2][0] * 2 / frames
        cores = int(np.ceil(core_s / 3600 / eff))
        log(f"on paper, 100 sensors x 1 hour at 90 frames/s = {need:,} frames: "
            f"{core_s / 3600:.0f} core-hours at this machine's 2-worker cost; in one hour "
            f"of wall time about {cores} cores (at the measured {100 * eff:.0f} % "
            f"efficiency), e.g. {int(np.ceil(cores / 32))} nodes of 32 cores")
        return {"frames": frames, "video_mib": size, "bare_ms": 1e3 * bare,
                "loop_ms": 1e3 * per_frame, "batch": res, "short": (short, s_short, peaks_short),
                "scaling": res[1][0] / res[2][0], "efficiency": eff, "cost": cost,
                "core_hours": core_s / 3600, "cores": cores}
    finally:
        shutil.rmtree(work, ignore_errors=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=20_000)
    ap.add_argument("--short", type=int, default=5_000)
    ap.add_argument("--loop", type=int, default=2_000)
    args = ap.parse_args()
    print(f"machine: {os.cpu_count()} cores ({_cpu()}); frames {H} x {W}")
    scaling_rows(args.frames, args.short, args.loop)


def _cpu() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return "unknown CPU"


if __name__ == "__main__":
    main()
