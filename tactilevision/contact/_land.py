"""When the gauge-block land meets the gel: the depth the bevel certifies.

The paper certifies a press when the bevel beside the indenter first shows in
the tactile image: the gel has reached the block land, which lies w0 below the
indenter's face, and the depth is taken as w0 (method.md, "Measurement
procedure"). A nearly incompressible gel, however, bulges up around the
indenter (the displaced volume has to go somewhere): the bulge crest meets the
land *before* the indenter is w0 deep. With a crest height b(w) above the
undeformed surface, first contact happens at the depth w_c with

``w_c + b(w_c) = w0``.

For a bonded layer the crest is 7 to 13% of w (nu = 0.45 to 0.49, a/h = 0.83,
from the finite-strain FEM surface), so certifying w0 overstates every depth
by that much; :func:`land_contact_depth` solves for w_c on the FEM surface of
:func:`tactilevision.fem.press_profile`.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Protocol

import numpy as np
from scipy.optimize import brentq

from .._checks import InputError
from ..fem import press_profile

__all__ = ["bulge_at", "bulge_height", "land_contact_depth"]


class _Profile(Protocol):
    a_over_h: float
    w_over_h: np.ndarray

    def depth_at(self, w_over_h: float, r_over_h: np.ndarray) -> np.ndarray: ...


def bulge_height(profile: _Profile, w_over_h: float) -> tuple[float, float]:
    """Height of the bulge crest above the undeformed gel outside the indenter.

    Parameters
    ----------
    profile : PressProfile
        Surface profiles of the press (:func:`tactilevision.fem.press_profile`).
    w_over_h : float
        Indentation depth over the layer thickness.

    Returns
    -------
    height_over_h : float
        Crest height (>= 0) in units of h.
    r_over_h : float
        Crest radius, units of h.
    """
    r = np.linspace(profile.a_over_h * 1.02, profile.a_over_h + 6.0, 1200)
    d = profile.depth_at(w_over_h, r)
    k = int(np.argmin(d))
    return max(-float(d[k]), 0.0), float(r[k])


def land_contact_depth(w0_over_h: float, profile: _Profile) -> float:
    """Depth at which the bulging gel first touches a land w0 below the indenter face.

    Parameters
    ----------
    w0_over_h : float
        Indenter protrusion over the land (the gauge block's w0), units of h.
    profile : PressProfile
        Surface profiles of the press at the gel's nu and a/h.

    Returns
    -------
    w_c_over_h : float
        The depth solving ``w + b(w) = w0`` (units of h); equals w0 for a gel
        that does not bulge.

    Raises
    ------
    InputError
        If `w0_over_h` is not positive or beyond the profile's depths.
    """
    w0 = float(w0_over_h)
    if not (np.isfinite(w0) and 0 < w0 <= profile.w_over_h[-1]):
        raise InputError(f"w0/h = {w0_over_h!r} must lie in (0, {profile.w_over_h[-1]:g}], "
                         "the depths of the press profile")

    def gap(w: float) -> float:
        return w + bulge_height(profile, w)[0] - w0

    if gap(w0) <= 0:
        return w0
    return float(brentq(gap, 0.0, w0, xtol=1e-9))


@lru_cache(maxsize=16)
def _cached_profile(a_over_h: float, nu: float, w_over_h_max: float):
    """The FEM press profile at (a/h, nu), cached (:func:`~tactilevision.fem.press_profile`)."""
    return press_profile(a_over_h, nu, w_over_h_max=w_over_h_max, steps=8, cell=0.5,
                         edge_refinements=5)


#: Poisson's ratios at which the cached FEM sweeps are solved; a quantity at any other nu
#: is interpolated linearly between the two nodes around it. The bulge grows smoothly with
#: nu (3.8% of w at nu 0.48, 4.3% at 0.49, a/h 0.83, 2.5 h from the axis): the linear
#: interpolation over 0.01 is off by under 0.01% of w, the land contact depth by under
#: 0.03% (``tests/test_vernier.py``), and a fit that moves nu by a few thousandths reuses
#: the same two sweeps instead of solving one per round.
_NU_NODES = np.concatenate([np.round(np.arange(0.0, 0.4901, 0.01), 2), [0.495, 0.499]])


def _nu_interpolated(nu: float, a_over_h: float, w_over_h_max: float, quantity) -> np.ndarray:
    """``quantity(profile)`` at `nu`, linear between the FEM sweeps at the nodes around it."""
    nu = float(nu)
    if not (np.isfinite(nu) and 0.0 <= nu <= _NU_NODES[-1]):
        raise InputError(f"nu = {nu!r} must lie in [0, {_NU_NODES[-1]:g}] for the FEM sweep")
    a_over_h = round(float(a_over_h), 6)
    w_max = round(float(np.ceil(max(0.22, w_over_h_max) / 0.02 - 1e-9)) * 0.02, 3)
    i = int(np.clip(np.searchsorted(_NU_NODES, nu, side="right") - 1, 0, _NU_NODES.size - 2))
    lo, hi = float(_NU_NODES[i]), float(_NU_NODES[i + 1])
    t = (nu - lo) / (hi - lo)
    q_lo = np.asarray(quantity(_cached_profile(a_over_h, lo, w_max)), np.float64)
    if t < 1e-9:
        return q_lo
    q_hi = np.asarray(quantity(_cached_profile(a_over_h, hi, w_max)), np.float64)
    return (1.0 - t) * q_lo + t * q_hi


def land_contact_depths_mm(w0_mm: np.ndarray, *, thickness_mm: float, radius_mm: float,
                           nu: float) -> np.ndarray:
    """:func:`land_contact_depth` for gauge-block depths in mm, from a cached FEM sweep.

    Parameters
    ----------
    w0_mm : (K,) array_like of float
        Gauge-block depths, mm.
    thickness_mm, radius_mm : float
        Layer thickness h and indenter radius a, mm.
    nu : float
        Poisson's ratio of the gel (the fit's estimate).

    Returns
    -------
    w_c_mm : (K,) float64 ndarray

    Notes
    -----
    The FEM sweep (bonded punch, a coarser mesh than the tables: the crest
    height changes by under 0.3% of it against the default mesh) takes a few
    seconds and is cached per a/h and nu node: at any other nu, the depths are
    interpolated linearly between the sweeps at the two nodes around it (0.01 apart).
    """
    w0 = np.atleast_1d(np.asarray(w0_mm, np.float64)) / thickness_mm
    return _nu_interpolated(
        nu, radius_mm / thickness_mm, float(w0.max()) * 1.05,
        lambda prof: [land_contact_depth(v, prof) for v in w0]) * thickness_mm


def bulge_at(r_mm: float, depth_mm: np.ndarray, *, thickness_mm: float, radius_mm: float,
             nu: float) -> np.ndarray:
    """How far the gel's surface rises at a distance from the indenter axis (the bulge), mm.

    Parameters
    ----------
    r_mm : float
        Distance from the indenter axis, mm (beyond the indenter radius).
    depth_mm : (N,) array_like of float
        Indentation depth w of each press, mm.
    thickness_mm, radius_mm : float
        Layer thickness h and indenter radius a, mm.
    nu : float
        Poisson's ratio of the gel.

    Returns
    -------
    bulge_mm : (N,) float64 ndarray
        Height of the surface above the undeformed gel at `r_mm` (positive
        towards the block), mm.

    Raises
    ------
    InputError
        For `r_mm` inside the indenter, a depth beyond the FEM sweep, or nu
        outside [0, 0.499].

    Notes
    -----
    From the finite-strain FEM surface of a bonded Neo-Hookean layer
    (:func:`tactilevision.fem.press_profile`, the cached coarse sweep of
    :func:`land_contact_depths_mm`: against the sample sessions' finer mesh
    the bulge at 2 to 3 h differs by under 1% of itself). For a/h = 0.83 and
    nu = 0.48 it is 7.7% of w at r = 2 h, 3.8% at 2.5 h, 2.0% at 3 h and 1.2% at
    3.5 h, and grows with nu (2.8%, 3.8%, 4.3% at 2.5 h for nu 0.45, 0.48,
    0.49): a gauge block's bevel read as a vernier must be corrected for it.
    """
    h = float(thickness_mm)
    w = np.atleast_1d(np.asarray(depth_mm, np.float64)) / h
    if r_mm <= radius_mm:
        raise InputError(f"the bevel at {r_mm:g} mm lies inside the indenter (radius "
                         f"{radius_mm:g} mm)")
    r = np.array([r_mm / h])
    return _nu_interpolated(
        nu, radius_mm / h, float(w.max()) * 1.05,
        lambda prof: [-float(prof.depth_at(float(v), r)[0]) * h for v in np.clip(w, 0, None)])
