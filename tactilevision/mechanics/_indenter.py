"""An indenter is one concept: its force law, contact radius, tables and what it observes.

:class:`Indenter` is the small interface every indenter shape implements;
:class:`FlatPunch` (the gauge block's flat-ended cylinder, the paper's) and
:class:`Sphere` (a ball) are its two shapes today. A third shape (a cylinder
lying on its side, a ring) is one new class registered in :data:`INDENTERS`:
the fit, the ramp reader and the depth from a contact circle read only this
interface.

Every force law is linear in E at a fixed nu (the Neo-Hookean law scales with
its moduli), so an indenter gives its force as ``E * shape_function``:
:meth:`Indenter.force` at ``E_mpa = 1`` is the design column of a fit of E.
"""

from __future__ import annotations

import inspect
import warnings
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass
from functools import lru_cache
from typing import ClassVar

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.optimize import brentq

from .._checks import InputError
from ..fem import SPHERE_W_GRID, SphereIndentation, sphere_indentation
from ._fem_tables import TABLE_EXTRAPOLATION, fem_force, kappa_n
from ._kappa import kappa
from ._pad_sweeps import shipped_pad_sweep
from ._sphere_table import (
    hertz_force_n,
    sphere_contact_ratio,
    sphere_force_ratio,
    sphere_reach,
    table_reach,
)

__all__ = ["INDENTERS", "FlatPunch", "Indenter", "Sphere", "indenter_from_config", "reach_of"]

#: Where a finite pad's FEM sweep may start (w/h): the largest below half the shallowest
#: press (:meth:`Sphere._ratio`).
_PAD_STARTS = (0.0005, 0.002, 0.01, 0.04, 0.10)
#: How far past its sweep's last depth a ball on a finite pad is read (the sweep's spline
#: in sqrt(w/h) carried on): 5 %, so that presses at the sweep's end with a contact point
#: a few tens of um late (the FEATS gel's 2.0 mm on h = 4 mm, 0.05 mm deeper) are fitted,
#: not refused; the infinite layer's table keeps its own reach.
PAD_EXTRAPOLATION = 1.05
#: Material laws an indenter's force follows.
LAWS = ("linear", "neo_hookean")


def _positive(value: object, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
        raise InputError(f"{name} must be a number, got {value!r}")
    v = float(value)
    if not (np.isfinite(v) and v > 0):
        raise InputError(f"{name} must be positive, got {value!r}")
    return v


class Indenter(ABC):
    """What every indenter shape provides.

    Attributes
    ----------
    shape : str
        Its name in ``session.toml`` (``[indenter] shape``).
    radius_mm : float
        Its characteristic radius (the punch's a, the ball's R), mm.
    contacts : tuple of str
        Contact conditions its tables hold; the first is the default.
    observes : str
        What a session's frames certify its depth by, in words.
    """

    shape: ClassVar[str]
    contacts: ClassVar[tuple[str, ...]]
    observes: ClassVar[str]
    radius_mm: float

    @abstractmethod
    def force(self, depth_mm: np.ndarray, *, E_mpa: float, nu: float, thickness_mm: float,
              law: str = "neo_hookean", contact: str | None = None) -> np.ndarray:
        """Force P (N) at depths w (mm) on a layer of thickness h bonded to a rigid base.

        Raises
        ------
        InputError
            For a depth past :meth:`reach_mm`, or geometry outside the tables.
        """

    @abstractmethod
    def contact_radius(self, depth_mm: np.ndarray, *, nu: float, thickness_mm: float,
                       law: str = "neo_hookean", contact: str | None = None) -> np.ndarray:
        """Contact radius a (mm) at depths w (mm)."""

    @abstractmethod
    def reach_mm(self, thickness_mm: float, law: str = "neo_hookean",
                 contact: str | None = None) -> float:
        """The deepest press its tables hold, mm, for `law` and `contact` (the one figure the
        fit, a ramp's reader and :meth:`depth_from_contact_radius` refuse past)."""

    def depth_from_contact_radius(self, contact_radius_mm: np.ndarray, *, nu: float,
                                  thickness_mm: float, law: str = "neo_hookean",
                                  contact: str | None = None) -> np.ndarray:
        """Depth w (mm) whose contact radius is a (mm): the inverse of :meth:`contact_radius`.

        Raises
        ------
        InputError
            When the shape's contact radius does not grow with depth (a flat
            punch), or for a radius outside what the tables reach.
        """
        raise InputError(f"a {self.shape}'s contact radius does not change with depth: its "
                         "depth cannot be read from its contact circle")

    def config(self) -> dict:
        """Its ``[indenter]`` keys of ``session.toml``."""
        return {"shape": self.shape, "radius_mm": self.radius_mm}

    @property
    def costly_in_nu(self) -> bool:
        """True when each nu costs a FEM sweep: a fit then does not profile nu."""
        return False

    def nu_limits(self, law: str = "neo_hookean") -> tuple[float, float]:
        """The range of nu its tables hold for `law`."""
        return 0.30, 0.50

    def _contact(self, contact: str | None) -> str:
        c = self.contacts[0] if contact is None else contact
        if c not in self.contacts:
            raise InputError(f"contact must be one of {self.contacts} for a {self.shape}, "
                             f"got {contact!r}")
        return c


@dataclass(frozen=True)
class FlatPunch(Indenter):
    """A rigid flat-ended cylinder of radius a: the paper's gauge-block indenter.

    Its force is eq. (1), P = 2 a E kappa_n w / (1 - nu^2): kappa_n of the
    finite-strain FEM table for ``law='neo_hookean'`` (bonded face), Hayes'
    small-strain kappa (frictionless) or the FEM's for ``law='linear'``. Its
    contact radius is a at every depth.
    """

    radius_mm: float
    shape: ClassVar[str] = "flat_punch"
    contacts: ClassVar[tuple[str, ...]] = ("bonded", "frictionless")
    observes: ClassVar[str] = ("the footprint of the punch and the bevel beside it (a vernier "
                               "or a mark)")

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius_mm", _positive(self.radius_mm, "radius_mm"))

    def reach_mm(self, thickness_mm: float, law: str = "neo_hookean",
                 contact: str | None = None) -> float:
        return 0.2 * TABLE_EXTRAPOLATION * thickness_mm if law == "neo_hookean" else np.inf

    def force(self, depth_mm, *, E_mpa, nu, thickness_mm, law="neo_hookean", contact=None):
        c = self._contact(contact)
        w = np.asarray(depth_mm, np.float64)
        if law == "neo_hookean":
            if c != "bonded":
                raise InputError("the finite-strain flat-punch table holds the bonded punch "
                                 "only")
            return fem_force(E_mpa, nu, self.radius_mm, thickness_mm, w)
        if law != "linear":
            raise InputError(f"law must be one of {LAWS}, got {law!r}")
        k = float(kappa(nu, self.radius_mm / thickness_mm, source="fem", contact=c))
        return 2 * self.radius_mm * E_mpa * k * w / (1 - nu**2)

    def contact_radius(self, depth_mm, *, nu, thickness_mm, law="neo_hookean", contact=None):
        return np.full(np.shape(depth_mm), self.radius_mm)

    def nu_limits(self, law: str = "neo_hookean") -> tuple[float, float]:
        """The finite-strain table stops at nu = 0.499; the small-strain kappa reaches 0.5."""
        return (0.30, 0.499) if law == "neo_hookean" else (0.30, 0.50)

    def kappa_n(self, depth_mm, *, nu, thickness_mm):
        """kappa_n(nu, a/h, w/h) of the finite-strain table (eq. 1-2)."""
        return kappa_n(nu, self.radius_mm / thickness_mm, np.asarray(depth_mm) / thickness_mm)


@dataclass(frozen=True)
class Sphere(Indenter):
    """A rigid sphere (a ball) of radius R.

    Its force and contact radius come from the project's FEM: P = P_Hertz(w)
    * force_ratio and a = sqrt(R w) * contact_ratio, linear or Neo-Hookean,
    frictionless or tied (no slip) between ball and gel, for R/h from 0.5 to
    20, nu 0.30 to 0.50 and w/h up to min(0.5, 0.6 R/h). On the infinite layer
    (``pad_radius_mm=None``) they are read from the table
    ``models/sphere_fem.npz`` (:func:`sphere_force_ratio`,
    :func:`sphere_contact_ratio`); on a pad of finite radius each (nu, law,
    contact) is one FEM sweep (:func:`tactilevision.fem.sphere_indentation`,
    minutes at finite strain, then kept in the disk cache). Both tend to
    Hertz's half-space (ratio 1) on a thick layer.

    A thick gel (R/h below 0.5, down to Hertz's half-space, R/h -> 0), on the
    infinite layer: the closed forms carried on from the table's R/h = 0.5 at
    the same w/R (:mod:`tactilevision.mechanics._sphere_closed`). The force is
    Hertz's (Johnson 1985, eq. 4.22-4.23) made a sphere's by Sneddon (1965)
    times Dimitriadis et al.'s bonded-layer series in chi = sqrt(R w)/h
    (Biophys. J. 82:2798, 2002, eq. 9-12; their layer bonded to its base as
    ours, their ball frictionless), times the table's own ratio to that closed
    form at R/h = 0.5 (continuous there): for ``law='linear'`` with
    ``contact='frictionless'`` that ratio is within 0.25 % of 1 to w/R = 0.26
    and 2.8 % at 0.6; ``'tied'`` carries the no-slip contact's stiffening
    (1.4 % at nu = 0.3, none at 0.5); ``'neo_hookean'`` carries the finite
    strain, trusted to w/R = 0.08 only (that transfer, tried from R/h = 1 to
    0.5, is within 1.3 % there and 2 to 21 % deeper), so the finite-strain
    law refuses deeper presses below R/h 0.5 where the small-strain law keeps
    w <= 0.6 R. Dimitriadis' layer-sliding variant has no contact here (every
    layer of this package is bonded to its base). :meth:`reach_mm` is the one
    reach the fit, a ramp's reader and :meth:`depth_from_contact_radius` use.

    Parameters
    ----------
    radius_mm : float
        R, mm, > 0.
    pad_radius_mm : float, optional
        Lateral radius of the gel pad (free sides, bonded base), mm; None for
        the infinite layer. A rectangular pad is not axisymmetric: its
        equal-area radius is a fair stand-in, its inscribed and circumscribed
        radii bracket it.
    friction : float, optional
        Coulomb's mu between ball and gel, >= 0: ``contact='coulomb'`` becomes
        available (``law='linear'`` only; the shear bounded by mu |p|, the
        normal contact tied, as in the FEATS authors' CalculiX model), one FEM
        sweep per nu as on a finite pad (:func:`tactilevision.fem.sphere_indentation`).
    dome_radius_mm : float, optional
        A domed gel: its top a spherical cap of this radius of curvature, mm
        (a GelSight Mini's is about 114 mm: 0.28 mm below the apex at 8 mm),
        the depth counted from first touch at the apex and the thickness
        taken there. Needs `pad_radius_mm` (the dome must stay within half
        the thickness of flat by the pad's edge); one FEM sweep per nu. In the
        half-space limit it is Hertz's contact of two curvatures, of radius
        R Rd / (R + Rd) (Johnson, Contact Mechanics, 1985, sec. 4.2).
    """

    radius_mm: float
    pad_radius_mm: float | None = None
    friction: float | None = None
    dome_radius_mm: float | None = None
    shape: ClassVar[str] = "sphere"
    contacts: ClassVar[tuple[str, ...]] = ("frictionless", "tied")
    observes: ClassVar[str] = "the contact circle, whose radius grows with depth (a^2 ~ R w)"

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius_mm", _positive(self.radius_mm, "radius_mm"))
        if self.pad_radius_mm is not None:
            object.__setattr__(self, "pad_radius_mm",
                               _positive(self.pad_radius_mm, "pad_radius_mm"))
        if self.friction is not None:
            mu = self.friction
            if isinstance(mu, bool) or not isinstance(mu, int | float | np.floating) \
                    or not (np.isfinite(mu) and mu >= 0):
                raise InputError(f"friction must be a number >= 0, got {mu!r}")
            object.__setattr__(self, "friction", float(mu))
        if self.dome_radius_mm is not None:
            object.__setattr__(self, "dome_radius_mm",
                               _positive(self.dome_radius_mm, "dome_radius_mm"))
            if self.pad_radius_mm is None or not self.dome_radius_mm > self.pad_radius_mm:
                raise InputError(f"a domed gel (dome_radius_mm = {self.dome_radius_mm:g}) needs "
                                 "the pad's radius (pad_radius_mm, [sensor] gel_radius_mm), "
                                 "smaller than the dome's")

    @property
    def costly_in_nu(self) -> bool:
        """True when each nu is a FEM sweep (a finite pad, or friction): a fit does not
        profile nu."""
        return self.pad_radius_mm is not None or self.friction is not None

    def _contact(self, contact: str | None) -> str:
        if contact == "coulomb":
            if self.friction is None:
                raise InputError("contact='coulomb' needs the ball's friction coefficient "
                                 "(Sphere(..., friction=mu))")
            return contact
        return super()._contact(contact)

    def reach_mm(self, thickness_mm: float, law: str = "neo_hookean",
                 contact: str | None = None) -> float:
        ratio = self.radius_mm / thickness_mm
        if self.pad_radius_mm is not None or contact == "coulomb":
            return sphere_reach(ratio) * PAD_EXTRAPOLATION * thickness_mm
        return table_reach(ratio, self._law(law), self._contact(contact)) * thickness_mm

    def _law(self, law: str) -> str:
        if law not in LAWS:
            raise InputError(f"law must be one of {LAWS}, got {law!r}")
        return law

    def _ratio(self, kind: str, w: np.ndarray, nu: float, h: float, law: str,
               contact: str | None, shallowest: float | None = None) -> np.ndarray:
        if contact == "coulomb" and self._law(law) != "linear":
            raise InputError("contact='coulomb' is computed for law='linear' only")
        if self.pad_radius_mm is None and contact != "coulomb":
            look = sphere_force_ratio if kind == "force" else sphere_contact_ratio
            return look(self.radius_mm / h, nu, w / h, model=self._law(law),
                        contact=self._contact(contact))
        x = w / h
        reach = sphere_reach(self.radius_mm / h) * PAD_EXTRAPOLATION
        if np.any(x < 0) or np.any(x > reach * (1 + 1e-9)):
            raise InputError(f"w/h = {float(np.max(x)):.4g} is outside the sphere's 0 to "
                             f"{reach:.4g}")
        # `shallowest` (w/h) chooses the sweep in place of these depths' own shallowest: one
        # sweep for every probe of an inversion (depth_from_contact_radius)
        sweep = _pad_sweep(*self.sweep_key(x if shallowest is None else np.array([shallowest]),
                                           nu, h, law, contact))
        # past the sweep's last depth (up to PAD_EXTRAPOLATION of it) the spline in
        # sqrt(w/h) is carried on: smooth, as the beta table is read 15 % beyond its last w/h
        return sweep[0 if kind == "force" else 1](np.sqrt(np.minimum(x, reach)))

    def sweep_key(self, w_over_h: np.ndarray, nu: float, h: float, law: str,
                  contact: str | None) -> tuple:
        """The arguments of :func:`pad_sweep_result` for depths `w_over_h` (one sweep
        of the FEM over the table's depths, on this ball's pad, dome and friction)."""
        # the sweep starts below half the shallowest press, at one of a few depths (so that
        # nearby queries share it): its surface cell (1/12 of the first contact radius) is
        # no finer than the presses need
        pos = w_over_h[w_over_h > 0]
        low = 0.5 * float(pos.min()) if pos.size else sphere_reach(self.radius_mm / h)
        start = max((v for v in _PAD_STARTS if v <= low), default=_PAD_STARTS[0])
        pad = 20.0 * h if self.pad_radius_mm is None else self.pad_radius_mm
        c = self._contact(contact)
        return (self.radius_mm / h, float(nu), pad / h, self._law(law), c, start,
                self.friction if c == "coulomb" else None,
                None if self.dome_radius_mm is None else self.dome_radius_mm / h)

    def force(self, depth_mm, *, E_mpa, nu, thickness_mm, law="neo_hookean", contact=None):
        w = np.asarray(depth_mm, np.float64)
        h = _positive(thickness_mm, "thickness_mm")
        ratio = self._ratio("force", w, nu, h, law, contact)
        return hertz_force_n(w, E_mpa=E_mpa, nu=nu, radius_mm=self.radius_mm) * ratio

    def contact_radius(self, depth_mm, *, nu, thickness_mm, law="neo_hookean", contact=None):
        w = np.asarray(depth_mm, np.float64)
        h = _positive(thickness_mm, "thickness_mm")
        ratio = self._ratio("contact", w, nu, h, law, contact)
        return np.sqrt(self.radius_mm * np.maximum(w, 0.0)) * ratio

    def depth_from_contact_radius(self, contact_radius_mm, *, nu, thickness_mm,
                                  law="neo_hookean", contact=None):
        a = np.atleast_1d(np.asarray(contact_radius_mm, np.float64))
        h = _positive(thickness_mm, "thickness_mm")
        top = self.reach_mm(h, law, contact)
        for ai in a.ravel():                        # checked before any table or sweep
            if not (np.isfinite(ai) and ai >= 0):
                raise InputError(f"contact radius {ai!r} mm: must be finite and >= 0")
            if ai >= self.radius_mm:
                raise InputError(f"contact radius {ai:.4g} mm is not smaller than the ball's "
                                 f"radius {self.radius_mm:.4g} mm")
        # one sweep (on a finite pad) for every probe: the one the shallowest press needs,
        # its depth guessed by Hertz's a^2 = R w (a sweep per probe's own depth would be
        # up to five FEM sweeps, each minutes, for one inversion)
        pos = a[a > 0]
        shallowest = (min(float(pos.min()) ** 2 / self.radius_mm, top) / h if pos.size
                      else None)

        def radius_at(w: float) -> float:
            ratio = self._ratio("contact", np.array([w]), nu, h, law, contact, shallowest)
            return float(np.sqrt(self.radius_mm * max(w, 0.0)) * ratio[0])

        a_top = radius_at(top)
        out = np.empty(a.size)
        for i, ai in enumerate(a.ravel()):
            if ai > a_top:
                raise InputError(f"contact radius {ai:.4g} mm is past the sphere table's "
                                 f"{a_top:.4g} mm (w = {top:.4g} mm on h = {h:g} mm)")
            if ai == 0:
                out[i] = 0.0
                continue
            out[i] = brentq(lambda w, ai=ai: radius_at(w) - ai, 0.0, top, xtol=1e-12,
                            rtol=1e-10)
        return out.reshape(np.shape(contact_radius_mm))

    def config(self) -> dict:
        out = super().config()
        if self.pad_radius_mm is not None:
            out["pad_radius_mm"] = self.pad_radius_mm
        if self.friction is not None:
            out["friction"] = self.friction
        if self.dome_radius_mm is not None:
            out["dome_radius_mm"] = self.dome_radius_mm
        return out


@lru_cache(maxsize=32)
def _pad_sweep(radius_over_h: float, nu: float, pad_over_h: float, law: str, contact: str,
               start: float, friction: float | None = None, dome_over_h: float | None = None
               ) -> tuple[CubicSpline, CubicSpline]:
    """Force and contact ratios of :func:`pad_sweep_result` (the shipped table's where it
    holds the sweep: :func:`~tactilevision.mechanics._pad_sweeps.shipped_pad_sweep`), as
    splines of sqrt(w/h) (through 1 at w = 0, Hertz's limit)."""
    key = (radius_over_h, nu, pad_over_h, law, contact, start, friction, dome_over_h)
    shipped = shipped_pad_sweep(*key)
    if shipped is not None:
        w, f, a = shipped
    else:
        res = pad_sweep_result(*key)
        w, f = res.w_over_h, res.hertz_ratio
        a = res.contact_radius / np.sqrt(radius_over_h * res.w_over_h)
    s = np.concatenate([[0.0], np.sqrt(w)])
    return (CubicSpline(s, np.concatenate([[1.0], f])),
            CubicSpline(s, np.concatenate([[1.0], a])))


@lru_cache(maxsize=32)
def pad_sweep_result(radius_over_h: float, nu: float, pad_over_h: float, law: str,
                     contact: str, start: float, friction: float | None = None,
                     dome_over_h: float | None = None) -> SphereIndentation:
    """One FEM sweep of the ball on a pad of radius `pad_over_h` (20: the infinite layer;
    with Coulomb friction, `friction`; on a domed top of radius `dome_over_h`) over the
    sphere table's depths from `start` to the reach (below the table's first depth, 0.01,
    doubling from `start`), from the disk cache where it was computed before.

    Raises
    ------
    InputError
        When each of the three meshes fails, Newton or the linear solver (SuperLU on a
        singular matrix); the message names the sweep and each mesh with its failure.
    """
    reach = sphere_reach(radius_over_h)
    grid = SPHERE_W_GRID[(SPHERE_W_GRID <= reach + 1e-12) & (SPHERE_W_GRID >= start - 1e-12)]
    below = start * 2.0 ** np.arange(8)                 # a thick gel's shallow presses
    grid = np.union1d(below[below < min(float(SPHERE_W_GRID[0]), reach) - 1e-12], grid)
    if grid[-1] < reach - 1e-12:
        grid = np.append(grid, reach)
    # at large depth (the gel wraps round the ball) Newton may fail: the sweep is run again
    # with load steps half as long, then on surface cells 1.6 times coarser (a finer mesh
    # folds first). R/h = 1.875, nu = 0.5, frictionless, pad 3.23 h: the first failed at
    # w/h = 0.49, the second reached 0.5.
    cell = min(0.0625, float(np.sqrt(radius_over_h * grid[0])) / 12.0)
    attempts = [dict(model=law, contact=contact, pad_radius_over_h=pad_over_h,
                     steps_per_depth=steps, surface_cell=min(0.125, factor * cell),
                     friction=friction, dome_radius_over_h=dome_over_h)
                for factor, steps in ((1.0, 2), (1.0, 4), (1.6, 4))]
    # a retry that converged before is in the disk cache; the attempts that failed before
    # it are not (only complete sweeps are kept), so it is looked for first
    res = next((hit for kw in attempts if (hit := sphere_indentation(
        radius_over_h, nu, grid, cache="only", **kw)) is not None), None)
    failed = []
    for kw in attempts if res is None else ():
        with warnings.catch_warnings():
            warnings.simplefilter("error", RuntimeWarning)
            try:
                res = sphere_indentation(radius_over_h, nu, grid, **kw)
                break
            except (RuntimeWarning, RuntimeError, np.linalg.LinAlgError) as exc:
                # Newton's failure (a RuntimeWarning naming the depth reached) or the
                # linear solver's (SuperLU's RuntimeError on a singular matrix)
                failed.append(f"surface cells {kw['surface_cell']:.4g} h with "
                              f"{kw['steps_per_depth']} load steps per depth: "
                              f"{type(exc).__name__}: {exc}")
    if res is None:
        raise InputError(
            f"the FEM sweep of the sphere (R/h = {radius_over_h:.4g}, nu = {nu:.4g}, {law}, "
            f"{contact} contact, pad radius {pad_over_h:.4g} h"
            + (f", friction {friction:g}" if friction else "")
            + (f", domed top of radius {dome_over_h:.4g} h" if dome_over_h else "")
            + f", depths w/h {grid[0]:.4g} to {grid[-1]:.4g}) failed on each of its "
            f"{len(attempts)} meshes: " + "; ".join(failed))
    return res


def reach_of(indenter: Indenter, thickness_mm: float, law: str = "neo_hookean",
             contact: str | None = None) -> float:
    """:meth:`Indenter.reach_mm` for `law` and `contact`: the one reach the fit, a ramp's
    reader, diagnose and :meth:`Indenter.depth_from_contact_radius` refuse past.

    An indenter written before ``reach_mm`` took a contact (``reach_mm(thickness_mm,
    law)``) is asked without it.

    Parameters
    ----------
    indenter : Indenter
    thickness_mm : float
        h, mm.
    law : str, default 'neo_hookean'
    contact : str, optional
        The indenter's contact condition (None: its default).

    Returns
    -------
    float
        The deepest press, mm.
    """
    try:
        takes = "contact" in inspect.signature(indenter.reach_mm).parameters
    except (TypeError, ValueError):
        takes = False
    if takes:
        return float(indenter.reach_mm(thickness_mm, law, contact))
    return float(indenter.reach_mm(thickness_mm, law))


#: Indenter shapes by their ``[indenter] shape`` name.
INDENTERS: dict[str, type[Indenter]] = {c.shape: c for c in (FlatPunch, Sphere)}


def indenter_from_config(section: Mapping[str, object], *, where: str = "[indenter]"
                         ) -> Indenter:
    """The indenter a ``session.toml`` ``[indenter]`` table describes.

    Parameters
    ----------
    section : mapping
        ``shape`` (default ``'flat_punch'``) and ``radius_mm``.
    where : str, default '[indenter]'
        Where the table came from, for messages (a file and table).

    Returns
    -------
    Indenter

    Raises
    ------
    InputError
        Naming `where` and the key: an unknown shape, a missing, non-numeric or
        non-positive ``radius_mm``.

    Examples
    --------
    >>> indenter_from_config({"shape": "sphere", "radius_mm": 3.75})
    Sphere(radius_mm=3.75, pad_radius_mm=None, friction=None, dome_radius_mm=None)
    """
    shape = section.get("shape", "flat_punch")
    if shape not in INDENTERS:
        raise InputError(f"{where} shape = {shape!r}: must be one of {sorted(INDENTERS)}")
    if "radius_mm" not in section:
        raise InputError(f"{where} has no radius_mm (the {shape}'s radius, mm)")
    try:
        return INDENTERS[str(shape)](section["radius_mm"])
    except InputError as err:
        raise InputError(f"{where} {err}") from None
