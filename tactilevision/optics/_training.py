"""Training a photometric calibration from ball presses (the work behind
:meth:`PhotometricCalibration.from_ball_presses`).

Pressing a ball of known radius R into the gel gives, inside each contact
circle, pixels whose surface normal is known exactly (:mod:`._ball`). Those
pixels, plus flat background pixels far from the contact, train a model from
colour change (and, for the MLP, reference colour and pixel position) to the
in-plane normal (n_x, n_y): a binned colour table (LUT, per position cell if
asked) or a small network exported to ONNX. With detected circles the centres
are refitted to the first model's gradients and the model is trained again.
"""

from __future__ import annotations

import datetime as _dt

import numpy as np
from tqdm.auto import tqdm

from .._checks import InputError, check_array
from .._version import __version__
from ._ball import (
    SLOPE_PEAK_AT,
    ball_gradients,
    fit_ball_centre,
    normals_from_gradients,
    slope_peak_radius,
)
from ._calibration_data import CalibrationData
from ._circles import detect_contact_circles
from ._features import colour_change, reference_inverse
from ._lut import fit_cell_luts, fit_colour_lut
from ._markers import marker_mask
from ._mlp import (
    BATCH_SIZE,
    cell_position_inputs,
    default_position_cell_px,
    mlp_inputs,
    train_mlp,
)
from ._reconstructor import DepthReconstructor

__all__ = ["fit_from_ball_presses"]


#: Network training: the most optimisation steps of a round; with more labelled pixels
#: the training stops part-way through its epochs, so its time no longer grows with the
#: folder (``benchmarks/bench_optics_calibration_time.py``).
MLP_MAX_STEPS = 2400

#: Network training: a round that starts from a trained network (the second round, on
#: refitted circles; a calibration given a ``warm_start``) takes this share of a cold
#: round's steps. On held-out presses (three folds, GelSlim 3.0 and GelSight Mini) it
#: read as a cold second round did (docs/validation/optics.md, "How long a calibration
#: takes").
MLP_WARM_FRACTION = 0.25


def fit_from_ball_presses(cls: type[CalibrationData], reference: np.ndarray,
                          frames: np.ndarray, centers_px: np.ndarray | None = None,
                          radii_px: np.ndarray | None = None, *, ball_radius_mm: float,
                          mm_per_px: float, model: str = "mlp", use_position: bool = True,
                          markers: bool | None = None, label_fraction: float | None = None,
                          refine_centers: bool | None = None, bins: int = 32,
                          lut_cells: tuple[int, int] = (1, 1), epochs: int = 30,
                          hidden: int = 128, blur_sigma: float = 0.0, seed: int = 0,
                          source: str = "", progress: bool = False,
                          detect_edge: str = "contact", flat_fraction: float = 0.03,
                          max_steps: int | None = MLP_MAX_STEPS,
                          position_cell_px: int | None = None,
                          warm_start: CalibrationData | None = None,
                          detected: bool | None = None):
    """Train a photometric calibration of class `cls` from ball presses.

    The parameters, return value and errors are those of
    :meth:`~tactilevision.optics.PhotometricCalibration.from_ball_presses`, which
    calls this with its own class.
    """
    reference, frames, ball_mm = _checked_presses(reference, frames, ball_radius_mm,
                                                  mm_per_px, model, detect_edge, flat_fraction)
    if position_cell_px is not None and (isinstance(position_cell_px, bool)
                                         or int(position_cell_px) != position_cell_px
                                         or position_cell_px < 0):
        raise InputError(f"position_cell_px must be a non-negative integer or None, got "
                         f"{position_cell_px!r}")
    none_given = centers_px is None and radii_px is None
    if detected is False and none_given:
        raise InputError("detected=False needs the circles: give centers_px and radii_px")
    detected = none_given if detected is None else bool(detected)
    warm = _warm_network(warm_start, model, reference.shape[:2], use_position,
                         position_cell_px)
    centers, radii = _press_circles(frames, reference, centers_px, radii_px, detect_edge)
    ball_px = ball_mm / mm_per_px              # (N,): each press's ball
    if label_fraction is None:     # the colour edge lies outside the contact (_circles.py)
        label_fraction = 0.85 if detected and detect_edge == "colour" else 1.0
    if refine_centers is None:
        refine_centers = detected
    bad = np.nonzero(radii * label_fraction >= ball_px)[0]
    if bad.size:
        raise InputError(f"press {bad[0]}: contact radius {radii[bad[0]]:.1f} px (x label "
                         f"fraction {label_fraction:g}) is not smaller than the ball radius "
                         f"{ball_px[bad[0]]:.1f} px: check ball_radius_mm and mm_per_px")
    ref_mask = marker_mask(reference)
    if markers is None:
        markers = bool(ref_mask.mean() > 0.02)
    ref_inv = reference_inverse(reference, marker_mask=ref_mask if markers else None)
    ref_colour = 1.0 / ref_inv
    changes, valid, background = _pixel_sets(frames, ref_inv, markers, blur_sigma,
                                             flat_fraction, seed, progress)

    cal = cls(model=model, reference=reference.copy(), mm_per_px=float(mm_per_px),
              use_position=use_position, markers=markers, blur_sigma=blur_sigma)
    if model == "mlp" and use_position:
        cal.position_cell_px = (default_position_cell_px(cal.shape) if position_cell_px is None
                                else int(position_cell_px))
    rounds = 2 if refine_centers else 1
    radius_scale = 1.0
    fell_back = np.zeros((0, 0), bool)         # position cells on the colour-only table
    for rnd in range(rounds):
        samples = _training_samples(changes, valid, background, centers,
                                    label_fraction * radii, ball_px)
        init = cal.onnx_bytes if rnd > 0 else warm
        fell_back = _fit_round(cal, samples, ref_colour, fell_back, flat_fraction=flat_fraction,
                               bins=bins, lut_cells=lut_cells, hidden=hidden, epochs=epochs,
                               seed=seed, progress=progress, max_steps=max_steps, init=init)
        if rnd + 1 < rounds:
            radius_scale = _refine_circles(DepthReconstructor(cal), frames, centers, radii,
                                           ball_px, label_fraction, detected)
            radii = radii * radius_scale
    cal.provenance = {
        "source": source,
        "created": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
        "n_presses": len(frames),
        "ball_radius_mm": (float(ball_mm[0]) if np.all(ball_mm == ball_mm[0])
                           else ball_mm.round(4).tolist()),
        "circles": "detected" if detected else "given",
        "detected_edge": detect_edge if detected else None,
        "centers_refined": bool(refine_centers),
        "radius_scale": float(radius_scale),
        "label_fraction": float(label_fraction),
        "flat_fraction": float(flat_fraction),
        "lut_cells": [int(c) for c in lut_cells] if model == "lut" else None,
        "lut_cells_fell_back": int(np.count_nonzero(fell_back)),
        "position_cell_px": int(cal.position_cell_px),
        "warm_start": None if warm is None else {
            "n_presses": warm_start.provenance.get("n_presses"),
            "steps_share": float(MLP_WARM_FRACTION)},
        "centers_px": centers.round(2).tolist(),
        "radii_px": radii.round(2).tolist(),
        "tactilevision": __version__,
    }
    return cal


def _refine_circles(recon: DepthReconstructor, frames: np.ndarray, centers: np.ndarray,
                    radii: np.ndarray, ball_px: np.ndarray, label_fraction: float,
                    detected: bool) -> float:
    """Refit every centre to the first model's gradients (in place: :func:`fit_ball_centre`)
    and, for detected circles, the scale their radii need: the median over the presses of
    where the first model's radial slope peaks (:func:`slope_peak_radius`) over the radius,
    against :data:`SLOPE_PEAK_AT` where circles annotated by hand put it (1.0 for given
    circles, or with under three presses the peak is read on). On GelSlim 3.0's 75 presses
    the slope peaked at 0.82 of the detected radius (taxim's detected circles 0.956, the
    GelSight Mini's 0.99, each read by a calibration trained on them): its detected contact
    edge lay 14 % outside the contact, the labels there taught the model the ball's slopes
    for the gel's flatter ones, and the
    held-out inner cap read +13 to +19 % (issue 55)."""
    peaks = []
    for i, f in enumerate(frames):
        gx, gy = recon.gradients(f)
        centers[i] = fit_ball_centre(gx, gy, centers[i], label_fraction * radii[i], ball_px[i])
        if detected:
            peaks.append(slope_peak_radius(gx, gy, centers[i], radii[i]) / radii[i])
    ok = np.asarray(peaks, np.float64)
    ok = ok[np.isfinite(ok)]
    if ok.size < 3:
        return 1.0
    return float(np.clip(np.median(ok) / SLOPE_PEAK_AT, 0.7, 1.2))


def _warm_network(warm_start: CalibrationData | None, model: str, shape: tuple[int, int],
                  use_position: bool, position_cell_px: int | None) -> bytes | None:
    """The network a calibration's first round starts from (None: a cold start), checked
    against the calibration asked for: a network of the same inputs (frame size,
    position inputs, position cells)."""
    if warm_start is None:
        return None
    if model != "mlp" or warm_start.model != "mlp" or warm_start.onnx_bytes is None:
        raise InputError(f"warm_start: a network starts only a network (model 'mlp'); got a "
                         f"{warm_start.model!r} calibration for model {model!r}")
    cell = (default_position_cell_px(shape) if position_cell_px is None
            else int(position_cell_px))
    want = (tuple(shape), bool(use_position), cell if use_position else 0)
    have = (tuple(warm_start.shape), bool(warm_start.use_position),
            int(warm_start.position_cell_px) if warm_start.use_position else 0)
    if want != have:
        raise InputError(f"warm_start's network takes other inputs: frame, position inputs, "
                         f"position cell {have} against {want} asked for")
    return warm_start.onnx_bytes


def _checked_presses(reference: np.ndarray, frames: np.ndarray, ball_radius_mm: float,
                     mm_per_px: float, model: str, detect_edge: str, flat_fraction: float
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The reference, the frames and each press's ball radius (N,), mm, checked."""
    reference = check_array(reference, "reference", [("H", "W", 3)], dtype=np.uint8)
    frames = check_array(frames, "frames", [("N", *reference.shape)], dtype=np.uint8)
    if model not in ("lut", "mlp"):
        raise InputError(f"model must be 'lut' or 'mlp', got {model!r}")
    if len(frames) < 2:
        raise InputError(f"need at least 2 ball presses, got {len(frames)}")
    ball_mm = np.asarray(ball_radius_mm, np.float64)
    if ball_mm.ndim > 1 or (ball_mm.ndim == 1 and ball_mm.size != len(frames)):
        raise InputError(f"ball_radius_mm must be one radius or one per press ({len(frames)}), "
                         f"got shape {ball_mm.shape}")
    ball_mm = np.broadcast_to(ball_mm, (len(frames),))
    if not (np.all(np.isfinite(ball_mm) & (ball_mm > 0)) and mm_per_px > 0):
        raise InputError("ball_radius_mm and mm_per_px must be positive")
    if detect_edge not in ("contact", "colour"):
        raise InputError(f"detect_edge must be 'contact' or 'colour', got {detect_edge!r}")
    if not 0 < flat_fraction <= 1:
        raise InputError(f"flat_fraction must be in (0, 1], got {flat_fraction!r}")
    return reference, frames, ball_mm


def _press_circles(frames: np.ndarray, reference: np.ndarray, centers_px: np.ndarray | None,
             radii_px: np.ndarray | None, detect_edge: str) -> tuple[np.ndarray, np.ndarray]:
    """Contact-circle centres (N, 2) (a copy, refitted in place) and radii (N,), px, float64:
    the given ones checked, or detected when neither is given."""
    if centers_px is None and radii_px is None:
        centers_px, radii_px = detect_contact_circles(frames, reference, edge=detect_edge)
    elif centers_px is None or radii_px is None:
        raise InputError("give both centers_px and radii_px, or neither (to detect them)")
    centers = check_array(centers_px, "centers_px", [(len(frames), 2)], finite=True)
    radii = check_array(radii_px, "radii_px", [(len(frames),)], finite=True)
    return centers.astype(np.float64).copy(), radii.astype(np.float64)


def _pixel_sets(frames: np.ndarray, ref_inv: np.ndarray, markers: bool, blur_sigma: float,
                flat_fraction: float, seed: int, progress: bool
                ) -> tuple[list[np.ndarray], list[np.ndarray], list[np.ndarray]]:
    """Per press: the colour change (H, W, 3), the pixels off the markers (H, W) and the
    flat-gel sample, a `flat_fraction` of those drawn with `seed` (H, W)."""
    h, w = frames.shape[1:3]
    rng = np.random.default_rng(seed)
    changes = [colour_change(f, ref_inv, blur_sigma=blur_sigma) for f in
               tqdm(frames, desc="colour change", disable=not progress)]
    valid = [~marker_mask(f) if markers else np.ones((h, w), bool) for f in frames]
    background = [(rng.random((h, w)) < flat_fraction) & v for v in valid]
    return changes, valid, background


def _fit_round(cal: CalibrationData, samples: tuple[np.ndarray, ...], ref_colour: np.ndarray,
               fell_back: np.ndarray, *, flat_fraction: float, bins: int,
               lut_cells: tuple[int, int], hidden: int, epochs: int, seed: int,
               progress: bool, max_steps: int | None, init: bytes | None) -> np.ndarray:
    """Fit `cal`'s model, contact threshold and colour range to one round's labelled pixels
    (:func:`_training_samples`) in place; returns the position cells left on the
    colour-only table (`fell_back` when no cell tables are fitted)."""
    x_all, y_all, f_all, n_all, bg_mag, in_disc = samples
    h, w = cal.shape
    if bg_mag.size == 0:
        raise InputError(f"flat_fraction {flat_fraction:g} leaves no flat pixel (beyond "
                         "twice the contact radius) to train on; raise it")
    cal.contact_threshold = float(np.percentile(bg_mag, 99.9))
    cal.colour_lo = np.percentile(f_all, 0.1, axis=0).astype(np.float32)
    cal.colour_hi = np.percentile(f_all, 99.9, axis=0).astype(np.float32)
    if cal.model == "lut":
        cal.lut = fit_colour_lut(f_all, n_all, bins=bins, lo=cal.colour_lo,
                                 hi=cal.colour_hi)
        if tuple(lut_cells) != (1, 1):
            cal.cell_luts, fell_back = fit_cell_luts(
                x_all, y_all, f_all, n_all, (h, w), lut_cells, lo=cal.colour_lo,
                hi=cal.colour_hi, bins=bins, fallback=cal.lut)
    else:
        if cal.position_cell_px:     # each pixel's position cell, not the pixel
            ref_in, x_in, y_in = cell_position_inputs(ref_colour, cal.position_cell_px)
            inputs = mlp_inputs(f_all, ref_in[y_all, x_all], x_in[y_all, x_all],
                                y_in[y_all, x_all], (h, w), use_position=cal.use_position)
        else:
            inputs = mlp_inputs(f_all, ref_colour[y_all, x_all], x_all, y_all, (h, w),
                                use_position=cal.use_position)
        cal.table_lo, cal.table_hi = _table_range(f_all, in_disc, cal.colour_lo, cal.colour_hi)
        if init is not None:        # a warm start: a share of a cold round's steps
            cold = epochs * -(-len(inputs) // BATCH_SIZE)
            max_steps = max(1, int(MLP_WARM_FRACTION * min(cold, max_steps or cold)))
        cal.onnx_bytes = train_mlp(inputs, n_all, hidden=hidden, epochs=epochs,
                                   seed=seed, progress=progress, max_steps=max_steps,
                                   init=init)
    return fell_back


def _table_range(change: np.ndarray, in_disc: np.ndarray, lo: np.ndarray, hi: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
    """The colour range of a network's table: the 1st and 99th percentiles of the labelled
    contact pixels' colour change, widened to the flat samples' 0.1 and 99.9, within the
    calibration's range `lo`, `hi`. The calibration's own range reaches its darkest
    reference pixels' ratios (on the GelSlim 3.0, red up to 17 times the reference), so
    32 colour cells over it were too coarse where contacts lie."""
    t_lo, t_hi = np.array(lo, np.float32), np.array(hi, np.float32)
    parts = [(change[in_disc], 1.0), (change[~in_disc], 0.1)]
    got = [(np.percentile(c, p, axis=0), np.percentile(c, 100 - p, axis=0))
           for c, p in parts if len(c)]
    if got:
        t_lo = np.maximum(t_lo, np.min([g[0] for g in got], axis=0)).astype(np.float32)
        t_hi = np.minimum(t_hi, np.max([g[1] for g in got], axis=0)).astype(np.float32)
    bad = t_hi <= t_lo
    t_lo[bad], t_hi[bad] = np.asarray(lo, np.float32)[bad], np.asarray(hi, np.float32)[bad]
    return t_lo, t_hi


def _training_samples(changes: list[np.ndarray], valid: list[np.ndarray],
                      background: list[np.ndarray], centers: np.ndarray,
                      label_radii: np.ndarray, ball_px: np.ndarray
                      ) -> tuple[np.ndarray, ...]:
    """Labelled pixels of all presses: inside each label disc the ball's normal,
    beyond twice the contact radius (sampled) the flat normal; the ring
    between, where the gel leaves the ball in an unknown shape, is left out.

    Returns x (M,), y (M,), colour change (M, 3), in-plane normal (M, 2),
    the background colour-change magnitudes (for the contact threshold) and
    whether each pixel lies in a label disc (M,).
    """
    h, w = changes[0].shape[:2]
    xs, ys, feats, labels, bg_mag, disc = [], [], [], [], [], []
    for change, ok, bg, centre, rad, ball in zip(changes, valid, background, centers,
                                                 label_radii, ball_px, strict=True):
        gx, gy, inside = ball_gradients((h, w), centre, rad, ball)
        dx = np.arange(w)[None, :] - centre[0]
        dy = np.arange(h)[:, None] - centre[1]
        far = (dx * dx + dy * dy) > (2.0 * rad) ** 2
        sel = (inside & ok) | (far & bg)
        yy, xx = np.nonzero(sel)
        xs.append(xx)
        ys.append(yy)
        feats.append(change[sel])
        labels.append(normals_from_gradients(gx[sel], gy[sel])[:, :2])
        bg_mag.append(np.abs(change[far & bg]).max(axis=-1))
        disc.append(inside[sel])
    return (np.concatenate(xs), np.concatenate(ys), np.concatenate(feats),
            np.concatenate(labels), np.concatenate(bg_mag), np.concatenate(disc))
