"""The accuracy report of a photometric calibration: what ``optics calibrate`` prints and
saves after every calibration."""

from __future__ import annotations

import math

import numpy as np

from .._checks import InputError
from ._ball import ball_press_metrics
from ._reconstructor import DepthReconstructor

__all__ = ["calibration_accuracy", "edge_cut", "holdout_presses", "max_tilt_deg"]


def edge_cut(centers_px: np.ndarray, radii_px: np.ndarray, shape: tuple[int, int]
             ) -> np.ndarray:
    """Whether each contact disc reaches past the image edge.

    Parameters
    ----------
    centers_px : (N, 2) float ndarray
        Circle centres (x, y), px.
    radii_px : (N,) float ndarray
        Circle radii, px.
    shape : (H, W)
        Image size.

    Returns
    -------
    cut : (N,) bool ndarray
        True where part of the disc lies outside the pixel centres 0..W-1,
        0..H-1: its rim, and so its steepest slopes, are not in the frame.
    """
    c = np.asarray(centers_px, np.float64).reshape(-1, 2)
    r = np.asarray(radii_px, np.float64).reshape(-1)
    h, w = shape
    return ((c[:, 0] - r < 0) | (c[:, 0] + r > w - 1) | (c[:, 1] - r < 0)
            | (c[:, 1] + r > h - 1))


def holdout_presses(centers_px: np.ndarray, radii_px: np.ndarray,
                    ball_radius_px: np.ndarray, shape: tuple[int, int],
                    share: float = 0.25) -> np.ndarray:
    """Presses held out of training for the accuracy report, stratified over the pad and
    the ball sizes.

    Only presses the report can score are held out: those whose contact disc lies
    inside the image (:func:`edge_cut`; the others are always trained on). Each ball
    size's such presses are ordered along the pad (in bands of a third of its height,
    left to right, alternate bands right to left), and every ``1 / share``-th of them is
    held out starting from the middle of the first stride, so the held-out presses
    spread over the pad and every ball size with two or more such presses has at least
    one.

    Parameters
    ----------
    centers_px : (N, 2) float ndarray
        Contact-circle centres (x, y), px.
    radii_px : (N,) float ndarray
        Contact-circle radii, px.
    ball_radius_px : (N,) float ndarray
        Each press's ball radius (the strata).
    shape : (H, W)
        Image size.
    share : float, default 0.25
        The share held out, 0 < share < 1.

    Returns
    -------
    held_out : (N,) bool ndarray

    Raises
    ------
    InputError
        For a share outside (0, 1) or arrays of different lengths.
    """
    if not 0 < share < 1:
        raise InputError(f"the held-out share must lie between 0 and 1, got {share!r}")
    c = np.asarray(centers_px, np.float64).reshape(-1, 2)
    ball = np.asarray(ball_radius_px, np.float64).reshape(-1)
    r = np.asarray(radii_px, np.float64).reshape(-1)
    if ball.size != len(c) or r.size != len(c):
        raise InputError(f"{len(c)} centres, {r.size} radii and {ball.size} ball radii: one "
                         "each per press")
    inside = ~edge_cut(c, r, shape)
    h, _ = shape
    band = np.clip((c[:, 1] * 3 // max(h, 1)).astype(int), 0, 2)
    x = np.where(band % 2 == 0, c[:, 0], -c[:, 0])        # a snake over the pad
    held = np.zeros(len(c), bool)
    stride = 1.0 / share
    for b in np.unique(ball):
        idx = np.flatnonzero((ball == b) & inside)
        if idx.size < 2:
            continue
        order = idx[np.lexsort((x[idx], band[idx]))]
        picks = np.arange(stride / 2 - 0.5, order.size, stride).astype(int)
        held[order[np.unique(np.clip(picks, 0, order.size - 1))]] = True
    return held


def _inner_cap(height_px: np.ndarray, d: np.ndarray, radius: float, ball_px: float,
               fraction: float = 0.8) -> float:
    """The inner cap's depth over the ball's, less one: the height at the disc's centre
    (mean within 1.5 px) above the median on the circle at `fraction` of the radius,
    against the sphere's drop there, R - sqrt(R^2 - (fraction r)^2). Inside the contact
    the ball surely touches the gel, so the rim's unknown shape does not enter. `d`: each
    pixel's distance from the disc's centre, px (:func:`_distances`)."""
    rho = fraction * radius
    middle = d <= 1.5
    ring = np.abs(d - rho) <= 1.0
    if not middle.any() or not ring.any():
        return math.nan
    drop = ball_px - math.sqrt(max(ball_px * ball_px - rho * rho, 0.0))
    return float((height_px[middle].mean() - np.median(height_px[ring])) / drop - 1.0)


def max_tilt_deg(radius_px: np.ndarray | float, ball_radius_px: np.ndarray | float
                 ) -> np.ndarray:
    """Tilt of a sphere of radius R at distance r from its axis, degrees:
    ``atan(r / sqrt(R^2 - r^2))`` (the slope at a contact disc's rim)."""
    r = np.asarray(radius_px, np.float64)
    big = np.asarray(ball_radius_px, np.float64)
    return np.degrees(np.arctan2(r, np.sqrt(np.maximum(big * big - r * r, 0.0))))


def _distances(shape: tuple[int, int], centre: np.ndarray) -> np.ndarray:
    """(H, W) distance of each pixel from `centre` (x, y), px."""
    yy, xx = np.mgrid[0:shape[0], 0:shape[1]]
    return np.hypot(xx - centre[0], yy - centre[1])


def _deepest_point(height_px: np.ndarray, d: np.ndarray, radius: float,
                   ball_px: float) -> float:
    """Reconstructed cap depth over the ball's, less one: the height at the disc's deepest
    point above the median height on its rim circle, against R - sqrt(R^2 - r^2). `d`:
    each pixel's distance from the disc's centre, px (:func:`_distances`)."""
    inside = d <= radius
    ring = np.abs(d - radius) <= 1.0
    if not inside.any() or not ring.any():
        return math.nan
    cap = ball_px - math.sqrt(max(ball_px * ball_px - radius * radius, 0.0))
    return float((height_px[inside].max() - np.median(height_px[ring])) / cap - 1.0)


def calibration_accuracy(recon: DepthReconstructor, frames: np.ndarray,
                         centers_px: np.ndarray, radii_px: np.ndarray,
                         ball_radius_px: np.ndarray, *, trained: np.ndarray,
                         label_fraction: float, circles: str = "given",
                         edge: str | None = None) -> dict:
    """Accuracy of a calibration on its ball presses, by ball size.

    Held-out presses (not `trained`) are scored; when every press was trained on, the
    training presses are, and the report says it is in sample. Presses whose disc
    reaches past the image edge are left out and counted.

    Parameters
    ----------
    recon : DepthReconstructor
        The calibration under test (its own reference).
    frames : (N, H, W, 3) uint8 ndarray
        All ball presses, BGR.
    centers_px : (N, 2) float ndarray
        Contact-circle centres (x, y), px.
    radii_px : (N,) float ndarray
        Circle radii, px: the contact's, or the colour edge's (``edge``).
    ball_radius_px : (N,) float ndarray
        Each press's ball radius, px.
    trained : (N,) bool ndarray
        The presses the calibration was trained on.
    label_fraction : float
        The fraction of each radius trained on: the slope range covered is
        read at ``label_fraction * radius`` of the training presses.
    circles : {'given', 'detected'}, default 'given'
        Where the circles came from (written into the report).
    edge : {'contact', 'colour'}, optional
        What the radii mark. ``'contact'`` (given circles; circles detected at
        the contact edge, :func:`locate_contact_edge`): they are scored as
        they are. ``'colour'`` (circles detected at the colour edge, outside
        the contact): scored at ``label_fraction`` of themselves, the contact
        the calibration assumed. Default: ``'contact'`` for given circles,
        ``'colour'`` for detected ones (the behaviour before the contact edge).

    Returns
    -------
    report : dict
        JSON-ready: ``in_sample`` (bool), ``circles``, ``edge``, ``label_fraction``, and
        ``balls``, one entry per ball radius (mm-free, px): ``ball_radius_px``,
        ``n_scored``, ``n_edge_cut`` (left out), ``normal_angle_deg`` (median
        over presses of the mean normal-angle error inside 0.9 of the radius),
        ``deepest_point`` (median relative error of the cap depth: reconstructed
        height at the deepest point above the rim, over R - sqrt(R^2 - r^2)),
        ``inner_cap`` (the same for the centre against 0.8 of the radius, where
        the ball surely touches: :func:`_inner_cap`), ``normal_angle_08_deg``
        (as ``normal_angle_deg``, inside 0.8 of the radius), ``presses`` (the
        scored presses' indices),
        ``trained_tilt_deg`` (the steepest slope the training labels reached,
        at ``label_fraction`` of the radius) and ``rim_tilt_deg`` (the steepest
        slope of the scored presses' rims), ``shape_rms_px``,
        ``fitted_radius_px`` and ``fitted_radius_std_px`` (means over the
        scored presses, as :func:`evaluate_ball_presses` gives them, inside 0.9
        of the radius); None where nothing is scored.
    """
    frames = np.asarray(frames)
    centers = np.asarray(centers_px, np.float64)
    radii = np.asarray(radii_px, np.float64)
    if edge is None:
        edge = "colour" if circles == "detected" else "contact"
    if edge not in ("contact", "colour"):
        raise InputError(f"edge must be 'contact' or 'colour', got {edge!r}")
    colour_edge = edge == "colour"
    if colour_edge:
        # the colour edge lies outside the contact: the calibration took label_fraction of
        # it as the contact, and so does its score
        radii = label_fraction * radii
    ball = np.broadcast_to(np.asarray(ball_radius_px, np.float64), radii.shape)
    trained = np.asarray(trained, bool)
    in_sample = bool(trained.all())
    scored = trained if in_sample else ~trained
    cut = edge_cut(centers, radii, frames.shape[1:3])
    mm = recon.calibration.mm_per_px
    balls = []
    for b in np.unique(ball):
        same = ball == b
        use = np.flatnonzero(same & scored & ~cut)
        entry = {"ball_radius_px": float(b), "n_scored": int(use.size),
                 "n_edge_cut": int(np.count_nonzero(same & scored & cut)),
                 "trained_tilt_deg": (float(max_tilt_deg(
                     radii[same & trained] * (1.0 if colour_edge else label_fraction),
                     b).max())
                                      if np.any(same & trained) else None),
                 "presses": [int(i) for i in use],
                 "normal_angle_deg": None, "normal_angle_08_deg": None,
                 "deepest_point": None, "inner_cap": None, "rim_tilt_deg": None,
                 "shape_rms_px": None, "fitted_radius_px": None, "fitted_radius_std_px": None}
        if use.size:
            per, inner, deepest, caps = [], [], [], []
            for i in use:       # each press reconstructed once, for every measure
                gx, gy = recon.gradients(frames[i])
                height_px = recon(frames[i]) / mm
                per.append(ball_press_metrics(gx, gy, height_px, centers[i], 0.9 * radii[i],
                                              float(b)))
                inner.append(ball_press_metrics(gx, gy, height_px, centers[i],
                                                0.8 * radii[i], float(b)).normal_angle_deg)
                d = _distances(height_px.shape, centers[i])
                deepest.append(_deepest_point(height_px, d, radii[i], float(b)))
                caps.append(_inner_cap(height_px, d, radii[i], float(b)))
            fitted = np.array([p.fitted_radius_px for p in per])
            entry["normal_angle_deg"] = float(np.median([p.normal_angle_deg for p in per]))
            entry["normal_angle_08_deg"] = float(np.median(inner))
            entry["deepest_point"] = float(np.nanmedian(deepest))
            entry["inner_cap"] = float(np.nanmedian(caps))
            entry["rim_tilt_deg"] = float(max_tilt_deg(radii[use], b).max())
            entry["shape_rms_px"] = float(np.mean([p.shape_rms_px for p in per]))
            entry["fitted_radius_px"] = float(fitted.mean())
            entry["fitted_radius_std_px"] = float(fitted.std())
        balls.append(entry)
    return {"in_sample": in_sample, "circles": circles, "edge": edge,
            "label_fraction": float(label_fraction),
            "balls": balls}
