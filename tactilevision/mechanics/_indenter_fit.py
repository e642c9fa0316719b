"""E (and nu where the presses pin it) from presses of any indenter: the ball's fit.

Every indenter's force is linear in E at a fixed nu (:mod:`._indenter`), so the
fit profiles nu: at each nu of a fine grid E is the weighted least-squares
slope of P on the indenter's force at E = 1, and the residual sum of squares
against nu is the profile whose minimum gives nu and whose rise gives its
interval. A profile that stays within the interval's threshold up to an end of
the table does not identify nu: E is then reported at a stated nu, with what it
would be over the nu the data allow beside it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from scipy import optimize, stats

from .._checks import InputError, check_array, check_presses
from ._indenter import Indenter, reach_of
from ._misfit import Misfit, assess_misfit, log_interval

__all__ = ["IndenterFit", "apparent_modulus", "fit_indenter", "json_ready"]

#: Default nu at which E is reported when the presses do not identify nu: a silicone gel
#: is nearly incompressible (the FEATS authors' fit of a GelSight Mini gel assumed 0.5).
NU_STATED = 0.5
#: Widest nu interval still called identified.
_NU_IDENTIFIED_WIDTH = 0.10
#: Widest ratio of E's interval's ends still called identified: e^2, where the symmetric
#: interval E +- t se would first reach zero (t se = E).
_E_IDENTIFIED_RATIO = math.exp(2.0)


@dataclass(frozen=True)
class IndenterFit:
    """Result of :func:`fit_indenter`. Units are in the names.

    Attributes
    ----------
    E_mpa : float
        Young's modulus at `nu`, MPa.
    E_ci95_mpa : (float, float)
        Its interval at `confidence`, in log E (it never reaches zero): the
        profile likelihood over nu when nu is identified, at the stated nu
        otherwise; widened by the misfit (:attr:`misfit`: the residuals' serial
        correlation, and to the shallowest and deepest presses' apparent E where
        it drifts with depth), then to the fits at the bounds of
        `depth_shared_mm` when given.
    nu : float
        The fitted nu when `nu_identified`, else the stated one.
    nu_ci95 : (float, float)
        The profile interval of nu over the table's range (whether identified
        or not: it says what the presses allow).
    nu_identified : bool
        The interval lies inside the table's range, away from both its ends,
        and is at most 0.10 wide.
    E_over_nu_ci_mpa : (float, float)
        E fitted at the ends of `nu_ci95`: what E would be over the nu the
        presses allow (the sensitivity to a stated nu).
    E_se_mpa : float
    shape, radius_mm, thickness_mm : str, float, float
        The indenter and the layer.
    law, contact : str
        Material law (``'linear'``, ``'neo_hookean'``) and contact condition.
    n_presses : int
    rmse_n : float
        Root mean square of P - P_fit, N.
    residuals_n, predicted_n : (N,) float64 ndarray
    apparent_E_mpa : (N,) float64 ndarray
        Each press's own E, P_i / P(w_i; E = 1) at `nu`: flat when the law is
        right, drifting with depth when an effect is missing.
    sigma0_n : float
        Force scatter the depth uncertainties do not explain (Paule-Mandel),
        N; the residual sd when no depth uncertainties are given.
    chi2, dof : float, int
        Weighted residual sum of squares at the optimum and its degrees of
        freedom.
    confidence : float
    notes : tuple of str
        What the fit did and found; a note starting ``warning:`` says the model does
        not explain the presses to within their noise (:attr:`misfit`).
    nu_bound : str or None
        Where nu's interval reaches one end of the table's range and not the other:
        the bound the presses put on nu (``'nu >= 0.4925'``); nu is then not
        identified, and E is reported at the stated nu.
    E_identified : bool
        False when E's interval spans more than a factor of e^2 (7.4): where the
        symmetric interval E +- t se would reach zero. E is then not a measurement;
        ``fit`` exits with status 3.
    misfit : Misfit or None
        The residuals against the stated noise and along depth
        (:func:`~tactilevision.mechanics.assess_misfit`): the Birge ratio, the
        residuals' serial correlation and the apparent E's drift, and the factor
        the intervals were widened by.
    """

    E_mpa: float
    E_ci95_mpa: tuple[float, float]
    nu: float
    nu_ci95: tuple[float, float]
    nu_identified: bool
    E_over_nu_ci_mpa: tuple[float, float]
    E_se_mpa: float
    shape: str
    radius_mm: float
    thickness_mm: float
    law: str
    contact: str
    n_presses: int
    rmse_n: float
    residuals_n: np.ndarray = field(repr=False)
    predicted_n: np.ndarray = field(repr=False)
    apparent_E_mpa: np.ndarray = field(repr=False)
    sigma0_n: float = math.nan
    chi2: float = math.nan
    dof: int = 0
    confidence: float = 0.95
    notes: tuple[str, ...] = ()
    nu_bound: str | None = None
    E_identified: bool = True
    misfit: Misfit | None = None

    def to_json_dict(self) -> dict[str, Any]:
        """JSON-ready dict (arrays as lists, NaN as None), with the keys every ``fit
        --json`` object carries (formats.md section 3): ``effects`` (none: a ball's
        fit has no catalogue effects), ``effect_params``, and ``c_n_per_mm`` and
        ``beta`` (eq. 5's intercept and stiffening, a flat punch's: null here);
        ``misfit`` as :meth:`Misfit.to_json_dict`."""
        out = {k: json_ready(getattr(self, k)) for k in self.__dataclass_fields__
               if k != "misfit"}
        out["misfit"] = None if self.misfit is None else self.misfit.to_json_dict()
        out.update(c_n_per_mm=None, beta=None, effects=[], effect_params={})
        return out


def json_ready(v: Any) -> Any:
    """`v` as JSON can hold it: arrays and tuples as lists, NaN and inf as None, numpy
    scalars as Python's, dicts cleaned value by value (the results' ``to_json_dict``)."""
    if isinstance(v, np.ndarray):
        return [json_ready(x) for x in v.tolist()]
    if isinstance(v, np.bool_ | bool):
        return bool(v)
    if isinstance(v, float | np.floating):
        return float(v) if math.isfinite(v) else None
    if isinstance(v, np.integer):
        return int(v)
    if isinstance(v, tuple | list):
        return [json_ready(x) for x in v]
    if isinstance(v, dict):
        return {k: json_ready(x) for k, x in v.items()}
    return v


def apparent_modulus(depth_mm: np.ndarray, force_n: np.ndarray, indenter: Indenter, *,
                     thickness_mm: float, nu: float, law: str = "neo_hookean",
                     contact: str | None = None) -> np.ndarray:
    """Each press's own E: P_i over the indenter's force at (w_i, E = 1, nu), MPa.

    Flat over depth when the law fits the gel; a drift with depth is the
    signature of a missing effect (finite strain, a force offset, a depth
    offset).

    Parameters
    ----------
    depth_mm, force_n : (N,) array_like of float
    indenter : Indenter
    thickness_mm, nu : float
    law : {'neo_hookean', 'linear'}
    contact : str, optional
        The indenter's default when None.

    Returns
    -------
    (N,) float64 ndarray, MPa
    """
    w = np.asarray(depth_mm, np.float64)
    g = indenter.force(w, E_mpa=1.0, nu=nu, thickness_mm=thickness_mm, law=law,
                       contact=contact)
    return np.asarray(force_n, np.float64) / g


def _slope(g: np.ndarray, P: np.ndarray, var: np.ndarray) -> tuple[float, float, float]:
    """Weighted least squares of P = E g with variances `var`: (E, (sum g^2/var)^-1, chi2)."""
    wt = 1.0 / var
    sgg = float(np.sum(wt * g * g))
    E = float(np.sum(wt * g * P)) / sgg
    r = P - E * g
    return E, 1.0 / sgg, float(np.sum(wt * r * r))


def paule_mandel(g: np.ndarray, P: np.ndarray, D: np.ndarray, dof: int) -> float:
    """Smallest t >= 0 with chi2(t) / dof <= 1 for variances t + D (Paule and Mandel 1982)."""
    floor = max((1e-12 * float(np.max(np.abs(P)))) ** 2, np.finfo(float).tiny)

    def excess(t: float) -> float:
        return _slope(g, P, np.maximum(t + D, floor))[2] / dof - 1.0

    E0 = _slope(g, P, np.ones_like(P))[0]
    upper = float(np.sum((P - E0 * g) ** 2)) / dof
    if dof <= 0 or upper <= 0 or excess(0.0) <= 0:
        return 0.0
    return float(optimize.brentq(excess, 0.0, upper, xtol=1e-14 * upper, rtol=1e-12))


def _profile(grid: np.ndarray, cols: list, P: np.ndarray, u: np.ndarray | None,
             f_sd: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, float, bool]:
    """E(nu), var_E(nu) and chi2(nu) over `grid` with one noise model for every nu.

    The noise model is fixed at the unweighted best nu: unit variances without depth
    uncertainties, else s0^2 + (E g' u)^2 with s0 by Paule and Mandel.

    Returns
    -------
    prof : (K, 4) ndarray
        nu, E, (sum g^2 / var)^-1, chi2.
    var : (N,) ndarray
    sigma0 : float
    weighted : bool
    stated : (N,) ndarray or None
        The stated variances alone (depth and force), without sigma0^2; None unweighted.
    """
    n = P.size
    dof = n - 2
    rss = np.array([_slope(g, P, np.ones(n))[2] for g, _ in cols])
    k0 = int(np.argmin(rss))
    weighted = (u is not None and bool(np.any(u > 0))) or (
        f_sd is not None and bool(np.any(f_sd > 0)))
    if weighted:
        g0, dg0 = cols[k0]
        D = (_slope(g0, P, np.ones(n))[0] * dg0 * (0.0 if u is None else u)) ** 2
        if f_sd is not None:
            D = D + f_sd ** 2
        t = paule_mandel(g0, P, D, max(dof, 1))
        var = np.maximum(t + D, max((1e-12 * float(np.max(P))) ** 2, np.finfo(float).tiny))
        sigma0 = math.sqrt(t)
        stated = D
    else:
        var = np.ones(n)
        sigma0 = math.sqrt(float(rss[k0]) / dof) if dof > 0 else math.nan
        stated = None
    prof = np.array([(v, *_slope(g, P, var)) for v, (g, _) in zip(grid, cols, strict=True)])
    return prof, var, sigma0, weighted, stated


def _read_profile(prof: np.ndarray, n: int, weighted: bool, confidence: float,
                  nu_range: tuple[float, float], nu: float | None, nu_stated: float,
                  notes: list[str], scale: float = 1.0) -> tuple:
    """E, var_E, E's interval, nu, nu's interval, whether nu is identified and the bound
    the presses put on it (module docstring of :func:`fit_indenter`, Notes); notes
    appended to `notes`. `scale` multiplies the residuals' variance (the misfit's factor
    squared)."""
    lo, hi = nu_range
    dof = n - 2
    k_best = int(np.argmin(prof[:, 3]))
    chi2_min = float(prof[k_best, 3])
    s2 = chi2_min / dof if dof > 0 else math.nan
    if weighted and dof > 0:
        s2 = max(s2, 1.0)        # the stated depth uncertainties explain the scatter
    s2 *= scale
    if dof > 0 and s2 > 0:
        thr = float(stats.f.ppf(confidence, 1, dof)) * s2
        inside = prof[:, 3] - chi2_min <= thr
        nu_ci = (float(prof[inside, 0].min()), float(prof[inside, 0].max()))
    else:
        thr, inside, nu_ci = math.nan, np.ones(prof.shape[0], bool), (lo, hi)
        notes.append(f"{n} presses leave no degree of freedom to test nu: it is not identified")
    at_lo, at_hi = nu_ci[0] <= lo + 1e-9, nu_ci[1] >= hi - 1e-9
    # identified: inside the table's range, off both its ends, and narrow
    nu_identified = bool(dof > 0 and not at_lo and not at_hi
                         and nu_ci[1] - nu_ci[0] <= _NU_IDENTIFIED_WIDTH)
    bound = None
    if dof > 0 and at_hi != at_lo:   # one end on the table's edge: a bound, not a value
        bound = f"nu >= {nu_ci[0]:.4g}" if at_hi else f"nu <= {nu_ci[1]:.4g}"
    if nu_identified:
        nu_fit = float(prof[k_best, 0])
        sel = prof[inside]
        half = np.sqrt(np.maximum(thr - (sel[:, 3] - chi2_min), 0.0) * sel[:, 2])
        # in log E: the interval of a positive modulus never reaches zero
        rel = half / sel[:, 1]
        E_ci = (float(np.min(sel[:, 1] * np.exp(-rel))), float(np.max(sel[:, 1] * np.exp(rel))))
        E_fit, E_var = float(prof[k_best, 1]), float(prof[k_best, 2]) * s2
        if nu is not None and abs(nu - nu_fit) > 1e-9:
            notes.append(f"nu stated {nu:g}; the presses identify nu = {nu_fit:.3f} "
                         f"[{nu_ci[0]:.3f}, {nu_ci[1]:.3f}]: E is reported at the fitted nu")
        return E_fit, E_var, E_ci, nu_fit, nu_ci, nu_identified, bound
    k = int(np.argmin(np.abs(prof[:, 0] - nu_stated)))
    # one parameter (E) at the stated nu: its own scale, n - 1 degrees of freedom
    s2_1 = float(prof[k, 3]) / (n - 1)
    if weighted:
        s2_1 = max(s2_1, 1.0)
    E_fit, E_var = float(prof[k, 1]), float(prof[k, 2]) * s2_1 * scale
    E_ci = log_interval(E_fit, math.sqrt(E_var), float(stats.t.ppf(0.5 + confidence / 2, n - 1)))
    if bound is not None:
        notes.append(f"nu not identified: {bound} ({confidence:.0%} profile interval "
                     f"[{nu_ci[0]:.4g}, {nu_ci[1]:.4g}] reaches the table's edge, "
                     f"{hi if at_hi else lo:g}: a bound, not a value); E is reported at the "
                     f"stated nu = {nu_stated:g}")
    else:
        notes.append(f"nu not identified: the presses allow nu from {nu_ci[0]:.3f} to "
                     f"{nu_ci[1]:.3f} ({confidence:.0%} profile interval); E is reported at "
                     f"the stated nu = {nu_stated:g}")
    if dof > 0 and not nu_ci[0] - 1e-9 <= nu_stated <= nu_ci[1] + 1e-9:
        notes.append(f"the stated nu = {nu_stated:g} lies outside what the presses allow "
                     f"([{nu_ci[0]:.4g}, {nu_ci[1]:.4g}]): E at it is not what they say")
    return E_fit, E_var, E_ci, nu_stated, nu_ci, False, bound


def _checked(depth_mm, force_n, indenter: Indenter, thickness_mm: float, law: str,
             contact: str | None, nu: float | None, nu_range: tuple[float, float],
             depth_std_mm, depth_shared_mm: float, confidence: float) -> tuple:
    """:func:`fit_indenter`'s arguments checked: (w, P, u, h, reach, contact, nu stated)."""
    w, P, h = check_presses(depth_mm, force_n, thickness_mm)
    if not 0 < confidence < 1:
        raise InputError(f"confidence must be in (0, 1), got {confidence!r}")
    n = w.size
    if n < 2:
        raise InputError(f"{n} press(es): the fit of E needs two or more")
    bad = np.flatnonzero(w <= 0)
    if bad.size:
        raise InputError(f"press {int(bad[0])}: depth_mm = {w[bad[0]]:g} must be positive")
    reach = reach_of(indenter, h, law, contact)     # the inverse's own (contact's) reach
    bad = np.flatnonzero(w > reach * (1 + 1e-9))
    if bad.size:
        raise InputError(f"press {int(bad[0])}: depth {w[bad[0]]:.4g} mm is past the "
                         f"{indenter.shape} table's reach, {reach:.4g} mm on h = {h:g} mm")
    bad = np.flatnonzero(P <= 0)
    if bad.size:
        raise InputError(f"press {int(bad[0])}: force_n = {P[bad[0]]:g} must be positive "
                         "(a press pushes into the gel)")
    lo, hi = map(float, nu_range)
    if not 0.0 <= lo < hi <= 0.5:
        raise InputError(f"nu_range must satisfy 0 <= lo < hi <= 0.5, got {nu_range!r}")
    nu_stated = min(NU_STATED, hi) if nu is None else float(nu)
    if not lo <= nu_stated <= hi:
        raise InputError(f"nu = {nu_stated!r} is outside nu_range {nu_range!r}")
    u = None
    if depth_std_mm is not None:
        u = check_array(depth_std_mm, "depth_std_mm", [(n,)], dtype=np.number,
                        finite=True).astype(np.float64)
        if np.any(u < 0):
            i = int(np.argmax(u < 0))
            raise InputError(f"press {i}: depth_std_mm = {u[i]:g} must be >= 0")
    shared = np.asarray(depth_shared_mm, np.float64)
    if shared.ndim > 1 or (shared.ndim == 1 and shared.size != w.size) or not (
            np.all(np.isfinite(shared)) and np.all(shared >= 0)):
        raise InputError("depth_shared_mm must be a number >= 0 or one per press, got "
                         f"{depth_shared_mm!r}")
    return w, P, u, h, reach, indenter._contact(contact), nu_stated



def _shared_hull(refit, w: np.ndarray, shared: np.ndarray, rel: float, reach: float,
                 E_ci: tuple, nu_ci: tuple, notes: list[str]) -> tuple[tuple, tuple]:
    """The intervals of E and nu widened to the hull of the fits with every depth moved to
    the bounds of a shared error (`shared` mm, one or per press; `rel` of each depth)."""
    E_hull, nu_hull = list(E_ci), list(nu_ci)
    for sgn in (-1.0, 1.0):
        ws = (w + sgn * shared) * (1.0 + sgn * rel)
        if np.any(ws <= 0) or np.any(ws > reach):
            notes.append(f"the depths moved by the shared error ({sgn:+.0f}) leave the "
                         "table: that side is not carried")
            continue
        other = refit(ws)
        E_hull = [min(E_hull[0], other.E_ci95_mpa[0]), max(E_hull[1], other.E_ci95_mpa[1])]
        nu_hull = [min(nu_hull[0], other.nu_ci95[0]), max(nu_hull[1], other.nu_ci95[1])]
    what = " and ".join(x for x in (
        (f"{float(shared) * 1e3:.3g} um" if shared.ndim == 0 else
         f"{float(shared.min()) * 1e3:.3g} to {float(shared.max()) * 1e3:.3g} um")
        if np.any(shared > 0) else "",
        f"{100 * rel:.3g} % of each depth" if rel > 0 else "") if x)
    notes.append(f"a depth error of {what} shared by every press: the intervals are the "
                 "hull of the fits with every depth moved to its bounds")
    return (E_hull[0], E_hull[1]), (nu_hull[0], nu_hull[1])


def fit_indenter(depth_mm: np.ndarray, force_n: np.ndarray, indenter: Indenter, *,
                 thickness_mm: float, law: str = "neo_hookean", contact: str | None = None,
                 nu: float | None = None, nu_range: tuple[float, float] | None = None,
                 depth_std_mm: np.ndarray | None = None,
                 depth_shared_mm: float | np.ndarray = 0.0,
                 confidence: float = 0.95,
                 force_std_n: np.ndarray | None = None,
                 depth_shared_rel: float = 0.0) -> IndenterFit:
    """Fit E (and nu, where the presses identify it) to presses of an indenter.

    Parameters
    ----------
    depth_mm : (N,) array_like of float
        Indentation depths w, mm, > 0, within the indenter's reach
        (:meth:`Indenter.reach_mm`).
    force_n : (N,) array_like of float
        Forces P, N.
    indenter : Indenter
        :class:`~tactilevision.mechanics.Sphere` or
        :class:`~tactilevision.mechanics.FlatPunch`.
    thickness_mm : float
        Layer thickness h, mm.
    law : {'neo_hookean', 'linear'}, default 'neo_hookean'
        Finite-strain or small-strain force law.
    contact : str, optional
        The indenter's contact condition (a sphere: ``'frictionless'``, the
        default, or ``'tied'``).
    nu : float, optional
        Poisson's ratio to report E at when the presses do not identify it;
        default 0.5. Given and the presses do identify nu, E is still the
        profile's (the fitted nu), and a note says how far the stated one is.
    nu_range : (float, float), optional
        The nu profiled; default the indenter's tables' range
        (:meth:`Indenter.nu_limits`: 0.30 to 0.50; a flat punch's finite-strain
        table stops at 0.499).
    depth_std_mm : (N,) array_like of float, optional
        Standard uncertainty of each depth, mm, >= 0: errors in both variables
        (effective variance, each press's force variance s0^2 + (dP/dw u)^2,
        s0 by the Paule-Mandel rule, as :func:`fit_indentation`).
    depth_shared_mm : float or (N,) array_like of float, default 0.0
        A depth error every press shares (a ramp's contact point), mm, >= 0 (a
        bound, not an sd), or, one per press, how far each depth moves when
        the shared error is at its bound (a ball's circles all too large by
        the detector's bias: each depth by its own dw/da): the fit is repeated
        with every depth moved by + and - this, and the intervals of E and nu
        are widened to the hull of the three fits' intervals.
    confidence : float, default 0.95
    force_std_n : (N,) array_like of float, optional
        Known standard uncertainty of each force, N, >= 0 (a dead weight's mass
        uncertainty times g; an F/T window's standard error): added to each
        press's force variance beside the depth's, s0 still fitted for what
        they leave unexplained.
    depth_shared_rel : float, default 0.0
        A depth error every press shares in proportion to its depth (a ball's
        contact circles all too large or too small by one fraction), a bound
        as a fraction, >= 0: the fit is repeated with every depth scaled by
        1 +- this and the intervals widened to the hull, as `depth_shared_mm`.

    Returns
    -------
    IndenterFit

    Raises
    ------
    ShapeError
        For arrays that are not 1-D, finite and of one length.
    InputError
        For a depth <= 0 or past the indenter's reach (naming the press), a
        force <= 0, fewer than two presses, a bad nu or nu_range, or a bad
        `confidence`.

    Notes
    -----
    The profile: for nu on a grid of 0.0025 over `nu_range`, E(nu) and the
    weighted residual sum chi2(nu) (variances at that nu); the interval of nu
    is where chi2(nu) - min chi2 <= F(1, n - 2) s^2, with s^2 = min chi2 / (n
    - 2) floored at 1 where depth uncertainties were given (a likelihood
    ratio with the scale estimated, as a Student t interval). E's interval at a
    fixed nu is E exp(-+ t(n - 1) se / E), the Student t interval of log E (a
    modulus is positive: its interval never reaches zero); with nu identified
    it is the union over the nu of the profile of E(nu) exp(-+ sqrt((threshold
    - excess(nu)) var_E(nu)) / E(nu)). An interval whose profile reaches one end
    of the table and not the other is a bound (`nu_bound`), never "identified".

    The misfit (:func:`~tactilevision.mechanics.assess_misfit`) is then read on
    the residuals at the reported nu: a serial correlation of the residuals
    along depth (a law that cannot follow the curve) widens both intervals by
    sqrt((1 + rho) / (1 - rho)), and a drift of the apparent E with depth
    widens E's to hold the shallowest and deepest quarters' apparent E; a note
    starting ``warning:`` names the factor and the drift. The Birge ratio on the
    stated noise is named there too; the fit's scale (the residual variance, or
    Paule and Mandel's sigma0) already carries it.
    """
    if nu_range is None:
        nu_range = indenter.nu_limits(law)
    w, P, u, h, reach, contact, nu_stated = _checked(
        depth_mm, force_n, indenter, thickness_mm, law, contact, nu, nu_range, depth_std_mm,
        depth_shared_mm, confidence)
    n, (lo, hi) = w.size, map(float, nu_range)

    def columns(wd: np.ndarray, v: float) -> tuple[np.ndarray, np.ndarray]:
        """The force at E = 1 and its slope dP/dw (centred differences), at nu = v."""
        kw = {"nu": float(v), "thickness_mm": h, "law": law, "contact": contact}
        eps = 1e-6 * h
        up, dn = np.minimum(wd + eps, reach), np.maximum(wd - eps, 1e-12)
        g = indenter.force(wd, E_mpa=1.0, **kw)
        dg = (indenter.force(up, E_mpa=1.0, **kw) - indenter.force(dn, E_mpa=1.0, **kw)) / (
            up - dn)
        return g, dg

    costly = bool(getattr(indenter, "costly_in_nu", False))
    grid = (np.array([nu_stated]) if costly else
            np.unique(np.append(np.round(np.arange(lo, hi + 1e-9, 0.0025), 6), nu_stated)))
    f_sd = _force_sd(force_std_n, n)
    prof, _, sigma0, weighted, stated = _profile(grid, [columns(w, v) for v in grid], P, u,
                                                 f_sd)
    kw = {"thickness_mm": h, "law": law, "contact": contact}

    def residuals(E_fit: float, nu_fit: float, ident: bool) -> tuple:
        g = indenter.force(w, E_mpa=1.0, nu=nu_fit, **kw)
        resid = P - E_fit * g
        return g, resid, assess_misfit(
            w, resid, P / g, noise_sd_n=None if stated is None else np.sqrt(stated),
            n_params=2 if ident else 1)

    # the misfit's factor read at the first reading's nu scales the residuals' variance of
    # the second (the profile's threshold and E's variance), then is read again where the
    # second puts nu
    args = (prof, n, weighted, confidence, (lo, hi), nu, nu_stated, costly, indenter.shape)
    first = _read(*args, 1.0)
    factor = residuals(first[0], first[3], first[5])[2].factor
    E_fit, E_var, E_ci, nu_fit, nu_ci, nu_identified, bound, E_over, notes = (
        _read(*args, factor ** 2) if factor > 1 else first)
    dof = n - 2
    if not (np.isfinite(depth_shared_rel) and 0 <= depth_shared_rel < 1):
        raise InputError(f"depth_shared_rel must be within [0, 1), got {depth_shared_rel!r}")
    g, resid, misfit = residuals(E_fit, nu_fit, nu_identified)
    misfit = replace(misfit, factor=factor)
    pred = E_fit * g
    E_ci, E_identified = _drift_hull(misfit, E_ci, confidence, notes)
    shared = np.asarray(depth_shared_mm, np.float64)
    if np.any(shared > 0) or depth_shared_rel > 0:
        def refit(ws: np.ndarray) -> IndenterFit:
            return fit_indenter(ws, P, indenter, thickness_mm=h, law=law, contact=contact,
                                nu=nu, nu_range=nu_range, depth_std_mm=u,
                                confidence=confidence, force_std_n=f_sd)

        E_ci, nu_ci = _shared_hull(refit, w, shared, depth_shared_rel, reach, E_ci, nu_ci,
                                   notes)
    k_nu = int(np.argmin(np.abs(prof[:, 0] - nu_fit)))
    if weighted:
        notes.append("errors in both variables: effective variance with the stated depth "
                     f"and force uncertainties, extra force scatter sigma0 = "
                     f"{sigma0 * 1e3:.3g} mN")
    return IndenterFit(
        E_mpa=E_fit, E_ci95_mpa=E_ci, nu=nu_fit, nu_ci95=nu_ci, nu_identified=nu_identified,
        E_over_nu_ci_mpa=E_over, E_se_mpa=math.sqrt(E_var) if E_var >= 0 else math.nan,
        shape=indenter.shape, radius_mm=indenter.radius_mm, thickness_mm=h, law=law,
        contact=contact, n_presses=n, rmse_n=float(np.sqrt(np.mean(resid ** 2))),
        residuals_n=resid, predicted_n=pred, apparent_E_mpa=P / g,
        sigma0_n=sigma0, chi2=float(prof[k_nu, 3]), dof=dof,
        confidence=confidence, notes=tuple(notes), nu_bound=bound, E_identified=E_identified,
        misfit=misfit)


def _force_sd(force_std_n: np.ndarray | None, n: int) -> np.ndarray | None:
    """`force_std_n` checked: (n,) float64, finite, >= 0 (naming the press), or None."""
    if force_std_n is None:
        return None
    f_sd = check_array(force_std_n, "force_std_n", [(n,)], dtype=np.number,
                       finite=True).astype(np.float64)
    if np.any(f_sd < 0):
        i = int(np.argmax(f_sd < 0))
        raise InputError(f"press {i}: force_std_n = {f_sd[i]:g} must be >= 0")
    return f_sd


def _read(prof: np.ndarray, n: int, weighted: bool, confidence: float,
          nu_range: tuple[float, float], nu: float | None, nu_stated: float, costly: bool,
          shape: str, scale: float) -> tuple:
    """The profile read with the residuals' variance times `scale`: E, var_E, E's and nu's
    intervals, nu, identified, bound, E at nu's ends, notes."""
    lo, hi = nu_range
    notes: list[str] = []
    if costly:     # one parameter at the stated nu; nu not profiled
        t_q = float(stats.t.ppf(0.5 + confidence / 2, max(n - 1, 1)))
        s2_1 = float(prof[0, 3]) / (n - 1)
        E_fit = float(prof[0, 1])
        E_var = float(prof[0, 2]) * (max(s2_1, 1.0) if weighted else s2_1) * scale
        notes.append(f"nu not profiled: each nu is a FEM sweep of this {shape} (a finite "
                     f"pad); E is reported at the stated nu = {nu_stated:g}")
        return (E_fit, E_var, log_interval(E_fit, math.sqrt(E_var), t_q), nu_stated,
                (lo, hi), False, None, (math.nan, math.nan), notes)
    E_fit, E_var, E_ci, nu_fit, nu_ci, ident, bound = _read_profile(
        prof, n, weighted, confidence, (lo, hi), nu, nu_stated, notes, scale)
    ends = [int(np.argmin(np.abs(prof[:, 0] - v))) for v in nu_ci]
    return (E_fit, E_var, E_ci, nu_fit, nu_ci, ident, bound,
            (float(min(prof[ends, 1])), float(max(prof[ends, 1]))), notes)


def _drift_hull(misfit: Misfit, E_ci: tuple[float, float], confidence: float,
                notes: list[str]) -> tuple[tuple[float, float], bool]:
    """E's interval widened to the drift's ends where the apparent E drifts, the misfit's
    warning noted, and whether E is identified (its interval within a factor e^2)."""
    if misfit.drifts:
        E_ci = (min(E_ci[0], misfit.E_shallow_mpa, misfit.E_deep_mpa),
                max(E_ci[1], misfit.E_shallow_mpa, misfit.E_deep_mpa))
    if misfit.warning:
        notes.append(f"warning: {misfit.warning}")
    identified = bool(E_ci[0] > 0 and E_ci[1] / E_ci[0] < _E_IDENTIFIED_RATIO)
    if not identified:
        notes.append(f"E not identified by these presses: its {confidence:.0%} interval "
                     f"[{E_ci[0]:.4g}, {E_ci[1]:.4g}] MPa spans more than a factor of "
                     f"{_E_IDENTIFIED_RATIO:.3g}")
    return E_ci, identified
