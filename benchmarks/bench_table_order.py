"""A network's table of order 0 against one of first order: accuracy against gs_sdk and cost.

    python benchmarks/bench_table_order.py [--mini FOLDER]

On the shared GelSight Mini (gs_sdk's own network, trained by its owners, and gs_sdk's own
gradients on six of the presses it was calibrated on, computed by gs_sdk itself:
``gs_sdk_reference.npz``), imported with ``PhotometricCalibration.from_gs_sdk``:

- per press, the median angle (degrees) between gs_sdk's surface normal and the
  default engine's, inside the contact (slope above 5 degrees), for tables of order 0
  (32 and 64 colour cells a channel) and of first order (16, 24 and 32 cells; the
  default read by both kernels, ``DepthReconstructor(kernel=...)``: numba's compiled
  pass where the ``fast`` extra is installed, and OpenCV and numpy), and for the exact
  engine (onnxruntime per pixel); beside them the largest angle at any contact pixel
  of the six presses;
- the per-frame cost of ``DepthReconstructor(cal)(frame)`` (one thread: OpenCV,
  onnxruntime, scipy.fft) for each, beside two same-run references at 320 x 240: a bare
  scipy DCT-II pair and a bare gather of two components per pixel (as
  ``bench_speed.py``), and their ratio;
- the table's size and the time to build it (the network evaluated over the cells,
  all cores; into an empty cache folder of this run, so nothing is read back).

The folder defaults to ``../shared/real/gelsight_mini`` beside the repository (or
``$TACTILEVISION_GELSIGHT_MINI``). Needs torch (to read gs_sdk's state dict).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import cv2
import numpy as np
import scipy.fft
from bench_speed import per_frame_ms  # the same timing as the 640 x 480 benchmark

from tactilevision.optics import DepthReconstructor, PhotometricCalibration, first_order_kernel

cv2.setNumThreads(1)
ROOT = Path(__file__).resolve().parents[1]
MM_PER_PX = 0.0634          # the shared GelSight Mini's scale (tests/_data.py)


def angle_deg(G: np.ndarray, gx: np.ndarray, gy: np.ndarray) -> np.ndarray:
    """Angle between gs_sdk's normal (its slope G of the height towards the camera: our
    depth slope is -G) and ours, degrees."""
    a = np.dstack([-G, np.ones(G.shape[:2])])
    b = np.dstack([gx, gy, np.ones(G.shape[:2])])
    cos = (a * b).sum(-1) / np.linalg.norm(a, axis=-1) / np.linalg.norm(b, axis=-1)
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def references_ms(shape: tuple[int, int], frames: list[np.ndarray]) -> tuple[float, float]:
    """A bare DCT-II pair and a bare gather of two components per pixel, same size."""
    field = np.random.default_rng(0).standard_normal(shape).astype(np.float32)
    dct = per_frame_ms(lambda f: scipy.fft.idctn(scipy.fft.dctn(field, type=2, workers=1),
                                                  type=2, workers=1), frames, 40)
    flat = np.random.default_rng(1).standard_normal(32 ** 3 * 2).astype(np.float32)
    idx = np.random.default_rng(2).integers(0, 32 ** 3, shape[0] * shape[1])
    gather = per_frame_ms(lambda f: (flat[2 * idx], flat[2 * idx + 1]), frames, 40)
    return dct, gather


#: The engines compared: (name, ``DepthReconstructor`` options).
ENGINES = [("table, order 0, 32 cells", dict(table_order=0, table_bins=32)),
           ("table, order 0, 64 cells", dict(table_order=0, table_bins=64)),
           ("table, order 1, 16 cells (default)", dict(table_order=1, table_bins=16)),
           ("the same, kernel 'numpy'", dict(table_order=1, table_bins=16, kernel="numpy")),
           ("table, order 1, 24 cells", dict(table_order=1, table_bins=24)),
           ("table, order 1, 32 cells", dict(table_order=1, table_bins=32)),
           ("exact (onnx)", dict(engine="onnx"))]


def measure(mini: Path, rounds: int = 2) -> dict | None:
    """The angles and costs above on the gs_sdk folder `mini` (None where it has no
    ``gs_sdk_reference.npz``): ``presses``, ``shape``, ``kernel`` ('numba' or 'OpenCV and
    numpy'), ``angles`` [{name, medians (per press), worst (the largest median), largest
    (the largest angle at any contact pixel), mb, build_s}] and ``costs`` (per round: the
    references ``dct`` and ``gather`` and ``ms`` {engine: ms per frame}, the exact engine
    left out)."""
    npz = mini / "gs_sdk_reference.npz"
    if not npz.is_file():
        return None
    ref = np.load(npz)
    background = cv2.imread(str(mini / "background.png"))
    cal = PhotometricCalibration.from_gs_sdk(mini / "model" / "nnmodel.pth", background,
                                             mm_per_px=MM_PER_PX)
    frames = [cv2.imread(str(mini / str(name) / "gelsight.png")) for name in ref["presses"]]
    slopes = [ref["gradients"][k].astype(np.float64) for k in range(len(frames))]
    contact = [np.hypot(G[..., 0], G[..., 1]) > np.tan(np.radians(5.0)) for G in slopes]
    out: dict = {"presses": [str(n) for n in ref["presses"]], "shape": cal.shape,
                 "angles": [], "costs": []}
    built = {}
    for name, kw in ENGINES:
        t0 = time.perf_counter()
        recon = DepthReconstructor(cal, **kw)
        build_s = time.perf_counter() - t0
        built[name] = recon
        got = [angle_deg(G, *recon.gradients(f))[c]
               for f, G, c in zip(frames, slopes, contact, strict=True)]
        meds = [float(np.median(a)) for a in got]
        table = recon._table
        mb = 0.0 if table is None else (table.gx_table.nbytes + table.gy_table.nbytes
                                        + (0 if table.slopes is None else table.slopes.nbytes)
                                        ) / 1e6
        out["angles"].append({"name": name, "medians": meds, "worst": max(meds),
                              "largest": float(max(a.max() for a in got)), "mb": mb,
                              "build_s": build_s})
    out["kernel"] = "numba" if first_order_kernel("auto") is not None else "OpenCV and numpy"
    for _ in range(rounds):
        dct, gather = references_ms(cal.shape, frames)
        out["costs"].append({"dct": dct, "gather": gather, "ms": {
            name: per_frame_ms(recon, frames, 60) for name, recon in built.items()
            if not name.startswith("exact")}})
    return out


def main() -> int:
    default = Path(os.environ.get("TACTILEVISION_GELSIGHT_MINI",
                                  ROOT.parent / "shared" / "real" / "gelsight_mini"))
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mini", type=Path, default=default, help="gs_sdk calibration folder")
    args = parser.parse_args()
    os.environ["TACTILEVISION_CACHE"] = tempfile.mkdtemp(prefix="bench_table_order_")
    m = measure(args.mini)
    if m is None:
        print(f"no {args.mini / 'gs_sdk_reference.npz'}: nothing to measure")
        return 1
    print(f"gs_sdk's GelSight Mini network, {len(m['presses'])} presses at {m['shape'][1]} x "
          f"{m['shape'][0]}; median angle to gs_sdk inside each contact (deg)\n")
    print("| engine | " + " | ".join(m["presses"]) + " | worst | largest | table MB | built (s) |")
    print("|---|" + "---|" * (len(m["presses"]) + 4))
    for a in m["angles"]:
        print(f"| {a['name']} | " + " | ".join(f"{x:.2f}" for x in a["medians"])
              + f" | {a['worst']:.2f} | {a['largest']:.2f} | {a['mb']:.0f} | "
                f"{a['build_s']:.1f} |")
    print(f"\nfirst-order tables read by {m['kernel']} (kernel 'auto'), and by OpenCV and "
          "numpy (kernel 'numpy')")
    print("\nper-frame cost, one thread, same run (ms):")
    for c in m["costs"]:
        ref = c["dct"] + c["gather"]
        print("; ".join([f"DCT-II pair {c['dct']:.3f}, gather {c['gather']:.3f}"]
                        + [f"{name}: {ms:.3f} ({ms / ref:.2f} x pair + gather)"
                           for name, ms in c["ms"].items()]))
    return 0

if __name__ == "__main__":
    sys.exit(main())
