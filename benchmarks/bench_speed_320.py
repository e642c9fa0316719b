"""Frame rate of absolute heights at 320 x 240 (GelSight Mini's size) on one core.

    python benchmarks/bench_speed_320.py

The real GelSight ball presses inside the ``taxim`` package, resized to 320 x 240,
a LUT calibrated on the even presses, and ``DepthReconstructor`` timed on the odd ones
(OpenCV, onnxruntime and scipy.fft on one thread): the camera-rate default (the frame's
median as zero), the two absolute-height paths (``level='far_field'``: a smooth surface
fitted to the gel outside the contact and subtracted; ``boundary='contact'``: zero
outside the contact region, integrated over it), and a same-run reference operation, a
bare forward and inverse ``scipy.fft.dctn`` pair on a 320 x 240 float32 array, so the
figures can be compared across machines as ratios. Median of repeated runs.
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import cv2
import numpy as np
import scipy.fft
from bench_speed import per_frame_ms  # the same timing as the 640 x 480 benchmark

from tactilevision.io import read_ball_presses, taxim_datapack
from tactilevision.optics import DepthReconstructor, PhotometricCalibration

cv2.setNumThreads(1)
SIZE = (320, 240)


def main() -> None:
    ps = read_ball_presses(taxim_datapack("gelsight"))
    ref = cv2.resize(ps.reference, SIZE, interpolation=cv2.INTER_AREA)
    frames = np.stack([cv2.resize(f, SIZE, interpolation=cv2.INTER_AREA) for f in ps.frames])
    scale = ps.reference.shape[1] / SIZE[0]
    cal = PhotometricCalibration.from_ball_presses(
        ref, frames[::2], ps.centers_px[::2] / scale, ps.radii_px[::2] / scale,
        ball_radius_mm=2.0, mm_per_px=0.0295 * scale, model="lut")
    test = frames[1::2][:8]
    a = np.random.default_rng(0).random(SIZE[::-1]).astype(np.float32)
    ref_ms = per_frame_ms(lambda _: scipy.fft.idctn(scipy.fft.dctn(a, norm="ortho"),
                                                    norm="ortho"), test, 15)
    print(f"{SIZE[0]} x {SIZE[1]}, LUT, one thread; reference: a dctn + idctn pair "
          f"{ref_ms:.2f} ms")
    print("| path | ms per frame | frames/s | x reference |")
    print("|---|---|---|---|")
    for label, kw in (("median zero (default)", {}),
                      ("absolute: level='far_field'", {"level": "far_field"}),
                      ("absolute: boundary='contact'", {"boundary": "contact"})):
        recon = DepthReconstructor(cal, reference=ref, **kw)
        ms = per_frame_ms(recon, test, 15)
        print(f"| {label} | {ms:.2f} | {1e3 / ms:.0f} | {ms / ref_ms:.1f} |")


if __name__ == "__main__":
    main()
