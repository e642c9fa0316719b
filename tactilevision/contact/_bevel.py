"""Footprint and bevel contact read from the colour change of a frame.

A flat punch leaves the gel flat under its face: no colour change inside the
footprint, a ring of strong change at its steep edge. Photometric depth is
least reliable exactly there (the slopes exceed what the ball calibration
saw), so the footprint is found in the colour change itself: the enclosed
hole of the contact ring, a circle fitted to its boundary.

A bevel mark with no vernier (``bevel_angle_deg = 0``) shows as a thin line
once the gel reaches the block land; :func:`bevel_score` measures a thin
straight feature at the place the block's geometry puts it. A machined bevel
ridge is read by :mod:`tactilevision.contact._vernier` instead.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from .._checks import check_array
from ._footprint import Footprint, _fit_circle_trimmed
from ._vernier import BevelGeometry, bevel_profile

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

    Notes
    -----
    The hole's outer boundary pixels (islands of colour change inside it
    filled first) are fitted with a circle (scikit-image's
    ``CircleModel``), then refitted without the points farther than
    max(1.5 px, 3 robust sd) from it: a blob of colour change reaching into
    the footprint (Taxim draws one beside the flat punch) otherwise pulls the
    fitted radius in by 10 %.
    """
    m = check_array(mask, "mask", [("H", "W")]).astype(bool)
    filled = ndimage.binary_fill_holes(m)
    holes, n = ndimage.label(filled & ~m)
    if n == 0:
        return None
    sizes = ndimage.sum(np.ones_like(holes), holes, index=np.arange(1, n + 1))
    k = int(np.argmax(sizes)) + 1
    if sizes[k - 1] < 50:
        return None
    # specks of colour change inside the footprint (a renderer's shading line, sensor
    # noise above the threshold) are islands in the hole: filled, so that only the ring's
    # inner edge is fitted (on a Taxim frame a line of specks across the flat face pulled
    # the fitted radius in from 2.40 to 2.10 mm)
    hole = ndimage.binary_fill_holes(holes == k)
    edge = hole & ~ndimage.binary_erosion(hole)
    ys, xs = np.nonzero(edge)
    if xs.size < 8:
        return None
    cx, cy, r, kept = _fit_circle_trimmed(np.column_stack([xs, ys]).astype(np.float64))
    r = r + 0.5          # boundary pixels are the hole's outermost: the edge lies half a pixel out
    xs, ys = xs[kept], ys[kept]
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
                mm_per_px: float, *, offset_mm: float, direction_deg: float = 0.0,
                length_mm: float = 2.4, search_mm: float = 0.3, reach_mm: float = 0.8) -> float:
    """Signal-to-noise ratio of a thin straight mark where the bevel's edge lies.

    A matched filter over widths and offsets: the colour change is averaged
    along the mark's line into a profile across it
    (:func:`~tactilevision.contact.bevel_profile`, clipped to the image), and
    the profile is fitted with a smooth background (a quadratic: the press's
    own shading) plus a Gaussian line and its derivative (a dip, a bump or a
    light-dark pair of any colours) of sd 0.8, 1.5 or 3 px centred anywhere
    within `search_mm` of the nominal line.

    Parameters
    ----------
    frame : (H, W, 3) array_like of uint8
    reference : (H, W, 3) array_like of uint8, optional
        The no-contact frame (static texture removed); None compares with a
        flat grey frame.
    centre_px : (x, y)
        Indenter axis (footprint centre), px.
    mm_per_px : float
    offset_mm, direction_deg, length_mm : float
        The mark: distance from the axis, direction (0 = +x along the
        columns, 90 = +y down the rows), length along the line.
    search_mm : float, default 0.3
        How far off the nominal line the mark may lie.
    reach_mm : float, default 0.8
        Half-length of the profile across the line: the background is what
        lies beyond the mark within it.

    Returns
    -------
    score : float
        ``sqrt(drop in residual sum of squares / residual variance)``, the
        residual variance corrected for its correlation along the profile:
        about 3 to 8 with no mark (the best of many widths and offsets over
        noise), far above with one. 0.0 when the line is not in the image.

    Raises
    ------
    ShapeError
        For frames that are not (H, W, 3) or differ in shape.
    """
    f = check_array(frame, "frame", [("H", "W", 3)])
    ref = np.zeros_like(f) if reference is None else check_array(reference, "reference",
                                                                 [f.shape])
    s = float(mm_per_px)
    geom = BevelGeometry(offset_mm=offset_mm, direction_deg=direction_deg, length_mm=length_mm)
    prof = bevel_profile(f, ref, centre_px, s, geom, reach_px=max(reach_mm / s, 12.0))
    if prof.coverage < 0.3:
        return 0.0
    return _line_snr(prof.u_px, prof.colour, max(search_mm / s, 2.0))


def _background_basis(u: np.ndarray) -> np.ndarray:
    """(n, 3) basis of the smooth background under a mark's profile: a quadratic in u."""
    scale = max(float(np.abs(u).max()), 1.0)
    return np.stack([np.ones_like(u), u / scale, (u / scale) ** 2], axis=1)


def _line_snr(u: np.ndarray, R: np.ndarray, search_px: float) -> float:
    """Best matched-filter SNR of a line (and its derivative) over widths and offsets."""
    B0 = _background_basis(u)
    c0, *_ = np.linalg.lstsq(B0, R, rcond=None)
    rss0 = float(np.sum((R - B0 @ c0) ** 2))
    best = (np.inf, None)
    step = float(u[1] - u[0])
    for sd in (0.8, 1.5, 3.0):
        for m in np.arange(-search_px, search_px + 1e-9, max(step, 0.25 * sd)):
            g = np.exp(-0.5 * ((u - m) / sd) ** 2)
            B = np.column_stack([B0, g, g * (u - m) / sd])
            coef, *_ = np.linalg.lstsq(B, R, rcond=None)
            r = R - B @ coef
            rss = float(np.sum(r * r))
            if rss < best[0]:
                best = (rss, r)
    rss1, resid = best
    dof = max(R.size - 5 * R.shape[1], 1)
    sigma2 = rss1 / dof
    rho = 0.0
    for lag in range(1, round(3.0 / step) + 1):
        a, b = resid[:-lag], resid[lag:]
        den = float(np.sqrt(np.sum(a * a) * np.sum(b * b)))
        r_lag = float(np.sum(a * b)) / den if den > 0 else 0.0
        if r_lag <= 0:
            break
        rho += r_lag
    return float(np.sqrt(max(rss0 - rss1, 0.0) / max(sigma2 * (1.0 + 2.0 * rho), 1e-12)))
