"""A ball as its own gauge: each press's depth from its contact circle, with its uncertainty.

A ball's contact circle grows with depth (a^2 ~ R w on a thick gel), almost independently of
E: the frames certify the depth through the indenter's a(w)
(:meth:`tactilevision.mechanics.Sphere.depth_from_contact_radius`). The circle comes from
the frame against the no-contact reference (:func:`tactilevision.optics.detect_contact_circles`,
the contact edge); its error, measured against hand-annotated circles
(:data:`tactilevision.optics.CIRCLE_ERROR`, 2.5 % of radii about 61 px), has a random part
(each press its own) and a systematic part (every press's radius off by the same amount).
An edge is located to a number of pixels whatever the circle's size, so the error is
carried in pixels (by default 2.5 % of 61 px, 1.5 px, for both parts): a small circle's
radius, hence its depth, is the less certain. The random part is ``depth_std_mm``; the
systematic part, ``depth_shared_mm``, is how far each depth moves when every radius is off
by its bound (``fit_indenter(depth_shared_mm=...)`` carries it into E's interval).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .._checks import InputError, check_array
from ..mechanics import Indenter
from ..optics import CIRCLE_ERROR, CircleError, detect_contact_circles, edge_cut

__all__ = ["CIRCLE_ERROR_RADIUS_PX", "BallDepths", "ball_press_depths"]

#: Radius of the hand-annotated circles the contact-edge detector's error was measured on
#: (:data:`tactilevision.optics.CIRCLE_ERROR`: the 48 real GelSight presses of ``taxim``).
CIRCLE_ERROR_RADIUS_PX = 61.0


@dataclass(frozen=True)
class BallDepths:
    """Depths certified by the contact circles of a ball's presses.

    Attributes
    ----------
    depth_mm : (N,) float64 ndarray
        w of each press, mm: a(w) inverted at its contact radius.
    depth_std_mm : (N,) float64 ndarray
        The circle's random error carried through dw/da, mm (1 sd).
    depth_shared_mm : (N,) float64 ndarray
        How far each depth moves when every circle's radius is off by the systematic
        bound, mm (``fit_indenter(depth_shared_mm=...)``).
    contact_radius_mm : (N,) float64 ndarray
    centres_px : (N, 2) float64 ndarray
        (x, y) of each circle.
    radii_px : (N,) float64 ndarray
    dw_da : (N,) float64 ndarray
        Slope of the inverse law at each press, mm/mm (2 w / a on a thick gel).
    radius_sd_px, radius_bias_px : float
        The circles' random and systematic radius errors carried, px.
    notes : tuple of str
    """

    depth_mm: np.ndarray
    depth_std_mm: np.ndarray
    depth_shared_mm: np.ndarray
    contact_radius_mm: np.ndarray
    centres_px: np.ndarray = field(repr=False)
    radii_px: np.ndarray = field(repr=False)
    dw_da: np.ndarray = field(repr=False)
    radius_sd_px: float = 0.0
    radius_bias_px: float = 0.0
    notes: tuple[str, ...] = ()


def contact_depths(indenter: Indenter, a: np.ndarray, kw: dict
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Depths w (mm) of contact radii `a` (mm, (N,)) and dw/da at each (central differences,
    a step of 1e-4 w), all read through one table or FEM sweep: on a finite pad the
    shallowest press's, not one per press's own depth. `kw`: the indenter's ``nu``,
    ``thickness_mm``, ``law`` and ``contact``.

    Raises
    ------
    InputError
        From :meth:`~tactilevision.mechanics.Indenter.depth_from_contact_radius`, for the
        first radius it refuses.
    """
    w = np.asarray(indenter.depth_from_contact_radius(a, **kw), np.float64)
    eps = 1e-4 * w
    da_dw = (indenter.contact_radius(w + eps, **kw) - indenter.contact_radius(w - eps, **kw)
             ) / (2 * eps)
    return w, 1.0 / da_dw


def ball_press_depths(frames: np.ndarray, reference: np.ndarray, indenter: Indenter, *,
                      mm_per_px: float, thickness_mm: float, nu: float = 0.5,
                      law: str = "neo_hookean", contact: str | None = None,
                      circle_error: CircleError = CIRCLE_ERROR,
                      error_radius_px: float = CIRCLE_ERROR_RADIUS_PX,
                      names: list[str] | None = None) -> BallDepths:
    """Each press's depth from its contact circle, through the indenter's a(w).

    Parameters
    ----------
    frames : (N, H, W, 3) uint8 ndarray
        One frame per press, BGR, the ball at rest at its depth.
    reference : (H, W, 3) uint8 ndarray
        The no-contact frame.
    indenter : Indenter
        A :class:`~tactilevision.mechanics.Sphere` (its contact radius grows with depth).
    mm_per_px : float
        Image scale on the gel, mm per pixel.
    thickness_mm, nu : float
        The layer's h and the nu of a(w) (a(w) hardly depends on E, and little on nu).
    law : {'neo_hookean', 'linear'}, default 'neo_hookean'
    contact : str, optional
        The ball's contact condition (the indenter's default).
    circle_error : CircleError, default :data:`~tactilevision.optics.CIRCLE_ERROR`
        The contact circles' random and systematic radius errors, as fractions of the
        radius they were measured at ...
    error_radius_px : float, default 61.0
        ... this one (px): carried as radius_sd x error_radius_px and radius_bias x
        error_radius_px pixels on every circle.
    names : list of str, optional
        Each frame's name, for messages (default ``frame <i>``).

    Returns
    -------
    BallDepths

    Raises
    ------
    InputError
        Naming the frame: no contact found, a contact circle running past the image's edge
        (its radius is not measured), a contact radius the indenter's table does not reach
        or not smaller than the ball; or a bad scale.

    Notes
    -----
    With a = r mm_per_px and w = a^-1(a): ``depth_std_mm = (dw/da) sd_px mm_per_px`` and
    ``depth_shared_mm = (dw/da) bias_px mm_per_px`` (2 w bias_px / r on a thick gel, where
    w = a^2 / R).
    """
    frames = check_array(frames, "frames", [("N", "H", "W", 3)], dtype=np.uint8)
    names = names or [f"frame {i}" for i in range(len(frames))]
    s = float(mm_per_px)
    if not (np.isfinite(s) and s > 0):
        raise InputError(f"mm_per_px must be positive, got {mm_per_px!r}")
    try:
        centres, radii = detect_contact_circles(frames, reference, edge="contact")
    except ValueError as exc:
        raise InputError(f"{exc} (frames: {', '.join(names[:3])}...)") from None
    cut = edge_cut(centres, radii, frames.shape[1:3])
    if np.any(cut):
        i = int(np.argmax(cut))
        raise InputError(f"{names[i]}: its contact circle (radius {radii[i]:.1f} px) runs past "
                         "the image's edge: its radius, hence its depth, is not measured")
    a = radii * s
    kw = {"nu": nu, "thickness_mm": thickness_mm, "law": law, "contact": contact}
    try:        # every press at once: one FEM sweep for all on a finite pad
        w, dw_da = contact_depths(indenter, a, kw)
    except InputError:
        for i, ai in enumerate(a):      # the press it refuses, named
            try:
                indenter.depth_from_contact_radius(np.array([ai]), **kw)
            except InputError as exc:
                raise InputError(f"{names[i]}: {exc}") from None
        raise
    sd_px = circle_error.radius_sd * float(error_radius_px)
    bias_px = circle_error.radius_bias * float(error_radius_px)
    return BallDepths(depth_mm=w, depth_std_mm=dw_da * sd_px * s,
                      depth_shared_mm=dw_da * bias_px * s, contact_radius_mm=a,
                      centres_px=centres, radii_px=radii, dw_da=dw_da, radius_sd_px=sd_px,
                      radius_bias_px=bias_px,
                      notes=(f"depths from the contact circles through a(w) ({law}, "
                             f"{indenter._contact(contact)}, nu = {nu:g}); circle radius "
                             f"error {sd_px:.2g} px random, {bias_px:.2g} px shared",))
