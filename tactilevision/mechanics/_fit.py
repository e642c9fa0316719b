"""The paper's in-situ fit: presses (w, P) -> c, beta -> nu, E (eq. 4-7)."""

from __future__ import annotations

import dataclasses
import math
import warnings
from functools import lru_cache

import numpy as np
from scipy import optimize, stats
from scipy.interpolate import PchipInterpolator

from .._checks import InputError, check_array
from ._beta import beta_relation
from ._effects import FIT_EFFECTS
from ._fem_tables import TABLE_EXTRAPOLATION, fem_force, kappa_n_nu_range
from ._kappa import _dkappa_dnu, kappa
from ._kappa import _table as _kappa_table
from ._misfit import assess_misfit, log_interval, widen_interval
from ._neohookean import neo_hookean_constants
from ._result import IndentationFit

__all__ = ["BETA_TABLE_REACH", "MAX_W_OVER_H", "carry_misfit", "fit_indentation",
           "past_beta_table_reach"]

#: Largest w/h for which the linear law (2) holds (paper, section VI.1).
MAX_W_OVER_H = 0.2
#: Deepest w/h the FEM beta table is read at (computed to MAX_W_OVER_H, read 15 % beyond:
#: ``TABLE_EXTRAPOLATION``); a press deeper than this is refused by ``beta_table='fem'``.
BETA_TABLE_REACH = MAX_W_OVER_H * TABLE_EXTRAPOLATION



def past_beta_table_reach(depth_mm: np.ndarray, thickness_mm: float,
                          depth_std_mm: np.ndarray | None = None) -> np.ndarray:
    """Which presses lie past the FEM beta table's reach (:data:`BETA_TABLE_REACH`) by more
    than two of their depth uncertainties: those ``fit_indentation(beta_table='fem')``
    refuses, and that ``calibrate`` and ``fit`` leave out of their fits, naming them (a
    press nearer the reach is read at the table's last w/h).

    Parameters
    ----------
    depth_mm : (N,) float ndarray
    thickness_mm : float
        h, mm (> 0).
    depth_std_mm : (N,) float ndarray, optional
        Standard uncertainties, mm (NaN counts as 0); default 0.

    Returns
    -------
    past : (N,) bool ndarray
    """
    w = np.asarray(depth_mm, np.float64)
    u = np.zeros_like(w) if depth_std_mm is None else np.nan_to_num(
        np.asarray(depth_std_mm, np.float64))
    return w - 2.0 * u > BETA_TABLE_REACH * float(thickness_mm) * (1 + 1e-12)


_NAN2 = (math.nan, math.nan)
_CI_METHOD = ("delta method through the HC3 (heteroscedasticity-consistent) covariance of "
              "slope and intercept, Student t with n - 2 degrees of freedom")
_EV_CI_METHOD = ("delta method through the effective-variance covariance (X^T W X)^-1 of "
                 "intercept and slope (errors in both variables: force scatter and certified "
                 "depth uncertainty, Orear 1982), Student t with n - 2 degrees of freedom")


def _positive(x: float, name: str) -> float:
    v = float(x)
    if not (math.isfinite(v) and v > 0):
        raise InputError(f"{name} must be a positive number, got {x!r}")
    return v


def _covariance(X: np.ndarray, resid: np.ndarray) -> tuple[np.ndarray, str | None]:
    """HC3 covariance of OLS coefficients; classical or NaN where HC3 is undefined."""
    n = X.shape[0]
    xtx_inv = np.linalg.inv(X.T @ X)  # 2x2
    if n <= 2:
        return np.full((2, 2), np.nan), "no residual degrees of freedom: intervals undefined"
    lev = np.einsum("ij,jk,ik->i", X, xtx_inv, X)  # (N,) leverages
    if np.max(lev) > 1 - 1e-9:
        cov = float(resid @ resid) / (n - 2) * xtx_inv
        return cov, ("a depth with a single press has leverage 1: classical OLS covariance "
                     "used instead of HC3")
    meat = X.T @ (X * (resid**2 / (1 - lev) ** 2)[:, None])
    return xtx_inv @ meat @ xtx_inv, None


def fit_indentation(depth_mm: np.ndarray, force_n: np.ndarray, *, thickness_mm: float,
                    radius_mm: float, beta_table: str = "fem",
                    a_over_h: float | None = None, contact: str = "bonded",
                    confidence: float = 0.95,
                    depth_std_mm: np.ndarray | None = None,
                    indenter: np.ndarray | None = None,
                    depth_indenter_std_mm: np.ndarray | None = None) -> IndentationFit:
    """Fit E and nu of a bonded gel layer to flat-punch presses (the paper's method).

    Parameters
    ----------
    depth_mm : (N,) array_like of float, mm
        Certified indentation depth w of each press, positive; at least two
        distinct depths.
    force_n : (N,) array_like of float, N
        Normal force P of each press, positive into the gel.
    thickness_mm : float, mm
        Gel thickness h.
    radius_mm : float, mm
        Flat indenter radius a.
    beta_table : {'fem', 'paper'}, default 'fem'
        Source of nu(beta) and kappa. ``'fem'``: the project's finite-strain
        FEM beta table (``models/beta_fem.npz``: the secant beta that eq. (5)
        fitted at these very depths gives on the FEM's P/w, at the exact
        a/h) and FEM kappa table (``models/kappa_fem.npz``), both for the
        punch condition `contact`. ``'paper'``: the paper's relation (7)
        (fitted at a/h = 0.8) and the Hayes 1972 kappa (frictionless), as in
        the paper.
    a_over_h : float, optional
        a/h at which kappa is read. Default: the exact ``radius_mm /
        thickness_mm``. The paper rounds a = 2.5, h = 3.0 to a/h = 0.8; pass
        0.8 to reproduce it.
    contact : {'bonded', 'frictionless'}, default 'bonded'
        Punch condition of the FEM tables (``beta_table='fem'`` only). The
        FEM beta table holds the bonded (no-slip) punch only: a frictionless
        sharp-edged punch does not converge at finite strain.
    confidence : float, default 0.95
        Level of the intervals, in (0, 1).
    depth_std_mm : (N,) array_like of float, mm, optional
        Standard uncertainty (1 sigma) of each certified depth, >= 0. Given
        and not all zero: eq. (5) is fitted with errors in both variables
        (effective variance, see Notes). None (default), or zero for every
        press: the depths are taken as exact (ordinary least squares below).
    indenter, depth_indenter_std_mm : (N,) array_like, optional
        Each press's indenter and the part of its `depth_std_mm` that the
        indenter's presses share (the mark rule's P(w0), counted n times over as
        `depth_std_mm` counts it), mm; with `depth_std_mm` only. The fit is
        unchanged; its misfit's structure and drift along depth are read on the
        indenters' means (:func:`~tactilevision.mechanics.assess_misfit`'s
        `group`), so that the indenters' stated shared errors are not taken for a
        misfit.

    Returns
    -------
    fit : IndentationFit

    Raises
    ------
    ShapeError
        When `depth_mm`, `force_n` or `depth_std_mm` is not 1-D, not numeric,
        not finite, or their lengths differ.
    InputError
        When a depth is not positive, a depth uncertainty is negative,
        fewer than two depths are distinct, `thickness_mm` or `radius_mm` is
        not positive, a/h is outside the kappa table [0.2, 2.0], the FEM
        table is missing, or it has no `contact` punch, or its beta does not
        increase with nu at this a/h (a bonded punch at a/h <~ 0.6: nu
        cannot be told from beta there), or (``'fem'``) a press lies past the
        FEM beta table's reach, w/h = 0.23 (computed to 0.2, read 15 %
        beyond), by two of its depth uncertainties or more (a press past it by
        less is within its uncertainty of the table, which is read at its
        last w/h for that press; a note says so).
    ValueError
        For an unknown `beta_table` or a `confidence` outside (0, 1).

    Warns
    -----
    UserWarning
        When a press exceeds w/h = 0.2, where the linear law (2) fails
        (paper, section VI.1); the fit goes on and says so in `notes`.

    Notes
    -----
    Ordinary least squares of ``y = P/w`` on ``x = w/h``, eq. (5):
    ``P/w = c beta (w/h) + c``, so the intercept is c and ``beta = slope / c``.
    Then nu = nu(beta) from the beta table (the inverse of the FEM beta(nu)
    at this a/h, or eq. 7 for ``'paper'``),
    ``E = c (1 - nu^2) / (2 a kappa(nu, a/h))`` (eq. 4; kappa from Hayes
    1972 for ``'paper'``; for ``'fem'`` the intercept of the FEM's kappa_n
    line fitted at these depths, the same line that gives beta, which tends
    to the small-strain FEM kappa as the depths go to 0), and the Neo-Hookean constants of
    :func:`neo_hookean_constants`. The beta table never enters the
    regression: residuals do not depend on it.

    At the edges of the FEM table: a beta above its largest (the peak of
    beta over nu) or below its smallest (where beta starts to rise with nu)
    whose interval still reaches into the table gives nu at that edge, the
    interval of nu from the smallest to the largest tabulated nu whose beta
    lies within beta's interval, and E at that nu with its interval over that
    range of nu and c's own bounds; a note says so. The same above the paper's
    relation (7), whose top is nu = 0.5: nu is put at 0.5, its interval from
    the nu of beta's lower bound. A beta whose interval does not reach the
    table gives no E and nu (`out_of_table`), as does any beta below the
    paper's relation (7) (its bottom, nu = 0.30, is where Hayes' kappa table
    starts).

    Intervals: delta method (first-order propagation) of the covariance of
    intercept and slope through beta, nu and E, with a Student t quantile on
    ``n - 2`` degrees of freedom. The covariance is the HC3
    heteroscedasticity-consistent estimate (MacKinnon and White 1985) because
    a constant force noise makes the noise of P/w grow as 1/w; the classical
    OLS covariance then covers nu only about 85% of the time at the nominal
    95% (tests/test_mechanics_fit.py measures the coverage). The kappa and
    beta tables are taken as exact: the intervals hold only the press scatter.

    With `depth_std_mm` (u_i), errors in both variables, by the effective
    variance method [4]_ (the first-order equivalent of orthogonal distance
    regression): eq. (5) times w is ``P(w) = c w + s w^2 / h``
    (``s = c beta``), and press i gets the force variance
    ``var_i = sigma0^2 + (dP/dw(w_i))^2 u_i^2``, ``dP/dw = c + 2 s w / h``
    at the ordinary fit. sigma0^2 >= 0 is the force scatter that the depth
    uncertainties do not explain, a random-effects extra variance chosen as
    the smallest value with reduced chi-square ``chi2 / (n - 2) <= 1`` (the
    Paule-Mandel rule [5]_; 0 when the depth uncertainties alone already
    give ``chi2 / (n - 2) <= 1``, and when n = 2). (c, s) is then the
    weighted least squares of P with weights ``1 / var_i`` (the same line as
    P/w on w/h with weights ``w_i^2 / var_i``) and its covariance
    ``(X^T W X)^-1``, so it never falls below what the stated depth
    uncertainties imply. The FEM beta table is read with the same weights
    (its secant is the weighted line through the FEM's own P/w at these
    depths), so on exact FEM forces the fit returns the FEM's E and nu. (Read
    with equal weights, as before 2026-11-25, E came out 9 % low on exact FEM
    forces at the paper's design and the 95 % intervals held the true E in
    15 of 60 generated sessions; now 58 of 60,
    ``benchmarks/bench_fit_depth_std_bias.py``.) The paper's relation (7)
    does not depend on the depths nor the weights. nu, E and the intervals
    then follow as above (delta method, Student t on ``n - 2`` degrees of
    freedom). `rmse_n` and `r_squared` are computed as in the ordinary fit
    (unweighted residuals of P, and of P/w against w/h), so they stay
    comparable. `depth_std_used`, `depth_std_median_mm` and `sigma0_n` of
    the result report it.

    References
    ----------
    .. [1] C. Zhao, J. Ren, H. Yu, D. Ma, "In-situ Mechanical Calibration for
       Vision-based Tactile Sensors", IEEE ICRA 2023,
       eq. (4)-(7) and section IV.
    .. [2] W. C. Hayes et al., J. Biomech. 5:541-551, 1972.
       doi:10.1016/0021-9290(72)90010-3
    .. [3] J. G. MacKinnon, H. White, "Some heteroskedasticity-consistent
       covariance matrix estimators with improved finite sample properties",
       J. Econometrics 29:305-325, 1985. doi:10.1016/0304-4076(85)90158-7
    .. [4] J. Orear, "Least squares when both variables have uncertainties",
       Am. J. Phys. 50:912-916, 1982. doi:10.1119/1.12972
    .. [5] R. C. Paule, J. Mandel, "Consensus values and weighting factors",
       J. Res. Natl. Bur. Stand. 87:377-385, 1982. doi:10.6028/jres.087.022

    Examples
    --------
    >>> import numpy as np
    >>> from tactilevision.mechanics import fit_indentation
    >>> w = np.array([0.15, 0.30, 0.40, 0.50, 0.60])
    >>> P = w * (5.2662 * w / 3.0 + 3.4943)            # the paper's line (6)
    >>> fit = fit_indentation(w, P, thickness_mm=3.0, radius_mm=2.5, a_over_h=0.8,
    ...                       beta_table="paper")
    >>> round(fit.nu, 4), round(fit.beta, 4)
    (0.4797, 1.5071)

    The same line with the FEM tables: no Neo-Hookean layer at a/h = 0.83
    stiffens that much (beta <= 0.80 for any nu, bonded punch).

    >>> fit_indentation(w, P, thickness_mm=3.0, radius_mm=2.5).out_of_table
    True
    """
    w = check_array(depth_mm, "depth_mm", [("N",)], dtype=np.number, finite=True)
    P = check_array(force_n, "force_n", [(w.shape[0],)], dtype=np.number, finite=True)
    w, P = w.astype(np.float64), P.astype(np.float64)
    h = _positive(thickness_mm, "thickness_mm")
    a = _positive(radius_mm, "radius_mm")
    if not 0 < confidence < 1:
        raise InputError(f"confidence must be in (0, 1), got {confidence!r}")
    if np.any(w <= 0):
        i = int(np.argmax(w <= 0))
        raise InputError(f"depth_mm[{i}] = {w[i]:g} mm: depths must be positive")
    depths = np.unique(w)
    if depths.size < 2:
        raise InputError(f"depth_mm holds {depths.size} distinct depth(s); the fit of "
                         "eq. (5) needs presses at two depths or more")
    u = None if depth_std_mm is None else _depth_std(depth_std_mm, w.size)
    shared = _indenter_shared(indenter, depth_indenter_std_mm, u, w.size)
    w_table, reach_note = _table_depths(w, u, h, beta_table)
    ah, kappa_source, contact = _geometry(w_table, h, a, beta_table, a_over_h, contact)
    if u is not None and np.any(u > 0):
        return _fit_with_depth_std(w, P, u, h=h, a=a, ah=ah, beta_table=beta_table,
                                       contact=contact, kappa_source=kappa_source,
                                       confidence=confidence,
                                       a_over_h_given=a_over_h is not None,
                                       w_table=w_table, reach_note=reach_note,
                                       shared=shared)
    zero_note = (("depth_std_mm is 0 for every press: the depths are taken as exact "
                  "(ordinary fit)",) if u is not None else ())

    # eq. (5): y = c + (c beta) x, ordinary least squares
    x, y = w / h, P / w  # (N,), (N,)
    X = np.column_stack([np.ones_like(x), x])  # Nx2
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    c, s = float(coef[0]), float(coef[1])
    resid = y - X @ coef
    tss = float(np.sum((y - y.mean()) ** 2))
    r2 = 1.0 - float(resid @ resid) / tss if tss > 0 else 1.0
    rmse = float(np.sqrt(np.mean((P - w * (X @ coef)) ** 2)))
    cov, cov_note = _covariance(X, resid)
    fit = material_fit(c, s, cov, depth_mm=w, thickness_mm=h, radius_mm=a, a_over_h=ah,
                       beta_table=beta_table, contact=contact, kappa_source=kappa_source,
                       confidence=confidence, dof=w.size - 2, rmse_n=rmse, r_squared=r2,
                       effects=FIT_EFFECTS, effect_params=None,
                       a_over_h_given=a_over_h is not None,
                       extra_notes=((cov_note,) if cov_note else ()) + zero_note,
                       ci_method=_CI_METHOD)
    return carry_misfit(fit, w, P, w * (X @ coef))


def _fem_law(fit: IndentationFit, w: np.ndarray) -> np.ndarray | None:
    """The FEM's finite-strain force at the fit's E and nu (eq. 5 alone, FEM table, bonded
    punch, E and nu computed inside the table, not put at its edge), or None."""
    if not (fit.beta_table == "fem" and fit.contact == "bonded" and fit.effects == FIT_EFFECTS
            and math.isfinite(fit.E_mpa) and math.isfinite(fit.nu) and fit.nu_bound is None):
        return None         # (at the table's edge the law at that nu is not the fitted one)
    lo, hi = kappa_n_nu_range()
    h = fit.thickness_mm
    if not lo <= fit.nu <= hi:
        return None
    try:
        return fem_force(fit.E_mpa, fit.nu, fit.radius_mm, h,
                         np.minimum(w, MAX_W_OVER_H * TABLE_EXTRAPOLATION * h))
    except InputError:
        return None


def carry_misfit(fit: IndentationFit, depth_mm: np.ndarray, force_n: np.ndarray,
                 predicted_n: np.ndarray, noise_sd_n: np.ndarray | None = None,
                 n_params: int = 2, structure: bool = True,
                 group: np.ndarray | None = None) -> IndentationFit:
    """`fit` with the misfit of its presses read and carried into its intervals.

    Parameters
    ----------
    fit : IndentationFit
    depth_mm, force_n, predicted_n : (N,) float ndarray
        The presses and the fit's force at each, mm and N.
    noise_sd_n : (N,) float ndarray, optional
        The stated noise of each press's force (the F/T window's and the depth's
        through dP/dw), N: gives the Birge ratio.
    n_params : int, default 2
        Parameters fitted (c and c beta for eq. 5 alone).
    structure : bool, default True
        Read the residuals' structure along depth (:func:`assess_misfit`); False for
        a model whose E the FEM's law at these depths gives while `predicted_n` is
        its line's.
    group : (N,) ndarray, optional
        Groups of presses that share a stated error (:func:`assess_misfit`).

    Returns
    -------
    IndentationFit
        With :attr:`~IndentationFit.misfit` set; where the residuals run in long
        runs along depth (a serial correlation), E's and nu's intervals widened
        by its factor (E's in log E, nu's clipped to [0, 0.5]); where each
        press's apparent E (E P / P_fit, P_fit the FEM's own force law at E and
        nu where the FEM table gave them, else `predicted_n`) drifts with
        depth, E's interval widened
        to hold the shallowest and deepest quarters' apparent E; a note
        ``warning: ...`` naming them. The fit's covariance (HC3, or Paule and
        Mandel's extra variance) already carries the residuals' size: the Birge
        ratio is named, not applied again. ``E_se_mpa`` and ``nu_se`` stay the
        fit's own (the press scatter's).
    """
    w, P = np.asarray(depth_mm, np.float64), np.asarray(force_n, np.float64)
    pred = np.asarray(predicted_n, np.float64)
    E = fit.E_mpa
    law = _fem_law(fit, w)
    if law is not None:
        # the FEM table's E and nu stand for the FEM's own force law, which eq. (5)'s line
        # only approximates (the table reads the line's secant beta at these depths): the
        # residuals that say what the model misses are the presses' against that law
        pred = law
    finite = math.isfinite(E) and E > 0 and bool(np.all(pred > 0))
    apparent = (E if finite else 1.0) * P / np.where(pred > 0, pred, np.nan)
    m = assess_misfit(w, P - pred, apparent, noise_sd_n=noise_sd_n, n_params=n_params,
                      structure=structure or law is not None, group=group)
    if not finite:        # no E: the drift is of the force's ratio, not a modulus
        m = dataclasses.replace(m, E_shallow_mpa=math.nan, E_deep_mpa=math.nan)
    E_ci, nu_ci = fit.E_ci95_mpa, fit.nu_ci95
    extra: tuple[str, ...] = ()
    if finite and math.isfinite(E_ci[0]) and E_ci[0] <= 0 < E_ci[1]:
        # the delta method's symmetric interval reaches zero: a modulus is positive, its
        # interval is taken in log E (the same half-width in units of E's se)
        E_ci = log_interval(E, E_ci[1] - E, 1.0)
        extra = (f"E is not identified by these presses: its interval reached zero, taken in "
                 f"log E it is [{E_ci[0]:.4g}, {E_ci[1]:.4g}] MPa",)
    if finite and m.factor > 1 and all(math.isfinite(v) and v > 0 for v in E_ci):
        E_ci = (E * (E_ci[0] / E) ** m.factor, E * (E_ci[1] / E) ** m.factor)
    if m.factor > 1 and math.isfinite(fit.nu) and all(math.isfinite(v) for v in nu_ci):
        nu_ci = widen_interval(fit.nu, nu_ci, m.factor, (0.0, 0.5))
    if finite and m.drifts:
        E_ci = (min(E_ci[0], m.E_shallow_mpa, m.E_deep_mpa),
                max(E_ci[1], m.E_shallow_mpa, m.E_deep_mpa))
    notes = fit.notes + extra + ((f"warning: {m.warning}",) if m.warning and finite else ())
    return dataclasses.replace(fit, E_ci95_mpa=E_ci, nu_ci95=nu_ci, misfit=m, notes=notes)


def _depth_std(depth_std_mm: object, n: int) -> np.ndarray:
    """`depth_std_mm` checked: (n,) float64, finite, >= 0.

    Raises
    ------
    ShapeError
        For a wrong shape or dtype, NaN or inf.
    InputError
        For a negative value.
    """
    u = check_array(depth_std_mm, "depth_std_mm", [(n,)], dtype=np.number, finite=True)
    u = u.astype(np.float64)
    if np.any(u < 0):
        i = int(np.argmax(u < 0))
        raise InputError(f"depth_std_mm[{i}] = {u[i]:g} mm: depth uncertainties must be >= 0")
    return u


def _wls(X: np.ndarray, P: np.ndarray, var: np.ndarray
         ) -> tuple[np.ndarray, np.ndarray, float]:
    """Weighted least squares of `P` (N,) on `X` (N, 2) with variances `var` (N,) > 0.

    Returns
    -------
    coef : (2,) ndarray
    cov : (2, 2) ndarray
        ``(X^T W X)^-1`` with ``W = diag(1 / var)``.
    chi2 : float
        ``sum((P - X coef)^2 / var)``.
    """
    sw = 1.0 / np.sqrt(var)  # (N,)
    A, b = X * sw[:, None], P * sw
    coef, *_ = np.linalg.lstsq(A, b, rcond=None)
    r = b - A @ coef
    return coef, np.linalg.inv(A.T @ A), float(r @ r)


def _extra_variance(X: np.ndarray, P: np.ndarray, v: np.ndarray, dof: int, upper: float,
                    floor: float) -> float:
    """Smallest t >= 0 with ``chi2(t) / dof <= 1`` (Paule and Mandel 1982).

    ``chi2(t)`` is the minimum over the coefficients of
    ``sum((P - X b)^2 / (t + v))``, decreasing in t. `upper` >= 0 must give
    ``chi2(upper) <= dof`` (the unweighted residual variance does, since
    v >= 0); variances are floored at `floor` > 0 so that a press with v = 0
    keeps a finite weight at t = 0.
    """
    def excess(t: float) -> float:
        return _wls(X, P, np.maximum(t + v, floor))[2] / dof - 1.0

    if upper <= 0 or excess(0.0) <= 0:
        return 0.0
    return float(optimize.brentq(excess, 0.0, upper, xtol=1e-14 * upper, rtol=1e-12))


def _effective_variance_fit(depth_mm: np.ndarray, force_n: np.ndarray,
                            depth_std_mm: np.ndarray, thickness_mm: float
                            ) -> tuple[np.ndarray, np.ndarray, float, np.ndarray]:
    """Eq. (5) with errors in both variables: (c, c beta), covariance, sigma0, weights.

    Parameters
    ----------
    depth_mm, force_n, depth_std_mm : (N,) float ndarray
        Depths w (mm, > 0, two distinct at least), forces P (N) and depth
        standard uncertainties u (mm, >= 0).
    thickness_mm : float
        h, mm.

    Returns
    -------
    coef : (2,) ndarray
        Intercept c and slope s = c beta of eq. (5), N/mm.
    cov : (2, 2) ndarray
        ``(X^T W X)^-1``, ``X = [w, w^2 / h]``, ``W = diag(1 / var)``, (N/mm)^2.
    sigma0_n : float
        Extra force scatter, N (0 when N = 2: no degrees of freedom).
    weights : (N,) ndarray
        ``w^2 / var``, each press's weight in the line of P/w on w/h, (mm/N)^2.

    Notes
    -----
    Effective variance (Orear 1982): ``var_i = sigma0^2 + D_i``,
    ``D_i = ((c0 + 2 s0 w_i / h) u_i)^2`` at the ordinary fit (c0, s0) of P/w
    on w/h; sigma0^2 the smallest t >= 0 with ``chi2(t) / (N - 2) <= 1``,
    chi2 the minimum over (c, s) of ``sum((P - c w - s w^2 / h)^2 / (t + D_i))``
    (Paule and Mandel 1982), whose minimiser is the returned (c, s).
    Variances are floored at ``(1e-12 max|P|)^2`` so that a press with u = 0
    keeps a finite weight when sigma0 = 0.
    """
    w, P, u, h = depth_mm, force_n, depth_std_mm, thickness_mm
    x = w / h
    X = np.column_stack([np.ones_like(x), x])  # (N, 2): P/w = c + s w/h
    c0, s0 = np.linalg.lstsq(X, P / w, rcond=None)[0]
    dof = w.size - 2
    Xp = X * w[:, None]  # (N, 2): P = c w + s w^2 / h
    rss = float(np.sum((P - Xp @ np.array([c0, s0])) ** 2))
    upper = rss / dof if dof > 0 else 0.0
    floor = max((1e-12 * float(np.max(np.abs(P)))) ** 2, np.finfo(float).tiny)
    D = ((c0 + 2 * s0 * x) * u) ** 2  # (dP/dw)^2 u^2, (N,)
    t = _extra_variance(Xp, P, D, dof, upper, floor) if dof > 0 else 0.0
    var = np.maximum(t + D, floor)  # (N,) variance of P
    coef, cov, _chi2 = _wls(Xp, P, var)
    return coef, cov, math.sqrt(t), w * w / var


def _table_depths(w: np.ndarray, u: np.ndarray | None, h: float, beta_table: str
                  ) -> tuple[np.ndarray, str | None]:
    """The depths the FEM beta table is read at, and a note when any was moved.

    A press past the table's reach (w/h above ``MAX_W_OVER_H * TABLE_EXTRAPOLATION``)
    by less than two of its stated depth uncertainties is within its uncertainty of the
    table: the table is read at its last w/h for it (the regression keeps its depth).
    Any other press past the reach is left as it is, for :func:`_geometry` to refuse.
    """
    top = MAX_W_OVER_H * TABLE_EXTRAPOLATION * h
    past = w > top + 1e-12 * h
    if beta_table != "fem" or u is None or not past.any():
        return w, None
    if past_beta_table_reach(w, h, u).any():
        return w, None
    idx = ", ".join(str(int(i)) for i in np.flatnonzero(past))
    note = (f"press(es) {idx} reach w/h = {float(np.max(w / h)):.4f}, past the FEM beta "
            f"table's {top / h:g} by less than two of their depth uncertainties: the table "
            "is read at its last w/h for them (their depths are fitted as certified)")
    return np.minimum(w, top), note


def _fit_with_depth_std(w: np.ndarray, P: np.ndarray, u: np.ndarray, *, h: float, a: float,
                            ah: float, beta_table: str, contact: str, kappa_source: str,
                            confidence: float, a_over_h_given: bool,
                            w_table: np.ndarray | None = None,
                            reach_note: str | None = None,
                            shared: tuple[np.ndarray, np.ndarray] | None = None
                            ) -> IndentationFit:
    """:func:`fit_indentation` with depth uncertainties: effective variance, then E and nu
    (the tables read at `w_table`, default `w`: :func:`_table_depths`, with the fit's
    weights)."""
    coef, cov, sigma0, weights = _effective_variance_fit(w, P, u, h)
    c, s = float(coef[0]), float(coef[1])
    x, y = w / h, P / w  # the ordinary fit's basis for R^2 and rmse
    resid = y - (c + s * x)
    tss = float(np.sum((y - y.mean()) ** 2))
    r2 = 1.0 - float(resid @ resid) / tss if tss > 0 else 1.0
    rmse = float(np.sqrt(np.mean((P - w * (c + s * x)) ** 2)))
    med = float(np.median(u))
    notes = [f"errors in both variables: effective variance (Orear 1982) with the certified "
             f"depth uncertainties (median {med * 1e3:.3g} um), the beta table read with the "
             f"same weights; extra force scatter sigma0 = "
             f"{sigma0 * 1e3:.3g} mN"
             + (" (the depth uncertainties explain the scatter)" if sigma0 == 0 and w.size > 2
                else "")]
    if reach_note:
        notes.append(reach_note)
    fit = material_fit(c, s, cov, depth_mm=w if w_table is None else w_table, thickness_mm=h,
                       radius_mm=a, a_over_h=ah, beta_table=beta_table, contact=contact,
                       kappa_source=kappa_source, confidence=confidence, dof=w.size - 2,
                       rmse_n=rmse, r_squared=r2, effects=FIT_EFFECTS, effect_params=None,
                       a_over_h_given=a_over_h_given, extra_notes=tuple(notes),
                       ci_method=_EV_CI_METHOD, weights=weights)
    fit = dataclasses.replace(fit, depth_std_used=True, depth_std_median_mm=med,
                              sigma0_n=sigma0)
    pred = w * (c + s * x)
    # no Birge ratio: the depth uncertainties are only part of the stated noise (the F/T
    # window's is not given here), and sigma0 carries the rest
    # where the indenters' presses share a stated depth error, the misfit is read on the
    # indenters' means (assess_misfit's group)
    group = None
    if shared is not None and np.any(shared[1] > 0):
        group = shared[0]
    return carry_misfit(fit, w, P, pred, group=group)


def _indenter_shared(indenter: object, depth_indenter_std_mm: object, u: np.ndarray | None,
                     n: int) -> tuple[np.ndarray, np.ndarray] | None:
    """:func:`fit_indentation`'s `indenter` and `depth_indenter_std_mm` checked, or None.

    Raises
    ------
    InputError
        Where one is given without the other or without ``depth_std_mm``, or a shared
        part is negative or exceeds its press's ``depth_std_mm``.
    ShapeError
        For a wrong shape, NaN or inf.
    """
    if indenter is None and depth_indenter_std_mm is None:
        return None
    if indenter is None or depth_indenter_std_mm is None or u is None:
        raise InputError("indenter and depth_indenter_std_mm go together, and with "
                         "depth_std_mm")
    g = check_array(indenter, "indenter", [(n,)], finite=True)
    ui = check_array(depth_indenter_std_mm, "depth_indenter_std_mm", [(n,)],
                     dtype=np.number, finite=True).astype(np.float64)
    bad = (ui < 0) | (ui > u * (1 + 1e-9) + 1e-15)
    if np.any(bad):
        i = int(np.argmax(bad))
        raise InputError(f"depth_indenter_std_mm[{i}] = {ui[i]:g} mm: the shared part must "
                         f"lie in [0, depth_std_mm[{i}] = {u[i]:g}]")
    return g, ui


def _geometry(w: np.ndarray, h: float, a: float, beta_table: str, a_over_h: float | None,
              contact: str) -> tuple[float, str, str]:
    """Check a/h and the table's range; return (a/h used, kappa source, contact)."""
    if beta_table not in ("paper", "fem"):
        raise InputError(f"beta_table must be 'paper' or 'fem', got {beta_table!r}")
    kappa_source = "fem" if beta_table == "fem" else "hayes"
    if beta_table == "paper":
        contact = "frictionless"  # relation (7) and Hayes: the paper's frictionless punch
    ah_exact = a / h
    ktab = _kappa_table(kappa_source, contact)
    lo, hi = float(ktab.a_over_h[0]), float(ktab.a_over_h[-1])
    kname = "FEM" if kappa_source == "fem" else "Hayes 1972"
    if a_over_h is None:
        ah = ah_exact
        if not lo <= ah <= hi:
            raise InputError(f"radius_mm / thickness_mm = {ah:g} is outside the {kname} "
                             f"kappa table range [{lo:g}, {hi:g}]")
    else:
        ah = float(a_over_h)
        if not lo <= ah <= hi:
            raise InputError(f"a_over_h = {ah:g} is outside the {kname} kappa table "
                             f"range [{lo:g}, {hi:g}]")
    top = MAX_W_OVER_H * TABLE_EXTRAPOLATION
    if beta_table == "fem" and float(np.max(w / h)) > top + 1e-12:
        raise InputError(f"a press reaches w/h = {float(np.max(w / h)):.3f}, beyond the FEM beta "
                         f"table's w/h <= {top:g} (computed to {MAX_W_OVER_H:g}, read "
                         f"{100 * (TABLE_EXTRAPOLATION - 1):.0f}% beyond): drop the deeper "
                         "presses or use beta_table='paper'")
    return ah, kappa_source, contact


def material_fit(c: float, slope: float, cov: np.ndarray, *, depth_mm: np.ndarray,
                 thickness_mm: float, radius_mm: float, a_over_h: float, beta_table: str,
                 contact: str, kappa_source: str, confidence: float, dof: int, rmse_n: float,
                 r_squared: float, effects: tuple[str, ...],
                 effect_params: dict[str, float] | None, a_over_h_given: bool,
                 extra_notes: tuple[str, ...] = (), ci_method: str = _CI_METHOD,
                 weights: np.ndarray | None = None) -> IndentationFit:
    """E and nu from the intercept c and slope c beta of eq. (5), with intervals.

    The second half of :func:`fit_indentation`, shared with models of
    effects (:func:`fit_model`): nu from the beta table, E from eq. (4),
    intervals by the delta method through `cov`.

    Parameters
    ----------
    c, slope : float
        Intercept c (N/mm) and slope c beta (N/mm) of P/w against w/h.
    cov : (2, 2) float ndarray
        Their covariance.
    depth_mm : (N,) float ndarray
        The depths (the FEM beta table is read at these w/h).
    thickness_mm, radius_mm, a_over_h : float
    beta_table, contact, kappa_source : str
    confidence : float
    dof : int
        Residual degrees of freedom of the Student t quantile.
    rmse_n, r_squared : float
    effects : tuple of str
    effect_params : dict or None
        Default ``{'beta': beta}``.
    a_over_h_given : bool
        Whether the caller chose a/h (for the notes).
    extra_notes : tuple of str
    ci_method : str
    weights : (N,) float ndarray, optional
        Each press's weight in the line of eq. (5) (``'fem'``: the beta table
        is read with them). Default: equal weights.

    Returns
    -------
    IndentationFit
    """
    w, h, a, ah = depth_mm, thickness_mm, radius_mm, a_over_h
    ah_exact = a / h
    s = slope
    # the FEM beta read at these very depths (eq. 5 fitted to the FEM's P/w there)
    fem = beta_table == "fem"
    rel = beta_relation(beta_table, a_over_h=ah, contact=contact,
                        w_over_h=tuple(np.round(w / h, 12)) if fem else None,
                        weights=tuple(weights) if fem and weights is not None else None)
    notes: list[str] = []
    n = w.size
    tq = _t_quantile(0.5 + confidence / 2, dof) if dof > 0 else math.nan
    beta = s / c if c != 0 else math.nan
    beta_se, beta_ci = (_interval(beta, np.array([-s / c**2, 1 / c]), cov, tq) if c
                        else (math.nan, _NAN2))
    m = _moduli(rel, c, s, cov, beta, beta_se, tq, a=a, ah=ah, kappa_source=kappa_source,
                contact=contact, confidence=confidence, beta_table=beta_table, notes=notes)
    _table_notes(notes, rel, a=a, h=h, ah=ah, beta_table=beta_table, contact=contact,
                 kappa_source=kappa_source, a_over_h_given=a_over_h_given,
                 extra_notes=extra_notes, ci_method=ci_method)
    wh = float(np.max(w)) / h
    if wh > MAX_W_OVER_H + 1e-12:
        text = (f"deepest press has w/h = {wh:.3f} > {MAX_W_OVER_H}: the linear law (2) "
                "may fail there (paper, section VI.1)")
        warnings.warn(text, UserWarning, stacklevel=2)
        notes.append(text)
    cs = float(np.sqrt(cov[0, 0])), float(np.sqrt(cov[1, 1]))
    return IndentationFit(
        E_mpa=m.E, nu=m.nu, c_n_per_mm=c, beta=beta, E_ci95_mpa=m.E_ci, nu_ci95=m.nu_ci,
        rmse_n=rmse_n, n_presses=n, effects=tuple(effects),
        effect_params=dict(effect_params) if effect_params is not None else {"beta": beta},
        C10_mpa=m.C10, D1_per_mpa=m.D1, a_over_h=ah, a_over_h_exact=ah_exact,
        thickness_mm=h, radius_mm=a, kappa=m.kap, beta_table=beta_table,
        kappa_source=kappa_source, contact=contact, slope_n_per_mm=s,
        c_se_n_per_mm=cs[0], slope_se_n_per_mm=cs[1],
        corr_c_slope=float(cov[0, 1] / (cs[0] * cs[1])) if cs[0] * cs[1] > 0 else math.nan,
        beta_se=beta_se, beta_ci95=beta_ci, nu_se=m.nu_se, E_se_mpa=m.E_se, r_squared=r_squared,
        confidence=confidence, ci_method=ci_method, max_w_over_h=wh,
        out_of_table=m.msg is not None, out_of_table_message=m.msg, notes=tuple(notes),
        nu_bound=m.bound,
    )


@lru_cache(maxsize=256)
def _t_quantile(q: float, dof: int) -> float:
    """Student's t quantile, ``scipy.stats.t.ppf(q, dof)``, once per (q, dof): a fit reads
    one, and scipy's distribution machinery took 0.6 ms of a 17 ms fit."""
    return float(stats.t.ppf(q, dof))


def _interval(est: float, grad: np.ndarray, cov: np.ndarray, tq: float
              ) -> tuple[float, tuple[float, float]]:
    """Standard error and interval of `est` by the delta method (gradient `grad`)."""
    se = float(np.sqrt(grad @ cov @ grad))
    return se, (est - tq * se, est + tq * se)


@dataclasses.dataclass
class _Moduli:
    """E and nu (with C10, D1, kappa and intervals) of :func:`material_fit`; `msg`: why not."""

    E: float = math.nan
    nu: float = math.nan
    C10: float = math.nan
    D1: float = math.nan
    kap: float = math.nan
    nu_se: float = math.nan
    E_se: float = math.nan
    E_ci: tuple[float, float] = _NAN2
    nu_ci: tuple[float, float] = _NAN2
    msg: str | None = None
    bound: str | None = None


def _moduli(rel, c: float, s: float, cov: np.ndarray, beta: float, beta_se: float, tq: float,
            *, a: float, ah: float, kappa_source: str, contact: str, confidence: float,
            beta_table: str, notes: list[str]) -> _Moduli:
    """nu from the beta table, E from eq. (4), with intervals (at the table's edge too)."""
    m = _Moduli()
    top = _table_top(rel, c, beta, beta_se, tq)
    bottom = _table_bottom(rel, c, beta, beta_se, tq)
    if top is not None or bottom is not None:
        # beta beyond the table's peak (or below its smallest beta) but within its interval:
        # nu at that edge, its interval from the part of the table that the interval reaches
        at_edge = _at_table_top if top is not None else _at_table_bottom
        if top is not None and getattr(rel, "beta_grid", None) is None:
            at_edge = _at_relation_top
        m.nu, m.nu_ci, m.E, m.E_ci, m.kap, edge_note = at_edge(
            rel, top if top is not None else bottom, c, cov, tq, a, ah, kappa_source, contact,
            confidence)
        m.C10, m.D1 = neo_hookean_constants(m.E, m.nu)
        m.nu_se, m.E_se = (m.nu_ci[1] - m.nu_ci[0]) / (2 * tq), (m.E_ci[1] - m.E_ci[0]) / (2 * tq)
        # nu put at the table's edge: what the presses say is a bound, not a value
        m.bound = (f"nu >= {m.nu_ci[0]:.4g}" if top is not None else f"nu <= {m.nu_ci[1]:.4g}")
        notes.append(edge_note)
    elif not (c > 0 and rel.beta_min <= beta < rel.beta_max):
        m.msg = (f"c = {c:.4g} N/mm and beta = {beta:.4g} are outside the {beta_table} beta "
                 f"table (c > 0, {rel.range_text()}): E and nu not computed")
        notes.append(m.msg)
    else:
        _in_table(m, rel, c, s, cov, beta, beta_se, tq, a=a, ah=ah, kappa_source=kappa_source,
                  contact=contact, confidence=confidence, notes=notes)
    return m


def _in_table(m: _Moduli, rel, c: float, s: float, cov: np.ndarray, beta: float,
              beta_se: float, tq: float, *, a: float, ah: float, kappa_source: str, contact: str,
              confidence: float, notes: list[str]) -> None:
    """Fill `m` for a beta within the table: the delta method, or beta's interval inverted
    through the table where it reaches the table's peak."""
    nu = float(rel.nu(beta))  # eq. (7) or the FEM table, inverted
    line = getattr(rel, "kappa_line_grid", None) is not None
    if line:  # the FEM line at these depths: its intercept, like its beta
        kap, dkap = rel.kappa_line(nu), rel.dkappa_line_dnu(nu)
    else:
        kap = float(kappa(nu, ah, source=kappa_source, contact=contact))
        dkap = _dkappa_dnu(nu, ah, source=kappa_source, contact=contact)
    E = c * (1 - nu**2) / (2 * a * kap)  # eq. (4)
    m.E, m.nu, m.kap = E, nu, kap
    m.C10, m.D1 = neo_hookean_constants(E, nu)
    g_nu = rel.dnu_dbeta(beta) * np.array([-s / c**2, 1 / c])  # d nu / d(c, s)
    dlnE_dnu = (-2 * nu / (1 - nu**2)
                - dkap / kap)
    m.nu_se, m.nu_ci = _interval(nu, g_nu, cov, tq)
    m.E_se, m.E_ci = _interval(E, E * (np.array([1 / c, 0.0]) + dlnE_dnu * g_nu), cov, tq)
    grid = getattr(rel, "beta_grid", None) is not None
    if (not grid and np.isfinite(beta_se) and beta - tq * beta_se >= rel.beta_min
            and (beta + tq * beta_se >= rel.beta_max or m.nu_ci[1] >= rel.nu_max)):
        # beta's interval (or nu's, by the delta method) reaches the relation's top, nu =
        # 0.5, past which no solid lies: the delta method's nu interval ran past 0.5 (a
        # Taxim mark session read nu [0.46, 0.52]) and E's, symmetric, over gels that
        # cannot be. The fit's confidence region projected instead, the gels past the top
        # put at it
        got = _over_ellipse(rel, c, s, cov, tq, a=a, ah=ah, kappa_source=kappa_source,
                            contact=contact)
        if got is not None:
            m.nu_ci = (min(got[0][0], nu), max(got[0][1], nu))
            m.E_ci = (min(got[1][0], E), max(got[1][1], E))
            m.nu_se, m.E_se = ((m.nu_ci[1] - m.nu_ci[0]) / (2 * tq),
                               (m.E_ci[1] - m.E_ci[0]) / (2 * tq))
            # an interval that reaches the relation's end: a bound, not a value (issue 82)
            m.bound = f"nu >= {m.nu_ci[0]:.4g}"
            notes.append(f"the {confidence:.0%} interval of beta or nu reaches the relation's top "
                         f"({rel.beta_max:.4f}, nu = {rel.nu_max:.2f}, an incompressible "
                         "gel): the intervals of nu and E are the fit's confidence region "
                         "of (c, c beta) projected through the relation and eq. (4), the "
                         f"gels past its top put at nu = {rel.nu_max:.2f}, not the delta "
                         "method")
            return
    if not grid and m.nu_ci[1] > rel.nu_max:
        # the region reaches below the relation too (no E there to project): no solid lies
        # past nu = 0.5 whatever the rest
        m.nu_ci = (m.nu_ci[0], float(rel.nu_max))
    if (grid and np.isfinite(beta_se) and beta + tq * beta_se >= rel.beta_max):
        # beta's interval reaches the table's peak, where d nu / d beta -> infinity and
        # the delta method fails: invert beta's interval through the table instead
        _, nu_ci, _, E_ci, _, _ = _at_table_top(rel, beta - tq * beta_se, c, cov, tq, a, ah,
                                                kappa_source, contact, confidence)
        m.nu_ci = (nu_ci[0], max(nu_ci[1], nu))
        m.E_ci = (min(E_ci[0], E), max(E_ci[1], E))
        m.nu_se, m.E_se = (m.nu_ci[1] - m.nu_ci[0]) / (2 * tq), (m.E_ci[1] - m.E_ci[0]) / (2 * tq)
        notes.append(f"the {confidence:.0%} interval of beta reaches the top of the table "
                     f"({rel.beta_max:.4f}, where beta peaks over nu): the intervals of nu "
                     "and E are beta's interval inverted through the table, not the delta "
                     "method")
    elif np.all(np.isfinite(m.nu_ci)) and not (rel.nu_min <= m.nu_ci[0]
                                                and m.nu_ci[1] < rel.nu_max):
        notes.append(f"the {confidence:.0%} interval of nu, [{m.nu_ci[0]:.4f}, "
                     f"{m.nu_ci[1]:.4f}], reaches outside the beta table "
                     f"({rel.range_text()})")


#: Points on the boundary of the confidence region :func:`_over_ellipse` reads.
_ELLIPSE_POINTS = 361
#: The nu at which :func:`_over_ellipse` reads the kappa table (then interpolates).
_ELLIPSE_NU_GRID = 9


def _over_ellipse(rel, c: float, s: float, cov: np.ndarray, tq: float, *, a: float,
                  ah: float, kappa_source: str, contact: str
                  ) -> tuple[tuple[float, float], tuple[float, float]] | None:
    """nu's and E's intervals over the fit's confidence region of (c, c beta).

    The region is the ellipse ``(x - x_hat)^T cov^-1 (x - x_hat) <= tq^2`` (one
    parameter's Student t quantile: for a quantity linear in c and c beta the
    projection is the delta method's interval exactly). nu rises with beta and E with c
    at a fixed beta (eq. 4, relation 7), so neither has an extreme inside the region and
    both are read on its boundary; a
    point whose beta lies past the relation's top is a gel at the top (nu = ``nu_max``,
    E of eq. 4 there), as a fitted beta past it is (:func:`_at_relation_top`).

    Returns
    -------
    (nu_lo, nu_hi), (E_lo, E_hi) : tuple of two (float, float), or None
        None where the covariance is not positive definite or the region reaches c <= 0
        or below the relation's smallest beta.
    """
    try:
        low = np.linalg.cholesky(np.asarray(cov, np.float64))
    except np.linalg.LinAlgError:
        return None
    phi = np.linspace(0.0, 2 * np.pi, _ELLIPSE_POINTS)
    pts = np.array([c, s])[:, None] + tq * low @ np.vstack([np.cos(phi), np.sin(phi)])
    cc, ss = pts
    if not np.all(cc > 0):
        return None
    beta = ss / cc
    if np.any(beta < rel.beta_min):
        return None
    nus = np.minimum(np.asarray(rel.nu(np.minimum(beta, rel.beta_max)), np.float64),
                     rel.nu_max)
    if getattr(rel, "kappa_line_grid", None) is not None:
        Es = np.array([_modulus(rel, ci, ni, a, ah, kappa_source, contact)[0]
                       for ci, ni in zip(cc, nus, strict=True)])
    else:
        # eq. (4) through kappa read on a grid of nu (one table interpolant per nu read:
        # 361 cost 0.1 s a fit), then exactly at the two extremes the grid finds
        grid = np.linspace(float(nus.min()), float(nus.max()), _ELLIPSE_NU_GRID)
        k = np.asarray(kappa(grid, ah, source=kappa_source, contact=contact), np.float64)
        k_at = PchipInterpolator(grid, k)(nus) if np.ptp(grid) > 0 else np.full_like(nus, k[0])
        Es = cc * (1 - nus ** 2) / (2 * a * k_at)
        for i in (int(np.argmin(Es)), int(np.argmax(Es))):
            Es[i] = _modulus(rel, float(cc[i]), float(nus[i]), a, ah, kappa_source, contact)[0]
    return (float(nus.min()), float(nus.max())), (float(Es.min()), float(Es.max()))


def _table_notes(notes: list[str], rel, *, a: float, h: float, ah: float, beta_table: str,
                 contact: str, kappa_source: str, a_over_h_given: bool,
                 extra_notes: tuple[str, ...], ci_method: str) -> None:
    """The notes on the intervals, the tables and the a/h they were read at."""
    notes.append(f"intervals: {ci_method}; the kappa and beta tables are taken as exact")
    notes.extend(extra_notes)
    notes.append(f"beta table '{beta_table}': {rel.source}; kappa: "
                 f"{'FEM, ' + contact + ' punch' if kappa_source == 'fem' else 'Hayes 1972'}")
    if abs(ah - rel.a_over_h) > 1e-6:
        notes.append(f"relation (7) was built for a/h = {rel.a_over_h:g} and is used here at "
                     f"a/h = {ah:.4f}")
    if not a_over_h_given:
        notes.append(f"kappa read at the exact a/h = {a:g}/{h:g} = {ah:.4f}; the paper rounds "
                     "to 0.8 (a_over_h=0.8 reproduces it)")
    else:
        notes.append(f"kappa read at a/h = {ah:g} as given (exact a/h = {a / h:.4f})")


def _table_top(rel, c: float, beta: float, beta_se: float, tq: float) -> float | None:
    """The lower end of beta's interval when beta lies above a tabulated relation's peak
    (or above the paper's relation (7) at its top, nu = 0.5) but its interval reaches back
    into the table; else None."""
    if not (c > 0 and np.isfinite(beta_se) and np.isfinite(tq)):
        return None
    lo = beta - tq * beta_se
    if beta >= rel.beta_max and lo < rel.beta_max:
        return float(lo)
    return None


def _table_bottom(rel, c: float, beta: float, beta_se: float, tq: float) -> float | None:
    """The upper end of beta's interval when beta lies below a tabulated relation's
    smallest beta (:attr:`beta_min`, at the start of its rising branch) but its interval
    reaches up into the table; else None.

    The paper's relation (7) has no grid: None (its lower end, nu = 0.30, is where the
    Hayes kappa table that E needs starts, not a flat stretch of beta(nu)).
    """
    grid = getattr(rel, "beta_grid", None)
    if grid is None or not (c > 0 and np.isfinite(beta_se) and np.isfinite(tq)):
        return None
    hi = beta + tq * beta_se
    if beta < rel.beta_min <= hi:
        return float(hi)
    return None


def nu_range_reaching(beta_of_nu, nu_first: float, nu_last: float, nu_peak: float,
                      beta_lo: float) -> tuple[float, float]:
    """The nu whose beta reaches `beta_lo`, between `nu_first` and `nu_last`: from the
    first on the rising branch to the last on the falling one (`nu_peak` when none does),
    on a grid of 2001."""
    fine = np.linspace(nu_first, nu_last, 2001)
    ok = np.asarray(beta_of_nu(fine)) >= beta_lo
    if not ok.any():
        return nu_peak, nu_peak
    return float(fine[np.argmax(ok)]), float(fine[len(ok) - 1 - np.argmax(ok[::-1])])


def nu_range_below(beta_of_nu, nu_first: float, nu_last: float, nu_bottom: float,
                   beta_hi: float) -> tuple[float, float]:
    """The nu whose beta is at most `beta_hi`, between `nu_first` and `nu_last`.

    The mirror of :func:`nu_range_reaching` at the bottom of a table.

    Parameters
    ----------
    beta_of_nu : callable
        beta(nu), vectorised.
    nu_first, nu_last : float
        The range of nu searched (the whole table).
    nu_bottom : float
        nu of the table's smallest beta (where nu is reported); always inside the range
        returned.
    beta_hi : float
        The upper bound of beta's interval.

    Returns
    -------
    nu_lo, nu_hi : float
        The smallest and the largest nu, on a grid of 2001 plus `nu_bottom`, whose beta is
        at most `beta_hi`: their hull, which holds every nu of the table that beta's
        interval reaches (at low nu a FEM beta can dip before it rises, and past its peak it
        falls again).
    """
    fine = np.union1d(np.linspace(nu_first, nu_last, 2001), [nu_bottom])
    ok = np.asarray(beta_of_nu(fine)) <= beta_hi
    if not ok.any():
        return nu_bottom, nu_bottom
    lo, hi = float(fine[np.argmax(ok)]), float(fine[len(ok) - 1 - np.argmax(ok[::-1])])
    return min(lo, nu_bottom), max(hi, nu_bottom)


def _modulus(rel, c: float, nu: float, a: float, ah: float, kappa_source: str,
             contact: str) -> tuple[float, float]:
    """E of eq. (4) at intercept `c` and `nu`, and the kappa it used.

    kappa is the FEM kappa_n line's intercept at the fitted depths where the relation
    holds it (as for beta), else the kappa table.
    """
    if getattr(rel, "kappa_line_grid", None) is not None:
        k = rel.kappa_line(nu)
    else:
        k = float(kappa(nu, ah, source=kappa_source, contact=contact))
    return c * (1 - nu ** 2) / (2 * a * k), k


def _modulus_over(rel, c: float, cov: np.ndarray, tq: float, nu: float, nus: tuple[float, ...],
                  a: float, ah: float, kappa_source: str, contact: str
                  ) -> tuple[float, tuple[float, float], float]:
    """E at (c, nu), its interval over `nus` with c at its own bounds, and kappa at nu:
    the modulus of a fit whose nu is put at an edge of the beta table."""
    E, kap = _modulus(rel, c, nu, a, ah, kappa_source, contact)
    c_se = float(np.sqrt(cov[0, 0]))
    Es = [_modulus(rel, cc, nn, a, ah, kappa_source, contact)[0]
          for cc in (c - tq * c_se, c + tq * c_se) for nn in nus]
    return E, (float(min(Es)), float(max(Es))), kap


#: What a beta beyond the table's top may also mean, said with E and nu put at that top.
_BEYOND_TABLE = (". A beta beyond the table also follows from deep presses stiffer for a "
                 "reason the model lacks (a stiffness gradient across the pad that the deep "
                 "presses sample, a force offset): E and its interval hold only if the model "
                 "is complete (diagnose)")


def _at_table_top(rel, beta_lo: float, c: float, cov: np.ndarray, tq: float, a: float,
                  ah: float, kappa_source: str, contact: str, confidence: float):
    """nu, its interval, E, its interval and kappa for beta at the top of the FEM table.

    Near its peak the FEM's beta(nu) is flat (a bonded punch at a/h ~ 0.8
    peaks near nu = 0.485 and falls beyond): a beta a little above the peak
    is the peak within the scatter. nu is put at the peak; its interval runs
    from the nu of beta's lower bound on the rising branch to the largest
    tabulated nu whose beta still reaches that bound (on the falling branch);
    E at the peak, its interval E over that range of nu with c at its own
    bounds.
    """
    first, last = rel.branch
    nu_peak = float(rel.nu_grid[last])
    nu_lo, nu_hi = nu_range_reaching(rel.beta, float(rel.nu_grid[first]),
                                     float(rel.nu_grid[-1]), nu_peak, beta_lo)
    E, E_ci, kap = _modulus_over(rel, c, cov, tq, nu_peak, (nu_lo, nu_hi), a, ah, kappa_source,
                                 contact)
    note = (f"beta lies above the largest beta of the table ({rel.beta_max:.4f}, at nu = "
            f"{nu_peak:.3f}) but within its {confidence:.0%} interval (lower bound "
            f"{beta_lo:.4f}): nu is put at the table's top, {nu_peak:.3f}, with the interval "
            f"[{nu_lo:.4f}, {nu_hi:.4f}] of the nu whose beta reaches that bound; E at "
            f"nu = {nu_peak:.3f}, its interval over that range" + _BEYOND_TABLE)
    return nu_peak, (nu_lo, nu_hi), E, E_ci, kap, note


def _at_relation_top(rel, beta_lo: float, c: float, cov: np.ndarray, tq: float, a: float,
                     ah: float, kappa_source: str, contact: str, confidence: float):
    """nu, its interval, E, its interval and kappa for beta above the paper's relation (7).

    Relation (7), nu = 0.0813 ln(beta) + 0.4464, reaches nu = 0.5 (an
    incompressible gel) at its largest beta: a beta above it whose interval
    reaches back below it is a gel at or near nu = 0.5 within the scatter. nu is
    put at the relation's top, 0.5; its interval runs from the nu of beta's
    lower bound to 0.5; E at nu = 0.5, its interval E over that range of nu
    with c at its own bounds (eq. 4 with Hayes' kappa, which reaches nu = 0.5).
    """
    nu_top = float(rel.nu_max)
    nu_lo = max(float(rel.nu_min), float(rel.nu(beta_lo)))
    E, E_ci, kap = _modulus_over(rel, c, cov, tq, nu_top, (nu_lo, nu_top), a, ah, kappa_source,
                                 contact)
    note = (f"beta lies above the relation's largest beta ({rel.beta_max:.4f}, nu = "
            f"{nu_top:.2f}) but within its {confidence:.0%} interval (lower bound "
            f"{beta_lo:.4f}): nu is put at the relation's top, {nu_top:.2f} (an "
            f"incompressible gel), with the interval [{nu_lo:.4f}, {nu_top:.2f}]; E at "
            f"nu = {nu_top:.2f}, its interval over that range" + _BEYOND_TABLE)
    return nu_top, (nu_lo, nu_top), E, E_ci, kap, note


def _at_table_bottom(rel, beta_hi: float, c: float, cov: np.ndarray, tq: float, a: float,
                     ah: float, kappa_source: str, contact: str, confidence: float):
    """nu, its interval, E, its interval and kappa for beta at the bottom of the FEM table.

    The mirror of :func:`_at_table_top`. Where the rising branch of the FEM's
    beta(nu) starts (a bonded punch at a/h ~ 0.8: nu = 0.36, after a shallow
    dip from nu = 0.30) beta is flat: a beta a little below the table's
    smallest is that smallest within the scatter. nu is put there; its
    interval is the hull of the tabulated nu whose beta is at most the upper
    bound `beta_hi` of beta's interval (the dip below the branch and, for a
    wide interval, the falling branch past the peak included); E at that nu,
    its interval E over that range of nu with c at its own bounds.

    Returns
    -------
    nu : float
    nu_ci : (2,) tuple of float
    E : float, MPa
    E_ci : (2,) tuple of float, MPa
    kappa : float
    note : str
    """
    nu_bottom = float(rel.nu_min)
    nu_lo, nu_hi = nu_range_below(rel.beta, float(rel.nu_grid[0]), float(rel.nu_grid[-1]),
                                  nu_bottom, beta_hi)
    E, E_ci, kap = _modulus_over(rel, c, cov, tq, nu_bottom, (nu_lo, nu_bottom, nu_hi), a, ah,
                                 kappa_source, contact)
    note = (f"beta lies below the smallest beta of the table ({rel.beta_min:.4f}, at nu = "
            f"{nu_bottom:.3f}) but within its {confidence:.0%} interval (upper bound "
            f"{beta_hi:.4f}): nu is put at the table's bottom, {nu_bottom:.3f}, with the "
            f"interval [{nu_lo:.4f}, {nu_hi:.4f}] of the nu whose beta is at most that bound; "
            f"E at nu = {nu_bottom:.3f}, its interval over that range")
    return nu_bottom, (nu_lo, nu_hi), E, E_ci, kap, note
