"""Frames -> height maps -> total force against the F/T log, per press, on the sample session.

    python benchmarks/bench_forces_session.py [--fit FIT.json] [--presses N]
        [--frames-per-press K] [--naive] [--optics lut|lut-colour|mlp|CAL.npz]
        [--ball-presses N] [--save-optics CAL.npz] [--true-surface]

Issue 6's end-to-end check. For every press of ``sample_frames/gelsight_session``
the frames of its hold (times from ``truth.json``, used only to group frames)
go through

1. photometric stereo calibrated for the session's sensor: the session's frames
   are rendered through Taxim's shading table, so its optics are calibrated as
   a rig's are, on ball presses of that sensor (256 presses of a 2 mm ball up
   to 1.4 mm deep rendered through the same table,
   :func:`tactilevision.sim.render_ball_presses` with ``partial=True``, and a
   LUT per cell of an 8 x 6 grid, ``lut_cells=(8, 6)``), with the height
   pinned to zero outside the contact (``DepthReconstructor(boundary='contact')``);
2. ``ForceEstimator`` (spectral, normal displacement, 'footprint' contact:
   height above 0.02 mm, non-negative pressure) with E, nu and beta of the
   session's calibration (``out/calibration/fit.json``, written by the
   README's first command; the true values when it is missing);

and the mean total Fz over the hold is compared with the F/T log's mean at
the same frames (the fit's clock offset). Prints one row per press, then the
median and range of the ratio by indenter depth. ``--naive`` adds the earlier
pipeline's totals (the shipped GelSight calibration, whole-image
integration, beta = 0) for comparison. ``--true-surface`` adds the force of
the press's true gel surface (the session's own Neo-Hookean FEM profile,
``truth.json``'s positions and depths) through the same estimator: what
the force model alone gives, so that the optics' share of the error shows.
``--optics`` picks the photometric model (a position-aware network needs
torch; ``--save-optics`` keeps it for the next run).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from tactilevision.fem import ForceEstimator
from tactilevision.io import read_session
from tactilevision.optics import DepthReconstructor, PhotometricCalibration
from tactilevision.pipeline import session_reconstructor
from tactilevision.sim import render_ball_presses, taxim_shading

ROOT = Path(__file__).resolve().parents[1]
SESSION = ROOT / "sample_frames" / "gelsight_session"


def session_optics(session, optics: str = "lut", presses: int = 256) -> PhotometricCalibration:
    """Calibration from ball presses rendered through the session's shading table.

    ``optics``: 'lut' (one colour table per cell of an 8 x 6 grid over the
    image, presses of a 2 mm ball up to 1.4 mm deep whose contacts may run
    off the image's edges: slopes to 3, as the punch walls have, at every
    position), 'lut-colour' (one colour-only table, a 4 mm ball up to 2 mm
    deep, contacts inside the image: the first version), 'mlp' (a
    position-aware network on the 'lut-colour' presses, needs torch) or the
    path of a saved calibration (``.npz``).
    """
    if optics not in ("lut", "lut-colour", "mlp"):
        return PhotometricCalibration.load(optics)
    table, _ = taxim_shading()
    cells = optics == "lut"
    radius, deepest = (2.0, 1.4) if cells else (4.0, 2.0)
    balls = render_ball_presses(table, session.reference, n=presses if cells else 24,
                                radius_mm=radius, depth_mm=(0.2, deepest), partial=cells, seed=5)
    return PhotometricCalibration.from_ball_presses(
        balls.reference, balls.frames, balls.centers_px, balls.radii_px, ball_radius_mm=radius,
        mm_per_px=session.config.mm_per_px, model="mlp" if optics == "mlp" else "lut",
        lut_cells=(8, 6) if cells else (1, 1), use_position=optics == "mlp")


def _quiet(*args, **kwargs) -> None:
    """A `log` that prints nothing."""


def measure(fit: Path, *, presses: int | None = None, frames_per_press: int | None = None,
            naive: bool = False, optics: str = "lut", ball_presses: int = 256,
            save_optics: Path | None = None, true_surface: bool = False,
            log=_quiet) -> dict:
    """Run the check (the command line's options as arguments) and return its figures.

    Prints through `log` (``print`` for the command line) what the command prints.
    Returns ``{"E", "nu", "beta", "offset", "source", "setup_s", "frames", "ms_per_frame",
    "presses": [{"press", "w0", "x_mm", "y_mm", "frames", "ft_n", "fz_n", "ratio", "face_mm",
    "naive", "true_surface"}], "by_depth": :func:`by_depth`'s rows, "trend"}`` (the
    ratios: the frames' mean total over the F/T log's mean at the same frames; ``naive``
    and ``true_surface`` NaN unless asked for; ``trend`` the linear trend of the presses
    >= 0.3 mm deep over the pad and depth, or None).
    """
    s = read_session(SESSION)
    truth = json.loads((SESSION / "truth.json").read_text())
    if fit is not None and fit.is_file():
        fitted = json.loads(fit.read_text())
        E, nu, beta, off = (fitted["E_mpa"], fitted["nu"], fitted["beta"],
                            fitted["clock_offset_s"])
        src = str(fit)
    else:
        E, nu, beta, off = truth["E_mpa"], truth["nu"], 0.82, truth["clock_offset_s"]
        src = "truth.json (no fit.json: run the README's first command)"
    h, mm = truth["thickness_mm"], s.config.mm_per_px
    log(f"E {E:.4f} MPa, nu {nu:.4f}, beta {beta:.3f}, clock offset {off:.4f} s from {src}")
    t0 = time.perf_counter()
    cal = session_optics(s, optics, ball_presses)
    if save_optics:
        cal.save(save_optics)
    rec = DepthReconstructor(cal, reference=s.reference, boundary="contact")
    est = ForceEstimator(s.shape, mm, thickness_mm=h, E_mpa=E, nu=nu, contact="footprint",
                         threshold_mm=0.02, beta=beta)
    earlier = None
    if naive:
        earlier = (session_reconstructor(s),
                   ForceEstimator(s.shape, mm, thickness_mm=h, E_mpa=E, nu=nu,
                                  contact="footprint", threshold_mm=0.02))
    surface = None
    if true_surface:
        from tactilevision.sim import SessionSpec, press_profile
        from tactilevision.sim._block import press_surface

        block = SessionSpec().block
        prof = press_profile(block.radius_mm / h, truth["nu"], w_over_h_max=0.22)

        def surface(p):
            c = (p["x_mm"] / mm + (s.shape[1] - 1) / 2, p["y_mm"] / mm + (s.shape[0] - 1) / 2)
            return press_surface(prof, block, indenter=p["indenter"],
                                 depth_mm=p["depth_mm"], centre_px=c, shape=s.shape,
                                 mm_per_px=mm, thickness_mm=h)[0]
    setup = time.perf_counter() - t0
    log(f"set-up (ball presses, optics, estimator): {setup:.1f} s")
    ft_t = s.force_times_s - off
    head = (f"{'press':>5s} {'w0 mm':>6s} {'frames':>6s} {'F/T N':>7s} {'frames N':>8s} "
            f"{'ratio':>6s} {'face mm':>7s}")
    log(head + (f" {'naive N':>8s}" if earlier else "")
        + (f" {'true surface N':>14s}" if surface else ""))
    rows = []
    t_frames = 0.0
    n_frames = 0
    for p in truth["presses"][:presses]:
        if p["edge"] or p["misaligned"]:
            continue
        hold = np.nonzero((s.frame_times_s >= p["hold_from_s"] + 0.05)
                          & (s.frame_times_s <= p["hold_from_s"] + 0.45))[0]
        if hold.size == 0:
            continue
        if frames_per_press:
            k = min(frames_per_press, hold.size)
            hold = hold[(hold.size - k) // 2:][:k]
        ft, fz, face, nv = [], [], [], []
        for i in hold:
            ft.append(float(np.interp(s.frame_times_s[i], ft_t, s.forces_n[:, 2])))
            t1 = time.perf_counter()
            hm = rec(s.frame(i))
            fm = est(hm)
            t_frames += time.perf_counter() - t1
            n_frames += 1
            fz.append(float(fm.total_n[2]))
            face.append(float(np.percentile(hm[fm.contact], 99)) if fm.contact.any() else 0.0)
            if earlier:
                nv.append(float(earlier[1](earlier[0](s.frame(i))).total_n[2]))
        r = np.mean(fz) / np.mean(ft)
        ts = float(est(surface(p)).total_n[2]) if surface else np.nan
        rows.append({"press": p["press"], "w0": p["w0_mm"], "x_mm": p["x_mm"],
                     "y_mm": p["y_mm"], "frames": int(hold.size), "ft_n": float(np.mean(ft)),
                     "fz_n": float(np.mean(fz)), "ratio": float(r),
                     "face_mm": float(np.mean(face)),
                     "naive": float(np.mean(nv) / np.mean(ft)) if earlier else np.nan,
                     "true_surface": ts / float(np.mean(ft))})
        log(f"{p['press']:5d} {p['w0_mm']:6.2f} {hold.size:6d} {np.mean(ft):7.3f} "
            f"{np.mean(fz):8.3f} {r:6.3f} {np.mean(face):7.3f}"
            + (f" {np.mean(nv):8.3f}" if earlier else "")
            + (f" {ts:14.3f}" if surface else ""), flush=True)
    ms = 1e3 * t_frames / max(n_frames, 1)
    log(f"\n{n_frames} frames, {ms:.0f} ms per frame (masked Poisson + footprint solve)")
    log(f"{'w0 mm':>6s} {'presses':>7s} {'median ratio':>12s} {'range':>15s} "
        f"{'within 5 %':>10s}" + (f" {'naive median':>12s}" if earlier else "")
        + (f" {'true surface: median, range':>30s}" if surface else ""))
    depths = by_depth(rows)
    for d in depths:
        line = (f"{d['w0']:6.2f} {d['n']:7d} {d['median']:12.3f} {d['lo']:7.3f} to "
                f"{d['hi']:5.3f} {d['within5']:10.0%}")
        if earlier:
            line += f" {d['naive']:12.3f}"
        if surface:
            q = d["true_surface"]
            line += f" {q[0]:14.3f}, {q[1]:.3f} to {q[2]:.3f}"
        log(line)
    trend = None
    deep = np.array([(r["w0"], r["ratio"], r["x_mm"], r["y_mm"]) for r in rows
                     if r["w0"] >= 0.3]).reshape(-1, 4)
    if len(deep) > 4:
        # where the per-press error comes from: a linear trend over the pad and depth
        # (a colour-only table leaves one along the pad; steep walls one along depth)
        X = np.column_stack([np.ones(len(deep)), deep[:, 2], deep[:, 3], deep[:, 0]])
        coef, *_ = np.linalg.lstsq(X, deep[:, 1], rcond=None)
        trend = {"coef": [float(c) for c in coef], "sd": float(deep[:, 1].std()),
                 "sd_after": float(np.std(deep[:, 1] - X @ coef))}
        log(f"presses >= 0.3 mm: ratio ~ {coef[0]:.3f} {coef[1]:+.4f} x_mm {coef[2]:+.4f} "
            f"y_mm {coef[3]:+.3f} w0_mm; sd {trend['sd']:.3f} -> "
            f"{trend['sd_after']:.3f} after it")
    return {"E": E, "nu": nu, "beta": beta, "offset": off, "source": src, "setup_s": setup,
            "frames": n_frames, "ms_per_frame": ms, "presses": rows, "by_depth": depths,
            "trend": trend}


def by_depth(rows: list[dict]) -> list[dict]:
    """Per w0 over :func:`measure`'s presses: ``{"w0", "n", "median", "lo", "hi",
    "within5"}`` of the ratio, ``"naive"`` (its median) and ``"true_surface"`` (median,
    least, most)."""
    out = []
    for w0 in sorted({r["w0"] for r in rows}):
        sub = [r for r in rows if r["w0"] == w0]
        r = np.array([x["ratio"] for x in sub])
        q = np.array([x["true_surface"] for x in sub])
        out.append({"w0": w0, "n": len(sub), "median": float(np.median(r)),
                    "lo": float(r.min()), "hi": float(r.max()),
                    "within5": float(np.mean(np.abs(r - 1) <= 0.05)),
                    "naive": float(np.median([x["naive"] for x in sub])),
                    "true_surface": (float(np.median(q)), float(q.min()), float(q.max()))})
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fit", type=Path, default=ROOT / "out" / "calibration" / "fit.json")
    ap.add_argument("--presses", type=int, default=None, help="first N presses only")
    ap.add_argument("--frames-per-press", type=int, default=None,
                    help="the middle K frames of each hold only (default all, 4)")
    ap.add_argument("--naive", action="store_true", help="also the earlier pipeline")
    ap.add_argument("--optics", default="lut",
                    help="'lut' (position cells), 'lut-colour', 'mlp' (needs torch) or a saved "
                         "calibration .npz")
    ap.add_argument("--ball-presses", type=int, default=256,
                    help="rendered ball presses to calibrate the 'lut' optics on")
    ap.add_argument("--save-optics", type=Path, default=None,
                    help="write the optics calibration here (reuse it with --optics PATH)")
    ap.add_argument("--true-surface", action="store_true",
                    help="also the estimator fed the true gel surface (the force model alone)")
    args = ap.parse_args()
    measure(args.fit, presses=args.presses, frames_per_press=args.frames_per_press,
            naive=args.naive, optics=args.optics, ball_presses=args.ball_presses,
            save_optics=args.save_optics, true_surface=args.true_surface, log=print)

if __name__ == "__main__":
    main()
