"""Per-frame time from height map to force map, on one core.

    python benchmarks/bench_forces.py

Prints set-up time and frames/s of ``ForceEstimator``: the spectral method at
427 x 320 (GelSlim 3.0 frames, 0.10577 mm/px, h 4 mm) and 640 x 480 (GelSight,
0.0295 mm/px, h 3 mm) in 'field' contact (one FFT pair per frame), single frames
and batches of 16; the 'footprint' contact (conjugate gradients) on one press;
the FEM method at 40 x 30 surface nodes (normal mode: one (1200 x 1200)
matrix-vector product); and frame -> height map -> force map with the shipped
GelSight calibration at 640 x 480; the memory each estimator holds and its
peak allocation per frame (tracemalloc). Issue 6's targets: spectral at 427 x 320
>= 200 frames/s, FEM 40 x 30 >= 1000 frames/s, frame to force >= 90 frames/s;
issue 21: the FEM's 'footprint' on a 2.5 mm punch against Hayes (1972), and its rate.
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

import resource  # noqa: E402
import time  # noqa: E402
import tracemalloc  # noqa: E402

import numpy as np  # noqa: E402


def rate(fn, n: int) -> float:
    fn()
    t0 = time.perf_counter()
    for _ in range(n):
        fn()
    return n / (time.perf_counter() - t0)


def held_mib(est) -> float:
    """MiB of arrays the estimator keeps (stiffness and compliance spectra, FEM matrices)."""
    total = 0
    for v in vars(est._op).values():
        if isinstance(v, np.ndarray):
            total += v.nbytes
        elif hasattr(v, "data") and hasattr(v, "indices"):        # scipy.sparse
            total += v.data.nbytes + v.indices.nbytes + v.indptr.nbytes
    return total / 2**20


def peak_mib(fn) -> float:
    """Peak MiB allocated (traced by tracemalloc, numpy included) during one call."""
    fn()
    tracemalloc.start()
    fn()
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return peak / 2**20


def press(shape, dx, radius_mm=2.0, depth_mm=0.3):
    yy, xx = np.indices(shape, dtype=np.float64)
    r = np.hypot(xx - shape[1] / 2, yy - shape[0] / 2) * dx
    return np.maximum(depth_mm - r**2 / (2 * radius_mm), 0.0)


def main() -> None:
    import cv2

    cv2.setNumThreads(1)
    from tactilevision.fem import ForceEstimator

    for name, (H, W), dx, h in (("GelSlim 3.0", (320, 427), 0.10577, 4.0),
                                ("GelSight", (480, 640), 0.0295, 3.0)):
        t0 = time.perf_counter()
        est = ForceEstimator((H, W), dx, thickness_mm=h, E_mpa=0.2, nu=0.48, contact="field")
        setup = time.perf_counter() - t0
        for dtype in (np.float32, np.float64):
            u = press((H, W), dx).astype(dtype)
            batch = np.repeat(u[None], 16, axis=0)
            f1 = rate(lambda est=est, u=u: est(u), 30)
            fb = 16 * rate(lambda est=est, b=batch: est(b), 3)
            print(f"spectral {name} {W} x {H} {np.dtype(dtype).name} (FFT grid "
                  f"{est._op.fshape[1]} x {est._op.fshape[0]}, pad 2 h): set-up "
                  f"{setup * 1e3:.0f} ms, {f1:.0f} frames/s single, {fb:.0f} frames/s in "
                  f"batches of 16; memory held {held_mib(est):.1f} MiB, peak per frame "
                  f"{peak_mib(lambda est=est, u=u: est(u)):.1f} MiB")
    H, W, dx = 320, 427, 0.10577
    est = ForceEstimator((H, W), dx, thickness_mm=4.0, E_mpa=0.2, nu=0.48, contact="footprint",
                         threshold_mm=0.005)
    u = press((H, W), dx)
    print(f"spectral GelSlim footprint (CG, non-negative): {rate(lambda: est(u), 2):.1f} "
          "frames/s")
    try:
        t0 = time.perf_counter()
        fem = ForceEstimator((H, W), dx, thickness_mm=4.0, E_mpa=0.2, nu=0.48, method="fem",
                             contact="field")
        setup = time.perf_counter() - t0
        st = fem._op.stiffness
        print(f"fem 40 x 30 nodes: set-up {setup:.2f} s ({'cache' if st.cached else 'built'}"
              f", build {st.build_s:.1f} s, stored {st.nbytes / 2**20:.1f} MiB): "
              f"{rate(lambda: fem(u), 200):.0f} frames/s single, "
              f"{16 * rate(lambda: fem(np.repeat(u[None], 16, 0)), 20):.0f} frames/s in "
              f"batches of 16; memory held {held_mib(fem):.1f} MiB, peak per frame "
              f"{peak_mib(lambda: fem(u)):.1f} MiB")
        # issue 21: a 2.5 mm flat punch 0.1 mm deep, 'footprint', the default grid, against
        # Hayes (1972); the spectral method and 'field' timed in the same run as references
        from tactilevision.mechanics import kappa

        H2, W2, dx2, a = 320, 427, 0.0806, 2.5
        yy, xx = np.indices((H2, W2), dtype=np.float64)
        punch = np.where(np.hypot(xx - (W2 - 1) / 2, yy - (H2 - 1) / 2) * dx2 <= a, 0.1, 0.0)
        kw = dict(thickness_mm=3.0, E_mpa=0.2, nu=0.48, threshold_mm=0.01)
        hayes = 2 * a * 0.2 * 0.1 * kappa(0.48, a / 3.0) / (1 - 0.48**2)
        fp = ForceEstimator((H2, W2), dx2, method="fem", contact="footprint", **kw)
        fd = ForceEstimator((H2, W2), dx2, method="fem", contact="field", **kw)
        sp = ForceEstimator((H2, W2), dx2, contact="footprint", **kw)
        print(f"fem 40 x 30 footprint, 2.5 mm punch at 427 x 320 (h 3, nu 0.48): "
              f"{fp(punch).total_n[2] / hayes:.3f} of Hayes (spectral "
              f"{sp(punch).total_n[2] / hayes:.3f}); {rate(lambda: fp(punch), 200):.0f} "
              f"frames/s ('field' {rate(lambda: fd(punch), 200):.0f} frames/s, same run)")
    except ImportError as exc:  # pragma: no cover
        print(f"fem: not available ({exc})")
    from tactilevision._assets import default_calibration_path
    from tactilevision.optics import DepthReconstructor, PhotometricCalibration
    from tactilevision.sim import taxim_shading

    cal = PhotometricCalibration.load(default_calibration_path("gelsight"))
    table, reference = taxim_shading("gelsight")
    frame = table.render(press(cal.shape, cal.mm_per_px).astype(np.float32), reference)
    recon = DepthReconstructor(cal, reference=reference)
    est = ForceEstimator(cal.shape, cal.mm_per_px, thickness_mm=3.0, E_mpa=0.2, nu=0.48,
                         contact="field")
    h_rate = rate(lambda: recon(frame), 10)
    both = rate(lambda: est(recon(frame)), 10)
    print(f"frame -> height map ({cal.shape[1]} x {cal.shape[0]}, shipped GelSight "
          f"calibration): {h_rate:.0f} frames/s; frame -> height -> force: {both:.0f} frames/s")
    print(f"process peak resident memory: "
          f"{resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MiB")


if __name__ == "__main__":
    main()
