"""Meshes of the axisymmetric indentation problem (the paper's Fig. 3).

A gel layer of thickness h and radius R_pad, bonded to a rigid base at z = 0,
its free surface at z = h, indented at r <= a by a rigid flat-ended cylinder.
Lengths are in units of h (h = 1). The (r, z) half-section is triangulated on a
tensor grid that has a node at r = a, then bisected repeatedly around the
punch edge (r, z) = (a, h), where the stress is singular.
"""

from __future__ import annotations

import numpy as np
from skfem import MeshTri

from .._checks import InputError

__all__ = ["indentation_mesh"]


def _graded(x0: float, x1: float, h0: float, growth: float) -> np.ndarray:
    """Nodes from x0 to x1, first step h0, each step ``growth`` times the last."""
    xs = [x0]
    step = h0
    while xs[-1] + step < x1 - 0.5 * step:
        xs.append(xs[-1] + step)
        step *= growth
    xs.append(x1)
    return np.array(xs)


def indentation_mesh(a_over_h: float, *, pad_radius_over_h: float = 20.0, cell: float = 0.125,
                     edge_refinements: int = 10, edge_zone: float = 0.5) -> MeshTri:
    """Triangle mesh of the (r, z) half-section, graded towards the punch edge.

    Parameters
    ----------
    a_over_h : float
        Punch radius a in units of the thickness h.
    pad_radius_over_h : float, default 20.0
        Pad radius R_pad / h. 20 approximates the infinite layer of Hayes
        (1972); the paper's pad is 15 mm / 3 mm = 5.
    cell : float, default 0.125
        Base cell size (units of h) under the punch and through the thickness;
        the grid grows geometrically (factor 1.25) beyond the punch. Halve it
        for a mesh-convergence study.
    edge_refinements : int, default 10
        Rounds of bisection of the triangles near the punch edge.
    edge_zone : float, default 0.5
        Radius (units of h) of the first refinement zone around the edge; each
        round shrinks it by 0.6.

    Returns
    -------
    mesh : skfem.MeshTri
        Coordinates ``(r, z)``; boundaries ``'bottom'`` (z = 0), ``'axis'``
        (r = 0), ``'outer'`` (r = R_pad), ``'punch'`` (z = h, r <= a) and
        ``'free'`` (z = h, r > a).

    Raises
    ------
    ValueError
        If a/h or the pad radius is not positive, or the pad is not wider
        than the punch.
    """
    a = float(a_over_h)
    big_r = float(pad_radius_over_h)
    if not (a > 0 and big_r > a):
        raise InputError(f"need 0 < a_over_h < pad_radius_over_h, got {a}, {big_r}")
    n_in = max(2, int(np.ceil(a / cell)))
    r_in = np.linspace(0.0, a, n_in + 1)
    r_out = _graded(a, big_r, a / n_in, 1.25)
    r = np.concatenate([r_in, r_out[1:]])
    z = np.linspace(0.0, 1.0, max(2, int(np.ceil(1.0 / cell))) + 1)
    mesh = MeshTri.init_tensor(r, z)
    zone = edge_zone
    for _ in range(edge_refinements):
        c = mesh.p[:, mesh.t].mean(axis=1)
        near = np.nonzero(np.hypot(c[0] - a, c[1] - 1.0) < zone)[0]
        mesh = mesh.refined(near)
        zone *= 0.6
    eps = 1e-9
    return mesh.with_boundaries({
        "bottom": lambda x: np.abs(x[1]) < eps,
        "axis": lambda x: np.abs(x[0]) < eps,
        "outer": lambda x: np.abs(x[0] - big_r) < eps,
        "punch": lambda x: (np.abs(x[1] - 1.0) < eps) & (x[0] <= a + eps),
        "free": lambda x: (np.abs(x[1] - 1.0) < eps) & (x[0] >= a - eps),
    })
