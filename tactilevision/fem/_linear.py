r"""Small-strain flat-punch indentation of a bonded layer: kappa(nu, a/h).

A rigid flat-ended cylinder of radius a is pressed to depth w into an elastic
layer of thickness h and radius R_pad, bonded to a rigid base. Lengths are in
units of h, E = 1 and w = 1, so the reaction is P / (E h w) and

    kappa = P (1 - nu^2) / (2 a E w),

which is 1 for a half-space (Sneddon) and is tabulated by Hayes et al. (1972).

Weak form (mixed u-p, free of volumetric locking)
-------------------------------------------------
With the pressure p = -lambda div u, the stress is sigma = 2 mu eps(u) - p I,
and the constraint div u + p / lambda = 0 holds in L2. Multiplying equilibrium
div sigma = 0 by a test displacement v, integrating by parts over the solid of
revolution (measure d Omega = 2 pi r dr dz) and testing the constraint with q:

    a(u, v) + b(v, p)            = 0   for all v with v = 0 on Dirichlet parts,
    b(u, q)           + c(p, q)  = 0   for all q,

    a(u, v) = int 2 mu eps(u) : eps(v) dOmega,
    b(v, p) = -int p div v dOmega,
    c(p, q) = -int p q / lambda dOmega,

with the axisymmetric eps and div of :mod:`._axisym` (hoop strain u_r / r),
integrated with order-4 Gauss rules. Their points are interior to the
triangles, so r > 0 at every one even next to the axis, and 1 / r needs no
special treatment; u_r = 0 on the axis keeps u_r / r bounded.
At nu = 0.5, 1 / lambda = 0 and c vanishes: the exactly incompressible limit
is the Stokes saddle point, stable for Taylor-Hood P2 (u) / P1 (p) triangles.
At nu = 0, lambda = 0 and p = 0, which is imposed. The traction-free outer
rim and free surface are natural conditions (no boundary term). Dirichlet
conditions: u = 0 on the bottom, u_r = 0 on the axis, u_z = -w on the punch
and, for a bonded punch, u_r = 0 there; a frictionless punch leaves u_r free,
which is zero shear traction.

With E = 1, mu = 1 / (2 (1 + nu)) and 1 / lambda = (1 + nu)(1 - 2 nu) / nu only
scale the nu-independent A, B, C: assembled once, one factorisation per nu.

Reaction force: with K the full (unconstrained) system matrix and x the
solution, the residual K x is zero at free dofs and equals the force the
supports exert at constrained dofs (the 2 pi r is in the measure, so its sum
is the total force). P is minus the sum over the punch's u_z dofs.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu, spsolve
from skfem import Basis, BilinearForm, ElementTriP1, ElementTriP2, ElementVector
from skfem.helpers import ddot

from .._checks import InputError
from ._axisym import axisym_div, axisym_strain, nested_dissection, ring_measure
from ._mesh import indentation_mesh

__all__ = ["LinearIndentation", "LinearIndentationSolver", "linear_indentation"]

_CONTACTS = ("frictionless", "bonded")


@BilinearForm
def _strain_energy(u, v, w):
    """a(u, v) / mu = int 2 eps(u) : eps(v) 2 pi r dr dz."""
    r = w.x[0]
    return 2.0 * ddot(axisym_strain(u, r), axisym_strain(v, r)) * ring_measure(w)


@BilinearForm
def _pressure_divergence(u, q, w):
    """b(u, q) = -int q div u 2 pi r dr dz (u trial, q test)."""
    return -q * axisym_div(u, w.x[0]) * ring_measure(w)


@BilinearForm
def _pressure_mass(p, q, w):
    """c(p, q) lambda = -int p q 2 pi r dr dz."""
    return -p * q * ring_measure(w)


@dataclass(frozen=True)
class LinearIndentation:
    """Result of one small-strain indentation solve (lengths in units of h).

    Attributes
    ----------
    kappa : float
        P (1 - nu^2) / (2 a E w), dimensionless.
    force : float
        P / (E h w), dimensionless reaction.
    a_over_h, nu, contact, pad_radius_over_h
        The inputs (see :func:`linear_indentation`).
    n_dofs : int
        Displacement plus pressure unknowns (before constraints).
    seconds : float
        Wall time of assembly plus solve.
    """

    kappa: float
    force: float
    a_over_h: float
    nu: float
    contact: str
    pad_radius_over_h: float
    n_dofs: int
    seconds: float


def _check_nu(nu: float | np.ndarray) -> np.ndarray:
    n = np.asarray(nu, dtype=np.float64)
    bad = ~((n >= 0.0) & (n <= 0.5))
    if np.any(bad):
        worst = np.ravel(n)[np.argmax(np.ravel(bad))]
        raise InputError(f"nu must be within [0, 0.5], got {worst!r}")
    return n


class LinearIndentationSolver:
    """Assembles A, B, C once for one (a/h, contact, mesh); solves for many nu.

    Parameters
    ----------
    a_over_h : float
        Punch radius over layer thickness, > 0.
    contact : {'frictionless', 'bonded'}, default 'frictionless'
        Zero shear under the punch (Hayes 1972) or u_r = 0 there.
    pad_radius_over_h : float, default 20.0
        R_pad / h, > a_over_h.
    cell, edge_refinements : float, int
        Mesh controls of :func:`~tactilevision.fem.indentation_mesh`.

    Raises
    ------
    InputError
        (a ``ValueError``) naming `a_over_h`, `contact`, `pad_radius_over_h`,
        `cell` or `edge_refinements` when out of range; `nu` in the methods.
    """

    def __init__(self, a_over_h: float, *, contact: str = "frictionless",
                 pad_radius_over_h: float = 20.0, cell: float = 0.125,
                 edge_refinements: int = 10) -> None:
        if not (np.isfinite(a_over_h) and a_over_h > 0):
            raise InputError(f"a_over_h must be positive and finite, got {a_over_h!r}")
        if contact not in _CONTACTS:
            raise InputError(f"contact must be one of {_CONTACTS}, got {contact!r}")
        if not (np.isfinite(pad_radius_over_h) and pad_radius_over_h > a_over_h):
            raise InputError(f"pad_radius_over_h must exceed a_over_h = {a_over_h!r}, "
                             f"got {pad_radius_over_h!r}")
        if not (np.isfinite(cell) and 0 < cell <= 1):
            raise InputError(f"cell must be within (0, 1], got {cell!r}")
        if int(edge_refinements) != edge_refinements or edge_refinements < 0:
            raise InputError(f"edge_refinements must be an integer >= 0, got {edge_refinements!r}")
        self.a_over_h, self.pad_radius_over_h = float(a_over_h), float(pad_radius_over_h)
        self.contact = contact
        t0 = time.perf_counter()
        self.mesh = indentation_mesh(a_over_h, pad_radius_over_h=pad_radius_over_h,
                                     cell=cell, edge_refinements=int(edge_refinements))
        ubasis = Basis(self.mesh, ElementVector(ElementTriP2()), intorder=4)
        pbasis = ubasis.with_element(ElementTriP1())
        self._a = _strain_energy.assemble(ubasis)                    # (Nu, Nu)
        self._b = _pressure_divergence.assemble(ubasis, pbasis)      # (Np, Nu)
        self._c = _pressure_mass.assemble(pbasis)                    # (Np, Np)
        self.n_u, self.n_dofs = ubasis.N, ubasis.N + pbasis.N
        punch = ubasis.get_dofs("punch")
        fixed = [ubasis.get_dofs("bottom").all(), ubasis.get_dofs("axis").all("u^1"),
                 punch.all("u^2")]
        if contact == "bonded":
            fixed.append(punch.all("u^1"))
        self._punch_uz = punch.all("u^2")
        self._fixed_u = np.unique(np.concatenate(fixed))
        self._x_fixed = np.zeros(self.n_dofs)
        self._x_fixed[self._punch_uz] = -1.0  # w = 1, downwards
        free = np.setdiff1d(np.arange(self.n_dofs), self._fixed_u)
        points = np.hstack([ubasis.doflocs, pbasis.doflocs])[:, free]
        pattern = sp.bmat([[self._a, self._b.T], [self._b, self._c]], format="csr")
        self._order = free[nested_dissection(pattern[free][:, free], points)]
        self.ubasis, self.pbasis = ubasis, pbasis
        self.assembly_seconds = time.perf_counter() - t0

    def system(self, nu: float) -> sp.csr_matrix:
        """Unconstrained symmetric (n_dofs, n_dofs) ``[[mu A, B^T], [B, C / lambda]]``, E = 1."""
        nu = float(_check_nu(nu))
        mu = 1.0 / (2.0 * (1.0 + nu))
        inv_lambda = 0.0 if nu == 0 else (1.0 + nu) * (1.0 - 2.0 * nu) / nu
        return sp.bmat([[mu * self._a, self._b.T], [self._b, inv_lambda * self._c]],
                       format="csr")

    def solve(self, nu: float) -> tuple[np.ndarray, np.ndarray]:
        """Solution and residual at one nu.

        Returns
        -------
        x : (n_dofs,) float64 ndarray
            Nodal u_r, u_z (units of h, for w = h) then p (units of E).
        residual : (n_dofs,) float64 ndarray
            K x: reactions at constrained dofs, ~0 elsewhere (units of E h w).
        """
        k = self.system(nu)
        order = self._order if nu > 0 else self._order[self._order < self.n_u]  # p = 0
        x = self._x_fixed.copy()
        rhs = -(k[order] @ x)
        k_oo = k[order][:, order].tocsc()
        # No pivoting keeps the nested-dissection order (see there); pivot if it failed.
        lu = splu(k_oo, permc_spec="NATURAL", diag_pivot_thresh=0.0,
                  options={"SymmetricMode": True})
        y = lu.solve(rhs)
        if not np.linalg.norm(k_oo @ y - rhs) <= 1e-10 * np.linalg.norm(rhs):
            y = spsolve(k_oo, rhs)
        x[order] = y
        return x, k @ x

    def force(self, nu: float | np.ndarray) -> float | np.ndarray:
        """P / (E h w) for each nu (float in, float out; array in, array out)."""
        n = _check_nu(nu)
        out = np.array([-self.solve(float(v))[1][self._punch_uz].sum() for v in n.ravel()])
        return float(out[0]) if n.ndim == 0 else out.reshape(n.shape)

    def kappa(self, nu: float | np.ndarray) -> float | np.ndarray:
        """kappa = P (1 - nu^2) / (2 a E w) for each nu, vectorised like :meth:`force`."""
        n = _check_nu(nu)
        return self.force(n if n.ndim else float(n)) * (1.0 - n**2) / (2.0 * self.a_over_h)

    def result(self, nu: float) -> LinearIndentation:
        """One solve at `nu` as a :class:`LinearIndentation` (seconds include assembly)."""
        t0 = time.perf_counter()
        force = self.force(float(nu))
        seconds = self.assembly_seconds + time.perf_counter() - t0
        kappa = force * (1.0 - float(nu) ** 2) / (2.0 * self.a_over_h)
        return LinearIndentation(kappa=kappa, force=force, a_over_h=self.a_over_h,
                                 nu=float(nu), contact=self.contact,
                                 pad_radius_over_h=self.pad_radius_over_h,
                                 n_dofs=self.n_dofs, seconds=seconds)


def linear_indentation(a_over_h: float, nu: float, *, contact: str = "frictionless",
                       pad_radius_over_h: float = 20.0, cell: float = 0.125,
                       edge_refinements: int = 10) -> LinearIndentation:
    """kappa(nu, a/h) of a rigid flat punch on a bonded layer, small strain.

    Parameters
    ----------
    a_over_h : float
        Punch radius a over layer thickness h, > 0.
    nu : float
        Poisson's ratio, within [0, 0.5] (0.5 is exactly incompressible).
    contact : {'frictionless', 'bonded'}, default 'frictionless'
        Zero shear traction under the punch (as Hayes et al. [1]_) or no slip.
    pad_radius_over_h : float, default 20.0
        Pad radius R_pad / h; 20 stands for Hayes's infinite layer.
    cell : float, default 0.125
        Base mesh size in units of h.
    edge_refinements : int, default 10
        Bisection rounds towards the punch edge.

    Returns
    -------
    LinearIndentation
        kappa, the reaction P / (E h w), the inputs, dof count and wall time.

    Raises
    ------
    InputError
        (a ``ValueError``) naming the argument: `nu` outside [0, 0.5],
        `a_over_h` <= 0, unknown `contact`, `pad_radius_over_h` <= `a_over_h`.

    Notes
    -----
    Taylor-Hood P2/P1 mixed u-p axisymmetric formulation; the weak form and
    its derivation are in the module docstring. The reaction P is the sum of
    the weak-form residual K x over the punch's u_z dofs. For a/h -> 0 kappa
    tends to 1, Sneddon's P = 2 a E w / (1 - nu^2) [2]_.

    References
    ----------
    .. [1] W. C. Hayes, L. M. Keer, G. Herrmann, L. F. Mockros, "A mathematical
       analysis for indentation tests of articular cartilage", J. Biomech.
       5:541-551, 1972. doi:10.1016/0021-9290(72)90010-3
    .. [2] I. N. Sneddon, "The relation between load and penetration in the
       axisymmetric Boussinesq problem for a punch of arbitrary profile",
       Int. J. Eng. Sci. 3:47-57, 1965. doi:10.1016/0020-7225(65)90019-4

    Examples
    --------
    >>> from tactilevision.fem import linear_indentation
    >>> res = linear_indentation(0.8, 0.5, cell=0.25, edge_refinements=6)
    >>> round(res.kappa, 1)
    2.9
    """
    _check_nu(nu)
    solver = LinearIndentationSolver(a_over_h, contact=contact,
                                     pad_radius_over_h=pad_radius_over_h, cell=cell,
                                     edge_refinements=edge_refinements)
    return solver.result(nu)
