"""Stored heights: bytes per frame and the error read back, the batch's codecs against
plain float32 with Zstandard.

    python benchmarks/bench_height_store.py [--frames 16]

Height maps of the sample session (sample_frames/gelsight_session, 640 x 480, its own
optics), evenly spaced over its frames, written as a batch writes them
(``tactilevision.batch``: rounded to HEIGHT_RESOLUTION_MM by ``quantize_heights``, then
Blosc Zstandard after a bit shuffle) and as plain float32 with Zstandard; printed: MB per
frame, the ratio, the largest error, and the time to round and write them.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
import zarr
from zarr.codecs import ZstdCodec

from tactilevision.batch import HEIGHT_RESOLUTION_MM, quantize_heights
from tactilevision.batch._store import _height_codecs
from tactilevision.io import open_source
from tactilevision.optics import DepthReconstructor, PhotometricCalibration

SESSION = Path(__file__).resolve().parents[1] / "sample_frames" / "gelsight_session"


def _stored(heights: np.ndarray, folder: Path, codecs: dict, quantize: bool = False
            ) -> tuple[float, np.ndarray, float]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        g = zarr.open_group(str(folder), mode="w")
        a = g.create_array("h", shape=heights.shape, chunks=(8, *heights.shape[1:]),
                           dtype="float32", fill_value=np.nan, **codecs)
        t0 = time.perf_counter()
        a[:] = quantize_heights(heights) if quantize else heights
        seconds = time.perf_counter() - t0
        back = a[:]
    size = sum(os.path.getsize(os.path.join(d, f)) for d, _, fs in os.walk(folder)
               for f in fs)
    return size / heights.shape[0] / 1e6, back, seconds / heights.shape[0]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=16)
    args = ap.parse_args()
    src = open_source(SESSION)
    rec = DepthReconstructor(PhotometricCalibration.load(SESSION / "optics.npz"),
                             reference=src.reference())
    idx = np.linspace(0, src.n_frames - 1, args.frames).astype(int)
    heights = np.stack([rec(src.frame(int(i))) for i in idx]).astype(np.float32)
    with tempfile.TemporaryDirectory() as tmp:
        plain, _, plain_s = _stored(heights, Path(tmp) / "plain.zarr",
                                    {"compressors": [ZstdCodec(level=3)]})
        ours, back, ours_s = _stored(heights, Path(tmp) / "ours.zarr", _height_codecs(),
                                     quantize=True)
    err = float(np.nanmax(np.abs(back - heights)))
    print(f"{args.frames} height maps {heights.shape[1]} x {heights.shape[2]} of {SESSION.name}")
    print(f"plain float32 + Zstandard: {plain:.3f} MB a frame")
    print(f"stored as batch stores them (resolution {HEIGHT_RESOLUTION_MM * 1e3:.3f} um): "
          f"{ours:.3f} MB a frame, {plain / ours:.1f} times smaller; largest error "
          f"{err * 1e3:.4f} um (bound {HEIGHT_RESOLUTION_MM * 5e2:.4f} um)")
    print(f"written in {ours_s * 1e3:.2f} ms a frame (rounding included), plain "
          f"{plain_s * 1e3:.2f} ms, this run")


if __name__ == "__main__":
    main()
