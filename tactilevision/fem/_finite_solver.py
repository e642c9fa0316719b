r"""Newton's method with a line search, and the rigid flat punch as an active set.

Newton
------
Unknowns x = [u, p], Dirichlet dofs D with values x_D^target, free dofs F.
Each iteration solves K_FF dx_F = -(R_F + K_FD dx_D) with
dx_D = x_D^target - x_D (zero after the predictor x + (dx/dw) dw of a depth
step, which moves the tied nodes to their target). A backtracking line search
halves the step until J = det F > 0 at every quadrature point and, once
dx_D = 0, until ||R_F|| falls below the largest of its last four values
(non-monotone Armijo); if no step length decreases it, the longest step with
J > 0 is taken. Converged: x_D = x_D^target and ||R_F|| <= 1e-9 ||R_D|| (the
reactions), or a full step smaller than 1e-10 max |x| (round-off level, for
tiny depths). The sparse LU is SuperLU in symmetric mode (minimum degree on
K + K^T, no pivoting: 4x less fill than COLAMD on the saddle-point matrix),
checked, with partial-pivoting COLAMD as the fallback.

Punch contact (frictionless, node to rigid body, penalty)
--------------------------------------------------------
The punch at depth w occupies {r <= a, z >= h - w}, its edge optionally
rounded to radius rho: the points within rho of P' = {r <= a - rho,
z >= h - w + rho}. Its signed distance is s(x) = dist(x, P') - rho and the
outward normal n = grad s. A node of the top surface at x = X + u that is
*engaged* stores the energy k s^2 / 2 (k = penalty (R + l), l the node's share
of the surface length, so that k / (R l) = penalty / l is a pressure per unit
penetration, stiffer on finer meshes). Its residual and tangent are

    R_c = k s n,      K_c = k (n n^T + s dn/dx),   dn/dx = (I - n n^T) / |x - c|

around the rounded edge (centre c; dn/dx = 0 on the face and the side wall).
Moving the punch down by dw is moving every node up by dw, so
dR_c/dw = K_c e_z. The set of engaged nodes is frozen during a Newton solve
(a smooth problem, quadratic convergence) and updated after it: a node that
penetrates by more than 1e-7 h is engaged, one that an engaged spring holds
more than 1e-7 h outside the punch (a tensile contact force) is released, and
Newton runs again until the set settles. Initially the nodes on the face are
engaged. The punch force on the gel is the weak-form residual of the solid
summed over the top surface's u_z dofs (at equilibrium it equals the contact
forces there).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from ._neohookean_forms import AxisymmetricNeoHookean

__all__ = ["ConstrainedNewton", "IndentationProblem", "RigidPunch"]

_TOL = 1e-7  # h: contact engage / release hysteresis


class _Factorised:
    """Sparse LU of K_FF: symmetric-mode SuperLU, COLAMD with pivoting as fallback."""

    def __init__(self, k_ff: sp.csc_matrix) -> None:
        try:
            self.lu = splu(k_ff, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                           options={"SymmetricMode": True})
            probe = np.ones(k_ff.shape[0])
            err = np.linalg.norm(k_ff @ self.lu.solve(probe) - probe)
            if not err < 1e-8 * np.sqrt(len(probe)):
                raise RuntimeError("inaccurate symmetric-mode factorisation")
        except RuntimeError:
            self.lu = splu(k_ff, permc_spec="COLAMD")

    def solve(self, b: np.ndarray) -> np.ndarray:
        return self.lu.solve(b)


class ConstrainedNewton:
    """Newton solver for R(x) = 0 at free dofs, x prescribed at `fixed` dofs.

    Parameters
    ----------
    problem : AxisymmetricNeoHookean or IndentationProblem
        Anything with ``residual(x)``, ``tangent(x)``, ``min_jacobian(x)`` and
        ``n_dofs``.
    fixed : (M,) int ndarray
        Dirichlet dofs; may be replaced later by :meth:`set_fixed`.

    Attributes
    ----------
    fixed, free : int ndarray
        Dirichlet and free dofs.
    cache : tuple or None
        (x, K(x), LU of K_FF) of the last linearisation; set to None whenever
        the problem changes at equal x (contact set, depth). A problem whose
        ``constant_tangent`` is True (linear elasticity) keeps it for every x
        until its free dofs change.
    """

    def __init__(self, problem: AxisymmetricNeoHookean | IndentationProblem,
                 fixed: np.ndarray) -> None:
        self.problem = problem
        self.cache: tuple[np.ndarray, sp.csr_matrix, _Factorised] | None = None
        self.set_fixed(fixed)

    def set_fixed(self, fixed: np.ndarray) -> None:
        fixed = np.unique(fixed)
        if not (hasattr(self, "fixed") and np.array_equal(fixed, self.fixed)):
            self.fixed = fixed
            self.free = np.setdiff1d(np.arange(self.problem.n_dofs), fixed)
            self.cache = None

    def linearise(self, x: np.ndarray) -> tuple[sp.csr_matrix, _Factorised]:
        """Tangent K(x) and the factorised K_FF (cached for the last x)."""
        # a constant tangent (linear elasticity) is factorised once per set of free dofs
        if self.cache is None or not (np.array_equal(self.cache[0], x)
                                      or getattr(self.problem, "constant_tangent", False)):
            k = self.problem.tangent(x)
            self.cache = (x.copy(), k, _Factorised(k[self.free][:, self.free].tocsc()))
        return self.cache[1], self.cache[2]

    def solve(self, x: np.ndarray, target: np.ndarray, *, max_iter: int = 30,
              rtol: float = 1e-9, tangent_after: bool = True) -> tuple[np.ndarray, int, bool]:
        """Newton from `x` to R_F = 0 with x_D = `target`; returns (x, iterations, ok).

        `tangent_after` False skips the factorised tangent at the converged x (kept in
        :attr:`cache` for dP/dw and the next predictor) where the caller has no use for
        it: a quarter of a finite-strain sphere sweep's factorisations."""
        prob, free, fixed = self.problem, self.free, self.fixed
        r = prob.residual(x)
        history: list[float] = []
        for it in range(1, max_iter + 1):
            k, lu = self.linearise(x)
            dx = np.zeros_like(x)
            dx[fixed] = target - x[fixed]
            dx[free] = lu.solve(-(r[free] + k[free][:, fixed] @ dx[fixed]))
            moving = bool(np.any(dx[fixed]))
            history.append(float(np.linalg.norm(r[free])))
            ref, alpha, best = max(history[-4:]), 1.0, None
            for _ in range(12):
                trial = x + alpha * dx
                if np.all(np.isfinite(trial)) and prob.min_jacobian(trial) > 0:
                    r_trial = prob.residual(trial)
                    if best is None:
                        best = (trial, r_trial)
                    if moving or np.linalg.norm(r_trial[free]) <= (1 - 1e-4 * alpha) * ref:
                        break
                alpha *= 0.5
            else:
                if best is None:
                    return x, it, False
                trial, r_trial = best
            x, r = trial, r_trial
            small = np.linalg.norm(r[free]) <= rtol * np.linalg.norm(r[fixed]) or (
                alpha == 1.0 and np.max(np.abs(dx)) <= 1e-10 * np.max(np.abs(x)))
            if np.array_equal(x[fixed], target) and small:
                if tangent_after:
                    self.linearise(x)  # converged tangent: dP/dw and the next predictor
                return x, it, True
        return x, max_iter, False


class RigidPunch:
    """Engaged-set penalty contact of the top-surface nodes with the rigid punch.

    Parameters
    ----------
    problem : AxisymmetricNeoHookean
        Its mesh has the boundaries 'punch' and 'free' at Z = 1 (h = 1).
    a_over_h : float
        Punch radius.
    edge_radius_over_h : float
        Radius rho of the rounded punch edge, in [0, a) (0: sharp).
    stuck : (M,) bool ndarray, optional
        Top-surface nodes (sorted by R) tied to the punch by Dirichlet
        conditions instead (bonded punch); never engaged here.
    penalty : float, default 1e3
        Units of E (see the module docstring).

    Attributes
    ----------
    ur, uz : (M,) int ndarray
        u_r and u_z dofs of the top-surface nodes, sorted by R.
    R : (M,) float64 ndarray
        Their reference radii.
    engaged : (M,) bool ndarray
        The current contact set.
    face_only : bool
        False. True replaces the punch by the plane of its face (no edge, no
        side wall): with the set never updated, the nodes initially on the face
        stay on its plane, the prescribed-displacement contact of the linear
        problem.
    """

    def __init__(self, problem: AxisymmetricNeoHookean, a_over_h: float,
                 edge_radius_over_h: float, *, stuck: np.ndarray | None = None,
                 penalty: float = 1e3) -> None:
        ub = problem.ubasis
        top = ub.get_dofs(np.concatenate([ub.mesh.boundaries["punch"],
                                          ub.mesh.boundaries["free"]]))
        ur, uz = top.all("u^1"), top.all("u^2")
        if not np.allclose(ub.doflocs[:, ur], ub.doflocs[:, uz]):
            raise RuntimeError("u_r and u_z dofs of the top surface are not paired")
        order = np.argsort(ub.doflocs[0, ur])
        self.ur, self.uz = ur[order], uz[order]
        self.R = ub.doflocs[0, self.ur]
        self.k = penalty * (self.R + np.gradient(self.R))
        self.a, self.rho = float(a_over_h), float(edge_radius_over_h)
        self.n_dofs = problem.n_dofs
        self.stuck = np.zeros(len(self.R), dtype=bool) if stuck is None else stuck
        self.face_only = False
        self.engaged = (self.signed_gap(np.zeros(self.n_dofs), 0.0)[0] <= 1e-12) & ~self.stuck

    def select(self, R_max: float) -> np.ndarray:
        """Nodes with R <= R_max (the bonded face)."""
        return self.R <= R_max * (1 + 1e-12)

    def signed_gap(self, x: np.ndarray, w: float) -> tuple[np.ndarray, ...]:
        """s (M,) (< 0: penetrating), normal n (2, M), edge curvature (M,) (0 off the edge)."""
        r, z = self.R + x[self.ur], 1.0 + x[self.uz]
        if self.face_only:                           # the face's plane, unbounded
            zero = np.zeros_like(r)
            return (1.0 - w) - z, np.stack([zero, zero - 1.0]), zero
        qr, qz = r - (self.a - self.rho), (1.0 - w + self.rho) - z   # > 0: outside P'
        edge = (qr > 0) & (qz > 0)
        dist = np.where(edge, np.hypot(qr, qz), np.maximum(qr, qz))
        safe = np.where(edge, dist, 1.0)
        n = np.where(edge, np.stack([qr, -qz]) / safe,
                     np.where(qr > qz, [[1.0], [0.0]], [[0.0], [-1.0]]))
        return dist - self.rho, n, np.where(edge, 1.0 / safe, 0.0)

    def update(self, x: np.ndarray, w: float) -> bool:
        """Engage penetrating nodes, release those held outside; True if the set changed."""
        s = self.signed_gap(x, w)[0]
        new = (self.engaged | (s < -_TOL)) & ~(s > _TOL) & ~self.stuck
        changed = not np.array_equal(new, self.engaged)
        self.engaged = new
        return changed

    def residual(self, x: np.ndarray, w: float) -> np.ndarray:
        """R_c = k s n at the engaged nodes, (n_dofs,)."""
        s, n, _ = self.signed_gap(x, w)
        ks = np.where(self.engaged, self.k * s, 0.0)
        out = np.zeros(self.n_dofs)
        out[self.ur], out[self.uz] = ks * n[0], ks * n[1]
        return out

    def tangent(self, x: np.ndarray, w: float) -> sp.csr_matrix:
        """K_c = k (n n^T + s (I - n n^T) / |x - c|) at the engaged nodes."""
        s, n, curv = self.signed_gap(x, w)
        on = self.engaged
        k, n, c = self.k[on], n[:, on], (s * curv)[on]
        dofs = (self.ur[on], self.uz[on])
        rows, cols, vals = [], [], []
        for i in range(2):
            for j in range(2):
                rows.append(dofs[i])
                cols.append(dofs[j])
                vals.append(k * ((1 - c) * n[i] * n[j] + c * (i == j)))
        return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                             shape=(self.n_dofs, self.n_dofs))

    def diagnostics(self, x: np.ndarray, w: float) -> tuple[float, float]:
        """Largest penetration (units of h), and the contact radius (largest current r
        of an engaged or stuck node)."""
        s = self.signed_gap(x, w)[0]
        held = self.engaged | self.stuck
        r = self.R + x[self.ur]
        return float(np.max(-s, initial=0.0)), float(r[held].max(initial=0.0))


class IndentationProblem:
    """The Neo-Hookean forms plus the punch's penalty at the current depth `w`.

    Has the ``residual``, ``tangent``, ``min_jacobian`` and ``n_dofs`` that
    :class:`ConstrainedNewton` needs.
    """

    def __init__(self, solid: AxisymmetricNeoHookean, punch: RigidPunch) -> None:
        self.solid, self.punch, self.w = solid, punch, 0.0
        self.n_dofs = solid.n_dofs
        self.min_jacobian = solid.min_jacobian

    def residual(self, x: np.ndarray) -> np.ndarray:
        return self.solid.residual(x) + self.punch.residual(x, self.w)

    def tangent(self, x: np.ndarray) -> sp.csr_matrix:
        return self.solid.tangent(x) + self.punch.tangent(x, self.w)
