"""Footprint and bevel contact read from the colour change of a frame.

A flat punch leaves the gel flat under its face: no colour change inside the
footprint, a ring of strong change at its steep edge. Photometric depth is
least reliable exactly there (the slopes exceed what the ball calibration
saw), so the footprint is found in the colour change itself: the enclosed
hole of the contact ring, a circle fitted to its boundary.

The bevel beside the indenter shows as a thin line once the gel reaches the
block land; :func:`bevel_score` measures a thin straight feature at the place
the block's geometry puts it.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from .._checks import InputError, check_array
from ._footprint import Footprint, _fit_circle

__all__ = ["bevel_score", "footprint_from_frame"]


def footprint_from_frame(mask: np.ndarray, mm_per_px: float, *, indenter_radius_mm: float,
                         radius_tol: float = 0.1) -> Footprint | None:
    """The flat footprint: the largest hole enclosed by the contact ring.

    Parameters
    ----------
    mask : (H, W) array_like of bool
        Contact mask of the frame (:func:`contact_mask`).
    mm_per_px : float
    indenter_radius_mm : float
        Radius a of the indenter.
    radius_tol : float, default 0.1
        Relative tolerance of :attr:`Footprint.radius_ok`.

    Returns
    -------
    Footprint or None
        None when the contact does not enclose a hole (no flat punch in view,
        or one cut open by the image edge). ``depth_mm`` is NaN (not measured
        here); ``cut_by_edge`` says whether the fitted circle leaves the image.

    Raises
    ------
    ShapeError
        For a mask that is not 2-D.
    """
    m = check_array(mask, "mask", [("H", "W")]).astype(bool)
    filled = ndimage.binary_fill_holes(m)
    holes, n = ndimage.label(filled & ~m)
    if n == 0:
        return None
    sizes = ndimage.sum(np.ones_like(holes), holes, index=np.arange(1, n + 1))
    k = int(np.argmax(sizes)) + 1
    hole = holes == k
    if sizes[k - 1] < 50:
        return None
    edge = hole & ~ndimage.binary_erosion(hole)
    ys, xs = np.nonzero(edge)
    if xs.size < 8:
        return None
    cx, cy, r = _fit_circle(np.column_stack([xs, ys]).astype(np.float64))
    r = r + 0.5          # boundary pixels are the hole's outermost: the edge lies half a pixel out
    rms = float(np.sqrt(np.mean((np.hypot(xs - cx, ys - cy) - (r - 0.5)) ** 2)))
    h, w = m.shape
    cut = bool(cx - r < 0 or cy - r < 0 or cx + r > w - 1 or cy + r > h - 1)
    r_mm = r * mm_per_px
    return Footprint(center_px=np.array([cx, cy]), radius_px=float(r), radius_mm=float(r_mm),
                     depth_mm=float("nan"), fit_rms_px=rms, n_edge_points=int(xs.size),
                     cut_by_edge=cut,
                     radius_ok=bool(abs(r_mm - indenter_radius_mm) <= radius_tol
                                    * indenter_radius_mm))


def bevel_score(frame: np.ndarray, reference: np.ndarray | None, centre_px: tuple[float, float],
                mm_per_px: float, *,
                offset_mm: float, angle_deg: float = 0.0, length_mm: float = 2.4,
                search_mm: float = 0.6, blur_mm: float = 0.15, at_mm: float = 0.1) -> float:
    """Strength of a thin straight line where the bevel edge lies.

    Parameters
    ----------
    frame : (H, W, 3) array_like of uint8
    reference : (H, W, 3) array_like of uint8, optional
        The no-contact frame: its static texture (dust, scratches, edges of
        the gel) is removed before the line is looked for.
    centre_px : (x, y)
        Indenter axis (footprint centre), px.
    mm_per_px : float
    offset_mm, angle_deg, length_mm : float
        Bevel edge: distance from the axis, direction (0 = +x along the
        columns, 90 = +y down the rows), length; the line runs across that
        direction.
    search_mm : float, default 0.6
        The background statistics are taken within this (at least 15 px) of
        `offset_mm` along the direction, leaving out the line's own
        neighbourhood (0.25 mm or 3 px).
    blur_mm : float, default 0.15
        Scale of the high-pass that removes the smooth shading of the bulge
        (at least 1.5 px).
    at_mm : float, default 0.1
        The line must peak within this of `offset_mm` (the footprint centre
        is known to a fraction of a pixel; a fixed place keeps the false-alarm
        rate of a peak search away).

    Returns
    -------
    score : float
        Peak of the line profile near `offset_mm` above the background's
        median, in robust standard deviations (about 0 to 4 without a line; NaN when
        the region leaves the image).

    Notes
    -----
    The colour change (frame - reference) is high-passed (minus its Gaussian blur, summed
    absolute over channels), averaged along the line direction in 1 px bins
    across it, and the peak bin is compared with the spread of the bins.
    """
    f = check_array(frame, "frame", [("H", "W", 3)]).astype(np.float32)
    if reference is not None:
        f = f - check_array(reference, "reference", [f.shape]).astype(np.float32)
    h, w = f.shape[:2]
    t = np.deg2rad(angle_deg)
    s = float(mm_per_px)
    blur_px = max(1.5, blur_mm / s)
    at_mm = max(at_mm, 1.01 * s)
    search_mm = max(search_mm, 15 * s)
    guard_mm = max(0.25, 3 * s)          # the line's own width, kept out of the background
    cx, cy = float(centre_px[0]), float(centre_px[1])
    bx, by = cx + offset_mm / s * np.cos(t), cy + offset_mm / s * np.sin(t)
    half = int(np.ceil((search_mm + 0.5 * length_mm) / s + 3 * blur_px)) + 2
    r0, r1 = int(np.floor(by - half)), int(np.ceil(by + half)) + 1
    c0, c1 = int(np.floor(bx - half)), int(np.ceil(bx + half)) + 1
    if r0 < 0 or c0 < 0 or r1 > h or c1 > w:
        return float("nan")
    roi = f[r0:r1, c0:c1]
    hp = np.abs(roi - ndimage.gaussian_filter(roi, (blur_px, blur_px, 0))).sum(axis=2)
    rows, cols = np.mgrid[r0:r1, c0:c1]
    dx, dy = (cols - cx) * s, (rows - cy) * s
    u = dx * np.cos(t) + dy * np.sin(t) - offset_mm
    v = -dx * np.sin(t) + dy * np.cos(t)
    sel = (np.abs(u) <= search_mm) & (np.abs(v) <= 0.4 * length_mm)
    if not sel.any():
        raise InputError("the bevel search region is empty: check bevel_length_mm and the scale")
    bins = np.round(u[sel] / s).astype(np.int64)
    lo = int(bins.min())
    sums = np.bincount(bins - lo, hp[sel])
    counts = np.bincount(bins - lo)
    ok = counts > 0
    prof = sums[ok] / counts[ok]
    centre = (np.arange(counts.size)[ok] + lo) * s
    bg = prof[np.abs(centre) > guard_mm]
    med = float(np.median(bg))
    mad = 1.4826 * float(np.median(np.abs(bg - med)))
    near = np.abs(centre) <= at_mm
    return float((prof[near].max() - med) / max(mad, 1e-6))
