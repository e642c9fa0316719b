"""Frame rate of height-map reconstruction at 640 x 480 on one core.

Times ``DepthReconstructor(cal)(frame)`` on real GelSight frames (taxim) for
each engine, with OpenCV, onnxruntime and scipy.fft held to one thread, and
splits the table path into its stages. Prints milliseconds per frame and
frames per second (median of repeated runs over 8 different frames).

Run: ``python benchmarks/bench_speed.py`` (about a minute; trains a LUT,
uses the shipped MLP calibration ``calibration/gelsight.npz``).
"""

from __future__ import annotations

import os
import statistics
import sys
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")

import cv2
import numpy as np

from tactilevision._assets import default_calibration_path
from tactilevision.io import read_ball_presses, taxim_datapack
from tactilevision.optics import (
    DepthReconstructor,
    PhotometricCalibration,
    gradients_from_normals,
    integrate_poisson,
)
from tactilevision.optics._features import blur_frames

cv2.setNumThreads(1)


def per_frame_ms(fn, frames: np.ndarray, rounds: int) -> float:
    fn(frames[0])
    times = []
    for _ in range(rounds):
        t0 = time.perf_counter()
        for f in frames:
            fn(f)
        times.append((time.perf_counter() - t0) / len(frames))
    return 1000 * statistics.median(times)


def measure() -> dict:
    """Time each engine and the table path's stages on 8 real GelSight frames, one thread,
    beside a bare DCT-II pair and a bare gather of the same run; returns the milliseconds
    per frame: ``rows`` [(engine, ms)], ``batch`` (name, ms), ``stages`` {lookup, poisson,
    blur}, ``dct``, ``gather``, ``classical`` and ``default`` (the default
    ``DepthReconstructor(cal)`` timed beside the classical pipeline), and ``shape``."""
    ps = read_ball_presses(taxim_datapack())
    frames = ps.frames[1::6][:8]
    lut = PhotometricCalibration.from_ball_presses(
        ps.reference, ps.frames[0::2], ps.centers_px[0::2], ps.radii_px[0::2],
        ball_radius_mm=2.0, mm_per_px=0.0295, model="lut")
    mlp = PhotometricCalibration.load(default_calibration_path("gelsight"))
    out: dict = {"shape": frames.shape[1:3], "rows": []}
    rows = [("LUT (colour only), table", DepthReconstructor(lut), 15),
            ("MLP position-aware, table", DepthReconstructor(mlp), 15),
            ("MLP position-aware, table, level='far_field'",
             DepthReconstructor(mlp, level="far_field"), 15),
            ("MLP position-aware, table, zero_background=True",
             DepthReconstructor(mlp, zero_background=True), 15),
            ("MLP position-aware, onnx", DepthReconstructor(mlp, engine="onnx"), 2)]
    for name, recon, rounds in rows:
        out["rows"].append((name, per_frame_ms(recon, frames, rounds)))
        if name.startswith("LUT"):
            batch = np.ascontiguousarray(frames)
            t0 = time.perf_counter()
            for _ in range(5):
                recon(batch)
            out["batch"] = (f"LUT, batch of {len(batch)}",
                            1000 * (time.perf_counter() - t0) / (5 * len(batch)))
    recon = rows[0][1]
    table = recon._table
    blurred = frames[0]
    gx, gy = table.gradients(blurred)
    out["stages"] = {"blur": per_frame_ms(lambda f: blur_frames(f, 1.0), frames, 20),
                     "lookup": per_frame_ms(table.gradients, frames, 20),
                     "poisson": per_frame_ms(lambda f: recon._solver(gx, gy), frames, 20)}
    # references of the same run: a bare DCT-II pair and a bare gather of the frame's size
    import scipy.fft as sfft

    field = np.random.default_rng(0).standard_normal(frames.shape[1:3]).astype(np.float32)
    out["dct"] = per_frame_ms(lambda f: sfft.idctn(sfft.dctn(field, type=2, workers=1),
                                                   type=2, workers=1), frames, 20)
    lut_flat = np.random.default_rng(1).standard_normal(32 ** 3 * 2).astype(np.float32)
    idx = np.random.default_rng(2).integers(0, 32 ** 3, frames.shape[1] * frames.shape[2])
    out["gather"] = per_frame_ms(lambda f: (lut_flat[2 * idx], lut_flat[2 * idx + 1]),
                                 frames, 20)
    # the classical pipeline (GelSight's original recipe): a binned colour-difference LUT
    # looked up in numpy, normals to gradients, Dirichlet DST Poisson in float64
    table32 = lut.lut
    ref = ps.reference.astype(np.float32)

    def classical(f: np.ndarray) -> np.ndarray:
        nxy = table32.normals((f.astype(np.float32) - ref) / 255.0)
        gx, gy = gradients_from_normals(nxy[..., 0], nxy[..., 1])
        return integrate_poisson(gx, gy, boundary="dirichlet")

    out["classical"] = per_frame_ms(classical, frames, 5)
    out["default"] = per_frame_ms(DepthReconstructor(mlp), frames, 15)
    return out


def main() -> int:
    m = measure()
    h, w = m["shape"]
    print(f"frames {w} x {h} px, one thread "
          f"(OpenCV {cv2.getNumThreads()}, onnxruntime 1, scipy.fft workers=1)\n")
    print("| engine | ms/frame | frames/s |")
    print("|---|---|---|")
    for name, ms in m["rows"]:
        print(f"| {name} | {ms:.2f} | {1000 / ms:.0f} |")
        if name.startswith("LUT"):
            bname, ms_b = m["batch"]
            print(f"| {bname} | {ms_b:.2f} | {1000 / ms_b:.0f} |")
    st = m["stages"]
    print(f"\nLUT stages (ms): table lookup {st['lookup']:.2f}, Poisson (DCT) "
          f"{st['poisson']:.2f}; a blur of sigma 1 (off by default) would add {st['blur']:.2f}")
    print(f"references of this run (ms): a bare scipy DCT-II pair {m['dct']:.2f}, a bare gather "
          f"of two components per pixel {m['gather']:.2f}")
    print(f"classical LUT + DST pipeline {m['classical']:.2f} ms against the default "
          f"DepthReconstructor(cal) {m['default']:.2f} ms in the same run: "
          f"{m['classical'] / m['default']:.1f} times faster")
    return 0

if __name__ == "__main__":
    sys.exit(main())
