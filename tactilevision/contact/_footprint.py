"""The flat indenter's footprint in a height map: plateau, circle fit, which indenter."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage
from skimage.measure import CircleModel

from .._checks import InputError, check_array

__all__ = ["Footprint", "fit_footprint", "nearest_indenter"]


@dataclass(frozen=True)
class Footprint:
    """A circle fitted to the edge of the flat footprint of a cylindrical indenter.

    Attributes
    ----------
    center_px : (2,) float64 ndarray
        (x, y) = (column, row) of the circle centre, px.
    radius_px, radius_mm : float
        Fitted radius.
    depth_mm : float
        Median height inside 0.8 of the radius (the plateau), mm.
    fit_rms_px : float
        RMS distance of the edge points from the circle, px.
    n_edge_points : int
    cut_by_edge : bool
        The circle reaches outside the image (the pad edge cuts the
        footprint).
    radius_ok : bool
        `radius_mm` within `radius_tol` of the indenter radius.
    """

    center_px: np.ndarray
    radius_px: float
    radius_mm: float
    depth_mm: float
    fit_rms_px: float
    n_edge_points: int
    cut_by_edge: bool
    radius_ok: bool


def _fit_circle(pts: np.ndarray) -> tuple[float, float, float]:
    """(xc, yc, r) by scikit-image's CircleModel (the >= 0.26 API, else the older one)."""

    if hasattr(CircleModel, "from_estimate"):
        model = CircleModel.from_estimate(pts)
        ok = bool(model)
        params = (*model.center, model.radius) if ok else ()
    else:  # scikit-image < 0.26
        model = CircleModel()
        ok = bool(model.estimate(pts))
        params = tuple(model.params) if ok else ()
    if not ok or not np.all(np.isfinite(params)):
        raise InputError("the footprint's edge does not fit a circle")
    return float(params[0]), float(params[1]), float(params[2])


def _fit_circle_trimmed(pts: np.ndarray, *, floor_px: float = 1.5,
                        rounds: int = 3) -> tuple[float, float, float, np.ndarray]:
    """(xc, yc, r, kept) by :func:`_fit_circle`, refitted without outlying edge points.

    A blob of colour change reaching into the footprint (a renderer's shadow,
    a speck of dust) makes a notch whose boundary pixels sit far inside the
    circle and pull the algebraic fit in. Points farther from the circle than
    ``max(floor_px, 3 x 1.4826 MAD)`` of the residuals are dropped and the
    circle refitted, up to `rounds` times (while at least 8 points remain).
    """
    keep = np.ones(len(pts), bool)
    xc, yc, r = _fit_circle(pts)
    for _ in range(rounds):
        res = np.hypot(pts[:, 0] - xc, pts[:, 1] - yc) - r
        med = float(np.median(res[keep]))
        tol = max(floor_px, 3.0 * 1.4826 * float(np.median(np.abs(res[keep] - med))))
        new = np.abs(res) <= tol
        if new.sum() < 8 or np.array_equal(new, keep):
            break
        keep = new
        xc, yc, r = _fit_circle(pts[keep])
    return xc, yc, r, keep


def fit_footprint(height_mm: np.ndarray, mm_per_px: float, *, indenter_radius_mm: float,
                  plateau_fraction: float = 0.9, radius_tol: float = 0.1) -> Footprint:
    """Fit a circle to the footprint of a flat-ended cylinder in a height map.

    Parameters
    ----------
    height_mm : (H, W) array_like of float
        Height map, mm, positive into the gel (as
        :class:`~tactilevision.optics.DepthReconstructor` returns).
    mm_per_px : float
        Image scale, > 0.
    indenter_radius_mm : float
        Radius a of the indenter, > 0.
    plateau_fraction : float, default 0.9
        The footprint is the connected region, around the deepest point, of
        heights above this fraction of the plateau depth. Outside a flat punch
        the surface falls steeply (for a half-space as (2 w / pi)
        arcsin(a / r)), so 0.9 places the edge 1.2% outside r = a.
    radius_tol : float, default 0.1
        Relative tolerance of :attr:`Footprint.radius_ok`.

    Returns
    -------
    Footprint

    Raises
    ------
    ShapeError
        For a height map that is not 2-D or has NaNs.
    InputError
        For non-positive scale or radius, a map with no depth (max <= 0), or
        a footprint with fewer than 8 edge points.

    Notes
    -----
    The plateau depth is first taken as the 99th percentile of the heights
    (robust to a few noisy pixels), the region above ``plateau_fraction`` of
    it is labelled and its component holding the deepest pixels is kept; its
    boundary pixels (the region minus its erosion) are fitted with a circle
    by scikit-image's ``CircleModel`` (algebraic least squares); the depth is
    the median height inside 0.8 of the fitted radius, then the threshold is
    recomputed from it and the fit repeated once.
    """

    z = check_array(height_mm, "height_mm", [("H", "W")], dtype=np.number,
                    finite=True).astype(np.float64)
    for name, v in (("mm_per_px", mm_per_px), ("indenter_radius_mm", indenter_radius_mm)):
        if not (np.isfinite(v) and v > 0):
            raise InputError(f"{name} must be positive, got {v!r}")
    depth = float(np.percentile(z, 99))
    if not depth > 0:
        raise InputError("the height map has no indentation (its 99th percentile is "
                         f"{depth:.3g} mm)")
    rows, cols = np.indices(z.shape)
    for _ in range(2):
        mask = z > plateau_fraction * depth
        labels, n = ndimage.label(mask)
        if n == 0:
            raise InputError("no footprint found in the height map")
        sizes = ndimage.sum(mask, labels, index=np.arange(1, n + 1))
        region = labels == (1 + int(np.argmax(sizes)))
        edge = region & ~ndimage.binary_erosion(region)
        ys, xs = np.nonzero(edge)
        if xs.size < 8:
            raise InputError(f"the footprint has only {xs.size} edge pixels: too small to fit a "
                             "circle")
        pts = np.column_stack([xs, ys]).astype(np.float64)
        xc, yc, r = _fit_circle(pts)
        inside = (cols - xc) ** 2 + (rows - yc) ** 2 <= (0.8 * r) ** 2
        if not inside.any():
            break
        depth = float(np.median(z[inside]))
    # edge pixels sit half a pixel inside the true boundary on average
    r_px = r + 0.5
    resid = np.hypot(pts[:, 0] - xc, pts[:, 1] - yc) - r
    h, w = z.shape
    cut = xc - r_px < 0 or yc - r_px < 0 or xc + r_px > w - 1 or yc + r_px > h - 1
    r_mm = r_px * mm_per_px
    return Footprint(center_px=np.array([xc, yc]), radius_px=r_px, radius_mm=r_mm,
                     depth_mm=depth, fit_rms_px=float(np.sqrt(np.mean(resid**2))),
                     n_edge_points=int(xs.size), cut_by_edge=bool(cut),
                     radius_ok=bool(abs(r_mm / indenter_radius_mm - 1) <= radius_tol))


def nearest_indenter(depth_mm: float, depths_mm: tuple[float, ...] | np.ndarray) -> int:
    """Index of the gauge-block depth nearest to a measured footprint depth.

    Parameters
    ----------
    depth_mm : float
        Plateau depth of a footprint (optical, so approximate), mm.
    depths_mm : (K,) sequence of float
        Gauge-block depths w0, indenter order.

    Returns
    -------
    index : int

    Raises
    ------
    InputError
        For an empty `depths_mm` or a non-finite depth.
    """
    d = np.asarray(depths_mm, dtype=np.float64)
    if d.size == 0 or not np.isfinite(depth_mm):
        raise InputError(f"cannot match depth {depth_mm!r} to gauge depths {list(d)}")
    return int(np.argmin(np.abs(d - depth_mm)))
