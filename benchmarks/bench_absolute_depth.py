"""Absolute depth: reconstructed heights against the undeformed gel, no offset removed.

    python benchmarks/bench_absolute_depth.py [--boundary {neumann,dirichlet,contact}]
        [--flat-reference] [--datasets taxim,fem,gelsight,gelslim] [--json PATH]
        [--taxim-no-shadow] [--fem-presses N] [--level far_field] [--zero-background]

The project's shape metrics (:func:`tactilevision.optics.evaluate_ball_presses`)
remove the unknown offset between a reconstruction and the truth; this
benchmark does not. For every frame it reports, against the true height map
(mm, positive into the gel, the undeformed gel at 0), with
:func:`tactilevision.optics.absolute_depth_metrics`:

- the deepest-point error: the largest reconstructed height inside the
  contact minus the true one (um and % of the true depth),
- the profile error inside the contact (RMS and mean of height - truth),
- the background beyond 1.5 contact radii (RMS and largest |height|),

plus, where the indenter is a ball, the spherical cap fitted against the
far-field gel level (:func:`tactilevision.optics.fit_ball_cap`: its depth d
and radius R) and the existing shape metrics (mean normal angle, shape RMS
after the offset is removed).

Data kinds (each skipped, with the reason printed, when its data is missing):

``taxim``
    Presses rendered by Taxim's own renderer (``taxim.Taxim(backend="jax")``,
    PyPI ``taxim``; shadows on; the conventions of
    ``benchmarks/taxim_gauge_session.py``: flat gel, ``contact_scale = 0``,
    XLA single-threaded, 1.5 grey levels of camera noise on the frames, a
    noise-free no-contact render as the reference): a ball of radius 2.0 mm
    and a flat punch of radius 2.5 mm at the centre of the 640 x 480 pad
    (0.0295 mm/px), at depths 0.1, 0.2, 0.4 and 0.6 mm. Truth: the
    indenter's surface inside the contact, 0 beyond 1.5 contact radii.
    Reconstructed with the shipped GelSight calibration and the Taxim
    no-contact frame as the reference. No tactilevision code draws them.
``fem``
    The sample session ``sample_frames/gelsight_session`` (finite-strain FEM
    gel surfaces under a flat punch of radius 2.5 mm, shaded with the Taxim
    authors' polynomial table on the sensor's real no-contact frame): the
    frames of each press's hold, for the first ``--fem-presses`` presses
    that are neither misaligned nor at the pad's edge. Truth: the punch face
    at the press's true depth inside 0.9 of its radius, 0 beyond 1.5 radii
    (the bevel's crest box excluded: the bevel presses the gel there). The
    FEM gel bulges around the punch and sinks in beside it, so the
    background's truth is not exactly 0: its own values over the same
    pixels are printed beside the table.
``gelsight``
    Real ball presses shipped in ``taxim`` (R = 2.0 mm, 0.0295 mm/px,
    annotated circles): the 24 odd-numbered presses, which the shipped
    calibration did not see. Truth (geometric): the ball cap
    ``sqrt(R^2 - r^2) - sqrt(R^2 - a^2)`` inside the annotated contact
    radius a (depth ``d = R - sqrt(R^2 - a^2)`` at its centre, the contact's
    rim at the gel level), 0 beyond 1.5 a.
``gelslim``
    Real GelSlim 3.0 ball presses (``$TACTILEVISION_GELSLIM``, R = 3.8 mm,
    0.0806 mm/px, circles detected, contact radius 0.85 x the detected
    one): a LUT calibration (``model="lut"``) on the even-numbered presses,
    tested on the odd ones; the same geometric truth.

Run: ``python benchmarks/bench_absolute_depth.py`` (about 1 minute on 2 busy
cores; 2 minutes with ``--boundary contact``). Tables and findings:
``docs/validation/optics.md``. From Python, with another reconstructor::

    from bench_absolute_depth import run, format_report
    res = run(lambda cal, ref: DepthReconstructor(cal, reference=ref, boundary="contact"))
    print(format_report(res))
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import platform
import shutil
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from pathlib import Path

# Taxim's renders bit-reproducible (see benchmarks/taxim_gauge_session.py): XLA's CPU
# kernels single-threaded; only effective if jax is not imported yet.
_DETERMINISTIC_XLA = "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"
if "jax" not in sys.modules and "xla_cpu_multi_thread_eigen" not in os.environ.get("XLA_FLAGS",
                                                                                     ""):
    os.environ["XLA_FLAGS"] = (os.environ.get("XLA_FLAGS", "") + " " + _DETERMINISTIC_XLA).strip()

import numpy as np  # noqa: E402

from tactilevision.optics import (  # noqa: E402
    DepthReconstructor,
    PhotometricCalibration,
    absolute_depth_metrics,
    evaluate_ball_presses,
    fit_ball_cap,
)

__all__ = ["DATASETS", "format_report", "main", "run"]

ROOT = Path(__file__).resolve().parents[1]
GELSLIM = Path(os.environ.get("TACTILEVISION_GELSLIM",
                              ROOT.parent / "shared" / "real" / "gelslim3"))
FEM_SESSION = ROOT / "sample_frames" / "gelsight_session"
DATASETS = ("taxim", "fem", "gelsight", "gelslim")

MM_PER_PX = 0.0295                 # Taxim's GelSight pad
SHAPE = (480, 640)
BALL_MM = 2.0
PUNCH_MM = 2.5
TAXIM_DEPTHS_MM = (0.1, 0.2, 0.4, 0.6)
CAMERA_NOISE_GREY = 1.5
GELSLIM_MM_PER_PX = 0.0806         # tests/_data.py: the only stated scale the frames allow
GELSLIM_BALL_MM = 3.8
DISC = 0.9                         # contact evaluated within this fraction of its radius
FAR = 1.5                          # background beyond this many contact radii
FAR_OUT = 3.0                      # far-field level: median height from FAR to FAR_OUT radii
CAL_BALL_MM = 3.0                  # --taxim-optics N: the calibration ball (not the test's)
OWN_LUT_CELLS = (4, 3)

Maker = Callable[[PhotometricCalibration, np.ndarray], DepthReconstructor]


def default_reconstructor(cal: PhotometricCalibration, ref: np.ndarray) -> DepthReconstructor:
    """The reconstructor as users build it: ``DepthReconstructor(cal, reference=ref)``."""
    return DepthReconstructor(cal, reference=ref)


# ------------------------------------------------------------------ helpers


def _grid_r_px(shape: tuple[int, int], centre: Sequence[float]) -> np.ndarray:
    yy, xx = np.indices(shape, dtype=np.float64)
    return np.hypot(xx - centre[0], yy - centre[1])


def _ball_truth(r_mm: np.ndarray, radius_mm: float, a_mm: float) -> np.ndarray:
    """The ball cap inside the contact radius a, its rim at the gel level, 0 outside."""
    cap = np.sqrt(np.maximum(radius_mm**2 - r_mm**2, 0.0)) - math.sqrt(radius_mm**2 - a_mm**2)
    return np.where(r_mm < a_mm, cap, 0.0)


def _row(label: str, height: np.ndarray, truth: np.ndarray, contact: np.ndarray,
         background: np.ndarray, far_ring: np.ndarray) -> dict:
    """Metrics of one frame; ``far_ring``: where the far-field level (median) is read."""
    m = absolute_depth_metrics(height, truth, contact, background_mask=background)
    return dict(case=label, true_depth_mm=m.true_deepest_mm,
                far_level_mm=float(np.median(height[far_ring])),
                deepest_error_mm=m.deepest_error_mm, deepest_error_rel=m.deepest_error_rel,
                profile_rms_mm=m.profile_rms_mm, profile_mean_mm=m.profile_mean_mm,
                background_rms_mm=m.background_rms_mm, background_mean_mm=m.background_mean_mm,
                background_max_mm=m.background_max_mm)


def _add_cap(row: dict, height: np.ndarray, mm: float, centre, a_px: float) -> None:
    fit = fit_ball_cap(height, mm, centre, a_px)
    row.update(cap_depth_mm=fit.depth_mm, cap_radius_mm=fit.radius_mm,
               cap_rim_mm=fit.rim_height_mm, gel_level_mm=fit.gel_level_mm)


def _add_shape(row: dict, recon: DepthReconstructor, frame: np.ndarray, centre, a_px: float,
               ball_px: float, mm: float) -> None:
    rep = evaluate_ball_presses(recon, frame[None], np.asarray([centre], float),
                                np.array([a_px]), ball_px)
    row.update(normal_angle_deg=rep.normal_angle_deg, shape_rms_mm=rep.shape_rms_px * mm)


def _mean_row(label: str, rows: list[dict]) -> dict:
    out: dict = {"case": label, "n": len(rows)}
    for k in rows[0]:
        if k == "case":
            continue
        vals = [r[k] for r in rows if isinstance(r.get(k), int | float)]
        if vals:
            out[k] = float(np.nanmean(vals)) if np.isfinite(vals).any() else math.nan
            out[k + "_sd"] = float(np.nanstd(vals)) if np.isfinite(vals).any() else math.nan
    t = [r["true_depth_mm"] for r in rows]
    out["true_depth_range_mm"] = (float(min(t)), float(max(t)))
    return out


def reference_op_ms(repeat: int = 7) -> float:
    """Median time (ms) of one ``scipy.fft.dctn`` + ``idctn`` pair on a 480 x 640 float64 array."""
    from scipy import fft

    a = np.random.default_rng(0).standard_normal(SHAPE)
    fft.idctn(fft.dctn(a, norm="ortho"), norm="ortho")
    ts = []
    for _ in range(repeat):
        t = time.perf_counter()
        fft.idctn(fft.dctn(a, norm="ortho"), norm="ortho")
        ts.append(time.perf_counter() - t)
    return 1000 * float(np.median(ts))


def machine() -> dict:
    """Platform, CPU model, core count and load average."""
    cpu = platform.processor() or ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    load = os.getloadavg() if hasattr(os, "getloadavg") else (math.nan,) * 3
    return dict(platform=platform.platform(), cpu=cpu, cores=os.cpu_count(),
                python=platform.python_version(), load_avg=[round(v, 2) for v in load])


# ------------------------------------------------------------------ (a) Taxim


@contextlib.contextmanager
def flat_gel_taxim():
    """Taxim's renderer (jax backend) on its GelSight calibration with a flat gel (its
    ``gelmap.npy`` at its maximum everywhere) and ``contact_scale = 0``; yields the
    ``taxim.Taxim`` instance (its calibration copied to a temporary folder)."""
    import taxim

    with tempfile.TemporaryDirectory(prefix="taxim_flat_") as tmp:
        src = Path(taxim.__file__).parent / "calib" / "gelsight"
        calib = Path(tmp) / "gelsight_flat"
        shutil.copytree(src, calib)
        gel = np.load(src / "gelmap.npy")
        np.save(calib / "gelmap.npy", np.full_like(gel, gel.max()))   # a flat gel
        yield taxim.Taxim(calib_folder=calib, backend="jax",
                          params={"simulator": {"contact_scale": 0.0}})


def render_taxim(depths_mm: Sequence[float] = TAXIM_DEPTHS_MM, *, shadow: bool = True,
                 seed: int = 0, calibration_presses: int = 0
                 ) -> tuple[np.ndarray, list[dict]] | tuple[np.ndarray, list[dict], dict]:
    """Ball and flat-punch presses at the pad's centre drawn by Taxim (BGR uint8).

    Returns the no-contact frame and, per press, ``kind``, ``depth_mm``, ``frame``,
    ``contact_radius_mm`` and ``taxim_gel_mm`` (Taxim's own deformed gel, positive into
    the gel, when its private method is reachable; else None). Taxim's object height
    map is the distance from the gel's undeformed surface (smaller = closer to the
    camera): the ball's lowest point and the punch's face at 0; ``press_depth`` pushes
    that point d into the gel.

    With ``calibration_presses`` N > 0 it also renders, with the same renderer, N
    presses of a ball of radius ``CAL_BALL_MM`` (another ball than the test's) at
    random positions (contacts may leave the image) and depths 0.2 to 1.2 mm, and
    returns a third item: ``frames`` (N, H, W, 3), ``centers_px`` (N, 2), ``radii_px``
    (N,), the contact circles, for ``PhotometricCalibration.from_ball_presses``.
    """
    import jax  # Taxim's jax backend; jit for its deformed gel

    h, w = SHAPE
    x = (np.arange(w) - (w - 1) / 2) * MM_PER_PX
    y = (np.arange(h) - (h - 1) / 2) * MM_PER_PX
    r = np.hypot(*np.meshgrid(x, y))
    objects = {
        "ball": np.where(r < BALL_MM, BALL_MM - np.sqrt(np.maximum(BALL_MM**2 - r * r, 0.0)),
                         BALL_MM + 1.0).astype(np.float32),
        "punch": np.where(r <= PUNCH_MM, 0.0, 1.0).astype(np.float32),
    }
    rng = np.random.default_rng(seed)

    def bgr(img: np.ndarray, noise: float) -> np.ndarray:
        img = np.asarray(img, np.float64) * 255.0        # Taxim renders RGB in [0, 1]
        if noise:
            img = img + rng.normal(0.0, noise, img.shape)
        return np.clip(np.rint(img), 0, 255).astype(np.uint8)[..., ::-1]

    out = []
    with flat_gel_taxim() as sim:
        ref = bgr(sim.render(np.full(SHAPE, 1.0, np.float32), with_shadow=shadow), 0.0)
        deform = getattr(sim, "_TaximJax__compute_gel_pad_deformation", None)
        shift = getattr(sim, "_TaximJax__get_shifted_height_map", None)
        gel_fn = None
        if deform is not None and shift is not None:
            gel_fn = jax.jit(lambda hm, d: -deform(shift(d, hm))[0])
        for kind, obj in objects.items():
            for d in depths_mm:
                frame = bgr(sim.render(obj, with_shadow=shadow, press_depth=float(d)),
                            CAMERA_NOISE_GREY)
                a = math.sqrt(2 * BALL_MM * d - d * d) if kind == "ball" else PUNCH_MM
                tgel = None
                if gel_fn is not None:
                    try:
                        tgel = np.asarray(gel_fn(obj, float(d)), np.float64)
                    except Exception:  # a private method: its absence only drops a note
                        tgel = None
                out.append(dict(kind=kind, depth_mm=float(d), frame=frame, contact_radius_mm=a,
                                taxim_gel_mm=tgel))
        if calibration_presses <= 0:
            return ref, out
        crng = np.random.default_rng(seed + 1)
        frames, centres, radii = [], [], []
        xx, yy = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
        for _ in range(calibration_presses):
            c = (crng.uniform(0, w - 1), crng.uniform(0, h - 1))
            d = float(crng.uniform(0.2, 1.2))
            rr = np.hypot(xx - c[0], yy - c[1]) * MM_PER_PX
            ball = np.where(rr < CAL_BALL_MM,
                            CAL_BALL_MM - np.sqrt(np.maximum(CAL_BALL_MM**2 - rr * rr, 0.0)),
                            CAL_BALL_MM + 1.0).astype(np.float32)
            frames.append(bgr(sim.render(ball, with_shadow=shadow, press_depth=d),
                              CAMERA_NOISE_GREY))
            centres.append(c)
            radii.append(math.sqrt(2 * CAL_BALL_MM * d - d * d) / MM_PER_PX)
    return ref, out, dict(frames=np.stack(frames), centers_px=np.array(centres),
                          radii_px=np.array(radii))


def _bench_taxim(make: Maker, *, shadow: bool, log, own_optics: int = 0,
                 optics_circles: str = "geometric") -> dict:
    t0 = time.perf_counter()
    if own_optics:
        ref, presses, balls = render_taxim(shadow=shadow, calibration_presses=own_optics)
    else:
        ref, presses = render_taxim(shadow=shadow)
    t_render = time.perf_counter() - t0
    log(f"[taxim] {len(presses) + 1 + own_optics} Taxim renders in {t_render:.1f} s")
    if own_optics:
        # the renderer's own optics, made as a rig makes them: ball presses of its sensor
        given = optics_circles == "geometric"
        cal = PhotometricCalibration.from_ball_presses(
            ref, balls["frames"], balls["centers_px"] if given else None,
            balls["radii_px"] if given else None,
            ball_radius_mm=CAL_BALL_MM, mm_per_px=MM_PER_PX, model="lut",
            lut_cells=OWN_LUT_CELLS)
    else:
        cal = PhotometricCalibration.load("gelsight")
    recon = make(cal, ref)
    centre = ((SHAPE[1] - 1) / 2, (SHAPE[0] - 1) / 2)
    r_px = _grid_r_px(SHAPE, centre)
    r_mm = r_px * MM_PER_PX
    rows, gel_far = [], []
    for p in presses:
        d, a = p["depth_mm"], p["contact_radius_mm"]
        a_px = a / MM_PER_PX
        if p["kind"] == "ball":
            truth = _ball_truth(r_mm, BALL_MM, a)
            label = f"ball R {BALL_MM:g} mm, d {d:g} mm"
        else:
            truth = np.where(r_mm < a, d, 0.0)
            label = f"punch a {PUNCH_MM:g} mm, d {d:g} mm"
        height = recon(p["frame"])
        row = _row(label, height, truth, r_mm < DISC * a, r_mm > FAR * a,
                   (r_mm >= FAR * a) & (r_mm <= FAR_OUT * a))
        if p["kind"] == "ball":
            _add_cap(row, height, MM_PER_PX, centre, a_px)
            _add_shape(row, recon, p["frame"], centre, a_px, BALL_MM / MM_PER_PX, MM_PER_PX)
        if p["taxim_gel_mm"] is not None:
            g = p["taxim_gel_mm"][r_mm > FAR * a]
            gel_far.append((label, float(np.sqrt(np.mean(g * g))), float(np.abs(g).max())))
        rows.append(row)
    notes = [f"Taxim {'with' if shadow else 'without'} shadows, flat gel, contact_scale 0, "
             f"{CAMERA_NOISE_GREY:g} grey levels of camera noise; reference: Taxim's "
             "no-contact render; truth 0 beyond "
             f"{FAR:g} a, contact evaluated within {DISC:g} a."]
    if own_optics:
        notes.append(f"Optics: LUT with {OWN_LUT_CELLS[0]} x {OWN_LUT_CELLS[1]} position cells "
                     f"calibrated on {own_optics} Taxim presses of a {CAL_BALL_MM:g} mm ball "
                     "(random positions, 0.2 to 1.2 mm deep), not the shipped calibration; "
                     + ("labelled to the geometric contact radius sqrt(2 R d - d^2)."
                        if optics_circles == "geometric" else
                        "circles detected (the contact edge, labelled to it)."))
    if gel_far:
        worst = max(gel_far, key=lambda t: t[2])
        notes.append("Taxim's own deformed gel beyond 1.5 a (its Gaussian-pyramid skirt): "
                     f"rms {1000 * min(t[1] for t in gel_far):.1f} to "
                     f"{1000 * max(t[1] for t in gel_far):.1f} um, largest "
                     f"{1000 * worst[2]:.0f} um ({worst[0]}).")
    return dict(rows=rows, notes=notes, render_s=t_render,
                optics=f"own ({own_optics} presses)" if own_optics else "shipped")


# ------------------------------------------------------------------ (b) FEM session


def _bench_fem(make: Maker, *, n_presses: int, log) -> dict:
    from tactilevision.io import read_session

    if not (FEM_SESSION / "session.toml").is_file():
        return dict(skipped=f"no session at {FEM_SESSION}")
    s = read_session(FEM_SESSION)
    cfg = s.config
    truth_doc = json.loads((FEM_SESSION / "truth.json").read_text())
    cal = PhotometricCalibration.load(cfg.calibration if cfg.calibration is not None
                                      else cfg.sensor_name)
    recon = make(cal, s.reference)
    mm, a = cfg.mm_per_px, cfg.indenter_radius_mm
    shape = s.shape
    presses = [p for p in truth_doc["presses"] if not p.get("misaligned") and not p.get("edge")]
    presses = presses[:n_presses]
    hold_s = 0.5                    # the sample session's hold (SessionSpec.hold_s)
    # the FEM's own surface (bulge and sink-in), for the note on the background's truth
    fem_surface = None
    try:
        from tactilevision.sim import GaugeBlock, press_profile, press_surface

        h_gel = float(truth_doc["thickness_mm"])
        deepest = max(p["depth_mm"] for p in presses)
        prof = press_profile(a / h_gel, float(truth_doc["nu"]),
                             w_over_h_max=max(0.22, deepest / h_gel * 1.05))
        block = GaugeBlock(depths_mm=cfg.depths_mm, radius_mm=a,
                           bevel_offset_mm=cfg.bevel_offset_mm,
                           bevel_direction_deg=cfg.bevel_direction_deg,
                           bevel_angle_deg=cfg.bevel_angle_deg,
                           bevel_length_mm=cfg.bevel_length_mm)

        def fem_surface(p: dict, centre: tuple[float, float]) -> np.ndarray:
            z, _ = press_surface(prof, block, indenter=int(p["indenter"]),
                                 depth_mm=float(p["depth_mm"]), centre_px=centre, shape=shape,
                                 mm_per_px=mm, thickness_mm=h_gel)
            return z
    except Exception as exc:  # the note only
        log(f"[fem] no FEM surface for the note: {exc}")
    rows, fem_bg = [], []
    yy, xx = np.indices(shape, dtype=np.float64)
    th = math.radians(cfg.bevel_direction_deg)
    for p in presses:
        sel = np.nonzero((s.frame_times_s >= p["hold_from_s"] + 0.05)
                         & (s.frame_times_s <= p["hold_from_s"] + hold_s - 0.05))[0]
        if sel.size == 0:
            continue
        centre = (p["x_mm"] / mm + (shape[1] - 1) / 2, p["y_mm"] / mm + (shape[0] - 1) / 2)
        dx, dy = (xx - centre[0]) * mm, (yy - centre[1]) * mm
        r_mm = np.hypot(dx, dy)
        u = dx * math.cos(th) + dy * math.sin(th) - cfg.bevel_offset_mm
        v = -dx * math.sin(th) + dy * math.cos(th)
        bevel_box = (np.abs(u) < 1.0) & (np.abs(v) < cfg.bevel_length_mm / 2 + 0.5)
        truth = np.where(r_mm < a, p["depth_mm"], 0.0)
        contact, background = r_mm < DISC * a, (r_mm > FAR * a) & ~bevel_box
        ring = background & (r_mm <= FAR_OUT * a)
        per = [_row("", recon(s.frame(int(i))), truth, contact, background, ring)
               for i in sel]
        row = _mean_row(f"press {p['press']} (w0 {p['w0_mm']:g} mm)", per)
        row["frames"] = int(sel.size)
        rows.append(row)
        if fem_surface is not None:
            z = fem_surface(p, centre)[background]
            fem_bg.append((float(z.mean()), float(z.min()), float(z.max())))
    notes = [f"{len(rows)} presses (misaligned and edge presses left out), the frames of "
             "each hold averaged; truth: the punch face at the true depth within "
             f"{DISC:g} a, 0 beyond {FAR:g} a, the bevel's crest box (|u| < 1 mm) left out."]
    if fem_bg:
        notes.append("The FEM surface itself over those background pixels (bulge > 0 is "
                     "towards the camera, i.e. negative height): mean "
                     f"{1000 * min(b[0] for b in fem_bg):+.1f} to "
                     f"{1000 * max(b[0] for b in fem_bg):+.1f} um, range "
                     f"{1000 * min(b[1] for b in fem_bg):+.0f} to "
                     f"{1000 * max(b[2] for b in fem_bg) + 0.0:+.0f} um: a reconstruction "
                     "exact to the FEM would read that as background error.")
    return dict(rows=[*rows, _mean_row("mean over presses", rows)], notes=notes)


# ------------------------------------------------------------------ (c) real frames


def _bench_balls(make: Maker, cal: PhotometricCalibration, ps, idx: np.ndarray,
                 centres: np.ndarray, radii: np.ndarray, mm: float, ball_mm: float,
                 label: str) -> dict:
    recon = make(cal, ps.reference)
    shape = ps.reference.shape[:2]
    rows = []
    for i in idx:
        c, a_px = centres[i], float(radii[i])
        r_mm = _grid_r_px(shape, c) * mm
        a = a_px * mm
        truth = _ball_truth(r_mm, ball_mm, a)
        height = recon(ps.frames[i])
        row = _row(f"press {i}", height, truth, r_mm < DISC * a, r_mm > FAR * a,
                   (r_mm >= FAR * a) & (r_mm <= FAR_OUT * a))
        _add_cap(row, height, mm, c, a_px)
        _add_shape(row, recon, ps.frames[i], c, a_px, ball_mm / mm, mm)
        rows.append(row)
    summary = _mean_row(label, rows)
    # a cap fitted to a reconstruction that is flat inside the contact runs off to a huge
    # R: such fits are left out of the cap's mean and named
    ok = [r for r in rows if ball_mm / 3 < r["cap_radius_mm"] < 3 * ball_mm]
    notes = []
    if len(ok) < len(rows):
        bad = [r["case"] for r in rows if r not in ok]
        notes.append(f"{label}: cap fits with R beyond 3x or below 1/3 of the ball's "
                     "radius (the reconstruction far flatter than the ball inside the "
                     f"contact), left out of the cap columns' mean: {', '.join(bad)}.")
        for k in ("cap_depth_mm", "cap_radius_mm", "cap_rim_mm", "gel_level_mm"):
            vals = [r[k] for r in ok]
            summary[k] = float(np.mean(vals)) if vals else math.nan
            summary[k + "_sd"] = float(np.std(vals)) if vals else math.nan
    summary["n_cap"] = len(ok)
    return dict(rows=[summary], per_press=rows, notes=notes)


def _bench_gelsight(make: Maker, *, log) -> dict:
    try:
        from tactilevision.io import read_ball_presses, taxim_datapack

        ps = read_ball_presses(taxim_datapack())
    except Exception as exc:
        return dict(skipped=f"taxim's GelSight data pack not readable: {exc}")
    cal = PhotometricCalibration.load("gelsight")
    idx = np.arange(1, len(ps.frames), 2)     # the shipped calibration saw the even ones
    out = _bench_balls(make, cal, ps, idx, ps.centers_px, ps.radii_px, MM_PER_PX, BALL_MM,
                       f"GelSight, {idx.size} odd presses (mean)")
    out["notes"] = out["notes"] + [
        "Real GelSight ball presses (taxim data pack), annotated circles, shipped "
        "calibration (fitted on the even presses); geometric truth d = R - sqrt(R^2 - a^2), "
        "the contact's rim at the gel level. Annotated a = "
        f"{ps.radii_px[idx].min() * MM_PER_PX:.2f} to {ps.radii_px[idx].max() * MM_PER_PX:.2f} "
        f"mm for R = {BALL_MM:g} mm: deep presses with steep rims."]
    return out


def _bench_gelslim(make: Maker, *, log) -> dict:
    if not GELSLIM.is_dir():
        return dict(skipped=f"GelSlim 3.0 frames not found at {GELSLIM}")
    from tactilevision.io import read_ball_presses
    from tactilevision.optics import detect_contact_circles

    rows, per, notes = [], [], []
    for sub in ("set_2020_11", "set_2020_09"):
        if not (GELSLIM / sub).is_dir():
            notes.append(f"{sub}: not found, skipped")
            continue
        ps = read_ball_presses(GELSLIM / sub)
        t = time.perf_counter()
        cal = PhotometricCalibration.from_ball_presses(
            ps.reference, ps.frames[0::2], None, None, ball_radius_mm=GELSLIM_BALL_MM,
            mm_per_px=GELSLIM_MM_PER_PX, model="lut")
        centres, r_det = detect_contact_circles(ps.frames, ps.reference, edge="contact")
        log(f"[gelslim] {sub}: LUT calibration and circles in {time.perf_counter() - t:.1f} s")
        idx = np.arange(1, len(ps.frames), 2)
        tag = ", markers" if sub.endswith("09") else ""
        res = _bench_balls(make, cal, ps, idx, centres, r_det,
                           GELSLIM_MM_PER_PX, GELSLIM_BALL_MM,
                           f"GelSlim {sub}{tag}, {idx.size} odd presses (mean)")
        rows += res["rows"]
        per += [dict(r, set=sub) for r in res["per_press"]]
        notes += res["notes"]
    notes.insert(0, "Real GelSlim 3.0 ball presses, LUT calibrated on the even presses "
                 "(circles detected), tested on the odd; contact radius: the detected contact "
                 f"edge; R = {GELSLIM_BALL_MM:g} mm at {GELSLIM_MM_PER_PX} mm/px. "
                 "The geometric truth hangs on that radius: at a = 0.6 R, 5% in a is 0.09 mm "
                 "in d.")
    return dict(rows=rows, per_press=per, notes=notes)


# ------------------------------------------------------------------ run


def run(make_reconstructor: Maker = default_reconstructor,
        datasets: Sequence[str] = DATASETS, *, taxim_shadow: bool = True,
        fem_presses: int = 10, taxim_optics: int = 0, taxim_optics_circles: str = "geometric",
        log: Callable[[str], None] | None = None) -> dict:
    """Run the benchmark with the reconstructor ``make_reconstructor(calibration, reference)``.

    Parameters
    ----------
    make_reconstructor : callable
        ``(PhotometricCalibration, reference BGR uint8) -> DepthReconstructor``, called
        once per data set (and per GelSlim set); default
        ``DepthReconstructor(cal, reference=ref)``.
    datasets : sequence of {'taxim', 'fem', 'gelsight', 'gelslim'}
        Which data kinds, in this order.
    taxim_shadow : bool, default True
        Taxim's ``with_shadow``.
    fem_presses : int, default 10
        Presses of the FEM session.
    taxim_optics : int, default 0
        0: read Taxim's frames with the shipped GelSight calibration; N > 0: with a
        position-cell LUT calibrated on N Taxim presses of another ball.
    taxim_optics_circles : {'geometric', 'detected'}, default 'geometric'
        The circles that LUT is labelled to: the geometric ones, sqrt(2 R d - d^2)
        (Taxim's smoothed gel leaves the ball at 0.86 to 0.93 of that), or those
        ``from_ball_presses`` detects (the contact edge).
    log : callable, optional
        Progress lines (default: to stderr).

    Returns
    -------
    dict
        ``machine``, ``reference_op_ms`` (one dctn + idctn pair on 480 x 640 float64,
        timed in this run), ``total_s`` and ``datasets``: per name ``rows`` (one dict per
        table row, lengths in mm), ``notes``, ``wall_s``, optional ``per_press``, or
        ``skipped`` with the reason.
    """
    unknown = [d for d in datasets if d not in DATASETS]
    if unknown:
        raise ValueError(f"unknown data set(s) {unknown}; choose from {DATASETS}")
    if log is None:
        def log(msg: str) -> None:
            print(msg, file=sys.stderr, flush=True)
    t_all = time.perf_counter()
    result: dict = {"machine": machine(), "reference_op_ms": reference_op_ms(), "datasets": {}}
    for name in datasets:
        t = time.perf_counter()
        if name == "taxim":
            try:
                import jax  # noqa: F401
                import taxim  # noqa: F401
            except ImportError as exc:
                res = dict(skipped=f"taxim or jax not installed ({exc})")
            else:
                res = _bench_taxim(make_reconstructor, shadow=taxim_shadow, log=log,
                                   own_optics=taxim_optics,
                                   optics_circles=taxim_optics_circles)
        elif name == "fem":
            res = _bench_fem(make_reconstructor, n_presses=fem_presses, log=log)
        elif name == "gelsight":
            res = _bench_gelsight(make_reconstructor, log=log)
        else:
            res = _bench_gelslim(make_reconstructor, log=log)
        res["wall_s"] = time.perf_counter() - t
        result["datasets"][name] = res
        log(f"[{name}] {res['wall_s']:.1f} s" + (f" (skipped: {res['skipped']})"
                                                  if "skipped" in res else ""))
    result["reference_op_ms_end"] = reference_op_ms()
    result["total_s"] = time.perf_counter() - t_all
    result["machine"]["load_avg_end"] = [round(v, 2) for v in os.getloadavg()]
    return result


TITLES = {"taxim": "(a) Taxim renders (its own renderer), shipped GelSight calibration",
          "fem": "(b) FEM-surface session sample_frames/gelsight_session, its own optics "
                 "(optics.npz, session.toml [optics])",
          "gelsight": "(c) Real GelSight ball presses (taxim data pack), shipped calibration",
          "gelslim": "(c) Real GelSlim 3.0 ball presses, LUT calibrated on the even presses"}


def _f(v, scale: float = 1.0, fmt: str = ".0f", sd: float | None = None) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    s = format(v * scale, fmt)
    return s if sd is None else f"{s} ± {format(sd * scale, fmt.replace('+', ''))}"


def format_report(result: dict) -> str:
    """The benchmark's tables (Markdown) from :func:`run`'s result."""
    m = result["machine"]
    ref_ms = result["reference_op_ms"]
    lines = [f"Machine: {m['cpu']}, {m['cores']} cores, {m['platform']}, Python {m['python']}; "
             f"load average {m['load_avg'][0]:.2f} at the start, "
             f"{m.get('load_avg_end', [math.nan])[0]:.2f} at the end.",
             f"Reference operation (one scipy.fft dctn + idctn pair, 480 x 640 float64): "
             f"{ref_ms:.1f} ms at the start, {result.get('reference_op_ms_end', math.nan):.1f} "
             "ms at the end.",
             f"Total: {result['total_s']:.0f} s.", ""]
    head = ("| case | true depth (mm) | deepest err (um) | deepest err (%) | profile rms (um) | "
            "profile mean (um) | bg rms (um) | bg max (um) | far level (um) | cap d (mm) | "
            "cap R (mm) | cap rim (um) | normal angle (deg) | shape rms (um) |")
    for name, res in result["datasets"].items():
        wall = res.get("wall_s", math.nan)
        title = TITLES.get(name, name)
        if name == "taxim" and str(res.get("optics", "shipped")).startswith("own"):
            title = title.replace("shipped GelSight calibration",
                                  f"its own optics, {res['optics']}")
        lines.append(f"### {title}")
        lines.append("")
        if "skipped" in res:
            lines += [f"Skipped: {res['skipped']}", ""]
            continue
        lines.append(f"Wall time {wall:.1f} s = {1000 * wall / ref_ms:.0f} x the reference "
                     "operation.")
        lines.append("")
        lines += [head, "|---" * 14 + "|"]
        for r in res["rows"]:
            spread = "n" in r and name in ("gelsight", "gelslim")

            def sd(k: str, r: dict = r, spread: bool = spread) -> float | None:
                return r.get(k + "_sd") if spread else None

            rng = r.get("true_depth_range_mm")
            true = (f"{rng[0]:.2f} to {rng[1]:.2f}" if rng and rng[1] - rng[0] > 0.005
                    else _f(r["true_depth_mm"], 1, ".3f"))
            lines.append(
                f"| {r['case']} | {true} "
                f"| {_f(r['deepest_error_mm'], 1000, '+.0f', sd('deepest_error_mm'))} "
                f"| {_f(r['deepest_error_rel'], 100, '+.0f', sd('deepest_error_rel'))} "
                f"| {_f(r['profile_rms_mm'], 1000)} "
                f"| {_f(r['profile_mean_mm'], 1000, '+.0f')} "
                f"| {_f(r['background_rms_mm'], 1000)} | {_f(r['background_max_mm'], 1000)} "
                f"| {_f(r['far_level_mm'], 1000, '+.0f')} "
                f"| {_f(r.get('cap_depth_mm'), 1, '.3f', sd('cap_depth_mm'))} "
                f"| {_f(r.get('cap_radius_mm'), 1, '.2f', sd('cap_radius_mm'))} "
                f"| {_f(r.get('cap_rim_mm'), 1000, '+.0f')} "
                f"| {_f(r.get('normal_angle_deg'), 1, '.1f')} "
                f"| {_f(r.get('shape_rms_mm'), 1000)} |")
        lines.append("")
        lines += [f"- {n}" for n in res.get("notes", [])]
        lines.append("")
    lines.append("deepest err: largest reconstructed height within 0.9 a minus the true one; "
                 "profile: height - truth within 0.9 a; bg: |height| beyond 1.5 a; far "
                 "level: the median height from 1.5 to 3 a (the reconstruction's zero error "
                 "next to the contact); cap: fit_ball_cap, d and R of the spherical cap over "
                 "that level, rim: the fitted cap's height at r = a over it (0 without "
                 "sink-in); normal angle and shape rms: evaluate_ball_presses (offset "
                 "removed), within a. All without offset removal except the last two. Real "
                 "presses: mean (± sd over presses). a: contact radius.")
    return "\n".join(lines)


def _jsonable(obj):
    if isinstance(obj, dict):
        return {k: _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--boundary", choices=("neumann", "dirichlet", "contact"), default="neumann",
                    help="DepthReconstructor's Poisson boundary (default neumann)")
    ap.add_argument("--datasets", default=",".join(DATASETS),
                    help=f"comma-separated, from {','.join(DATASETS)}")
    ap.add_argument("--flat-reference", action="store_true",
                    help="DepthReconstructor(flat_reference=True): the model's gradient on the "
                         "reference subtracted")
    ap.add_argument("--level", choices=("median", "far_field"), default="median",
                    help="DepthReconstructor's zero level (default median)")
    ap.add_argument("--level-degree", type=int, default=4,
                    help="degree of the far-field surface (default 4)")
    ap.add_argument("--zero-background", action="store_true",
                    help="DepthReconstructor(zero_background=True): the gradients outside "
                         "each frame's contact region set to zero before integrating")
    ap.add_argument("--json", type=Path, default=None, help="also write the result as JSON")
    ap.add_argument("--taxim-no-shadow", action="store_true", help="Taxim with_shadow=False")
    ap.add_argument("--fem-presses", type=int, default=10)
    ap.add_argument("--taxim-optics", type=int, default=0, metavar="N",
                    help="read Taxim's frames with a LUT (4 x 3 cells) calibrated on N Taxim "
                         "presses of a 3 mm ball instead of the shipped calibration")
    ap.add_argument("--taxim-optics-circles", choices=("geometric", "detected"),
                    default="geometric",
                    help="--taxim-optics: label its LUT to the geometric circles (default) or "
                         "to the circles it detects (the contact edge)")
    a = ap.parse_args(argv)
    names = [d.strip() for d in a.datasets.split(",") if d.strip()]
    bad = [d for d in names if d not in DATASETS]
    if bad:
        ap.error(f"unknown data set(s) {bad}; choose from {DATASETS}")

    kwargs: dict = {"boundary": a.boundary}
    if a.flat_reference:
        kwargs["flat_reference"] = True
    if a.level != "median":
        kwargs.update(level=a.level, level_degree=a.level_degree)
    if a.zero_background:
        kwargs["zero_background"] = True

    def make(cal: PhotometricCalibration, ref: np.ndarray) -> DepthReconstructor:
        return DepthReconstructor(cal, reference=ref, **kwargs)

    res = run(make, names, taxim_shadow=not a.taxim_no_shadow, fem_presses=a.fem_presses,
              taxim_optics=a.taxim_optics, taxim_optics_circles=a.taxim_optics_circles)
    res["command"] = " ".join(["python benchmarks/bench_absolute_depth.py",
                               *(sys.argv[1:] if argv is None else argv)])
    res["boundary"] = a.boundary
    call = ", ".join(f"{k}={v!r}" for k, v in kwargs.items())
    res["reconstructor"] = f"DepthReconstructor(cal, reference=ref, {call})"
    print(f"Command: {res['command']}")
    print(f"Reconstructor: {res['reconstructor']}\n")
    print(format_report(res))
    if a.json:
        a.json.write_text(json.dumps(_jsonable(res), indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
