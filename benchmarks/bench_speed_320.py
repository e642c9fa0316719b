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

With torch installed (``--torch``, on by default when it imports) it also times the
pipeline the issue compares against: a per-pixel network of gs_sdk's form (1 x 1
convolutions 5-32-32-32-2 with batch normalisation, on (B, G, R) / 255 and (x / W,
y / H)) run by torch on the whole frame, its tangents less the reference's, integrated
by a DCT Poisson solve (Neumann, scipy.fft): written here, none of gs_sdk's code. The
same network (random weights: the time does not depend on them) is then imported with
``PhotometricCalibration.from_gs_sdk`` and run by ``DepthReconstructor``, tabulated
(the default engine) and, for reference, exact through onnxruntime.
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


def torch_pipeline(ref: np.ndarray):
    """A torch per-pixel MLP (gs_sdk's form, eval mode) with a DCT Poisson solve, on one
    thread: ``(state_dict, frame -> height)``."""
    import torch
    from torch import nn

    torch.set_num_threads(1)
    torch.manual_seed(0)
    net = nn.Module()                       # gs_sdk's names: conv1, bn1, ..., conv4
    for k, (n_in, n_out) in enumerate(((5, 32), (32, 32), (32, 32), (32, 2)), start=1):
        setattr(net, f"conv{k}", nn.Conv2d(n_in, n_out, 1))
        if k < 4:
            setattr(net, f"bn{k}", nn.BatchNorm2d(n_out))
    net.eval()
    state = net.state_dict()

    def forward(x):
        for k in (1, 2, 3):
            x = torch.relu(getattr(net, f"bn{k}")(getattr(net, f"conv{k}")(x)))
        return net.conv4(x)

    h, w = ref.shape[:2]
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    xy = torch.from_numpy(np.stack([xx / w, yy / h]))[None]

    def slopes(frame: np.ndarray) -> np.ndarray:
        bgr = torch.from_numpy(np.ascontiguousarray(frame.transpose(2, 0, 1),
                                                    np.float32) / 255.0)[None]
        with torch.no_grad():
            return torch.tan(forward(torch.cat([bgr, xy], 1)))[0].numpy()

    bg = slopes(ref)
    ky = np.pi * np.arange(h)[:, None] / h
    kx = np.pi * np.arange(w)[None, :] / w
    denom = (2 * np.cos(kx) - 2) + (2 * np.cos(ky) - 2)
    denom[0, 0] = 1.0

    def height(frame: np.ndarray) -> np.ndarray:
        gx, gy = slopes(frame) - bg
        div = np.gradient(gx, axis=1) + np.gradient(gy, axis=0)
        f = scipy.fft.dctn(div, norm="ortho")
        f /= denom
        f[0, 0] = 0.0
        return scipy.fft.idctn(f, norm="ortho")

    return state, height


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
    try:
        import torch  # noqa: F401
    except ImportError:
        print("\n(torch not installed: the torch per-pixel MLP comparison is left out)")
        return
    state, torch_height = torch_pipeline(ref)
    net_cal = PhotometricCalibration.from_gs_sdk(state, ref, mm_per_px=0.0295 * scale)
    torch_ms = per_frame_ms(torch_height, test, 15)
    print("\nThe same network (gs_sdk's form, random weights), same frames, same run:\n")
    print("| pipeline | ms per frame | frames/s | torch pipeline / this |")
    print("|---|---|---|---|")
    print(f"| torch per-pixel MLP + DCT Poisson (reference) | {torch_ms:.2f} | "
          f"{1e3 / torch_ms:.0f} | 1.0 |")
    for label, recon in (
            ("DepthReconstructor, tabulated MLP (default engine)",
             DepthReconstructor(net_cal, reference=ref)),
            ("DepthReconstructor, tabulated MLP, level='far_field'",
             DepthReconstructor(net_cal, reference=ref, level="far_field")),
            ("DepthReconstructor, LUT (above)", DepthReconstructor(cal, reference=ref)),
            ("DepthReconstructor, MLP exact (onnxruntime)",
             DepthReconstructor(net_cal, reference=ref, engine="onnx"))):
        ms = per_frame_ms(recon, test, 15)
        print(f"| {label} | {ms:.2f} | {1e3 / ms:.0f} | {torch_ms / ms:.1f} |")


if __name__ == "__main__":
    main()
