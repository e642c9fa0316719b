"""The contact point, baseline and E of a force-depth ramp (an Instron's or a robot's).

A ramp is one continuous loading curve: stage travel z_i (mm, into the gel) and
force P_i (N), the contact point z0 not marked. The model is

    P_i = F0 + E g(z_i - z0),    g(w) = the indenter's force at E = 1 (0 for w <= 0),

with F0 the force sensor's baseline. Given z0 it is linear in F0 and E, so z0 is
found on its profile: the residual sum of squares, least squares in (F0, E) at each
z0 (variable projection, Golub and Pereyra 1973), scanned on a grid and refined;
its interval is where RSS(z0) - RSS_min <= F(1, n - 3) s^2, s^2 = RSS_min / (n - 3)
(Bates and Watts 1988, §6.1: a likelihood-ratio interval with the scale
estimated). E (and nu where the ramp identifies it) is then
:func:`~tactilevision.mechanics.fit_indenter`'s on the contact part read as presses
(depth z_i - z0, force P_i - F0), with z0's uncertainty carried into E's interval
as a depth error every press shares.

nu is stated (0.5 unless given) for the profile of z0. When the presses then
identify nu, z0 and nu are fitted together: the profile of z0 is minimised over
nu as well (nu on a grid, the threshold F(1, n - 4) s^2, s^2 = RSS_min / (n - 4)),
since z0 and nu trade against each other in the curve's shape near contact, and a
contact point profiled at a wrong nu drags the nu the presses then give.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
from scipy import optimize, stats

from .._checks import InputError, check_array, check_positive
from ._indenter import Indenter, reach_of
from ._indenter_fit import NU_STATED, IndenterFit, fit_indenter, json_ready
from ._misfit import serial_correlation

__all__ = ["MAX_RAMP_PRESSES", "RampFit", "fit_ramp"]

#: Most presses the ramp's contact part is handed to the fit of E as (averaged in depth bins).
MAX_RAMP_PRESSES = 200
#: Fewest points a ramp must hold past its contact point, within the reach.
_MIN_CONTACT = 5
#: Fewest points of a loading part.
_MIN_LOADING = 10
#: Nodes of the z0 grid and of the force table g(w) the profile interpolates.
_GRID, _TABLE = 401, 4001
#: How many sds of its scatter the force must rise by to count as a contact.
_RISE_SDS = 10.0


@dataclass(frozen=True)
class RampFit:
    """Result of :func:`fit_ramp`. Units are in the names.

    Attributes
    ----------
    contact_point_mm : float
        z0, the stage displacement at first contact, mm (the ramp's own zero).
    contact_point_ci_mm : (float, float)
        Its profile interval at `confidence`, mm (profiled over nu as well
        when the ramp identifies nu).
    baseline_n : float
        F0, the force before contact, N.
    E_mpa : float
        Young's modulus, MPa, at `nu`.
    E_ci95_mpa : (float, float)
        Its interval: :func:`fit_indenter`'s, widened to the hull of the fits
        with every depth moved by +/- the larger side of z0's interval.
    nu : float
        The fitted nu when `nu_identified`, else the stated one.
    nu_ci95 : (float, float)
        What the ramp allows of nu (:attr:`IndenterFit.nu_ci95`).
    nu_identified : bool
    n_points : int
        Points of the ramp the contact point was fitted to (the loading part,
        within the reach).
    n_dropped : int
        Points left out: the unloading, and those past the reach.
    rmse_n : float
        Root mean square of the ramp model's residuals over the `n_points`, N.
    depth_mm, force_n : (M,) float64 ndarray
        The presses E was fitted to: depth z - z0 (mm) and force P - F0 (N),
        averaged in at most 200 bins evenly spaced in depth.
    indenter_fit : IndenterFit
        That fit.
    shape : str
        The indenter's shape.
    thickness_mm : float
    law, contact : str
    confidence : float
    notes : tuple of str
        What was dropped, resampled or bounded, then the fit of E's notes.
    """

    contact_point_mm: float
    contact_point_ci_mm: tuple[float, float]
    baseline_n: float
    E_mpa: float
    E_ci95_mpa: tuple[float, float]
    nu: float
    nu_ci95: tuple[float, float]
    nu_identified: bool
    n_points: int
    n_dropped: int
    rmse_n: float
    depth_mm: np.ndarray = field(repr=False)
    force_n: np.ndarray = field(repr=False)
    indenter_fit: IndenterFit = field(repr=False)
    shape: str = ""
    thickness_mm: float = math.nan
    law: str = "neo_hookean"
    contact: str = ""
    confidence: float = 0.95
    notes: tuple[str, ...] = ()

    @property
    def nu_bound(self) -> str | None:
        """The bound the ramp puts on nu where its interval reaches the table's edge
        (:attr:`IndenterFit.nu_bound`)."""
        return self.indenter_fit.nu_bound

    @property
    def E_identified(self) -> bool:
        """Whether E's interval is a measurement (:attr:`IndenterFit.E_identified`)."""
        return self.indenter_fit.E_identified

    def to_json_dict(self) -> dict[str, Any]:
        """JSON-ready dict (arrays as lists, NaN as None, the fit of E nested; its
        ``nu_bound``, ``E_identified`` and ``misfit`` repeated at the top)."""
        out = {k: json_ready(getattr(self, k)) for k in self.__dataclass_fields__
               if k != "indenter_fit"}
        out["indenter_fit"] = self.indenter_fit.to_json_dict()
        for k in ("nu_bound", "E_identified", "misfit"):
            out[k] = out["indenter_fit"][k]
        return out


class _Tables(NamedTuple):
    """g(w; nu), the force at E = 1, tabulated for the profile: depths (T,), forces (M, T),
    nu (M,)."""

    w: np.ndarray
    g: np.ndarray
    nu: np.ndarray


class _Profile(NamedTuple):
    """z0's profile read: its minimum, interval and the linear fit there."""

    z0: float
    lo: float
    hi: float
    F0: float
    E: float
    nu: float       # the nu of the tables' best fit
    m: int          # its index in the tables
    rss: float
    dof: int        # n - 3, or n - 4 with nu profiled too
    lo_edge: bool   # the interval reaches the scan's lower end
    hi_edge: bool   # ... its upper end


def _noise(x: np.ndarray) -> float:
    """A robust sd of a sampled signal's noise: the MAD of its second differences / sqrt(6)."""
    if x.size < 4:
        return 0.0
    d2 = np.diff(x, 2)
    return float(1.4826 * np.median(np.abs(d2 - np.median(d2))) / math.sqrt(6.0))


def _loading(z: np.ndarray, P: np.ndarray, name: str) -> tuple[int, float]:
    """The loading part's length and a first guess of where the force rises.

    Raises
    ------
    InputError
        When the displacement never increases by more than its noise, or the
        force never rises by more than 10 sds of its scatter.
    """
    k = int(np.argmax(z)) + 1
    zl, Pl = z[:k], P[:k]
    sd_z = _noise(z)
    rise_z = float(zl.max() - zl.min())
    if k < _MIN_LOADING or rise_z <= _RISE_SDS * sd_z or rise_z <= 0:
        raise InputError(f"{name} has no loading part: the displacement never increases by more "
                         f"than its noise ({k} point(s) up to its largest value, a travel of "
                         f"{rise_z:.3g} mm against a noise of {sd_z:.2g} mm)")
    sd_P = _noise(Pl)
    base = float(np.median(Pl[:max(_MIN_LOADING, k // 20)]))
    rise = float(Pl.max() - base)
    if rise <= max(_RISE_SDS * sd_P, 1e-12 * float(np.max(np.abs(Pl)))):
        raise InputError(f"{name} has no contact: its force never rises above its baseline "
                         f"scatter (a rise of {rise:.3g} N against a scatter of {sd_P:.2g} N "
                         "over the loading part)")
    thr = base + max(5 * sd_P, 0.02 * rise)
    below = np.flatnonzero(Pl <= thr)
    i_rise = int(below[-1]) + 1 if below.size else 0
    return k, float(zl[min(i_rise, k - 1)])


def _tables(indenter: Indenter, wmax: float, nus: np.ndarray, h: float, law: str,
            contact: str) -> _Tables:
    """g(w; nu), the force at E = 1, on `_TABLE` depths from 0 to `wmax`, at each nu of `nus`."""
    w = np.linspace(0.0, wmax, _TABLE)
    nus = np.atleast_1d(np.asarray(nus, np.float64))
    g = np.zeros((nus.size, _TABLE))
    for m, v in enumerate(nus):
        g[m, 1:] = indenter.force(w[1:], E_mpa=1.0, nu=float(v), thickness_mm=h, law=law,
                                  contact=contact)
    return _Tables(w, g, nus)


def _rss(z: np.ndarray, P: np.ndarray, z0s: np.ndarray, tab: _Tables
         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """RSS, F0 and E of the least-squares fit P = F0 + E g(z - z0; nu), each (K, M): at each
    z0 of `z0s` (K,) and each nu of the tables (M,); g linear between the table's depths."""
    Pc = P - P.mean()
    syy = float(Pc @ Pc)
    dw, last = float(tab.w[1] - tab.w[0]), tab.w.size - 1
    step = max(1, 1_000_000 // max(z.size, 1))
    rss, F0, E = (np.empty((z0s.size, tab.nu.size)) for _ in range(3))
    for a in range(0, z0s.size, step):
        b = slice(a, a + step)
        x = np.clip((z[None, :] - z0s[b, None]) / dw, 0.0, last)   # (K, n) table positions
        i = np.minimum(x.astype(np.intp), last - 1)
        t = x - i
        for m in range(tab.nu.size):
            g = tab.g[m]
            G = g[i] * (1.0 - t) + g[i + 1] * t
            gm = G.mean(axis=1)
            Gc = G - gm[:, None]
            sxx, sxy = np.einsum("kn,kn->k", Gc, Gc), Gc @ Pc
            ok = sxx > 0
            E[b, m] = np.where(ok, sxy / np.where(ok, sxx, 1.0), 0.0)
            rss[b, m] = np.where(ok, syy - E[b, m] * sxy, syy)
            F0[b, m] = P.mean() - E[b, m] * gm
    return np.maximum(rss, 0.0), F0, E


def _g_at(w: np.ndarray, tab: _Tables, m: int) -> np.ndarray:
    """g(w) of the tables' nu number `m`, linear between the table's depths (0 for w <= 0)."""
    return np.interp(w, tab.w, tab.g[m], left=0.0)


def _refine(grid: np.ndarray, rss: np.ndarray, at: Callable[[float], float]
            ) -> tuple[float, float]:
    """The minimum of a profile known on `grid`: Brent's bounded search about its best node."""
    k = int(np.argmin(rss))
    a, b = grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]
    res = optimize.minimize_scalar(at, bounds=(a, b), method="bounded",
                                   options={"xatol": 1e-6 * (grid[-1] - grid[0]) / grid.size
                                            + 1e-9})
    if res.fun < rss[k]:
        return float(res.x), float(res.fun)
    return float(grid[k]), float(rss[k])


def _scan(z: np.ndarray, P: np.ndarray, L: float, U: float, tab: _Tables,
          confidence: float) -> _Profile:
    """z0's profile over [L, U], minimised over the tables' nu too when they hold several:
    grid, refined minimum, interval (module docstring)."""
    grid = np.linspace(L, U, _GRID)
    rss = _rss(z, P, grid, tab)[0].min(axis=1)

    def at(x: float) -> float:
        return float(_rss(z, P, np.array([x]), tab)[0].min())

    z0, rmin = _refine(grid, rss, at)
    dof = z.size - (3 if tab.nu.size == 1 else 4)
    # residuals that run along the travel (a law that does not follow the curve) carry
    # fewer independent points than the ramp holds: the threshold grows by their factor^2
    r, F0, E = _rss(z, P, np.array([z0]), tab)
    m = int(np.argmin(r[0]))
    order = np.argsort(z, kind="stable")
    resid = P - F0[0, m] - E[0, m] * _g_at(z - z0, tab, m)
    inflation = serial_correlation(resid[order])[2] ** 2
    thr = float(stats.f.ppf(confidence, 1, dof)) * rmin / dof * inflation
    excess = rss - rmin - thr

    def end(side: int) -> tuple[float, bool]:
        nodes = np.flatnonzero(grid < z0)[::-1] if side < 0 else np.flatnonzero(grid > z0)
        out = nodes[excess[nodes] > 0]
        if not out.size:
            return (L if side < 0 else U), True
        j = int(out[0])
        inner = float(grid[j - side]) if (j - side) in nodes else z0
        if at(inner) - rmin - thr >= 0:   # a noise-free ramp: the threshold is 0
            return inner, False
        return float(optimize.brentq(lambda x: at(x) - rmin - thr, *sorted((grid[j], inner)),
                                     xtol=1e-9)), False

    (lo, lo_edge), (hi, hi_edge) = end(-1), end(+1)
    return _Profile(z0, lo, hi, float(F0[0, m]), float(E[0, m]), float(tab.nu[m]), m, rmin,
                    dof, lo_edge, hi_edge)


def _nu_window(z: np.ndarray, P: np.ndarray, L: float, U: float, tab: _Tables,
               confidence: float) -> np.ndarray:
    """The nu the joint profile of z0 runs over: where the coarse tables' profile of nu (z0,
    F0 and E fitted at each) lies within its threshold, widened by 0.01, on a 0.0025 grid."""
    grid = np.linspace(L, U, _GRID)
    R = _rss(z, P, grid, tab)[0]
    best = np.empty(tab.nu.size)
    for m in range(tab.nu.size):
        one = _Tables(tab.w, tab.g[m:m + 1], tab.nu[m:m + 1])
        best[m] = _refine(grid, R[:, m],
                          lambda x, one=one: float(_rss(z, P, np.array([x]), one)[0][0, 0]))[1]
    dof = z.size - 4
    thr = float(stats.f.ppf(confidence, 1, dof)) * best.min() / dof
    inside = tab.nu[best - best.min() <= thr]
    lo, hi = max(tab.nu[0], inside.min() - 0.01), min(tab.nu[-1], inside.max() + 0.01)
    return np.round(np.arange(lo, hi + 1e-9, 0.0025), 6)


def _locate(z: np.ndarray, P: np.ndarray, limit: float, z_rise: float, tab: _Tables,
            confidence: float, past: str) -> tuple[np.ndarray, _Profile, float, float]:
    """z0 with only the points within `limit` of it: (kept mask, profile, scan's ends L, U).

    The scan over [L, U] keeps the points z <= L + limit, which lie within the
    reach for every z0 >= L. L starts a reach before where the force first rises
    (the ramp's start for a ramp shorter than the reach), moves back while z0's
    interval reaches it, then up to the interval's lower end less its width (or 1 %
    of the reach, if more).
    """
    z_min = float(z.min())
    L = z_min if z.max() - z_min <= limit else max(z_min, z_rise - limit)
    back = max(limit, 0.25 * float(z.max() - z_min))   # a step back: at most 4 to the start
    refined = False
    for _ in range(12):
        keep = z <= L + limit
        zk = np.sort(z[keep])
        U = float(zk[-_MIN_CONTACT]) if zk.size >= _MIN_CONTACT + 3 else -math.inf
        if U <= L and L > z_min:
            L = max(z_min, L - back)
            continue
        if U <= L:
            break
        prof = _scan(z[keep], P[keep], L, U, tab, confidence)
        if prof.lo_edge and L > z_min:
            L = max(z_min, L - back)
            continue
        new_L = max(z_min, prof.lo - max(prof.hi - prof.lo, 0.01 * limit))
        if refined or new_L <= L or z.max() <= L + limit:
            return keep, prof, L, U
        L, refined = new_L, True
    raise InputError(past)


def _presses(z: np.ndarray, P: np.ndarray, prof: _Profile, tab: _Tables, reach: float,
             name: str, notes: list[str]) -> tuple[np.ndarray, np.ndarray, float]:
    """The contact part as presses for the fit of E: (depth, force, z0's shared error).

    The depths kept lie past z0's error `half` and where the model stands 3
    scatter sds above the baseline (no press whose force the noise may turn
    negative: the depth, not the force, selects), and within the reach less
    `half` (so both shifted fits stay in the table); more than
    :data:`MAX_RAMP_PRESSES` are averaged in bins evenly spaced in depth.
    """
    half = max(prof.z0 - prof.lo, prof.hi - prof.z0)
    s = math.sqrt(prof.rss / prof.dof)
    wg, gt = tab.w, tab.g[prof.m]
    strong = np.flatnonzero(prof.E * gt >= 3 * s)
    w_lo = max(half, float(wg[strong[0]]) if strong.size else math.inf)
    w_hi = min(float(wg[-1]), reach - half)
    w, F = z - prof.z0, P - prof.F0
    sel = (w > w_lo) & (w <= w_hi)
    neg = sel & (F <= 0)
    if np.any(neg):
        notes.append(f"{int(neg.sum())} point(s) in contact with a force at or below the "
                     "baseline left out of the fit of E")
    sel &= ~neg
    w, F = w[sel], F[sel]
    if w.size < _MIN_CONTACT:
        raise InputError(f"{name}: only {w.size} point(s) lie from {w_lo * 1e3:.3g} um (where "
                         f"the force clears its scatter) to {w_hi:.4g} mm past the contact "
                         f"point: too few to fit E (at least {_MIN_CONTACT})")
    if w.size > MAX_RAMP_PRESSES:
        edges = np.linspace(w.min(), w.max(), MAX_RAMP_PRESSES + 1)
        idx = np.clip(np.searchsorted(edges, w, side="right") - 1, 0, MAX_RAMP_PRESSES - 1)
        cnt = np.bincount(idx, minlength=MAX_RAMP_PRESSES)
        full = cnt > 0
        notes.append(f"the {w.size} points in contact were averaged in {int(full.sum())} bins "
                     f"evenly spaced in depth ({w.min():.4g} to {w.max():.4g} mm) for the fit "
                     "of E")
        w = np.bincount(idx, w, MAX_RAMP_PRESSES)[full] / cnt[full]
        F = np.bincount(idx, F, MAX_RAMP_PRESSES)[full] / cnt[full]
    return w, F, half


def _checked(displacement_mm: np.ndarray, force_n: np.ndarray, indenter: Indenter,
             thickness_mm: float, contact: str | None, confidence: float,
             max_depth_mm: float | None) -> tuple:
    """:func:`fit_ramp`'s arguments checked: (z, P, h, contact, limit, why the limit)."""
    z = check_array(displacement_mm, "displacement_mm", [("N",)], dtype=np.number, finite=True)
    P = check_array(force_n, "force_n", [(z.shape[0],)], dtype=np.number, finite=True)
    h = check_positive(thickness_mm, "thickness_mm")
    if not 0 < confidence < 1:
        raise InputError(f"confidence must be in (0, 1), got {confidence!r}")
    limit, why = math.inf, ""
    if max_depth_mm is not None:
        limit, why = check_positive(max_depth_mm, "max_depth_mm"), "max_depth_mm"
    return (z.astype(np.float64), P.astype(np.float64), h, indenter._contact(contact), limit,
            why)


def _edge_reason(z: np.ndarray, P: np.ndarray, prof: _Profile, L: float, z_rise: float,
                 shape: str, name: str) -> str:
    """Why a contact point whose interval reaches the ramp's first point cannot be fitted:
    the ramp starts in contact, or (its force flat for a stretch of travel before it rises)
    the law cannot follow the curve."""
    before = z < z_rise
    travel = float(np.ptp(z[before])) if before.any() else 0.0
    # flat: no rise of the force along the first half of the travel before z_rise (the
    # second may hold the contact's toe) that its scatter does not explain
    first = z < float(np.min(z)) + 0.5 * travel
    rising = (first.sum() >= _MIN_LOADING // 2 and travel > 0
              and (line := stats.linregress(z[first], P[first])).slope > 0
              and line.pvalue < 0.01)
    if before.sum() < _MIN_LOADING or not travel > 0 or rising:
        return (f"{name} starts in contact, or too close to it: its contact point's interval "
                f"reaches its first point ({L:.4g} mm), so the force before contact, the "
                "baseline, is not seen; record the approach from before the indenter touches")
    sd = _noise(P)
    rms = math.sqrt(prof.rss / prof.dof) if prof.dof > 0 else math.nan
    times = f", {rms / sd:.3g} times the force's noise ({sd * 1e3:.3g} mN)" if sd > 0 else ""
    return (f"{name}: the {shape} law cannot follow this curve: its force stays at its "
            f"baseline for {travel:.3g} mm of travel ({int(before.sum())} points) before it "
            f"rises at {z_rise:.4g} mm, so it does not start in contact, yet the law puts the "
            f"contact point's interval at the first point fitted ({L:.4g} mm), with a residual "
            f"of {rms * 1e3:.3g} mN rms{times}: the indenter's shape or size, the gel's "
            "thickness or the material law is not the rig's (a curve near-linear in depth is "
            "a flat punch's, not a ball's)")


def _fit_pass(z: np.ndarray, P: np.ndarray, indenter: Indenter, tab: _Tables, *, h: float,
              law: str, contact: str, nu: float | None, confidence: float, limit: float,
              why: str, z_rise: float, name: str) -> tuple:
    """One pass of :func:`fit_ramp` with the profile's g tabulated in `tab`: (kept mask,
    profile, scan's ends L and U, presses' depth and force, IndenterFit, notes)."""
    past = (f"{name}: fewer than {_MIN_CONTACT} points lie between its contact point and "
            f"{limit:.4g} mm past it ({why}): every point in contact is past that depth")
    keep, prof, L, U = _locate(z, P, limit, z_rise, tab, confidence, past)
    rise = prof.E * float(np.interp(z[keep].max() - prof.z0, tab.w, tab.g[prof.m]))
    if not rise > _RISE_SDS * math.sqrt(prof.rss / prof.dof):
        raise InputError(past)
    if prof.lo_edge:
        raise InputError(_edge_reason(z, P, prof, L, z_rise, indenter.shape, name))
    notes: list[str] = []
    if prof.hi_edge:
        notes.append(f"the contact point's interval reaches the last {_MIN_CONTACT} points "
                     "within the reach: the ramp does not bound it from above")
    w, F, half = _presses(z[keep], P[keep], prof, tab, reach_of(indenter, h, law, contact),
                          name, notes)
    fit = fit_indenter(w, F, indenter, thickness_mm=h, law=law, contact=contact, nu=nu,
                       depth_shared_mm=half, confidence=confidence)
    return keep, prof, L, U, w, F, fit, notes


def fit_ramp(displacement_mm: np.ndarray, force_n: np.ndarray, indenter: Indenter, *,
             thickness_mm: float, law: str = "neo_hookean", contact: str | None = None,
             nu: float | None = None, confidence: float = 0.95,
             max_depth_mm: float | None = None,
             source: str | os.PathLike[str] | None = None) -> RampFit:
    """Fit the contact point, the baseline and E (nu where identified) to a force-depth ramp.

    Parameters
    ----------
    displacement_mm : (N,) array_like of float
        Stage travel z, mm, increasing into the gel, any zero.
    force_n : (N,) array_like of float
        Force P, N, positive into the gel, any baseline.
    indenter : Indenter
        :class:`~tactilevision.mechanics.FlatPunch`,
        :class:`~tactilevision.mechanics.Sphere` or any other shape.
    thickness_mm : float
        Layer thickness h, mm.
    law : {'neo_hookean', 'linear'}, default 'neo_hookean'
    contact : str, optional
        The indenter's contact condition (its default when None).
    nu : float, optional
        Poisson's ratio the contact point is profiled at and E reported at
        unless the ramp identifies nu (default 0.5, as :func:`fit_indenter`);
        when it does (:func:`fit_indenter` on the first pass identifies it),
        the contact point is profiled over nu as well (the nu the ramp allows,
        on a grid of 0.0025), and E fitted again at that contact point.
    confidence : float, default 0.95
        Of the contact point's interval and of E's.
    max_depth_mm : float, optional
        Deepest depth past the contact point fitted, mm (default: the
        indenter's reach, :meth:`Indenter.reach_mm`).
    source : str or path-like, optional
        What the ramp is called in messages: its file (``Ramp.path``);
        default ``'the ramp'``.

    Returns
    -------
    RampFit

    Raises
    ------
    ShapeError
        For arrays that are not 1-D, finite and of one length.
    InputError
        Naming `source`: no loading part (fewer than 10 points up to the
        largest displacement, or a travel within 10 sds of its noise: the
        robust sd of its second differences), no contact (the force's rise
        within 10 sds of its scatter), fewer than 5 points between the contact
        point and the reach (or `max_depth_mm`), or fewer than 5 presses left
        for E; a bad `thickness_mm`, `confidence`, `max_depth_mm`, `contact`
        or `nu` (as the indenter's tables or :func:`fit_indenter` refuse it).

    Notes
    -----
    Only the loading part is fitted: the points from the start to the largest
    displacement (the unloading, a hold at the top, are dropped and a note
    says so). z0's profile (module docstring) keeps the points within the
    reach of every z0 it scans; its grid of 401 nodes is refined by Brent's
    bounded minimisation and its interval's ends by Brent's root finder, with
    g interpolated in a table of 4001 depths. E is then
    :func:`fit_indenter`'s with ``depth_shared_mm`` the larger side of z0's
    interval: the hull of the fits with every depth moved by +/- that
    (conservative: it adds z0's part of E's error to the rest instead of in
    quadrature). The presses handed to it are the contact points deeper than
    that side and than where the fitted force reaches 3 scatter sds (a depth
    rule, so no press is chosen by its noise), F0 taken off.
    """
    name = "the ramp" if source is None else str(source)
    z, P, h, contact, limit, why = _checked(displacement_mm, force_n, indenter, thickness_mm,
                                            contact, confidence, max_depth_mm)
    k, z_rise = _loading(z, P, name)
    reach = reach_of(indenter, h, law, contact)
    if reach < limit:
        limit, why = reach, f"the {indenter.shape} table's reach on h = {h:g} mm"
    zl, Pl = z[:k], P[:k]
    wmax = limit if math.isfinite(limit) else float(zl.max() - zl.min())
    kw = {"h": h, "law": law, "contact": contact, "nu": nu, "confidence": confidence,
          "limit": limit, "why": why, "z_rise": z_rise, "name": name}
    # the stated nu's default lies inside the indenter's tables (a flat punch's finite-strain
    # table stops at 0.499)
    nu0 = min(NU_STATED, indenter.nu_limits(law)[1]) if nu is None else float(nu)
    tab = _tables(indenter, wmax, [nu0], h, law, contact)
    keep, prof, L, U, w, F, fit, notes = _fit_pass(zl, Pl, indenter, tab, **kw)
    if fit.nu_identified or fit.nu_bound is not None:
        # the ramp says something of nu (identified, or bounded by the table's edge at the
        # stated nu's contact point, which a wrong nu drags): z0 and nu together
        coarse = _tables(indenter, wmax, np.round(np.linspace(*indenter.nu_limits(law), 21), 6),
                         h, law, contact)
        window = _nu_window(zl[keep], Pl[keep], L, U, coarse, confidence)
        tab = _tables(indenter, wmax, window, h, law, contact)
        keep, prof, L, U, w, F, fit, notes = _fit_pass(zl, Pl, indenter, tab, **kw)
        notes.insert(0, f"the ramp identifies nu: its contact point was profiled over nu from "
                        f"{window[0]:.4g} to {window[-1]:.4g} as well (best {prof.nu:.4g})")
    head = []
    if k < z.size:
        head.append(f"{z.size - k} point(s) after the largest displacement ({z[k - 1]:.4g} mm), "
                    "the unloading, dropped")
    if not keep.all():
        head.append(f"{int((~keep).sum())} point(s) of the loading part deeper than "
                    f"{limit:.4g} mm past the contact point ({why}) dropped")
    wk = zl[keep] - prof.z0
    g = np.zeros(wk.size)
    g[wk > 0] = indenter.force(wk[wk > 0], E_mpa=fit.E_mpa, nu=fit.nu, thickness_mm=h, law=law,
                               contact=contact)
    resid = Pl[keep] - prof.F0 - g
    return RampFit(
        contact_point_mm=prof.z0, contact_point_ci_mm=(prof.lo, prof.hi), baseline_n=prof.F0,
        E_mpa=fit.E_mpa, E_ci95_mpa=fit.E_ci95_mpa, nu=fit.nu, nu_ci95=fit.nu_ci95,
        nu_identified=fit.nu_identified, n_points=int(keep.sum()),
        n_dropped=int(z.size - keep.sum()), rmse_n=float(np.sqrt(np.mean(resid ** 2))),
        depth_mm=w, force_n=F, indenter_fit=fit, shape=indenter.shape, thickness_mm=h, law=law,
        contact=contact, confidence=confidence, notes=(*head, *notes, *fit.notes))
