"""The gel's surface around a ball: how far it lies below its undeformed level at each radius.

A ball pressed to depth w carries the gel's surface down beyond its contact too: Hertz's
sink-in on a half-space is w/2 at the contact's edge and falls as 1/r far from it
(K. L. Johnson, Contact Mechanics, 1985, eq. 3.42b); a thin layer bonded to its base
sinks in less. A height map's cap measured against the gel level just around the contact
is therefore the depth less that level's sink-in: :func:`sphere_surface_depth` gives the
surface at any radius, from the small-strain FEM's sweep of the ball on the layer
(:func:`tactilevision.fem.sphere_indentation`, the same sweep a pad's force law is read
from, kept in the disk cache).
"""

from __future__ import annotations

import numpy as np

from .._checks import InputError
from ._indenter import Sphere, pad_sweep_result
from ._sphere_table import sphere_reach

__all__ = ["hertz_surface_depth", "sphere_surface_depth"]


def hertz_surface_depth(depth_mm: float, r_mm: np.ndarray, radius_mm: float) -> np.ndarray:
    """Depth of a half-space's surface under a rigid sphere, Hertz's closed form.

    Inside the contact radius a = sqrt(R w) the surface is the ball's in Hertz's
    theory, its paraboloid ``w - r^2 / 2R``; outside it,
    ``((2 a^2 - r^2) asin(a / r) + a sqrt(r^2 - a^2)) / (pi R)`` (Johnson 1985,
    eq. 3.42b): w/2 at the edge from both sides.

    Parameters
    ----------
    depth_mm : float
        w, mm, >= 0.
    r_mm : (M,) array_like of float
        Radii from the ball's axis, mm, >= 0.
    radius_mm : float
        R, mm.

    Returns
    -------
    (M,) float64 ndarray
        Depth below the undeformed surface, mm (positive into the gel).
    """
    r = np.abs(np.asarray(r_mm, np.float64))
    a = float(np.sqrt(radius_mm * depth_mm))
    inside = depth_mm - r * r / (2.0 * radius_mm)
    safe = np.maximum(r, a + 1e-300)
    outside = ((2 * a * a - safe**2) * np.arcsin(np.minimum(a / safe, 1.0))
               + a * np.sqrt(np.maximum(safe**2 - a * a, 0.0))) / (np.pi * radius_mm)
    return np.where(r <= a, inside, outside)


def sphere_surface_depth(ball: Sphere, depth_mm: np.ndarray, r_mm: np.ndarray, *, nu: float,
                         thickness_mm: float, contact: str | None = None,
                         shallowest_mm: float | None = None) -> np.ndarray:
    """Depth of the gel's surface below its undeformed level around a pressed ball (small strain).

    Each press's surface comes from the small-strain FEM's sweep of the ball on
    the layer (:func:`tactilevision.fem.sphere_indentation`, on the ball's pad and
    dome, the stated contact): between the sweep's depths the profiles are
    interpolated in sqrt(w) at the same radius over the contact radius, and
    scaled by w. On a thick layer it is Hertz's (:func:`hertz_surface_depth`;
    ``tests/test_sphere_surface.py``).

    Parameters
    ----------
    ball : Sphere
    depth_mm : (K,) array_like of float
        The ball's depths w, mm, within its reach on this layer.
    r_mm : (M,) array_like of float
        Radii from the ball's axis, mm, >= 0 (past the pad's edge: the edge's).
    nu : float
    thickness_mm : float
        h, mm.
    contact : str, optional
        The ball's contact condition (its default).
    shallowest_mm : float, optional
        The shallowest depth the sweep must resolve (default: the shallowest of
        `depth_mm`). A caller that queries depth after depth (a root finder) gives
        it once, so that every query reads the same sweep.

    Returns
    -------
    (K, M) float64 ndarray
        Depth below the undeformed surface, mm (positive into the gel); w at r = 0.

    Raises
    ------
    InputError
        For a depth outside 0 to the ball's reach, a negative or non-finite
        radius, or a sweep that does not converge.
    """
    h = float(thickness_mm)
    w = np.atleast_1d(np.asarray(depth_mm, np.float64))
    r = np.atleast_1d(np.asarray(r_mm, np.float64))
    reach = sphere_reach(ball.radius_mm / h) * h
    if not (np.all(np.isfinite(w)) and np.all(w >= 0) and np.all(w <= reach * (1 + 1e-9))):
        raise InputError(f"depths must lie within 0 to the ball's reach {reach:.4g} mm on "
                         f"h = {h:g} mm, got {float(np.min(w)):.4g} to {float(np.max(w)):.4g}")
    if not (np.all(np.isfinite(r)) and np.all(r >= 0)):
        raise InputError("radii must be finite and >= 0")
    key_w = w if shallowest_mm is None else np.array([float(shallowest_mm)])
    res = pad_sweep_result(*ball.sweep_key(key_w / h, nu, h, "linear", contact))
    s_grid = np.sqrt(res.w_over_h * h)
    a_grid = res.contact_radius * h
    ratio = a_grid / np.sqrt(ball.radius_mm * res.w_over_h * h)
    nodes = res.surface_r * h
    depth = -res.surface_uz * h                                   # (K0, M0), into the gel
    out = np.zeros((w.size, r.size))
    for k, wk in enumerate(w):
        if wk <= 0:
            continue
        s = float(np.sqrt(wk))
        ak = float(np.sqrt(ball.radius_mm * wk) * np.interp(s, s_grid, ratio))
        j = int(np.clip(np.searchsorted(s_grid, s), 1, s_grid.size - 1))
        t = float(np.clip((s - s_grid[j - 1]) / (s_grid[j] - s_grid[j - 1]), 0.0, 1.0))
        shape = [np.interp(r / ak * a_grid[i], nodes, depth[i]) / s_grid[i] ** 2
                 for i in (j - 1, j)]
        out[k] = wk * ((1 - t) * shape[0] + t * shape[1])
    return out
