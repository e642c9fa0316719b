"""The height map's cap as a cross-check of a ball's depths from its contact circles.

A ball session certifies each depth by its contact circle through a(w)
(:func:`~tactilevision.pipeline.ball_press_depths`). The photometric height map gives a
second reading that shares nothing with the circle but the circle's centre: the spherical
cap of the ball's radius fitted inside the contact against the gel level read around it
(:func:`tactilevision.optics.fit_ball_cap`, the annulus from 1.5 to 3 contact radii). That
level has sunk in with the press (:func:`tactilevision.mechanics.sphere_surface_depth`), so
the cap is the depth less the sink-in there: the mechanics turns either reading into the
other. Where they disagree beyond the heights' scale error, either the circles are biased
or the optics calibration does not fit these frames.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from .._checks import InputError, check_array
from ..mechanics import Sphere, sphere_reach, sphere_surface_depth
from ..optics import fit_ball_cap
from ._ball import BallDepths

__all__ = ["CAP_PRESS_SD", "CAP_SCALE_SD", "BallCaps", "ball_press_caps"]

#: The heights' scale error a cap carries, 1 sd, shared by a session's presses: the median
#: inner caps of held-out real presses under this project's calibrations lie within 5 %
#: (docs/guide/optics.md: GelSight +2.5 %, GelSlim 3.0 -0.1 %, GelSight Mini +2.1 %),
#: taken as a 2-sd bound.
CAP_SCALE_SD = 0.025

#: One press's own cap error about that scale, 1 sd, where the optics calibration does not
#: state its own (``provenance["inner_cap_sd"]``, from ``optics calibrate``'s held-out
#: presses): the largest of the shared sensors' held-out sd, GelSlim 3.0's 7.7 % (GelSight
#: 5.5 %, GelSight Mini 2.4 %; docs/guide/optics.md, "What a new press's cap will read").
CAP_PRESS_SD = 0.077

#: The far-field annulus the gel level is read from, in contact radii (fit_ball_cap's).
_ANNULUS = (1.5, 3.0)


@dataclass(frozen=True)
class BallCaps:
    """Each press's cap in the height map beside what its circle's depth predicts.

    Attributes
    ----------
    cap_mm : (N,) float64 ndarray
        The fitted cap's depth below the gel level around the contact, mm
        (:class:`~tactilevision.optics.BallCapFit` ``depth_mm``, its sphere's radius
        fitted too).
    expected_mm : (N,) float64 ndarray
        The same quantity at the circle's depth w: w less the surface's sink-in over
        the annulus the level is read from (its median over the same pixels), mm.
    depth_mm : (N,) float64 ndarray
        The depth the cap reads: w whose expected cap is `cap_mm`, mm (NaN where none
        within the ball's reach does).
    depth_std_mm : (N,) float64 ndarray
        Its standard uncertainty from the heights' errors, mm: the scale error the
        session's presses share (:data:`CAP_SCALE_SD`) and one press's own (`press_sd`
        of :func:`ball_press_caps`) in quadrature, of the cap, through dw/dcap.
    ratio : (N,) float64 ndarray
        ``cap_mm / expected_mm``: 1 where the heights and the circles agree.
    rms_mm : (N,) float64 ndarray
        RMS residual of each cap's fit, mm.
    press_sd : float
        One press's own relative cap error, 1 sd, that `depth_std_mm` carries.
    """

    cap_mm: np.ndarray
    expected_mm: np.ndarray
    depth_mm: np.ndarray
    depth_std_mm: np.ndarray
    ratio: np.ndarray
    rms_mm: np.ndarray
    press_sd: float = CAP_PRESS_SD

    def summary(self) -> str:
        """One sentence: the caps against the circles, median and range."""
        r = self.ratio[np.isfinite(self.ratio)]
        if r.size == 0:
            return "cap cross-check: no cap was fitted"
        return (f"cap cross-check: the height map's caps read {100 * (np.median(r) - 1):+.1f} % "
                f"(median; {100 * (r.min() - 1):+.1f} to {100 * (r.max() - 1):+.1f} %) against "
                f"what the circles' depths predict, where the heights' scale is good to "
                f"+-{200 * CAP_SCALE_SD:.0f} % and one press's cap to "
                f"+-{200 * np.hypot(CAP_SCALE_SD, self.press_sd):.0f} %"
                + ("" if np.all(np.isfinite(self.depth_mm))
                   else "; some caps lie past the ball's reach"))


def _annulus_radii(centre: np.ndarray, radius_px: float, shape: tuple[int, int]
                   ) -> np.ndarray:
    """Distances (px) of the pixels in the far-field annulus, clipped to the image."""
    h, w = shape
    yy, xx = np.mgrid[0:h, 0:w]
    d = np.hypot(xx - centre[0], yy - centre[1]).ravel()
    return d[(d >= _ANNULUS[0] * radius_px) & (d <= _ANNULUS[1] * radius_px)]


def ball_press_caps(heights_mm: np.ndarray, depths: BallDepths, ball: Sphere, *,
                    mm_per_px: float, thickness_mm: float, nu: float = 0.5,
                    contact: str | None = None, press_sd: float = CAP_PRESS_SD) -> BallCaps:
    """Each press's cap in its height map, against what its contact circle predicts.

    Parameters
    ----------
    heights_mm : (N, H, W) float ndarray
        Height maps of the presses' frames, mm, positive into the gel (any zero:
        the cap is measured against the gel level around the contact).
    depths : BallDepths
        The presses' circles and depths (:func:`ball_press_depths`), in the same order.
    ball : Sphere
    mm_per_px, thickness_mm, nu : float
    contact : str, optional
        The ball's contact condition (its default).
    press_sd : float, default CAP_PRESS_SD
        One press's own relative cap error, 1 sd (the optics calibration's
        ``provenance["inner_cap_sd"]`` where it states one).

    Returns
    -------
    BallCaps

    Raises
    ------
    InputError
        For heights not one map per press, a press whose annulus holds no pixel, or a
        `press_sd` that is not a finite number >= 0.

    Notes
    -----
    The sink-in is the small-strain FEM's (:func:`tactilevision.mechanics.sphere_surface_depth`;
    Hertz's closed form on a thick gel), whatever law the force was fitted with.
    """
    n = depths.depth_mm.size
    heights_mm = check_array(heights_mm, "heights_mm", [(n, "H", "W")])
    if (isinstance(press_sd, bool) or not isinstance(press_sd, int | float)
            or not np.isfinite(press_sd) or press_sd < 0):
        raise InputError(f"press_sd must be a finite number >= 0, got {press_sd!r}")
    rel_sd = float(np.hypot(CAP_SCALE_SD, press_sd))
    s, h = float(mm_per_px), float(thickness_mm)
    reach = sphere_reach(ball.radius_mm / h) * h
    cap, rms, expected = np.empty(n), np.empty(n), np.empty(n)
    rings = []
    for i in range(n):
        # the sphere's radius free: a height map whose scale is off by a factor has its
        # cap's depth off by that factor (with R fixed, the fit's compromise between
        # depth and curvature read 0.84 for heights scaled by 0.8)
        fit = fit_ball_cap(heights_mm[i], s, tuple(depths.centres_px[i]), depths.radii_px[i])
        cap[i], rms[i] = fit.depth_mm, fit.rms_mm
        rings.append(_annulus_radii(depths.centres_px[i], depths.radii_px[i],
                                    heights_mm.shape[1:]) * s)
        if rings[-1].size == 0:
            raise InputError(f"press {i}: no pixel of the image lies 1.5 to 3 contact radii "
                             "from its centre")

    # one sweep for every press and every depth the root finder tries
    shallowest = float(np.min(depths.depth_mm))

    def predicted(w: float, ring: np.ndarray) -> float:
        if w <= 0:
            return 0.0
        sink = sphere_surface_depth(ball, [w], ring, nu=nu, thickness_mm=h, contact=contact,
                                    shallowest_mm=shallowest)
        return w - float(np.median(sink))

    read, std = np.full(n, np.nan), np.full(n, np.nan)
    for i in range(n):
        expected[i] = predicted(float(depths.depth_mm[i]), rings[i])
        top = predicted(reach, rings[i])
        if 0 < cap[i] < top:
            w = brentq(lambda v, i=i: predicted(v, rings[i]) - cap[i], 0.0, reach,
                       xtol=1e-7)
            eps = 1e-3 * w
            slope = (predicted(w, rings[i]) - predicted(w - eps, rings[i])) / eps
            read[i], std[i] = w, rel_sd * cap[i] / slope
    return BallCaps(cap_mm=cap, expected_mm=expected, depth_mm=read, depth_std_mm=std,
                    ratio=cap / expected, rms_mm=rms, press_sd=float(press_sd))
