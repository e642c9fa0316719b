"""Gel height maps of flat-punch presses from the finite-strain FEM.

The surface of the gel under a press is the deformed top surface of
:func:`tactilevision.fem.neo_hookean_indentation`: a flat footprint at depth w
and, around it, the sink-in and (for nearly incompressible gels) the bulge
that takes up the displaced volume. One depth sweep gives the profiles at all
depths; :class:`PressProfile` interpolates between them and draws them on the
image grid.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import PchipInterpolator

from .._checks import InputError
from ._finite import neo_hookean_indentation

__all__ = ["PressProfile", "press_profile"]


@dataclass(frozen=True)
class PressProfile:
    """Axisymmetric surface profiles of one indenter at a series of depths (units of h).

    Attributes
    ----------
    a_over_h, nu : float
    contact : str
    w_over_h : (K,) float64 ndarray
        Depths, increasing, starting at 0.
    r : (K, M) float64 ndarray
        Deformed radii of the top-surface nodes, increasing along M.
    depth : (K, M) float64 ndarray
        Their depth into the gel (-u_z), positive down; ``depth[k]`` equals
        ``w_over_h[k]`` on the footprint.
    force : (K,) float64 ndarray
        P / (E h^2) at each depth.
    """

    a_over_h: float
    nu: float
    contact: str
    w_over_h: np.ndarray
    r: np.ndarray
    depth: np.ndarray
    force: np.ndarray

    def depth_at(self, w_over_h: float, r_over_h: np.ndarray) -> np.ndarray:
        """Surface depth (units of h, positive into the gel) at radii `r_over_h`
        for a press to `w_over_h`, linear between the sweep's depths.

        Raises
        ------
        InputError
            For a depth outside [0, max of `w_over_h`].
        """
        w = float(w_over_h)
        if not 0.0 <= w <= self.w_over_h[-1] + 1e-12:
            raise InputError(f"w_over_h = {w:g} is outside the simulated depths "
                             f"[0, {self.w_over_h[-1]:g}]")
        k = int(np.clip(np.searchsorted(self.w_over_h, w) - 1, 0, len(self.w_over_h) - 2))
        t = (w - self.w_over_h[k]) / (self.w_over_h[k + 1] - self.w_over_h[k])
        r = np.asarray(r_over_h, np.float64)
        lo = np.interp(r, self.r[k], self.depth[k])
        hi = np.interp(r, self.r[k + 1], self.depth[k + 1])
        return (1.0 - t) * lo + t * hi

    def depth_at_many(self, w_over_h: np.ndarray, r_over_h: float) -> np.ndarray:
        """Surface depth (units of h) at one radius for many depths (0 where w <= 0).

        Parameters
        ----------
        w_over_h : (N,) array_like of float
        r_over_h : float

        Returns
        -------
        depth : (N,) float64 ndarray
            Linear between the sweep's depths and between its nodes.
        """
        w = np.clip(np.asarray(w_over_h, np.float64), 0.0, self.w_over_h[-1])
        at = np.array([np.interp(r_over_h, self.r[k], self.depth[k])
                       for k in range(len(self.w_over_h))])
        return np.interp(w, self.w_over_h, at)

    def force_at(self, w_over_h: float) -> float:
        """P / (E h^2) at `w_over_h` (PCHIP through the sweep's forces)."""
        return float(PchipInterpolator(self.w_over_h, self.force)(w_over_h))

    def height_map(self, shape: tuple[int, int], mm_per_px: float, thickness_mm: float,
                   center_px: tuple[float, float], depth_mm: float) -> np.ndarray:
        """The press drawn on an image grid.

        Parameters
        ----------
        shape : (H, W)
        mm_per_px : float
        thickness_mm : float
            Gel thickness h, mm.
        center_px : (x, y)
            Press centre, column and row, px (sub-pixel allowed).
        depth_mm : float
            Indentation depth w, mm.

        Returns
        -------
        height : (H, W) float32 ndarray
            Depth into the gel, mm (the convention of
            :class:`~tactilevision.optics.DepthReconstructor`).
        """
        rows, cols = np.indices(shape, dtype=np.float64)
        r_mm = np.hypot(cols - center_px[0], rows - center_px[1]) * mm_per_px
        d = self.depth_at(depth_mm / thickness_mm, r_mm / thickness_mm)
        return (d * thickness_mm).astype(np.float32)


def press_profile(a_over_h: float, nu: float, *, w_over_h_max: float = 0.22, steps: int = 11,
                  contact: str = "bonded", pad_radius_over_h: float = 20.0,
                  **mesh) -> PressProfile:
    """Run one finite-strain depth sweep and keep its surface profiles.

    Parameters
    ----------
    a_over_h, nu : float
        Indenter radius over thickness; Poisson's ratio.
    w_over_h_max : float, default 0.22
        Deepest depth simulated (a little beyond the paper's 0.2).
    steps : int, default 11
    contact : {'bonded', 'frictionless'}, default 'bonded'
    pad_radius_over_h : float, default 20.0
    **mesh
        ``cell``, ``edge_refinements`` for the FEM mesh.

    Returns
    -------
    PressProfile

    Raises
    ------
    InputError
        For bad arguments (see :func:`~tactilevision.fem.neo_hookean_indentation`)
        or a sweep that stops before `w_over_h_max`.
    """
    res = neo_hookean_indentation(a_over_h, nu, contact=contact, w_over_h_max=w_over_h_max,
                                  steps=steps, pad_radius_over_h=pad_radius_over_h, **mesh)
    if not res.complete:
        raise InputError(f"the FEM sweep (a/h = {a_over_h:g}, nu = {nu:g}, {contact}) stopped at "
                         f"w/h = {res.w_over_h[-1]:.3g} of {w_over_h_max:g}")
    r0 = res.surface_r[None, :]
    r = np.vstack([r0, r0 + res.surface_ur])
    depth = np.vstack([np.zeros_like(r0), -res.surface_uz])
    # the node next to the punch edge may slide under the edge by the contact
    # penalty's tolerance (~1e-5 h): a vertical step in the height map; a
    # larger fold would be the gel wrapping round the punch, not a height map
    fold = float(np.max(np.maximum.accumulate(r, axis=1) - r))
    if fold > 1e-3:
        raise InputError(f"the deformed surface folds over itself by {fold:.2g} h")
    r = np.maximum.accumulate(r, axis=1)
    return PressProfile(a_over_h=float(a_over_h), nu=float(nu), contact=contact,
                        w_over_h=np.concatenate([[0.0], res.w_over_h]), r=r, depth=depth,
                        force=np.concatenate([[0.0], res.force]))
