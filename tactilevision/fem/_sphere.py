r"""A rigid sphere pressed into a bonded gel layer: force P(w) and contact radius a(w).

A rigid sphere of radius R is pressed to depth w into an elastic layer of
thickness h and radius R_pad, bonded to a rigid base at z = 0 (free surface at
z = h = 1; lengths in units of h, E = 1). Two material models and two contact
conditions:

- ``model='linear'``: small strain, the tangent of the Neo-Hookean forms at
  the undeformed state (isotropic linear elasticity, mixed u-p, exact at
  nu = 0.5), with the sphere's exact gap f(r) = R - sqrt(R^2 - r^2) imposed at
  the nodes' reference radii (the linearised contact of Hertz and Sneddon, but
  with the sphere rather than its paraboloid);
- ``model='neo_hookean'``: finite strain, the compressible Neo-Hookean solid of
  :mod:`._neohookean_forms` (total Lagrangian, Newton of :mod:`._finite_solver`),
  the sphere a rigid body in the current configuration.

- ``contact='frictionless'``: zero shear between sphere and gel. Linear: the
  nodes in contact have u_z = -w + f(R_i), u_r free (Dirichlet active set,
  released when their reaction pulls); Neo-Hookean: the engaged-set penalty
  contact of :class:`._finite_solver.RigidPunch` with a punch whose flat face
  has shrunk to a point and whose edge radius is R, i.e. a sphere (its upper
  half replaced by a cylinder, which no press below the equator touches).
- ``contact='tied'``: no slip, full stick: a surface node that meets the
  sphere is tied to it from then on and moves with it (Dirichlet on both
  components; never released).
- ``contact='coulomb'`` (``model='linear'`` only): Coulomb friction of
  coefficient mu between the two, as in the FEATS authors' CalculiX model
  (friction 1.0). A node that meets the sphere sticks where it touches; where
  its shear reaction exceeds mu times its normal reaction it slips, held
  by a shear force mu p against its slip (a node-wise active set, the slip
  forces' normal reactions iterated to a fixed point), and sticks again where
  it would slide with its friction force. In the normal direction it is the
  tied contact (a node that touches stays on the sphere, as CalculiX's TIED
  overclosure), the shear bounded by mu |p|: a large mu is the tied contact,
  mu = 0 the frictionless one but for the rare node that would pull away.
  The load path matters: the steps are those of tied contact.

The depth is stepped on a grid uniform in sqrt(w) (the contact radius grows
like sqrt(R w)); tied contact depends on the path, and its steps move the
contact edge by at most one surface cell; the requested depths are among the
steps.

Contact radius. The node-wise contact set resolves a only to a surface cell.
Just outside the edge of a smooth contact the gap opens as (r - a)^(3/2)
(Hertz's solution; K. L. Johnson, Contact Mechanics, 1985, ch. 4): g^(2/3)
is a straight line in r through zero at a, fitted to the first four free
nodes and kept between the last node in contact and the first free one. This
sub-cell estimate is what `contact_radius` holds (radius in the current
configuration for ``'neo_hookean'``, reference for ``'linear'``);
`contact_radius_nodes` is the plain node-wise one.
"""

from __future__ import annotations

import functools
import os
import time
import warnings
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from skfem import MeshTri

from .._cache import code_digest
from .._checks import InputError
from ._finite_solver import ConstrainedNewton, IndentationProblem, RigidPunch
from ._neohookean_forms import AxisymmetricNeoHookean
from ._sweep_cache import read_sweep, write_sweep

__all__ = ["SPHERE_CONTACTS", "SPHERE_MODELS", "SphereIndentation", "dome_sag", "hertz_force",
           "sphere_indentation", "sphere_mesh"]

SPHERE_MODELS = ("linear", "neo_hookean")
SPHERE_CONTACTS = ("frictionless", "tied")
#: Contact conditions of :func:`sphere_indentation`: the tables' two and Coulomb friction.
CONTACTS = (*SPHERE_CONTACTS, "coulomb")
_TOL = 1e-9          # h: engage / release tolerance of the linear active set
_MAX_SET_UPDATES = 40
_MAX_BISECTIONS = 3


def hertz_force(radius_over_h: float, w_over_h: np.ndarray, nu: float) -> np.ndarray:
    """Hertz's force of a rigid sphere on an elastic half-space, P / (E h^2).

    P = 4/3 E / (1 - nu^2) R^(1/2) w^(3/2) (Hertz 1882; Johnson, Contact
    Mechanics, 1985, eq. 4.23 with a rigid sphere), the paraboloid limit
    w << R; its contact radius is a = sqrt(R w).

    Parameters
    ----------
    radius_over_h : float
        R / h.
    w_over_h : (K,) float ndarray
        Depths w / h.
    nu : float

    Returns
    -------
    (K,) float64 ndarray
    """
    w = np.asarray(w_over_h, dtype=np.float64)
    return 4.0 / 3.0 / (1.0 - nu**2) * np.sqrt(radius_over_h) * w**1.5


def _graded(x0: float, x1: float, h0: float, growth: float) -> np.ndarray:
    xs = [x0]
    step = h0
    while xs[-1] + step < x1 - 0.5 * step:
        xs.append(xs[-1] + step)
        step *= growth
    xs.append(x1)
    return np.array(xs)


def sphere_mesh(contact_radius_max: float, surface_cell: float, *,
                pad_radius_over_h: float = 20.0, cell: float = 0.125,
                dome_radius_over_h: float | None = None) -> MeshTri:
    """Triangles of the (r, z) half-section, graded towards the top surface under the sphere.

    Parameters
    ----------
    contact_radius_max : float
        The largest contact radius the sweep reaches, units of h. The finest
        cells line the top surface from the axis to 1.25 times it.
    surface_cell : float
        Cell size along the top surface there, units of h: `cell` is halved
        (red refinement of the triangles near that stretch, each round in a
        band six of its cells wide) until it is at most this.
    pad_radius_over_h : float, default 20.0
    cell : float, default 0.125
        Base cell size through the thickness and under the sphere.
    dome_radius_over_h : float, optional
        A domed top: the free surface a spherical cap of this radius (units of
        h), the layer 1 thick on the axis and ``1 - dome_sag(r)`` at radius r
        (:func:`dome_sag`), each node's height scaled by that factor. None: flat.

    Returns
    -------
    skfem.MeshTri
        Boundaries ``'bottom'``, ``'axis'``, ``'outer'``, ``'punch'`` (the
        top surface within the fine stretch) and ``'free'`` (the rest of it).

    Raises
    ------
    InputError
        If the pad is not wider than 1.3 times the largest contact radius, or
        the dome falls by more than half the thickness before the pad's edge.
    """
    a = float(contact_radius_max)
    if not (a > 0 and pad_radius_over_h > 1.3 * a):
        raise InputError(f"the pad radius {pad_radius_over_h:g} h must exceed 1.3 times the "
                         f"largest contact radius {a:.3g} h")
    zone = min(1.25 * a, 0.5 * (pad_radius_over_h + 1.25 * a))
    reach = min(zone + 6 * cell, pad_radius_over_h)
    n_in = max(2, int(np.ceil(reach / cell)))
    r_in = np.linspace(0.0, reach, n_in + 1)
    # where the fine stretch reaches the pad's edge there is nothing beyond it: a second
    # node at the edge would make cells of zero width (a singular stiffness matrix)
    r_out = (_graded(reach, pad_radius_over_h, reach / n_in, 1.25)
             if pad_radius_over_h > reach + 1e-9 else np.array([reach]))
    r = np.concatenate([r_in, r_out[1:]])
    z = np.linspace(0.0, 1.0, max(2, int(np.ceil(1.0 / cell))) + 1)
    mesh = MeshTri.init_tensor(r, z)
    size = cell
    while size > surface_cell * (1 + 1e-9):
        c = mesh.p[:, mesh.t].mean(axis=1)
        dist = np.hypot(np.maximum(c[0] - zone, 0.0), 1.0 - c[1])
        mesh = mesh.refined(np.nonzero(dist < 6 * size)[0])
        size *= 0.5
    eps = 1e-9
    mesh = mesh.with_boundaries({
        "bottom": lambda x: np.abs(x[1]) < eps,
        "axis": lambda x: np.abs(x[0]) < eps,
        "outer": lambda x: np.abs(x[0] - pad_radius_over_h) < eps,
        "punch": lambda x: (np.abs(x[1] - 1.0) < eps) & (x[0] <= zone + eps),
        "free": lambda x: (np.abs(x[1] - 1.0) < eps) & (x[0] >= zone - eps),
    })
    if dome_radius_over_h is None:
        return mesh
    p = mesh.p.copy()
    p[1] *= 1.0 - dome_sag(p[0], dome_radius_over_h, pad_radius_over_h)
    return replace(mesh, doflocs=p)


def dome_sag(r: np.ndarray, dome_radius_over_h: float, pad_radius_over_h: float
             ) -> np.ndarray:
    """How far a domed top lies below its apex at radius r: ``Rd - sqrt(Rd^2 - r^2)``.

    Parameters
    ----------
    r : (M,) float ndarray
        Radii, units of h, within the pad.
    dome_radius_over_h : float
        Rd / h, the top's radius of curvature (convex).
    pad_radius_over_h : float
        The pad's radius; the sag there must be at most half the thickness.

    Returns
    -------
    (M,) float64 ndarray
        Units of h, >= 0.

    Raises
    ------
    InputError
        When the dome is not wider than the pad or falls by more than 0.5 h by
        its edge (then the pad's radius is what to give).
    """
    rd = float(dome_radius_over_h)
    edge = rd - np.sqrt(max(rd * rd - pad_radius_over_h**2, 0.0)) if rd > 0 else np.inf
    if not (np.isfinite(rd) and rd > pad_radius_over_h and edge <= 0.5):
        raise InputError(f"the dome of radius {rd:g} h falls by {edge:.3g} h by the pad's edge "
                         f"({pad_radius_over_h:g} h): at most 0.5 h (give the pad's own "
                         "radius, or a flatter dome)")
    r = np.asarray(r, dtype=np.float64)
    return rd - np.sqrt(rd * rd - np.minimum(r * r, rd * rd))


@dataclass(frozen=True)
class SphereIndentation:
    """One depth sweep of a rigid sphere into the bonded layer (units of h, forces of E h^2).

    Attributes
    ----------
    radius_over_h, nu : float
        Sphere radius R / h; small-strain Poisson's ratio.
    model : {'linear', 'neo_hookean'}
    contact : {'frictionless', 'tied', 'coulomb'}
    pad_radius_over_h : float
    w_over_h : (K,) float64 ndarray
        The requested depths reached, increasing.
    force : (K,) float64 ndarray
        P / (E h^2).
    contact_radius : (K,) float64 ndarray
        a / h, the sub-cell estimate (module docstring).
    contact_radius_nodes : (K,) float64 ndarray
        a / h of the outermost node in contact.
    hertz_ratio : (K,) float64 ndarray
        `force` over Hertz's half-space force at the same depth.
    complete : bool
        False when the sweep stopped before the last depth.
    n_dofs : int
    surface_cell : float
        Cell size along the top surface under the sphere, units of h.
    seconds : float
    newton_iterations : (K,) int ndarray
        Iterations since the previous requested depth.
    min_jacobian : (K,) float64 ndarray
    penetration : (K,) float64 ndarray
        Largest penetration of a surface node into the sphere, units of h.
    surface_r : (M,) float64 ndarray
        Reference radii of the top-surface nodes, increasing.
    surface_ur, surface_uz : (K, M) float64 ndarray
        Their displacements at each depth (u_z < 0 into the gel).
    from_cache : bool
    friction : float
        Coulomb's mu (``contact='coulomb'``; 0 otherwise).
    slip_radius : (K,) float64 ndarray or None
        Coulomb contact: radius of the innermost slipping node in contact, units
        of h (the stick zone's edge; the contact radius where none slips).
    surface_fz, surface_fr : (K, M) float64 ndarray or None
        Coulomb contact: the nodal forces of the sphere on each top-surface node
        (normal, < 0 pressing; shear), per radian, units of E h^2; zero off the
        contact.
    dome_radius_over_h : float or None
        The domed top's radius of curvature (None: a flat top). `hertz_ratio`
        stays the ball's Hertz force (radius R), not the two curvatures'.
    """

    radius_over_h: float
    nu: float
    model: str
    contact: str
    pad_radius_over_h: float
    w_over_h: np.ndarray
    force: np.ndarray
    contact_radius: np.ndarray
    contact_radius_nodes: np.ndarray
    hertz_ratio: np.ndarray
    complete: bool
    n_dofs: int
    surface_cell: float
    seconds: float
    newton_iterations: np.ndarray
    min_jacobian: np.ndarray
    penetration: np.ndarray
    surface_r: np.ndarray | None = None
    surface_ur: np.ndarray | None = None
    surface_uz: np.ndarray | None = None
    from_cache: bool = False
    friction: float = 0.0
    slip_radius: np.ndarray | None = None
    surface_fz: np.ndarray | None = None
    surface_fr: np.ndarray | None = None
    dome_radius_over_h: float | None = None


class _RigidSphere(RigidPunch):
    """The flat punch of :class:`RigidPunch` shrunk to its rounded edge: a sphere.

    Its contact set is updated without the flat punch's hysteresis: a node
    held by any tensile force (outside the sphere, s > 0) is released, one
    that penetrates by more than ``1e-6 w`` engaged. The flat punch's absolute
    1e-7 h let a node be held by a tensile force of several percent of P at
    the shallow depths of a sphere (w/h ~ 0.003), and the force then depended
    on the load steps (-3.5 % at w/h = 0.0025, R/h = 1, two steps).
    """

    lift: np.ndarray | None = None

    def __init__(self, problem: AxisymmetricNeoHookean, radius: float, penalty: float) -> None:
        super().__init__(problem, radius, radius, penalty=penalty)
        lift = problem.ubasis.doflocs[1, self.uz] - 1.0
        if np.any(lift != 0.0):                      # a domed top: the nodes lie below 1
            self.lift = lift
            self.engaged = (self.signed_gap(np.zeros(self.n_dofs), 0.0)[0] <= 1e-12) \
                & ~self.stuck

    def signed_gap(self, x: np.ndarray, w: float) -> tuple[np.ndarray, ...]:
        """The punch's gap, the top-surface nodes at their own reference heights."""
        if self.lift is None:
            return super().signed_gap(x, w)
        y = x.copy()
        y[self.uz] += self.lift
        return super().signed_gap(y, w)

    def update(self, x: np.ndarray, w: float) -> bool:
        tol = 1e-6 * max(w, 1e-9)
        s = self.signed_gap(x, w)[0]
        new = (self.engaged | (s < -tol)) & ~(s > 0.0) & ~self.stuck
        changed = not np.array_equal(new, self.engaged)
        self.engaged = new
        return changed


class _LinearSolid:
    """K0 x - f: the Neo-Hookean tangent at the undeformed state (linear elasticity),
    less the nodal forces f (Coulomb contact's slip forces)."""

    #: K0 at every x: :class:`ConstrainedNewton` factorises it once per set of free dofs
    constant_tangent = True

    def __init__(self, solid: AxisymmetricNeoHookean) -> None:
        self.k0 = solid.tangent(np.zeros(solid.n_dofs)).tocsr()
        self.n_dofs = solid.n_dofs
        self.ubasis = solid.ubasis
        self.f_ext = np.zeros(solid.n_dofs)

    def residual(self, x: np.ndarray) -> np.ndarray:
        return self.k0 @ x - self.f_ext

    def tangent(self, x: np.ndarray) -> sp.csr_matrix:
        return self.k0

    @staticmethod
    def min_jacobian(x: np.ndarray) -> float:
        return 1.0


class _Surface:
    """Top-surface nodes (sorted by R) and the sphere's geometry at depth w."""

    def __init__(self, ubasis, radius: float, paraboloid: bool = False) -> None:
        self.paraboloid = paraboloid
        top = ubasis.get_dofs(np.concatenate([ubasis.mesh.boundaries["punch"],
                                              ubasis.mesh.boundaries["free"]]))
        ur, uz = top.all("u^1"), top.all("u^2")
        order = np.argsort(ubasis.doflocs[0, ur])
        self.ur, self.uz = ur[order], uz[order]
        self.R = ubasis.doflocs[0, self.ur]
        self.Z = ubasis.doflocs[1, self.uz]          # 1, or below it on a domed top
        self.radius = float(radius)

    def sphere_z(self, r: np.ndarray, w: float) -> np.ndarray:
        """Height of the sphere's lower surface above the base at radius r (inf past R)."""
        if self.paraboloid:
            return 1.0 - w + r**2 / (2.0 * self.radius)
        rr = np.minimum(np.abs(r), self.radius)
        z = 1.0 - w + self.radius - np.sqrt(self.radius**2 - rr**2)
        return np.where(np.abs(r) < self.radius, z, np.inf)

    def gap(self, x: np.ndarray, w: float, linear: bool) -> np.ndarray:
        """Signed gap (>= 0 free, < 0 penetrating), units of h."""
        if linear:
            return self.sphere_z(self.R, w) - (self.Z + x[self.uz])
        r, z = self.R + x[self.ur], self.Z + x[self.uz]
        c = 1.0 - w + self.radius
        return np.hypot(r, z - c) - self.radius

    def project(self, x: np.ndarray, w: float, linear: bool) -> tuple[np.ndarray, np.ndarray]:
        """(u_r, u_z) that put each node on the sphere (linear: straight down)."""
        if linear:
            return x[self.ur].copy(), self.sphere_z(self.R, w) - self.Z
        r, z = self.R + x[self.ur], self.Z + x[self.uz]
        c = 1.0 - w + self.radius
        d = np.maximum(np.hypot(r, z - c), 1e-300)
        return r * self.radius / d - self.R, c + (z - c) * self.radius / d - self.Z


def _edge(radii: np.ndarray, gaps: np.ndarray, held: np.ndarray, n_fit: int = 4
          ) -> tuple[float, float]:
    """(sub-cell contact radius, node-wise contact radius) from the surface's gaps.

    The gap just outside the edge of a smooth contact opens as C (r - a)^(3/2):
    g^(2/3) is a straight line in r that crosses zero at a. It is fitted (least
    squares) to the first `n_fit` free nodes past the last node in contact, and
    a kept between that node and the first free one.
    """
    if not held.any():
        return 0.0, 0.0
    last = int(np.flatnonzero(held).max())
    r0 = float(radii[last])
    r = radii[last + 1:last + 1 + n_fit]
    g = gaps[last + 1:last + 1 + n_fit]
    if r.size < 2 or not np.all(g > 0):
        return r0, r0
    slope, icpt = np.polyfit(r, g ** (2.0 / 3.0), 1)
    if not slope > 0:
        return r0, r0
    return float(np.clip(-icpt / slope, r0, r[0])), r0


def _check(radius_over_h: float, nu: float, model: str, contact: str,
           w_over_h: np.ndarray, pad_radius_over_h: float, surface_cell: float,
           penalty: float, friction: float | None) -> None:
    if not (np.isfinite(radius_over_h) and radius_over_h > 0):
        raise InputError(f"radius_over_h must be positive and finite, got {radius_over_h!r}")
    if not (np.isfinite(nu) and 0.0 <= nu <= 0.5):
        raise InputError(f"nu must be within [0, 0.5], got {nu!r}")
    if model not in SPHERE_MODELS:
        raise InputError(f"model must be one of {SPHERE_MODELS}, got {model!r}")
    if contact not in CONTACTS:
        raise InputError(f"contact must be one of {CONTACTS}, got {contact!r}")
    if contact == "coulomb" and model != "linear":
        raise InputError("contact='coulomb' is built for model='linear' only")
    if (contact == "coulomb") != (friction is not None):
        raise InputError("friction (Coulomb's mu) is given with contact='coulomb', and only "
                         f"then; got contact={contact!r}, friction={friction!r}")
    if friction is not None and not (np.isfinite(friction) and friction >= 0):
        raise InputError(f"friction must be finite and >= 0, got {friction!r}")
    if w_over_h.size == 0 or not np.all(np.isfinite(w_over_h)) or np.any(w_over_h <= 0) \
            or np.any(np.diff(w_over_h) <= 0):
        raise InputError("w_over_h must be positive, finite and increasing")
    if w_over_h[-1] > min(0.6, radius_over_h):
        raise InputError(f"w_over_h reaches {w_over_h[-1]:g}: at most 0.6 and at most the "
                         f"sphere's radius {radius_over_h:g} (its equator)")
    if not (np.isfinite(surface_cell) and 0 < surface_cell <= 0.125):
        raise InputError(f"surface_cell must be within (0, 0.125], got {surface_cell!r}")
    if not (np.isfinite(penalty) and penalty > 0):
        raise InputError(f"penalty must be positive and finite, got {penalty!r}")
    if not np.isfinite(pad_radius_over_h):
        raise InputError(f"pad_radius_over_h must be finite, got {pad_radius_over_h!r}")


def default_surface_cell(radius_over_h: float, w_over_h_min: float) -> float:
    """A surface cell of 1/12 of the first depth's Hertz contact radius, at most h/16."""
    return float(min(0.0625, np.sqrt(radius_over_h * w_over_h_min) / 12.0))


def sphere_indentation(radius_over_h: float, nu: float, w_over_h: np.ndarray, *,
                       model: str = "neo_hookean", contact: str = "frictionless",
                       pad_radius_over_h: float = 20.0, surface_cell: float | None = None,
                       steps_per_depth: int = 2, penalty: float = 1e3,
                       profile: str = "sphere", friction: float | None = None,
                       dome_radius_over_h: float | None = None,
                       cache: bool | str = True,
                       cache_dir: str | os.PathLike | None = None) -> SphereIndentation | None:
    """P(w) and a(w) of a rigid sphere pressed into a bonded layer, linear or Neo-Hookean.

    Parameters
    ----------
    radius_over_h : float
        Sphere radius R over layer thickness h, > 0.
    nu : float
        Poisson's ratio, within [0, 0.5] (0.5 exactly incompressible).
    w_over_h : (K,) array_like of float
        Depths w / h, increasing, positive, at most min(0.6, R / h).
    model : {'neo_hookean', 'linear'}, default 'neo_hookean'
    contact : {'frictionless', 'tied', 'coulomb'}, default 'frictionless'
        'coulomb' (with `friction`) for ``model='linear'`` only.
    pad_radius_over_h : float, default 20.0
        R_pad / h (20: the infinite layer).
    surface_cell : float, optional
        Cell size along the surface under the sphere, units of h; default
        :func:`default_surface_cell` of the first depth.
    steps_per_depth : int, default 2
        Load steps between requested depths, at least (on the sqrt(w) grid).
        Tied contact depends on the path (a node sticks where it first
        touches): its steps are also cut so that the contact edge moves by at
        most one surface cell per step. At R/h = 20, nu = 0.3, Neo-Hookean,
        w/h = 0.005, two steps per depth gave P/P_Hertz 1.361, six 1.396 and
        twelve 1.405: the edge's step, not the depth's, is what converges.
    penalty : float, default 1e3
        Frictionless Neo-Hookean contact penalty, units of E.
    profile : {'sphere', 'paraboloid'}, default 'sphere'
        The indenter's shape; 'paraboloid' (z = r^2 / 2R, Hertz's
        approximation, ``model='linear'`` only) is for checks against
        closed forms built on it (Hertz, Dimitriadis et al. 2002).
    friction : float, optional
        Coulomb's coefficient mu >= 0, with ``contact='coulomb'`` and only then.
    dome_radius_over_h : float, optional
        A domed gel: its top a spherical cap of radius Rd / h (convex, the
        layer 1 h thick on the axis, thinner towards the pad's edge;
        :func:`sphere_mesh`), w measured from first touch at the apex. In the
        half-space limit the contact is Hertz's of two curvatures, radius
        R Rd / (R + Rd) (Johnson 1985, sec. 4.2). A GelSight Mini's gel is
        domed (FEATS: 0.28 mm at 8 mm, Rd about 114 mm). None: a flat top.
    cache : bool or 'only', default True
        Read and write complete sweeps in the disk cache (as
        :func:`~tactilevision.fem.neo_hookean_indentation`); ``'only'``: the
        cached sweep, or None without computing one.
    cache_dir : path-like, optional

    Returns
    -------
    SphereIndentation

    Raises
    ------
    InputError
        Naming the argument out of range.

    Warns
    -----
    RuntimeWarning
        When Newton fails at a depth even after bisection; the result holds the
        depths reached (``complete=False``).

    References
    ----------
    .. [1] H. Hertz, "Ueber die Beruehrung fester elastischer Koerper", J. reine
       angew. Math. 92:156-171, 1882.
    .. [2] K. L. Johnson, Contact Mechanics, Cambridge University Press, 1985.
    .. [3] E. K. Dimitriadis, F. Horkay, J. Maresca, B. Kachar, R. S. Chadwick,
       "Determination of elastic moduli of thin layers of soft material using
       the atomic force microscope", Biophys. J. 82:2798-2810, 2002.
    """
    w_req = np.atleast_1d(np.asarray(w_over_h, dtype=np.float64))
    _check(radius_over_h, nu, model, contact, w_req, pad_radius_over_h,
           0.125 if surface_cell is None else surface_cell, penalty, friction)
    if surface_cell is None:
        surface_cell = default_surface_cell(radius_over_h, float(w_req[0]))
    inputs = {"kind": "sphere", "source": _source_digest(),
              "radius_over_h": float(radius_over_h), "nu": float(nu),
              "w_over_h": [float(v) for v in w_req], "model": model, "contact": contact,
              "pad_radius_over_h": float(pad_radius_over_h),
              "surface_cell": float(surface_cell), "steps_per_depth": int(steps_per_depth),
              "penalty": float(penalty), "profile": profile}
    if friction is not None:
        inputs["friction"] = float(friction)
    if dome_radius_over_h is not None:
        dome_sag(np.zeros(1), dome_radius_over_h, pad_radius_over_h)       # checked
        inputs["dome_radius_over_h"] = float(dome_radius_over_h)
    if profile not in ("sphere", "paraboloid") or (profile == "paraboloid" and model != "linear"):
        raise InputError(f"profile must be 'sphere', or 'paraboloid' with model='linear' "
                         f"(Hertz's approximation, for checks), got {profile!r}")
    if cache:
        hit = read_sweep(inputs, SphereIndentation, cache_dir)
        if hit is not None or cache == "only":
            return hit
    res = _sweep(float(radius_over_h), float(nu), w_req, model, contact,
                 float(pad_radius_over_h), float(surface_cell), int(steps_per_depth),
                 float(penalty), profile, 0.0 if friction is None else float(friction),
                 None if dome_radius_over_h is None else float(dome_radius_over_h))
    if cache and res.complete:
        write_sweep(inputs, res, cache_dir)
    return res


#: The modules whose code decides a sphere sweep's numbers: this one (mesh, contact, load
#: steps) and the solver and material forms it imports (their syntax trees enter the key).
SPHERE_SOURCES = ("_sphere.py", "_finite_solver.py", "_neohookean_forms.py")


@functools.lru_cache(maxsize=1)
def _source_digest() -> str:
    """SHA-256 of :data:`SPHERE_SOURCES`' code (docstrings and comments left out): a cached
    sphere sweep misses when any of them changes (the flat punch's sweeps, keyed on their
    own modules, are not touched)."""
    here = Path(__file__).resolve().parent
    return code_digest(*(here / name for name in SPHERE_SOURCES))


def _load_steps(w_req: np.ndarray, per: int, ds_max: float = np.inf) -> np.ndarray:
    """Load steps: each interval of sqrt(w) between requested depths cut in `per` or
    more, so that no step of sqrt(w) exceeds `ds_max`."""
    s = np.sqrt(np.concatenate([[0.0], w_req]))
    fine = [np.linspace(s[i], s[i + 1], max(per, int(np.ceil((s[i + 1] - s[i]) / ds_max)))
                        + 1)[1:] for i in range(len(w_req))]
    return np.concatenate(fine) ** 2


class _Sweep:
    """One depth sweep: the mesh, the solid, the contact set and the Newton solver."""

    def __init__(self, R: float, nu: float, w_max: float, model: str, contact: str,
                 pad: float, surface_cell: float, penalty: float, profile: str,
                 friction: float = 0.0, dome: float | None = None) -> None:
        a_max = float(np.sqrt(max(2 * R * w_max - w_max**2, 0.0)))   # geometric, > elastic
        mesh = sphere_mesh(a_max, surface_cell, pad_radius_over_h=pad, dome_radius_over_h=dome)
        bulk = np.inf if nu == 0.5 else 1.0 / (3.0 * (1.0 - 2.0 * nu))
        self.solid = solid = AxisymmetricNeoHookean(mesh, 1.0 / (4.0 * (1.0 + nu)), bulk)
        self.R, self.linear, self.tied = R, model == "linear", contact == "tied"
        self.coulomb, self.mu = contact == "coulomb", float(friction)
        self.surf = _Surface(solid.ubasis, R, paraboloid=profile == "paraboloid")
        self.base = np.concatenate([solid.ubasis.get_dofs("bottom").all(),
                                    solid.ubasis.get_dofs("axis").all("u^1")])
        self.punch: _RigidSphere | None = None
        if self.linear or self.tied:
            self.problem = _LinearSolid(solid) if self.linear else solid
        else:
            self.punch = _RigidSphere(solid, R, penalty)
            self.problem = IndentationProblem(solid, self.punch)
        m = self.surf.R.size
        # contact set: nodes held on the sphere by Dirichlet conditions (linear, tied)
        self.held = np.zeros(m, dtype=bool)
        self.held[0] = True                          # the apex touches first
        self.target_ur = np.zeros(m)                 # tied: u_r where each node stuck
        self.offset_z = np.zeros(m)                  # tied NH: z on sphere + w at sticking
        self.stick = np.zeros(m, dtype=bool)         # Coulomb: held nodes that stick
        self.stick[0] = True
        self.slip_force = np.zeros(m)                # Coulomb: +-mu p on slipping nodes
        self.newton = ConstrainedNewton(self.problem, self.fixed_and_target(0.0)[0])

    def fixed_and_target(self, w: float) -> tuple[np.ndarray, np.ndarray]:
        """Dirichlet dofs (sorted) and their values at depth w: base, axis, held nodes."""
        if self.punch is not None:
            return self.base, np.zeros(self.base.size)
        surf, idx = self.surf, np.flatnonzero(self.held)
        vz = (surf.sphere_z(surf.R[idx], w) - surf.Z[idx]) if self.linear \
            else self.offset_z[idx] - w
        dofs, vals = [self.base, surf.uz[idx]], [np.zeros(self.base.size), vz]
        if self.tied or self.coulomb:
            idx = idx[self.stick[idx]] if self.coulomb else idx
            dofs.append(surf.ur[idx])
            vals.append(self.target_ur[idx])
        d, v = np.concatenate(dofs), np.concatenate(vals)
        order = np.argsort(d)
        return d[order], v[order]

    def state(self) -> tuple:
        return (self.held.copy(), self.target_ur.copy(), self.offset_z.copy(),
                self.stick.copy(), self.slip_force.copy(),
                None if self.punch is None else self.punch.engaged.copy())

    def restore(self, saved: tuple) -> None:
        self.held[:], self.target_ur[:], self.offset_z[:] = saved[:3]
        self.stick[:], self.slip_force[:] = saved[3:5]
        if self.punch is not None:
            self.punch.engaged = saved[5]

    def _solve(self, x: np.ndarray, w: float) -> tuple[np.ndarray, int, bool]:
        """One solve at depth w with the current contact set (and slip forces)."""
        fixed, target = self.fixed_and_target(w)
        self.newton.set_fixed(fixed)
        if self.punch is not None:
            self.problem.w = w
        if self.coulomb:
            self.problem.f_ext[:] = 0.0
            self.problem.f_ext[self.surf.ur] = self.slip_force
        if not self.linear:      # K0 does not change with depth, nor with the slip forces
            self.newton.cache = None
        full = np.zeros(self.solid.n_dofs)
        full[fixed] = target                           # set_fixed drops repeated dofs
        # no tangent at the converged x: the next solve starts from a fresh one
        return self.newton.solve(x, full[self.newton.fixed], tangent_after=self.linear)

    def settle_coulomb(self, x: np.ndarray, w: float) -> tuple[np.ndarray, int, bool]:
        """Solve at depth w under Coulomb friction: contact, stick and slip sets and the
        slip forces +-mu p updated until they settle (p to 1e-6 of the largest)."""
        n_it, surf, mu = 0, self.surf, self.mu
        for _ in range(4 * _MAX_SET_UPDATES):
            x, n, ok = self._solve(x, w)
            n_it += n
            if not ok:
                return x, n_it, False
            reac = self.problem.residual(x)
            p, q = -reac[surf.uz], reac[surf.ur]       # the sphere's push and shear on the gel
            scale = max(float(np.max(np.abs(p))), 1e-300)
            first = np.arange(self.held.size) > 0
            enter = (~self.held) & (surf.gap(x, w, True) < -_TOL) & (surf.R < self.R)
            stuck, sliding = self.held & self.stick, self.held & ~self.stick
            slip = stuck & (np.abs(q) > mu * np.abs(p) + 1e-9 * scale) & first
            drift = x[surf.ur] - self.target_ur
            back = sliding & (self.slip_force * drift > 0) & (np.abs(drift) > 1e-12 * w)
            force = np.where(sliding, np.sign(self.slip_force) * mu * np.abs(p), 0.0)
            moved = np.abs(force - self.slip_force) > 1e-6 * scale
            if not (enter.any() or slip.any() or back.any() or moved.any()):
                self.target_ur[sliding] = x[surf.ur][sliding]   # a slipped node's new anchor
                return x, n_it, True
            self.slip_force = force
            self.slip_force[slip] = np.sign(q[slip]) * mu * np.abs(p[slip])
            self.stick[slip] = False
            self.stick[back] = True
            self.target_ur[back | enter] = x[surf.ur][back | enter]
            self.slip_force[back] = 0.0
            self.held[enter], self.stick[enter] = True, True
        return x, n_it, False

    def settle(self, x: np.ndarray, w: float) -> tuple[np.ndarray, int, bool]:
        """Solve at depth w, updating the contact set until it settles."""
        if self.coulomb:
            return self.settle_coulomb(x, w)
        n_it, surf = 0, self.surf
        for _ in range(_MAX_SET_UPDATES):
            x, n, ok = self._solve(x, w)
            n_it += n
            if not ok:
                return x, n_it, False
            if self.punch is not None:
                if not self.punch.update(x, w):
                    return x, n_it, True
                continue
            g = surf.gap(x, w, self.linear)
            enter = (~self.held) & (g < -_TOL) & (surf.R < self.R)
            leave = np.zeros_like(self.held)
            if not self.tied:                          # frictionless linear: release pulls
                reac = self.problem.residual(x)[surf.uz]
                leave = (self.held & (reac > 1e-12 * np.max(np.abs(reac)))
                         & (np.arange(self.held.size) > 0))
            if not enter.any() and not leave.any():
                return x, n_it, True
            if self.tied:
                ur, uz = surf.project(x, w, self.linear)
                self.target_ur[enter] = ur[enter]
                self.offset_z[enter] = uz[enter] + w
            self.held[enter] = True
            self.held[leave] = False
        return x, n_it, False

    def record(self, x: np.ndarray, w: float) -> tuple[float, ...]:
        """(w, force, a sub-cell, a node-wise, min J, penetration, slip radius) at a
        converged depth."""
        surf = self.surf
        e_z = np.zeros(self.solid.n_dofs)
        e_z[surf.uz] = 1.0
        res = self.problem.residual(x) if self.linear else self.solid.residual(x)
        g = surf.gap(x, w, self.linear)
        inside = self.held if self.punch is None else self.punch.engaged
        radii = surf.R if self.linear else surf.R + x[surf.ur]
        a_sub, a_node = _edge(radii, g, inside)
        sliding = inside & ~self.stick if self.coulomb else np.zeros_like(inside)
        return (w, -2.0 * np.pi * float(e_z @ res), a_sub, a_node,
                1.0 if self.linear else self.solid.min_jacobian(x),
                float(np.max(-g[inside], initial=0.0)),
                float(surf.R[sliding].min()) if sliding.any() else a_node)


def _sweep(R: float, nu: float, w_req: np.ndarray, model: str, contact: str,
           pad: float, surface_cell: float, per: int, penalty: float,
           profile: str, friction: float = 0.0, dome: float | None = None) -> SphereIndentation:
    t0 = time.perf_counter()
    sw = _Sweep(R, nu, float(w_req[-1]), model, contact, pad, surface_cell, penalty, profile,
                friction, dome)
    x = np.zeros(sw.solid.n_dofs)
    x_prev, w_prev, w_pp = x.copy(), 0.0, 0.0
    # tied contact depends on the path: each step moves the edge by at most a surface cell
    # (Hertz's a = sqrt(R w)); frictionless contact does not (per requested depth only)
    steps = _load_steps(w_req, per, surface_cell / np.sqrt(R) if contact != 'frictionless'
                         else np.inf)
    rows, its_list, surf_ur, surf_uz, forces = [], [], [], [], []
    its, complete = 0, True
    for w_next in steps:
        stack = [float(w_next)]
        while stack:                                   # bisect a failed step
            w = stack[-1]
            saved = sw.state()
            x_try = x.copy()
            if w_prev > w_pp:                          # secant predictor
                x_try = x + (x - x_prev) * ((w - w_prev) / (w_prev - w_pp))
                if not sw.solid.min_jacobian(x_try) > 0:
                    x_try = x.copy()
            x_try, n_it, ok = sw.settle(x_try, w)
            its += n_it
            if ok:
                x_prev, x = x, x_try
                w_pp, w_prev = w_prev, w
                stack.pop()
                continue
            sw.restore(saved)
            if len(stack) > _MAX_BISECTIONS:
                break
            stack.append(0.5 * (w_prev + stack[-1]))
        if stack:
            complete = False
            warnings.warn(f"sphere_indentation(R/h={R}, nu={nu}, {model}, {contact}): Newton "
                          f"failed beyond w/h = {w_prev:.4g}", RuntimeWarning, stacklevel=3)
            break
        if np.any(np.isclose(w_next, w_req, rtol=1e-12, atol=0)):
            rows.append(sw.record(x, float(w_next)))
            its_list.append(its)
            surf_ur.append(x[sw.surf.ur].copy())
            surf_uz.append(x[sw.surf.uz].copy())
            if sw.coulomb:
                reac = sw.problem.residual(x)
                forces.append(np.where(sw.held, reac[sw.surf.uz], 0.0))
                forces.append(np.where(sw.held, reac[sw.surf.ur] + sw.slip_force, 0.0))
            its = 0
    res = np.array(rows, dtype=np.float64).reshape(-1, 7)
    w = res[:, 0]
    m = sw.surf.R.size
    return SphereIndentation(
        radius_over_h=R, nu=nu, model=model, contact=contact, pad_radius_over_h=pad,
        w_over_h=w, force=res[:, 1], contact_radius=res[:, 2], contact_radius_nodes=res[:, 3],
        hertz_ratio=res[:, 1] / hertz_force(R, w, nu), complete=complete,
        n_dofs=int(sw.solid.n_dofs), surface_cell=surface_cell,
        seconds=time.perf_counter() - t0, newton_iterations=np.array(its_list, dtype=int),
        min_jacobian=res[:, 4], penetration=res[:, 5], surface_r=sw.surf.R.copy(),
        surface_ur=np.array(surf_ur).reshape(-1, m), surface_uz=np.array(surf_uz).reshape(-1, m),
        friction=friction, slip_radius=res[:, 6] if contact == "coulomb" else None,
        surface_fz=np.array(forces[0::2]).reshape(-1, m) if sw.coulomb else None,
        surface_fr=np.array(forces[1::2]).reshape(-1, m) if sw.coulomb else None,
        dome_radius_over_h=dome)
