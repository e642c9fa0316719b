"""Axisymmetric (r, z) FEM helpers: kinematics for scikit-fem forms, dof ordering.

A torsion-free axisymmetric displacement u = (u_r, u_z)(r, z) has the small
strain, in the order (r, z, theta),

    eps = [[d_r u_r,                 (d_z u_r + d_r u_z) / 2, 0      ],
           [(d_z u_r + d_r u_z) / 2, d_z u_z,                 0      ],
           [0,                       0,                       u_r / r]]

and div u = tr eps = d_r u_r + u_r / r + d_z u_z. Integrals over the solid of
revolution are integrals over the half-section with the measure 2 pi r dr dz.

The hoop term u_r / r is evaluated only at quadrature points, which are
interior to the triangles, so r > 0 there even for triangles that touch the
axis r = 0; u_r = 0 is imposed on the axis, so u_r / r stays bounded.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from skfem.helpers import div, sym_grad

__all__ = ["axisym_div", "axisym_strain", "nested_dissection", "ring_measure"]


def ring_measure(w) -> np.ndarray:
    """The factor 2 pi r of the measure 2 pi r dr dz, at the quadrature points.

    Parameters
    ----------
    w : skfem FormExtraParams
        The third argument of a form; ``w.x[0]`` is r.

    Returns
    -------
    (n_elements, n_points) float64 ndarray, units of h
    """
    return 2.0 * np.pi * w.x[0]


def axisym_strain(u, r: np.ndarray) -> np.ndarray:
    """Small strain of an axisymmetric vector field, components (r, z, theta).

    Parameters
    ----------
    u : skfem DiscreteField of a 2-vector element
        The field (u_r, u_z) in a form.
    r : (n_elements, n_points) float64 ndarray
        Radius at the quadrature points (``w.x[0]``), positive.

    Returns
    -------
    eps : (3, 3, n_elements, n_points) float64 ndarray, dimensionless
    """
    g = sym_grad(u)  # 2 x 2 x elements x points
    hoop = u[0] / r
    zero = np.zeros_like(hoop)
    return np.array([[g[0, 0], g[0, 1], zero],
                     [g[1, 0], g[1, 1], zero],
                     [zero, zero, hoop]])


def axisym_div(u, r: np.ndarray) -> np.ndarray:
    """Divergence d_r u_r + u_r / r + d_z u_z (the trace of the strain).

    Parameters
    ----------
    u : skfem DiscreteField of a 2-vector element
    r : (n_elements, n_points) float64 ndarray
        Radius at the quadrature points, positive.

    Returns
    -------
    (n_elements, n_points) float64 ndarray, dimensionless
    """
    return div(u) + u[0] / r


def nested_dissection(adjacency: sp.csr_matrix, points: np.ndarray,
                       leaf: int = 128) -> np.ndarray:
    """Fill-reducing elimination order by geometric nested dissection.

    Parameters
    ----------
    adjacency : (N, N) sparse matrix
        Sparsity pattern (symmetric) of the matrix to factorise.
    points : (2, N) float64 ndarray, units of h
        Location of each dof (``basis.doflocs``).
    leaf : int, default 128
        Blocks this small are not split further.

    Returns
    -------
    order : (N,) int64 ndarray
        A permutation of ``range(N)``: eliminate ``order[0]`` first.

    Notes
    -----
    The dofs are halved at the median of their longer coordinate extent; the
    dofs of the first half coupled to the second form the separator, ordered
    after both halves, which recurse. Index order is kept within a block, so
    displacement dofs (numbered first) precede the pressure dofs they couple
    to, which lets a saddle-point matrix be factorised without pivoting. On
    the 69k-dof default indentation mesh, SuperLU with this order takes 1.7 s
    against 4 to 5 s with its own COLAMD ordering.
    """
    blocks: list[np.ndarray] = []

    def split(idx: np.ndarray) -> None:
        if idx.size <= leaf:
            blocks.append(idx)
            return
        pts = points[:, idx]
        axis = int(np.argmax(np.ptp(pts, axis=1)))
        first = pts[axis] <= np.median(pts[axis])
        if first.all():
            blocks.append(idx)
            return
        lo, hi = idx[first], idx[~first]
        in_hi = np.zeros(adjacency.shape[0], dtype=np.int64)
        in_hi[hi] = 1
        rows = adjacency[lo]
        counts = np.concatenate([[0], np.cumsum(in_hi[rows.indices])])
        touches = counts[rows.indptr[1:]] > counts[rows.indptr[:-1]]
        split(lo[~touches])
        split(hi)
        blocks.append(lo[touches])

    split(np.arange(adjacency.shape[0]))
    return np.concatenate(blocks)
