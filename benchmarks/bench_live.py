"""End-to-end rate and latency of the live pipeline (``tactilevision.live``), one core.

Frames: the real GelSight presses of ``sample_frames/gelsight_ball`` (and their
reference), resized to GelSlim 3.0's 427 x 320 and kept at GelSight's 640 x 480,
with a LUT calibration fitted to them at each size. They come from an in-memory
"camera" that never waits, through the pipeline's capture thread, under the
'every' policy (every frame processed: the pipeline's own rate). For each size,
height only and height + forces, with the spectral method (every pixel) and the
inverse FEM (``method='fem'``, 40 x 30 nodes), on the whole height map ('field'), and the
pipeline's default with forces (the footprint on blocks of pixels, level 'contact'):

- frames/s and the latency from capture to result (median, 95th percentile);
  with forces, at the heights' level 'median' (camera rate) and 'contact' (zero
  outside the contact: the accurate footprint, the ``forces`` command's default);
- the same as a ratio to the bare per-frame work timed in the same run (the
  reconstructor, and the force estimator, called in a plain loop): the
  pipeline's own overhead.

The design goal (issue 21): height + forces at 427 x 320 at 90 frames/s or more,
latency under 2 frame periods (22 ms). The inverse FEM's node forces cost about a
millisecond a frame on top of the heights, the spectral method's several.

Run: ``python benchmarks/bench_live.py [--frames 600]``.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import cv2
import numpy as np

from tactilevision.fem import ForceEstimator
from tactilevision.live import Pipeline
from tactilevision.live._pipeline import _OneBlasThread
from tactilevision.optics import DepthReconstructor, PhotometricCalibration

BALL = Path(__file__).resolve().parents[1] / "sample_frames" / "gelsight_ball"


def _sensor(w: int, h: int):
    def size(img):
        return cv2.resize(img, (w, h), interpolation=cv2.INTER_AREA)

    ref = size(cv2.imread(str(BALL / "reference.png")))
    presses = [size(cv2.imread(str(p))) for p in sorted((BALL / "frames").glob("press_*.png"))]
    cal = PhotometricCalibration.from_ball_presses(
        ref, np.stack(presses), ball_radius_mm=2.0, mm_per_px=0.0295 * 640 / w, model="lut")
    return cal, ref, presses


#: The work timed at each size: (forces, the heights' level, the force method, the
#: traction region). The last: the pipeline's default with forces (the footprint on blocks
#: of pixels, heights pinned outside the contact, ``binning='auto'``).
WORK = ((False, "median", None, "field"), (True, "median", "spectral", "field"),
        (True, "median", "fem", "field"), (True, "contact", "spectral", "field"),
        (True, "contact", "fem", "field"), (True, "contact", "spectral", "footprint"))
SIZES = ((427, 320), (640, 480))


def rows(n_frames: int = 600) -> list[dict]:
    """Every size and work of the module docstring, timed: one dict each with ``size``
    (w, h), ``forces``, ``level``, ``method``, ``fps`` (the pipeline's own rate under
    'every'), ``ms`` and ``bare_ms`` (a frame through the pipeline and in the plain loop),
    ``latency_queued_ms`` (median, every frame queued) and ``latency_ms``,
    ``latency_p95_ms`` (a camera at 0.9 times the pipeline's rate, 'latest')."""
    cv2.setNumThreads(1)
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    out = []
    for w, h in SIZES:
        cal, ref, presses = _sensor(w, h)
        # the presses moved sideways by up to 20 px: their colour change against the
        # reference rolled, not the frame (whose rolled edge would read as contact)
        change = [p.astype(np.int16) - ref for p in presses]
        frames = [np.clip(ref + np.roll(change[i % 4], (i % 40) - 20, axis=1), 0, 255
                          ).astype(np.uint8) for i in range(n_frames)]
        for forces, level, method, contact in WORK:
            kw = ({"E_mpa": 0.2, "nu": 0.48, "thickness_mm": 3.0, "method": method,
                   "contact": contact} if forces else {})
            # the bare work, in a plain loop (BLAS on one thread, as the pipeline runs it)
            est = ForceEstimator(cal.shape, cal.mm_per_px, thickness_mm=3.0, E_mpa=0.2,
                                 nu=0.48, method=method, contact=contact) if forces else None
            blocks = est.blocks if est is not None and level == "contact" else 1
            recon = DepthReconstructor(cal, reference=ref,
                                       boundary="contact" if level == "contact" else "neumann",
                                       binning=blocks)
            blas = _OneBlasThread()
            t0 = time.perf_counter()
            for f in frames:
                with blas:
                    z = recon(f)
                    recon.contact_mask(f)
                    if est is not None:
                        est(z)
            bare = (time.perf_counter() - t0) / len(frames)
            pipe = Pipeline(cal, reference=ref, level=level, **kw)
            lat = []
            t0 = time.perf_counter()
            for r in pipe.stream(iter(frames), policy="every"):
                lat.append(r.latency_s)
            per = (time.perf_counter() - t0) / len(frames)
            # latency of a camera at the pipeline's own rate (no backlog): 'latest' policy
            period = 1.1 * per

            def camera(period=period, frames=frames):
                nxt = time.perf_counter()
                for f in frames[:200]:
                    nxt += period
                    time.sleep(max(0.0, nxt - time.perf_counter()))
                    yield f

            live = [r.latency_s for r in pipe.stream(camera(), policy="latest")]
            out.append({"size": (w, h), "forces": forces, "level": level, "method": method,
                        "contact": contact,
                        "fps": 1 / per, "ms": 1e3 * per, "bare_ms": 1e3 * bare,
                        "latency_queued_ms": 1e3 * float(np.median(lat)),
                        "latency_ms": 1e3 * float(np.median(live)),
                        "latency_p95_ms": 1e3 * float(np.percentile(live, 95))})
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=600)
    args = ap.parse_args()
    print(f"{os.cpu_count()} cores; OpenCV on 1 thread; {args.frames} frames per run, "
          "'every' policy")
    for r in rows(args.frames):
        w, h = r["size"]
        what = (f"height + forces ({r['method']}, {r['contact']}), level '{r['level']}'"
                if r["forces"] else "height only")
        print(f"{w} x {h}, {what}: {r['fps']:.0f} frames/s ({r['ms']:.2f} ms a frame, "
              f"{r['ms'] / r['bare_ms']:.2f} x the bare loop's {r['bare_ms']:.2f} ms); latency "
              f"with every frame queued: median {r['latency_queued_ms']:.0f} ms; from a camera "
              f"at 0.9 x that rate ('latest'): median {r['latency_ms']:.1f} ms, "
              f"95th percentile {r['latency_p95_ms']:.1f} ms")


if __name__ == "__main__":
    main()
