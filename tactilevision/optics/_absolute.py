"""Absolute depth: heights against the undeformed gel, no offset removed.

The shape metrics of :mod:`._ball` subtract the unknown offset between a
reconstruction and the truth before comparing them. The functions here do
not: a height map (mm, positive into the gel, the undeformed gel at 0) is
compared pixel by pixel with a true height map, and a ball's cap is fitted
against the gel level read from the far field, so that errors of the zero
level, background tilts and bowls, and depths lost at saturated slopes all
show.

- :func:`fit_ball_cap`: depth d and radius R of the spherical cap
  ``z = d - (R - sqrt(R^2 - r^2))`` fitted to the heights inside a contact,
  above the gel level of an annulus beyond it.
- :func:`absolute_depth_metrics`: deepest-point, profile and background
  errors of a height map against its truth.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy.ndimage import distance_transform_edt
from scipy.optimize import least_squares

from .._checks import InputError, check_array, check_positive

__all__ = ["AbsoluteDepthMetrics", "BallCapFit", "absolute_depth_metrics", "fit_ball_cap"]

GelLevel = Literal["far_field", "zero"]


@dataclass(frozen=True)
class BallCapFit:
    """A spherical cap fitted to a height map above the gel level.

    Attributes
    ----------
    depth_mm : float
        d: the cap's deepest point below the gel level, mm (positive into
        the gel).
    radius_mm : float
        R: the sphere's radius, mm (the given one when it was fixed).
    centre_px : tuple of float
        (x = column, y = row) of the cap's axis, px (the given centre when
        it was not fitted).
    gel_level_mm : float
        The level subtracted before fitting, mm on the height map's own
        scale: the median of the far-field annulus, 0 for
        ``gel_level='zero'``, or the given number.
    rim_height_mm : float
        The fitted cap's height at the given contact radius,
        ``d - (R - sqrt(R^2 - a^2))``, mm: how far the contact's rim lies
        below the gel level (0 for a gel that does not sink in around the
        contact; NaN when ``a >= R``).
    rms_mm : float
        RMS residual of the fit, mm.
    n_pixels : int
        Pixels fitted.
    n_far_field : int
        Pixels of the far-field annulus (0 unless ``gel_level='far_field'``).
    radius_fixed : bool
        Whether R was given rather than fitted.
    """

    depth_mm: float
    radius_mm: float
    centre_px: tuple[float, float]
    gel_level_mm: float
    rim_height_mm: float
    rms_mm: float
    n_pixels: int
    n_far_field: int
    radius_fixed: bool


@dataclass(frozen=True)
class AbsoluteDepthMetrics:
    """Errors of a height map against its truth, no offset removed (mm).

    Attributes
    ----------
    deepest_mm : float
        Largest reconstructed height inside the contact, mm.
    true_deepest_mm : float
        Largest true height inside the contact, mm.
    deepest_error_mm : float
        ``deepest_mm - true_deepest_mm``: negative when the reconstruction
        is too shallow.
    deepest_error_rel : float
        ``deepest_error_mm / true_deepest_mm`` (NaN when the true maximum is
        not positive).
    profile_rms_mm, profile_mean_mm : float
        RMS and mean of ``height - truth`` over the contact mask.
    background_rms_mm, background_mean_mm, background_max_mm : float
        RMS, mean and largest absolute value of ``height - truth`` over the
        background mask (by default where the truth is 0, so these are
        those of the height itself: the undeformed gel should read 0).
    n_contact, n_background : int
        Pixels in the two masks.
    """

    deepest_mm: float
    true_deepest_mm: float
    deepest_error_mm: float
    deepest_error_rel: float
    profile_rms_mm: float
    profile_mean_mm: float
    background_rms_mm: float
    background_mean_mm: float
    background_max_mm: float
    n_contact: int
    n_background: int


def _mask(x: object, name: str, shape: tuple[int, ...]) -> np.ndarray:
    m = check_array(x, name, [shape], dtype=np.bool_)
    if not m.any():
        raise InputError(f"{name} selects no pixel: give at least one True pixel")
    return m


def _far_field_level(height: np.ndarray, cx: float, cy: float, a_px: float,
                     far_field: tuple[float, float]) -> tuple[float, int]:
    inner, outer = far_field
    h, w = height.shape
    yy, xx = np.ogrid[0:h, 0:w]
    r2 = (xx - cx) ** 2 + (yy - cy) ** 2
    ring = (r2 >= (inner * a_px) ** 2) & (r2 <= (outer * a_px) ** 2)
    n = int(ring.sum())
    if n == 0:
        raise InputError(f"the far-field annulus ({inner:g} to {outer:g} contact radii, "
                         f"{inner * a_px:.1f} to {outer * a_px:.1f} px from ({cx:.1f}, "
                         f"{cy:.1f})) has no pixel inside the {w} x {h} image: widen "
                         "far_field or give gel_level as a number")
    return float(np.median(height[ring])), n


def fit_ball_cap(height_mm: np.ndarray, mm_per_px: float,
                 center_px: tuple[float, float] | np.ndarray, contact_radius_px: float, *,
                 ball_radius_mm: float | None = None,
                 gel_level: GelLevel | float = "far_field", fit_fraction: float = 0.9,
                 far_field: tuple[float, float] = (1.5, 3.0), fit_centre: bool = True
                 ) -> BallCapFit:
    """Depth and radius of a ball's cap against the far-field gel level.

    The gel level L is read first (by default the median height over the
    annulus from ``far_field[0]`` to ``far_field[1]`` contact radii around
    the centre, clipped to the image); then the cap
    ``z = L + d - (R - sqrt(R^2 - r^2))``, r the distance from its axis,
    is fitted by least squares (:func:`scipy.optimize.least_squares`) to
    the heights inside ``fit_fraction`` of the contact radius. d is thus
    the depth of the deepest point below the undeformed gel around the
    contact, not below the contact's rim.

    Parameters
    ----------
    height_mm : (H, W) float ndarray
        Height map, mm, positive into the gel; finite.
    mm_per_px : float
        Image scale, mm per px; positive.
    center_px : (2,) float
        Contact centre (x = column, y = row), px; the fit starts there.
    contact_radius_px : float
        Contact radius a, px; positive. Sets the fitted disc and the
        far-field annulus.
    ball_radius_mm : float, optional
        R fixed at this value (mm); None fits it.
    gel_level : {'far_field', 'zero'} or float, default 'far_field'
        'far_field': the median over the annulus; 'zero': the height map's
        own 0; a number: that level, mm.
    fit_fraction : float, default 0.9
        The disc fitted, as a fraction of the contact radius (the rim's
        steep slopes are the least sure); positive.
    far_field : (inner, outer), default (1.5, 3.0)
        The annulus, in contact radii; ``0 < inner < outer``.
    fit_centre : bool, default True
        Fit the cap's axis too (False: keep ``center_px``).

    Returns
    -------
    fit : BallCapFit
        d, R and centre, the gel level used, the height of the cap at the
        contact radius, the residual.

    Raises
    ------
    ShapeError
        If `height_mm` is not a finite (H, W) float array or `center_px`
        not two numbers.
    InputError
        If `mm_per_px`, `contact_radius_px`, `ball_radius_mm` or
        `fit_fraction` is not positive, `far_field` is not
        ``0 < inner < outer``, `gel_level` is unknown, the fitted disc has
        fewer than 10 pixels in the image, or the far-field annulus none.

    Examples
    --------
    A 0.3 mm deep press of a 2 mm ball on a gel whose level reads 0.05 mm:

    >>> import numpy as np
    >>> yy, xx = np.mgrid[0:200, 0:200]
    >>> r2 = ((xx - 100.0) ** 2 + (yy - 100.0) ** 2) * 0.03 ** 2
    >>> z = 0.05 + np.maximum(0.3 - (2.0 - np.sqrt(np.maximum(4.0 - r2, 0))), 0)
    >>> a_px = np.sqrt(2 * 2.0 * 0.3 - 0.3 ** 2) / 0.03
    >>> fit = fit_ball_cap(z, 0.03, (100.0, 100.0), a_px)
    >>> round(fit.depth_mm, 4), round(fit.radius_mm, 3), round(fit.gel_level_mm, 3)
    (0.3, 2.0, 0.05)
    """
    height = check_array(height_mm, "height_mm", [("H", "W")], dtype=np.floating, finite=True)
    c = check_array(center_px, "center_px", [(2,)], dtype=np.number, finite=True)
    s = check_positive(mm_per_px, "mm_per_px")
    a_px = check_positive(contact_radius_px, "contact_radius_px")
    frac = check_positive(fit_fraction, "fit_fraction")
    r_fixed = None if ball_radius_mm is None else check_positive(ball_radius_mm,
                                                                 "ball_radius_mm")
    try:
        inner, outer = (float(v) for v in far_field)
    except (TypeError, ValueError):
        raise InputError(f"far_field must be two numbers (inner, outer), got {far_field!r}"
                         ) from None
    if not 0 < inner < outer:
        raise InputError(f"far_field must satisfy 0 < inner < outer, got {far_field!r}")
    cx, cy = float(c[0]), float(c[1])

    h, w = height.shape
    rf = frac * a_px
    x0, y0 = max(math.floor(cx - rf), 0), max(math.floor(cy - rf), 0)
    x1, y1 = max(min(math.ceil(cx + rf) + 1, w), x0), max(min(math.ceil(cy + rf) + 1, h), y0)
    yy, xx = np.mgrid[y0:y1, x0:x1].astype(np.float64)
    inside = (xx - cx) ** 2 + (yy - cy) ** 2 < rf * rf
    n = int(inside.sum())
    if n < 10:
        raise InputError(f"the disc fitted ({rf:.1f} px about ({cx:.1f}, {cy:.1f})) has {n} "
                         f"pixel(s) in the {w} x {h} image, fewer than 10")
    n_far = 0
    if isinstance(gel_level, str):
        if gel_level == "far_field":
            level, n_far = _far_field_level(height, cx, cy, a_px, (inner, outer))
        elif gel_level == "zero":
            level = 0.0
        else:
            raise InputError(f"gel_level must be 'far_field', 'zero' or a number, got "
                             f"{gel_level!r}")
    else:
        try:
            level = float(gel_level)
        except (TypeError, ValueError):
            raise InputError(f"gel_level must be 'far_field', 'zero' or a number, got "
                             f"{gel_level!r}") from None
        if not math.isfinite(level):
            raise InputError(f"gel_level must be finite, got {gel_level!r}")

    x = (xx[inside] - cx) * s            # mm from the given centre
    y = (yy[inside] - cy) * s
    z = height[y0:y1, x0:x1][inside].astype(np.float64) - level

    # start: z = d - r^2 / (2 R), the paraboloid of the cap, by linear least squares
    r2 = x * x + y * y
    coef = np.linalg.lstsq(np.column_stack([np.ones_like(r2), r2]), z, rcond=None)[0]
    rf_mm = rf * s
    r0 = -0.5 / coef[1] if coef[1] < 0 else 10.0 * rf_mm
    r0 = float(np.clip(r0, 1.05 * rf_mm, 1e3 * rf_mm)) if r_fixed is None else r_fixed
    d0 = float(np.mean(z + r0 - np.sqrt(np.maximum(r0 * r0 - r2, 0.0))))

    def unpack(p: np.ndarray) -> tuple[float, float, float, float]:
        d = p[0]
        big_r = r_fixed if r_fixed is not None else p[1]
        k = 1 if r_fixed is not None else 2
        ox, oy = (p[k], p[k + 1]) if fit_centre else (0.0, 0.0)
        return d, big_r, ox, oy

    def residual(p: np.ndarray) -> np.ndarray:
        d, big_r, ox, oy = unpack(p)
        rr = (x - ox) ** 2 + (y - oy) ** 2
        return d - (big_r - np.sqrt(np.maximum(big_r * big_r - rr, 0.0))) - z

    p0 = [d0] + ([] if r_fixed is not None else [r0]) + ([0.0, 0.0] if fit_centre else [])
    lo = [-np.inf] + ([] if r_fixed is not None else [1e-6]) + ([-np.inf] * 2 if fit_centre
                                                                  else [])
    scale = [max(abs(d0), 1e-3)] + ([] if r_fixed is not None else [r0]) + (
        [rf_mm] * 2 if fit_centre else [])
    sol = least_squares(residual, np.array(p0), bounds=(lo, np.inf), x_scale=np.array(scale))
    d, big_r, ox, oy = unpack(sol.x)
    a_mm = a_px * s
    rim = d - (big_r - math.sqrt(big_r * big_r - a_mm * a_mm)) if a_mm < big_r else math.nan
    return BallCapFit(
        depth_mm=float(d), radius_mm=float(big_r),
        centre_px=(float(cx + ox / s), float(cy + oy / s)),
        gel_level_mm=level, rim_height_mm=float(rim),
        rms_mm=float(np.sqrt(np.mean(sol.fun ** 2))), n_pixels=n, n_far_field=n_far,
        radius_fixed=r_fixed is not None)


def absolute_depth_metrics(height_mm: np.ndarray, truth_mm: np.ndarray, contact_mask: np.ndarray,
                           *, background_mask: np.ndarray | None = None) -> AbsoluteDepthMetrics:
    """Deepest-point, profile and background errors, no offset removed.

    Parameters
    ----------
    height_mm : (H, W) float ndarray
        Reconstructed height, mm, positive into the gel, the undeformed gel
        at 0; finite.
    truth_mm : (H, W) float ndarray
        True height on the same scale; finite.
    contact_mask : (H, W) bool ndarray
        Pixels where the truth is known inside the contact (for instance
        the indenter's face within 0.9 of its radius); not empty.
    background_mask : (H, W) bool ndarray, optional
        Pixels of undeformed gel. Default: where the truth is 0 and the
        distance to the nearest contact pixel exceeds half the contact's
        equivalent radius ``sqrt(area / pi)`` (for a disc of radius a:
        beyond 1.5 a from its centre). Must not be empty.

    Returns
    -------
    metrics : AbsoluteDepthMetrics
        In mm: ``max(height) - max(truth)`` over the contact (and relative
        to the true maximum), RMS and mean of ``height - truth`` over the
        contact, RMS, mean and largest ``|height - truth|`` over the
        background.

    Raises
    ------
    ShapeError
        If the arrays are not finite (H, W) floats of one shape, or the
        masks not bool arrays of that shape.
    InputError
        If the contact mask or the background mask (given or default)
        selects no pixel.

    Examples
    --------
    >>> import numpy as np
    >>> truth = np.zeros((50, 50))
    >>> truth[20:30, 20:30] = 0.2
    >>> m = absolute_depth_metrics(truth + 0.01, truth, truth > 0)
    >>> round(m.deepest_error_mm, 6), round(m.profile_mean_mm, 6), round(m.background_rms_mm, 6)
    (0.01, 0.01, 0.01)
    """
    height = check_array(height_mm, "height_mm", [("H", "W")], dtype=np.floating, finite=True)
    truth = check_array(truth_mm, "truth_mm", [height.shape], dtype=np.floating, finite=True)
    contact = _mask(contact_mask, "contact_mask", height.shape)
    if background_mask is None:
        a_eq = math.sqrt(float(contact.sum()) / math.pi)
        far = distance_transform_edt(~contact) > 0.5 * a_eq
        background = far & (truth == 0)
        if not background.any():
            raise InputError("no background pixel: nothing where the truth is 0 lies farther "
                             f"than {0.5 * a_eq:.1f} px (half the contact's equivalent radius) "
                             "from the contact; give background_mask")
    else:
        background = _mask(background_mask, "background_mask", height.shape)
    hc = height[contact].astype(np.float64)
    tc = truth[contact].astype(np.float64)
    deep, true_deep = float(hc.max()), float(tc.max())
    err = hc - tc
    bg = height[background].astype(np.float64) - truth[background].astype(np.float64)
    return AbsoluteDepthMetrics(
        deepest_mm=deep, true_deepest_mm=true_deep, deepest_error_mm=deep - true_deep,
        deepest_error_rel=(deep - true_deep) / true_deep if true_deep > 0 else math.nan,
        profile_rms_mm=float(np.sqrt(np.mean(err * err))), profile_mean_mm=float(err.mean()),
        background_rms_mm=float(np.sqrt(np.mean(bg * bg))), background_mean_mm=float(bg.mean()),
        background_max_mm=float(np.abs(bg).max()),
        n_contact=int(contact.sum()), n_background=int(background.sum()))

