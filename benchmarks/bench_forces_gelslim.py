"""Contact force maps from real GelSlim 3.0 frames with markers (set_2020_09).

    python benchmarks/bench_forces_gelslim.py [--presses N] [--figure docs/gelslim_forces.png]

(a) A LUT photometric calibration from the even-numbered ball presses of
``$TACTILEVISION_GELSLIM/set_2020_09`` (contact circles detected, marker dots
masked and filled in), the same recipe as ``benchmarks/bench_optics_real.py``.
(b) For each odd-numbered (held-out) press: the height map, the marker
tracks and their dense lateral field (:func:`tactilevision.optics.track_markers`,
:func:`~tactilevision.optics.lateral_displacement`), and the force map of
:class:`~tactilevision.fem.ForceEstimator` with ``mode='full'`` and
``contact='footprint'``, the footprint being the detected contact circle (the
outer edge of the colour change). Prints per press the total (Fx, Fy, Fz), the
largest pressure, the share of |Fz| on compressive nodes, the distance of the
pressure centroid from the circle centre, the share of Fz within 1.2 contact
radii, the Hertz force of a half-space with the same ball and contact radius
(a reference, not a truth: the layer is stiffer), and the same force map on a
generous footprint of 1.5 radii (the non-negativity sweep then decides the
contact): its Fz against the circle's, its share within 1.2 radii and its
centroid; also the mean marker motion d within the circle and the angle
between (Fx, Fy) and d. Then medians and ranges.
(c) Per-frame times on one core (OpenCV, BLAS and scipy.fft on one thread):
frame -> height map, height -> force map ('spectral', 'normal', 'field', float32
heights) and the two together at 427 x 320 (issue 6's target: >= 90 frames/s),
the marker tracking and lateral field, the 'full' footprint solve, and set-up;
frames/s by the wall clock and by the process's CPU time (what one core does
while other processes share the machine). ``--presses 0`` prints the times
only (10 s). About 2.5 minutes in all on this 2-core machine.

Assumptions (stated, not measured): gel thickness h = 3.0 mm (the GelSlim 3.0
session example of ``docs/formats.md``), E = 0.2 MPa and nu = 0.48 (the
fit example there and the README's GelSlim figures); the Ma et al. ICRA 2019
and Taylor et al. 2022 values could not be retrieved here. The scale is the
uncertain one of ``tests/_data.py``: 0.0806 mm/px, because the release's
other figure, 0.10577 mm/px, makes the 7.6 mm ball (35.9 px) smaller than the
contact circles (up to 47 px) and the calibration refuses it. Fz scales with
E; with h and the scale it changes non-linearly.

The frames are CC BY-NC 4.0 (Taylor, Dong, Rodriguez, MCube Lab): the figure
shows derived height and pressure maps only, never frame pixels, and carries
the credit line.
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402

cv2.setNumThreads(1)

from tactilevision.fem import ForceEstimator  # noqa: E402
from tactilevision.io import read_ball_presses  # noqa: E402
from tactilevision.optics import (  # noqa: E402
    DepthReconstructor,
    PhotometricCalibration,
    PoissonSolver,
    detect_contact_circles,
    lateral_displacement,
    marker_centres,
    marker_mask,
    track_markers,
)

SET = Path(os.environ.get("TACTILEVISION_GELSLIM", Path(__file__).resolve().parents[1].parent
                          / "shared" / "real" / "gelslim3")) / "set_2020_09"
CREDIT = "GelSlim 3.0 frames: Taylor, Dong, Rodriguez (MCube Lab), CC BY-NC 4.0"
BALL_MM = 3.8


def disc(shape: tuple[int, int], centre: np.ndarray, radius: float) -> np.ndarray:
    """(H, W) bool: pixels within `radius` px of `centre` (x, y)."""
    yy, xx = np.indices(shape)
    return np.hypot(xx - centre[0], yy - centre[1]) < radius


def press_metrics(fm, centre: np.ndarray, radius: float) -> dict:
    """Totals and shape figures of one force map against the detected circle."""
    fz = fm.forces_n[..., 2].astype(np.float64)
    yy, xx = np.indices(fz.shape)
    tot = float(fz.sum())
    r = np.hypot(xx - centre[0], yy - centre[1])
    cx, cy = (fz * xx).sum() / tot, (fz * yy).sum() / tot
    return dict(F=np.asarray(fm.total_n, float), pmax=float(fm.pressure_kpa.max()),
                positive=float(fz[fz > 0].sum() / np.abs(fz).sum()),
                centroid=float(np.hypot(cx - centre[0], cy - centre[1])),
                within=float(fz[r < 1.2 * radius].sum() / tot))


def hertz_n(contact_mm: float, ball_mm: float, E: float, nu: float) -> float:
    """Hertz force (N) of a rigid ball on an elastic half-space at contact radius a."""
    return 4.0 * E / (1.0 - nu * nu) * contact_mm**3 / (3.0 * ball_mm)


def rate(fn, items, repeat: int = 3) -> tuple[float, float]:
    """Calls per second of fn over items (after one warm-up call): by the wall
    clock, and by this process's CPU time (one thread: what one core does,
    less the time other processes take the core away on a loaded machine)."""
    fn(items[0])
    w0, c0 = time.perf_counter(), time.process_time()
    for _ in range(repeat):
        for it in items:
            fn(it)
    n = repeat * len(items)
    return n / (time.perf_counter() - w0), n / (time.process_time() - c0)


def figure(path: Path, rows: list[dict], mm: float, h_mm: float, E: float, nu: float) -> None:
    """Height map with marker arrows, and pressure with tangential-force arrows, per press."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle

    fig, axes = plt.subplots(len(rows), 2, figsize=(10.5, 3.6 * len(rows)), squeeze=False,
                             layout="constrained")
    for ax_h, ax_p, row in zip(axes[:, 0], axes[:, 1], rows, strict=True):
        h, fm, flow, (cx, cy), r = row["height"], row["fm"], row["flow"], row["c"], row["r"]
        H, W = h.shape
        ext = (-0.5 * mm, (W - 0.5) * mm, (H - 0.5) * mm, -0.5 * mm)
        im = ax_h.imshow(h, cmap="viridis", extent=ext)
        fig.colorbar(im, ax=ax_h, shrink=0.85, label="depth into the gel (mm)")
        v = flow.valid
        p, d = flow.positions_px[v] * mm, flow.displacement_px[v] * mm
        q = ax_h.quiver(p[:, 0], p[:, 1], d[:, 0], d[:, 1], color="w", angles="xy",
                        scale_units="xy", scale=0.2, width=0.003)
        ax_h.quiverkey(q, 0.45, 0.06, 0.1, "0.1 mm motion (drawn x5)", labelpos="E",
                       labelcolor="w", fontproperties={"size": 8})
        ax_h.add_patch(Circle((cx * mm, cy * mm), r * mm, fill=False, ec="w", ls="--", lw=0.8))
        ax_h.set_title(f"{row['name']}: height map and marker motion", fontsize=9)
        ax_h.set_xlabel("x (mm)")
        ax_h.set_ylabel("y (mm)")
        # pressure, zoomed on the contact
        half = 2.0 * r
        c0, c1 = int(max(cx - half, 0)), int(min(cx + half, W))
        r0, r1 = int(max(cy - half, 0)), int(min(cy + half, H))
        pk = fm.pressure_kpa[r0:r1, c0:c1]
        zext = ((c0 - 0.5) * mm, (c1 - 0.5) * mm, (r1 - 0.5) * mm, (r0 - 0.5) * mm)
        im = ax_p.imshow(pk, cmap="magma", vmin=0, extent=zext)
        fig.colorbar(im, ax=ax_p, shrink=0.85, label="pressure (kPa)")
        step = 10
        ft = fm.forces_n[r0:r1, c0:c1, :2]
        R, C = (ft.shape[0] // step) * step, (ft.shape[1] // step) * step
        blk = ft[:R, :C].reshape(R // step, step, C // step, step, 2).sum(axis=(1, 3))
        bx = (c0 + np.arange(C // step) * step + (step - 1) / 2) * mm
        by = (r0 + np.arange(R // step) * step + (step - 1) / 2) * mm
        mag = np.hypot(blk[..., 0], blk[..., 1])
        if mag.max() > 0:
            bx, by = np.meshgrid(bx, by)
            show = mag > 0.05 * mag.max()
            qf = ax_p.quiver(bx[show], by[show], blk[..., 0][show], blk[..., 1][show], color="c",
                             angles="xy", scale_units="xy", scale=mag.max() / (1.2 * step * mm),
                             width=0.007, headwidth=4, headlength=5)
            ax_p.quiverkey(qf, 0.55, 0.06, float(mag.max()), f"{mag.max() * 1e3:.0f} mN",
                           labelpos="E", labelcolor="w", fontproperties={"size": 8})
        ax_p.add_patch(Circle((cx * mm, cy * mm), r * mm, fill=False, ec="w", ls="--", lw=0.8))
        F = fm.total_n
        ax_p.set_title(f"pressure, tangential force; Fz {F[2]:.2f} N, Fx {F[0]:.2f} N, "
                       f"Fy {F[1]:.2f} N", fontsize=9)
        ax_p.set_xlabel("x (mm)")
    fig.suptitle("GelSlim 3.0 ball presses (set_2020_09, held out): height map (photometric "
                 "stereo, LUT) and marker motion;\nforce map of the layer model with the "
                 "marker field, footprint = detected circle (dashed)", fontsize=9)
    fig.supxlabel(f"{CREDIT}; derived maps only, no frame pixels. Assumed h {h_mm:g} mm, "
                  f"E {E:g} MPa, nu {nu:g}, {mm:g} mm/px.", fontsize=7, color="0.35")
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=90)
    plt.close(fig)


def measure(set_dir: Path = SET, *, presses: int | None = None, mm: float = 0.0806,
            thickness_mm: float = 3.0, E_mpa: float = 0.2, nu: float = 0.48,
            log=print) -> dict:
    """Calibrate on the even presses of `set_dir`, map the held-out ones, time the steps.

    Prints through `log` what the command prints. Returns ``{"n_presses", "shape",
    "markers", "rows": [{"name", "height", "fm", "flow", "c", "r", "m"}] (one a held-out
    press; ``m`` its figures, :func:`press_metrics` and more), "summary"``:
    :func:`summaries`' figures (None without presses), ``"speed"``: :func:`speed`'s}``.
    """
    kw = dict(thickness_mm=thickness_mm, E_mpa=E_mpa, nu=nu, threshold_mm=0.01)
    ps = read_ball_presses(set_dir)
    t0 = time.perf_counter()
    cc, rr = detect_contact_circles(ps.frames, ps.reference)
    t_detect = time.perf_counter() - t0
    t0 = time.perf_counter()
    cal = PhotometricCalibration.from_ball_presses(ps.reference, ps.frames[0::2],
                                                   ball_radius_mm=BALL_MM, mm_per_px=mm,
                                                   model="lut", source=str(set_dir))
    t_cal = time.perf_counter() - t0
    t0 = time.perf_counter()
    recon = DepthReconstructor(cal)
    t_recon = time.perf_counter() - t0
    shape = cal.shape
    t0 = time.perf_counter()
    est_full = ForceEstimator(shape, mm, mode="full", contact="footprint", **kw)
    t_full = time.perf_counter() - t0
    t0 = time.perf_counter()
    est_fast = ForceEstimator(shape, mm, contact="field", **kw)  # 'spectral', 'normal'
    t_fast = time.perf_counter() - t0
    t0 = time.perf_counter()
    markers = marker_centres(ps.reference)
    t_markers = time.perf_counter() - t0
    log(f"{set_dir.name}: {len(ps.frames)} presses, {shape[1]} x {shape[0]} px; calibration "
        f"(LUT, even presses, markers {cal.markers}) {t_cal:.1f} s; circles detected in "
        f"{t_detect:.1f} s; {len(markers)} markers in ref.jpg ({t_markers * 1e3:.0f} ms)")
    log(f"assumed: h {thickness_mm} mm, E {E_mpa} MPa, nu {nu}, {mm} mm/px, "
        f"ball radius {BALL_MM} mm\n")
    idx = np.arange(1, len(ps.frames), 2)[:presses]
    hdr = (f"{'press':>13s} {'r px':>5s} {'Fx N':>7s} {'Fy N':>7s} {'Fz N':>6s} {'pmax kPa':>8s} "
           f"{'pos':>5s} {'cen px':>6s} {'in1.2r':>6s} {'Hertz N':>7s} {'tracks':>6s} {'d px':>5s} "
           f"{'Ft^d':>5s} "
           f"{'| 1.5r: Fz/Fz':>13s} {'in1.2r':>6s} {'cen px':>6s} {'r_eq/r':>6s}")
    log(hdr)
    rows, t_solve = [], []
    for i in idx:
        f = ps.frames[i]
        h = recon(f)
        flow = track_markers(ps.reference, f, positions_px=markers)
        lat = lateral_displacement(flow, shape, mm)
        t0 = time.perf_counter()
        fm = est_full(h, lat, contact_mask=disc(shape, cc[i], rr[i]))
        t_solve.append(time.perf_counter() - t0)
        wide = est_full(h, lat, contact_mask=disc(shape, cc[i], 1.5 * rr[i]))
        m, mw = press_metrics(fm, cc[i], rr[i]), press_metrics(wide, cc[i], rr[i])
        inside = flow.valid & (np.hypot(*(flow.positions_px - cc[i]).T) < rr[i])
        d = flow.displacement_px[inside].mean(axis=0)
        ft = m["F"][:2]
        cos = float(ft @ d / (np.linalg.norm(ft) * np.linalg.norm(d)))
        m.update(wide_ratio=mw["F"][2] / m["F"][2], wide_within=mw["within"],
                 angle=float(np.degrees(np.arccos(np.clip(cos, -1, 1)))),
                 marker_px=float(np.linalg.norm(d)),
                 wide_centroid=mw["centroid"],
                 wide_r=float(np.sqrt(wide.contact.sum() / np.pi) / rr[i]),
                 hertz=hertz_n(0.85 * rr[i] * mm, BALL_MM, E_mpa, nu),
                 tracks=float(flow.valid.mean()))
        rows.append(dict(name=ps.names[i], height=h, fm=fm, flow=flow, c=cc[i], r=rr[i], m=m))
        F = m["F"]
        log(f"{ps.names[i]:>13s} {rr[i]:5.1f} {F[0]:7.3f} {F[1]:7.3f} {F[2]:6.2f} "
            f"{m['pmax']:8.0f} {m['positive']:5.3f} {m['centroid']:6.1f} {m['within']:6.3f} "
            f"{m['hertz']:7.2f} {m['tracks']:6.3f} {m['marker_px']:5.1f} {m['angle']:5.0f} "
            f"{m['wide_ratio']:13.2f} "
            f"{m['wide_within']:6.3f} {m['wide_centroid']:6.1f} {m['wide_r']:6.2f}")

    ms = [r["m"] for r in rows]
    summary = summaries(ms, log) if rows else None
    rates = speed(ps, recon, est_fast, shape, markers, t_solve,
                  dict(recon=t_recon, fast=t_fast, full=t_full, cal=t_cal), log)
    return {"n_presses": len(ps.frames), "shape": shape, "markers": len(markers),
            "rows": rows, "summary": summary, "speed": rates}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--presses", type=int, default=None, help="only the first N held-out presses")
    ap.add_argument("--figure", type=Path, default=None, help="write the figure (PNG) here")
    ap.add_argument("--mm-per-px", type=float, default=0.0806)
    ap.add_argument("--thickness-mm", type=float, default=3.0)
    ap.add_argument("--E-mpa", type=float, default=0.2)
    ap.add_argument("--nu", type=float, default=0.48)
    args = ap.parse_args(argv)
    if not SET.is_dir():
        print(f"GelSlim 3.0 frames not found at {SET}", file=sys.stderr)
        return 1
    mm = args.mm_per_px
    got = measure(SET, presses=args.presses, mm=mm, thickness_mm=args.thickness_mm,
                  E_mpa=args.E_mpa, nu=args.nu)
    rows = got["rows"]
    if args.figure and len(rows) >= 3:
        ms = [r["m"] for r in rows]
        pick = np.argsort([m["F"][2] for m in ms])
        sel = [rows[k] for k in pick[[0, len(pick) // 2, -1]]]
        figure(args.figure, sel, mm, args.thickness_mm, args.E_mpa, args.nu)
        print(f"\nfigure: {args.figure} ({', '.join(r['name'] for r in sel)})")
    return 0


#: The figures :func:`summaries` gives over the presses: (key, label, the value of a
#: press's figures ``m``, format), for the detected circle and for the 1.5 r footprint.
CIRCLE = [
    ("fz", "Fz (N)", lambda m: m["F"][2], ".2f"),
    ("tangential", "|(Fx, Fy)| / Fz", lambda m: np.hypot(*m["F"][:2]) / m["F"][2], ".2f"),
    ("marker", "mean marker motion in the circle, d (px)", lambda m: m["marker_px"], ".1f"),
    ("angle", "angle between (Fx, Fy) and d (deg)", lambda m: m["angle"], ".0f"),
    ("hertz", "Fz / Hertz half-space", lambda m: m["F"][2] / m["hertz"], ".2f"),
    ("pmax", "max pressure (kPa)", lambda m: m["pmax"], ".0f"),
    ("positive", "share of |Fz| compressive (1 by construction: tensile nodes leave the "
     "footprint)", lambda m: m["positive"], ".3f"),
    ("centroid", "pressure centroid to circle centre (px)", lambda m: m["centroid"], ".1f"),
    ("within", "share of Fz within 1.2 r (1 by construction)", lambda m: m["within"], ".3f"),
    ("tracks", "valid marker tracks", lambda m: m["tracks"], ".3f"),
]
WIDE = [
    ("wide_ratio", "Fz / Fz(circle)", lambda m: m["wide_ratio"], ".2f"),
    ("wide_within", "share of Fz within 1.2 r", lambda m: m["wide_within"], ".3f"),
    ("wide_centroid", "pressure centroid to circle centre (px)", lambda m: m["wide_centroid"],
     ".1f"),
    ("wide_r", "equivalent radius of the final contact / r", lambda m: m["wide_r"], ".2f"),
]


def summ(name: str, vals, fmt: str = ".2f", log=print) -> tuple[float, float, float]:
    """Print the median and range of `vals`; return them."""
    v = np.asarray(vals, float)
    log(f"  {name}: median {np.median(v):{fmt}}, range {v.min():{fmt}} to {v.max():{fmt}}")
    return float(np.median(v)), float(v.min()), float(v.max())


def summaries(ms: list[dict], log=print) -> dict[str, tuple[float, float, float]]:
    """Medians and ranges over the presses, printed: ``{key: (median, least, most)}`` for
    the keys of :data:`CIRCLE` and :data:`WIDE`."""
    out = {}
    log(f"\n{len(ms)} held-out presses, footprint = detected circle:")
    for key, name, value, fmt in CIRCLE:
        out[key] = summ(name, [value(m) for m in ms], fmt, log)
    log("footprint = 1.5 r (the non-negativity sweep decides the contact):")
    for key, name, value, fmt in WIDE:
        out[key] = summ(name, [value(m) for m in ms], fmt, log)
    return out


def speed(ps, recon, est_fast, shape, markers, t_solve, setup: dict, log=print) -> dict:
    """Per-frame times on one core (and set-up times), printed: ``{"height", "force",
    "both", "tracking"}``: (frames/s by the wall clock, by CPU time); ``"parts_ms"``:
    {part: ms of CPU time}; ``"lateral_ms"``, ``"solve_s"`` (median, least, most, or
    None), ``"setup"`` (as given), ``"load"`` (the load average), ``"cores"``."""
    frames = ps.frames[1::2][:8]
    heights = [recon(f) for f in frames]
    assert heights[0].dtype == np.float32
    f_h = rate(recon, frames, 15)
    f_f = rate(est_fast, heights, 15)
    f_hf = rate(lambda f: est_fast(recon(f)), frames, 15)
    f_tr = rate(lambda f: track_markers(ps.reference, f, positions_px=markers), frames, 2)
    flow = track_markers(ps.reference, frames[0], positions_px=markers)
    f_lat = rate(lambda fl: lateral_displacement(fl, shape, recon.calibration.mm_per_px),
                 [flow], 5)
    load = os.getloadavg()[0]
    log(f"\nspeed on one core, {shape[1]} x {shape[0]}, frames/s by the wall clock (by CPU "
        f"time; load average {load:.1f} on {os.cpu_count()} cores):")
    log(f"  frame -> height map (LUT, markers filled): {f_h[0]:.0f} ({f_h[1]:.0f})")
    log(f"  height map -> force map (spectral, 'normal', 'field', float32): {f_f[0]:.0f} "
        f"({f_f[1]:.0f})")
    log(f"  frame -> height map -> force map: {f_hf[0]:.0f} ({f_hf[1]:.0f}); issue 6 target "
        ">= 90")
    f0, h0 = frames[0], heights[0]
    gx, gy = recon.gradients(f0)
    solver = PoissonSolver(shape)
    parts = [("marker mask", lambda f: marker_mask(f)),
             ("colour -> gradients (lookup, marker mask and fill)", recon.gradients),
             ("Poisson integration", lambda f: solver(gx, gy)),
             ("spectral force map", lambda f: est_fast(h0))]
    parts_ms = {name: 1e3 / rate(fn, [f0], 50)[1] for name, fn in parts}
    log("  per frame, ms of CPU time: " + "; ".join(
        f"{name} {ms:.1f}" for name, ms in parts_ms.items()))
    log(f"  marker tracking: {f_tr[0]:.0f} ({f_tr[1]:.0f}) frames/s; lateral field "
        f"(thin-plate spline, step 4 px): {1e3 / f_lat[1]:.0f} ms of CPU time")
    solve = None
    if t_solve:
        solve = (float(np.median(t_solve)), min(t_solve), max(t_solve))
        log(f"  'full' footprint solve (conjugate gradients), per press: median "
            f"{solve[0]:.1f} s, {solve[1]:.1f} to {solve[2]:.1f} s")
    log(f"  set-up: DepthReconstructor {1e3 * setup['recon']:.0f} ms, ForceEstimator "
        f"'normal' {1e3 * setup['fast']:.0f} ms, 'full' {1e3 * setup['full']:.0f} ms; "
        f"calibration {setup['cal']:.1f} s")
    return {"height": f_h, "force": f_f, "both": f_hf, "tracking": f_tr,
            "parts_ms": parts_ms, "lateral_ms": 1e3 / f_lat[1], "solve_s": solve,
            "setup": setup, "load": load, "cores": os.cpu_count()}


if __name__ == "__main__":
    sys.exit(main())
