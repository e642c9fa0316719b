r"""Finite-strain flat-punch indentation of a bonded Neo-Hookean layer: kappa_n, beta.

The layer of :func:`~tactilevision.fem.indentation_mesh` (h = 1, E = 1) is
pressed by a rigid flat punch of radius a to depth w in increments up to
w/h = 0.2; at each depth the mixed u-p equations of
:mod:`._neohookean_forms` are solved by Newton's method. With P the punch
force,

    kappa_n(nu, a/h, w/h) = P (1 - nu^2) / (2 a E w)                      (eq. 1)

and the paper's procedure (eq. 5) fits P / w = c (1 + beta w/h) over the depths
(the secant beta). Differentiating P = c w (1 + beta w/h) gives the tangent
form dP/dw = c_t (1 + 2 beta_t w/h), fitted to the exact tangent stiffness of
each converged state (beta_t = beta when eq. 2 holds exactly).

Solution
--------
Unknowns x = [u, p]; u = 0 on the bottom and u_r = 0 on the axis. The punch is
a rigid body in frictionless penalty contact with the top surface (module
:mod:`._finite_solver`: engaged-set contact, so the gel can neither enter the
punch face nor its side wall, and material can slide onto the face or around
its edge). ``contact='bonded'`` ties the nodes initially under the flat face
(u_r = 0, u_z = -w, Dirichlet); the rest of the surface still touches the
punch without friction. Each depth increment starts from the first-order
predictor x + (dx/dw) dw, then Newton with a line search; a failed increment
is bisected (up to three times); a sweep that still fails stops and reports the
depths it reached (``complete=False``, a ``RuntimeWarning``).

The punch force is the weak-form residual of the solid: P = -2 pi times the
sum of R_u over the top surface's u_z dofs (zero at free nodes, the contact
force at touching ones). Its derivative dP/dw comes from the converged tangent:
K dx/dw = -dR/dw (one solve with the factorisation already at hand).
"""

from __future__ import annotations

import os
import time
import warnings
from dataclasses import dataclass

import numpy as np

from .._checks import InputError
from ._finite_solver import ConstrainedNewton, IndentationProblem, RigidPunch
from ._mesh import indentation_mesh
from ._neohookean_forms import AxisymmetricNeoHookean
from ._sweep_cache import read_sweep, write_sweep

__all__ = ["FiniteIndentation", "neo_hookean_indentation"]

_CONTACTS = ("frictionless", "bonded")
_MAX_SET_UPDATES = 20
_MAX_BISECTIONS = 3


@dataclass(frozen=True)
class FiniteIndentation:
    """One finite-strain depth sweep (lengths in units of h, forces of E h^2).

    Attributes
    ----------
    a_over_h, nu : float
        Punch radius over thickness; small-strain Poisson's ratio.
    contact : {'frictionless', 'bonded'}
    pad_radius_over_h : float
    w_over_h : (K,) float64 ndarray
        Depths reached, increasing (K < `steps` when the sweep stopped early).
    force : (K,) float64 ndarray
        P / (E h^2) at those depths.
    kappa_n : (K,) float64 ndarray
        P (1 - nu^2) / (2 a E w), eq. (1).
    kappa0 : float
        Small-strain limit w -> 0 (the tangent of the undeformed state, which
        is the linear problem).
    beta_secant : float
        beta of the least-squares line P/w = c (1 + beta w/h) over `w_over_h`
        (the paper's eq. 5 procedure); NaN with fewer than two depths.
    beta_tangent : float
        beta_t of the line dP/dw = c_t (1 + 2 beta_t w/h) fitted to
        `tangent_stiffness` (equal to `beta_secant` when P/w is exactly linear;
        the fit dP/dw = c_t (1 + b w/h) without the 2 gives b = 2 beta_t).
    linearity_r2 : float
        R^2 of the straight line P/w against w/h.
    newton_iterations : (K,) int ndarray
        Newton iterations spent to reach each depth (bisections and contact-set
        updates included).
    min_jacobian : (K,) float64 ndarray
        Smallest J = det F over the quadrature points at each depth.
    n_dofs : int
        Displacement plus pressure unknowns.
    seconds : float
        Wall time of the whole sweep.
    tangent_stiffness : (K,) float64 ndarray
        dP/dw / (E h) at each depth, from the converged tangent.
    penetration : (K,) float64 ndarray
        Largest penetration of a surface node into the punch, units of h
        (penalty and set tolerance, ~1e-5).
    contact_radius : (K,) float64 ndarray
        Largest current radius of a node touching or tied to the punch.
    complete : bool
        False when Newton failed before `w_over_h_max`.
    surface_r : (M,) float64 ndarray
        Reference radii R of the top-surface nodes (P2 vertices and edge
        midpoints), increasing, units of h.
    surface_ur, surface_uz : (K, M) float64 ndarray
        Their displacements at each depth, units of h (u_z < 0: into the
        gel; u_z = -w under a bonded face). The deformed surface is
        (R + u_r, 1 + u_z).
    from_cache : bool
        True when the sweep was read from the disk cache (`seconds` is then
        the wall time of the run that stored it).
    """

    a_over_h: float
    nu: float
    contact: str
    pad_radius_over_h: float
    w_over_h: np.ndarray
    force: np.ndarray
    kappa_n: np.ndarray
    kappa0: float
    beta_secant: float
    beta_tangent: float
    linearity_r2: float
    newton_iterations: np.ndarray
    min_jacobian: np.ndarray
    n_dofs: int
    seconds: float
    tangent_stiffness: np.ndarray
    penetration: np.ndarray
    contact_radius: np.ndarray
    complete: bool
    surface_r: np.ndarray | None = None
    surface_ur: np.ndarray | None = None
    surface_uz: np.ndarray | None = None
    from_cache: bool = False


def _line_fit(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float]:
    """Intercept, slope and R^2 of the least-squares line y = c0 + c1 x."""
    if len(x) < 2:
        return float("nan"), float("nan"), float("nan")
    c1, c0 = np.polyfit(x, y, 1)
    ss_tot = float(np.sum((y - y.mean()) ** 2))
    r2 = 1.0 - float(np.sum((y - c0 - c1 * x) ** 2)) / ss_tot if ss_tot > 0 else 1.0
    return float(c0), float(c1), r2


def _settle(newton: ConstrainedNewton, punch: RigidPunch, x: np.ndarray, target: np.ndarray,
            search: bool) -> tuple[np.ndarray, int, bool]:
    """Newton with the contact set frozen, then set updates until it settles."""
    its = 0
    for _ in range(_MAX_SET_UPDATES):
        x, n, ok = newton.solve(x, target)
        its += n
        if not ok:
            return x, its, False
        if not (search and punch.update(x, newton.problem.w)):
            return x, its, True
        newton.cache = None
    return x, its, False


def _check(a_over_h: float, nu: float, contact: str, w_over_h_max: float, steps: int,
           pad_radius_over_h: float, cell: float, edge_refinements: int,
           edge_radius_over_h: float, penalty: float) -> None:
    if not (np.isfinite(a_over_h) and a_over_h > 0):
        raise InputError(f"a_over_h must be positive and finite, got {a_over_h!r}")
    if not (np.isfinite(nu) and 0.0 <= nu <= 0.5):
        raise InputError(f"nu must be within [0, 0.5], got {nu!r}")
    if contact not in _CONTACTS:
        raise InputError(f"contact must be one of {_CONTACTS}, got {contact!r}")
    if not (np.isfinite(w_over_h_max) and 0 < w_over_h_max <= 0.5):
        raise InputError(f"w_over_h_max must be within (0, 0.5], got {w_over_h_max!r}")
    if isinstance(steps, bool) or int(steps) != steps or steps < 1:
        raise InputError(f"steps must be a positive integer, got {steps!r}")
    if not (np.isfinite(pad_radius_over_h) and pad_radius_over_h > a_over_h):
        raise InputError(f"pad_radius_over_h must exceed a_over_h = {a_over_h!r}, "
                         f"got {pad_radius_over_h!r}")
    if not (np.isfinite(cell) and 0 < cell <= 1):
        raise InputError(f"cell must be within (0, 1], got {cell!r}")
    if isinstance(edge_refinements, bool) or int(edge_refinements) != edge_refinements \
            or edge_refinements < 0:
        raise InputError(f"edge_refinements must be a non-negative integer, "
                         f"got {edge_refinements!r}")
    if not (np.isfinite(edge_radius_over_h) and 0 <= edge_radius_over_h < a_over_h):
        raise InputError(f"edge_radius_over_h must be within [0, a_over_h), "
                         f"got {edge_radius_over_h!r}")
    if not (np.isfinite(penalty) and penalty > 0):
        raise InputError(f"penalty must be positive and finite, got {penalty!r}")


def neo_hookean_indentation(a_over_h: float, nu: float, *, contact: str = "frictionless",
                            w_over_h_max: float = 0.2, steps: int = 10,
                            pad_radius_over_h: float = 20.0, cell: float = 0.25,
                            edge_refinements: int = 7, edge_radius_over_h: float = 0.0,
                            contact_search: bool = True,
                            penalty: float = 1e3,
                            c20_over_c10: float = 0.0, cache: bool = True,
                            cache_dir: str | os.PathLike | None = None) -> FiniteIndentation:
    """Finite-strain flat-punch indentation of a bonded compressible Neo-Hookean layer.

    Parameters
    ----------
    a_over_h : float
        Punch radius a over layer thickness h, > 0.
    nu : float
        Small-strain Poisson's ratio, within [0, 0.5]; C10 = E / (4 (1 + nu)),
        D1 = 6 (1 - 2 nu) / E (0.5: exactly incompressible).
    contact : {'frictionless', 'bonded'}, default 'frictionless'
        Zero shear between punch and gel, or no slip on the flat face (the
        nodes initially under it are tied to the punch).
    w_over_h_max : float, default 0.2
        Final depth w/h, within (0, 0.5].
    steps : int, default 10
        Equal depth increments (the depths of the result); each is bisected
        when Newton fails.
    pad_radius_over_h : float, default 20.0
        R_pad / h, > a_over_h (the paper's pad: 15 / 3 = 5).
    cell : float, default 0.25
        Base mesh size of :func:`~tactilevision.fem.indentation_mesh`, (0, 1].
    edge_refinements : int, default 7
        Bisection rounds towards the punch edge, >= 0. The defaults are the
        beta table's mesh: at a/h = 0.8, nu = 0.49, bonded, the secant beta
        is 0.7863, 0.7706, 0.7629 with 4, 6, 8 refinements at cell 0.25 and
        0.7601 at cell 0.125 with 8 (34k dofs, 146 s), so within about 1%.
    edge_radius_over_h : float, default 0.0
        Radius of the rounded punch edge, [0, a_over_h) (0: sharp).
    contact_search : bool, default True
        Update the contact set. False keeps the nodes initially on the face on
        its plane, wherever they slide, and lets every other node pass through
        the punch: the prescribed-displacement contact of the linear problem
        (and of the prototype in method.md), for comparison.
    penalty : float, default 1e3
        Contact penalty in units of E (per unit penetration and surface
        length; see :mod:`tactilevision.fem._finite_solver`).
    c20_over_c10 : float, default 0.0
        Strain stiffening, >= 0: Yeoh's second-order term C20 (I1bar - 3)^2
        added to the isochoric energy, C20 in units of C10 (see
        :mod:`tactilevision.fem._neohookean_forms`). 0 is the Neo-Hookean law;
        an extension for asking whether the material law explains a measured
        beta, not part of the tables.
    cache : bool, default True
        Read a complete sweep from, and write it to, the disk cache
        (:mod:`tactilevision.fem._sweep_cache`): the key holds every input,
        the library versions and a digest of the solver's own source, so an
        entry is always the sweep this code computes. A sweep that stopped
        early is never stored. False runs the sweep and leaves the cache alone.
    cache_dir : path-like, optional
        Cache folder; default ``$TACTILEVISION_CACHE/fem`` if that variable
        is set, else ``~/.cache/tactilevision/fem`` (the pad stiffness's).

    Returns
    -------
    FiniteIndentation
        Depths, forces, kappa_n, kappa0, secant and tangent beta, R^2 of the
        P/w line, Newton iterations and min det F per depth, dofs, wall time.

    Raises
    ------
    InputError
        (a ``ValueError``) naming the argument: `a_over_h` <= 0, `nu` outside
        [0, 0.5], unknown `contact`, `w_over_h_max` outside (0, 0.5], `steps`
        < 1, `pad_radius_over_h` <= `a_over_h`, `cell` outside (0, 1],
        `edge_refinements` < 0, `edge_radius_over_h` outside [0, a_over_h),
        `penalty` <= 0, `c20_over_c10` < 0.

    Warns
    -----
    RuntimeWarning
        When Newton fails at some depth even after bisecting the increment;
        the result then holds the depths reached (``complete=False``).

    Notes
    -----
    Total Lagrangian, axisymmetric (hoop stretch 1 + u_r / R), measure
    2 pi R dR dZ, Taylor-Hood P2/P1 mixed u-p form of the Abaqus Neo-Hookean
    energy [2]_,

        Pi(u, p) = int [C10 (J^(-2/3) I1 - 3) + p (J - 1) - p^2 / (2 K)] dV,

    stationary in p at p = K (J - 1) = 2 (J - 1) / D1, which returns the
    Abaqus energy. Its residual and consistent tangent are derived in
    :mod:`tactilevision.fem._neohookean_forms`, the Newton, line-search and
    contact scheme in :mod:`tactilevision.fem._finite_solver`. kappa_n is
    eq. (1) of the paper (after Zhang et al. [1]_), and beta the slope over
    intercept of P/w against w/h, eq. (5).

    Limits: with a bonded punch the sweep reaches w/h = 0.2 on every mesh
    tried (down to edge cells of h/2048) and on the whole table grid (a/h
    0.2 to 2.0, nu 0.30 to 0.499). A frictionless sharp-edged punch drags the
    gel round its edge (inwards for nu <~ 0.45, outwards near 0.5); the
    elements at the edge fold and Newton fails, near w/h = 0.06 to 0.14 on
    the coarse edge mesh and earlier on finer ones, and the node-wise contact
    radius changes by one edge cell at a time. On the default mesh at
    a/h = 0.8: with ``contact_search=False`` the sweep stops at w/h = 0.02
    (nu = 0.45 and 0.49) on cell 0.25 with 6 edge refinements; with the
    search and an edge rounded to 0.02 h at 0.14 and 0.12; rounded to 0.05 h
    it completes but P/w is far from a line
    (R^2 0.91 at nu = 0.45, 0.16 at 0.49). Read ``complete`` and
    ``linearity_r2`` before trusting a frictionless beta; the beta table holds
    the bonded punch only.

    References
    ----------
    .. [1] M. Zhang, Y. P. Zheng, A. F. T. Mak, "Estimating the effective
       Young's modulus of soft tissues from indentation tests - nonlinear finite
       element analysis of effects of friction and large deformation",
       Med. Eng. Phys. 19:512-517, 1997. doi:10.1016/S1350-4533(97)00017-9
    .. [2] Abaqus Analysis User's Guide, "Hyperelastic behavior of rubberlike
       materials": U = C10 (I1bar - 3) + (J - 1)^2 / D1.

    Examples
    --------
    >>> from tactilevision.fem import neo_hookean_indentation
    >>> res = neo_hookean_indentation(0.8, 0.45, contact="bonded", w_over_h_max=0.1,
    ...                               steps=2, cell=0.25, edge_refinements=3)
    >>> res.complete, bool(res.beta_secant > 0)
    (True, True)
    """
    _check(a_over_h, nu, contact, w_over_h_max, steps, pad_radius_over_h, cell,
           edge_refinements, edge_radius_over_h, penalty)
    if not (np.isfinite(c20_over_c10) and c20_over_c10 >= 0):
        raise InputError(f"c20_over_c10 must be non-negative and finite, got {c20_over_c10!r}")
    inputs = {"a_over_h": float(a_over_h), "nu": float(nu), "contact": contact,
              "w_over_h_max": float(w_over_h_max), "steps": int(steps),
              "pad_radius_over_h": float(pad_radius_over_h), "cell": float(cell),
              "edge_refinements": int(edge_refinements),
              "edge_radius_over_h": float(edge_radius_over_h),
              "contact_search": bool(contact_search), "penalty": float(penalty),
              "c20_over_c10": float(c20_over_c10)}
    if cache:
        hit = read_sweep(inputs, FiniteIndentation, cache_dir)
        if hit is not None:
            return hit
    result = _sweep(a_over_h, nu, contact, w_over_h_max, steps, pad_radius_over_h, cell,
                    edge_refinements, edge_radius_over_h, contact_search, penalty, c20_over_c10)
    if cache and result.complete:
        write_sweep(inputs, result, cache_dir)
    return result


def _sweep(a_over_h: float, nu: float, contact: str, w_over_h_max: float, steps: int,
           pad_radius_over_h: float, cell: float, edge_refinements: int,
           edge_radius_over_h: float, contact_search: bool, penalty: float,
           c20_over_c10: float) -> FiniteIndentation:
    t0 = time.perf_counter()
    a, rho = float(a_over_h), float(edge_radius_over_h)
    mesh = indentation_mesh(a, pad_radius_over_h=pad_radius_over_h, cell=cell,
                            edge_refinements=int(edge_refinements))
    bulk = np.inf if nu == 0.5 else 1.0 / (3.0 * (1.0 - 2.0 * nu))
    c10 = 1.0 / (4.0 * (1.0 + nu))
    solid = AxisymmetricNeoHookean(mesh, c10, bulk, c20=c20_over_c10 * c10)
    ub = solid.ubasis
    punch = RigidPunch(solid, a, rho, penalty=penalty)
    if contact == "bonded":
        punch = RigidPunch(solid, a, rho, penalty=penalty, stuck=punch.select(a - rho))
    punch.face_only = not contact_search
    prob = IndentationProblem(solid, punch)
    newton = ConstrainedNewton(prob, np.concatenate([
        ub.get_dofs("bottom").all(), ub.get_dofs("axis").all("u^1"),
        punch.ur[punch.stuck], punch.uz[punch.stuck]]))
    down = np.isin(newton.fixed, punch.uz[punch.stuck])   # d x_D / dw = -1 there
    e_z = np.zeros(prob.n_dofs)
    e_z[punch.uz] = 1.0

    def rate(x: np.ndarray) -> tuple[np.ndarray, float]:
        """dx/dw and dP/dw at the equilibrium x (K dx/dw = -dR/dw, dR_c/dw = K_c e_z)."""
        k, lu = newton.linearise(x)
        k_c = punch.tangent(x, prob.w)
        dx = np.zeros_like(x)
        dx[newton.fixed] = np.where(down, -1.0, 0.0)
        rhs = k[newton.free][:, newton.fixed] @ dx[newton.fixed] + (k_c @ e_z)[newton.free]
        dx[newton.free] = lu.solve(-rhs)
        return dx, -2.0 * np.pi * float(e_z @ (k @ dx - k_c @ dx))

    x = np.zeros(prob.n_dofs)
    dxdw, dpdw0 = rate(x)
    rows: list[tuple[float, ...]] = []
    surf_ur: list[np.ndarray] = []
    surf_uz: list[np.ndarray] = []
    w_done, complete = 0.0, True
    for w_next in np.linspace(0.0, w_over_h_max, int(steps) + 1)[1:]:
        stack, its = [w_next], 0
        while stack:                                         # bisect failed increments
            prob.w, newton.cache = stack[-1], None           # the tangent depends on w
            x_try = x + dxdw * (prob.w - w_done)
            if not solid.min_jacobian(x_try) > 0:
                x_try = x
            saved = punch.engaged.copy()
            x_try, n_it, ok = _settle(newton, punch, x_try, np.where(down, -prob.w, 0.0),
                                      contact_search)
            its += n_it
            if ok:
                x, w_done = x_try, stack.pop()
                dxdw, dpdw = rate(x)
            else:
                punch.engaged = saved
                if len(stack) > _MAX_BISECTIONS:
                    break
                stack.append(0.5 * (w_done + stack[-1]))
        if stack:
            complete, prob.w, newton.cache = False, w_done, None
            warnings.warn(f"neo_hookean_indentation(a_over_h={a}, nu={nu}, contact={contact!r}):"
                          f" Newton failed beyond w/h = {w_done:.4g}; the sweep stops there "
                          f"(requested {w_over_h_max})", RuntimeWarning, stacklevel=3)
            break
        pen, radius = punch.diagnostics(x, w_done)
        surf_ur.append(x[punch.ur].copy())
        surf_uz.append(x[punch.uz].copy())
        rows.append((w_done, -2.0 * np.pi * float(e_z @ solid.residual(x)), dpdw, its,
                     solid.min_jacobian(x), pen, radius))
    res = np.array(rows, dtype=np.float64).reshape(-1, 7)
    w, p, dpdw = res[:, 0], res[:, 1], res[:, 2]
    c, cb, r2 = _line_fit(w, p / w)
    ct, ctb, _ = _line_fit(w, dpdw)
    return FiniteIndentation(
        a_over_h=a, nu=float(nu), contact=contact, pad_radius_over_h=float(pad_radius_over_h),
        w_over_h=w, force=p, kappa_n=p * (1.0 - nu**2) / (2.0 * a * w),
        kappa0=dpdw0 * (1.0 - nu**2) / (2.0 * a), beta_secant=cb / c,
        beta_tangent=ctb / (2.0 * ct), linearity_r2=r2,
        newton_iterations=res[:, 3].astype(int), min_jacobian=res[:, 4], n_dofs=int(prob.n_dofs),
        seconds=time.perf_counter() - t0, tangent_stiffness=dpdw, penetration=res[:, 5],
        contact_radius=res[:, 6], complete=complete, surface_r=punch.R.copy(),
        surface_ur=np.array(surf_ur).reshape(-1, punch.R.size),
        surface_uz=np.array(surf_uz).reshape(-1, punch.R.size))
