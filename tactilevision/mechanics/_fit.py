"""The paper's in-situ fit: presses (w, P) -> c, beta -> nu, E (eq. 4-7)."""

from __future__ import annotations

import math
import warnings

import numpy as np
from scipy import stats

from .._checks import InputError, check_array
from ._beta import beta_relation
from ._effects import FIT_EFFECTS
from ._kappa import _dkappa_dnu, kappa
from ._kappa import _table as _kappa_table
from ._neohookean import neo_hookean_constants
from ._result import IndentationFit

__all__ = ["MAX_W_OVER_H", "fit_indentation"]

#: Largest w/h for which the linear law (2) holds (paper, section VI.1).
MAX_W_OVER_H = 0.2

_NAN2 = (math.nan, math.nan)
_CI_METHOD = ("delta method through the HC3 (heteroscedasticity-consistent) covariance of "
              "slope and intercept, Student t with n - 2 degrees of freedom")


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
                    confidence: float = 0.95) -> IndentationFit:
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

    Returns
    -------
    fit : IndentationFit

    Raises
    ------
    ShapeError
        When `depth_mm` or `force_n` is not 1-D, not numeric, not finite, or
        their lengths differ.
    InputError
        When a depth is not positive, fewer than two depths are distinct,
        `thickness_mm` or `radius_mm` is not positive, a/h is outside the
        kappa table [0.2, 2.0], the FEM table is missing, or it has no
        `contact` punch, or its beta does not increase with nu at this a/h
        (a bonded punch at a/h <~ 0.6: nu cannot be told from beta there).
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

    Intervals: delta method (first-order propagation) of the covariance of
    intercept and slope through beta, nu and E, with a Student t quantile on
    ``n - 2`` degrees of freedom. The covariance is the HC3
    heteroscedasticity-consistent estimate (MacKinnon and White 1985) because
    a constant force noise makes the noise of P/w grow as 1/w; the classical
    OLS covariance then covers nu only about 85% of the time at the nominal
    95% (tests/test_mechanics_fit.py measures the coverage). The kappa and
    beta tables are taken as exact: the intervals hold only the press scatter.

    References
    ----------
    .. [1] "In-situ Mechanical Calibration for Vision-based Tactile Sensors",
       eq. (4)-(7) and section IV.
    .. [2] W. C. Hayes et al., J. Biomech. 5:541-551, 1972.
       doi:10.1016/0021-9290(72)90010-3
    .. [3] J. G. MacKinnon, H. White, "Some heteroskedasticity-consistent
       covariance matrix estimators with improved finite sample properties",
       J. Econometrics 29:305-325, 1985. doi:10.1016/0304-4076(85)90158-7

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
        raise ValueError(f"confidence must be in (0, 1), got {confidence!r}")
    if np.any(w <= 0):
        i = int(np.argmax(w <= 0))
        raise InputError(f"depth_mm[{i}] = {w[i]:g} mm: depths must be positive")
    depths = np.unique(w)
    if depths.size < 2:
        raise InputError(f"depth_mm holds {depths.size} distinct depth(s); the fit of "
                         "eq. (5) needs presses at two depths or more")
    ah, kappa_source, contact = _geometry(w, h, a, beta_table, a_over_h, contact)

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
    return material_fit(c, s, cov, depth_mm=w, thickness_mm=h, radius_mm=a, a_over_h=ah,
                        beta_table=beta_table, contact=contact, kappa_source=kappa_source,
                        confidence=confidence, dof=w.size - 2, rmse_n=rmse, r_squared=r2,
                        effects=FIT_EFFECTS, effect_params=None,
                        a_over_h_given=a_over_h is not None,
                        extra_notes=(cov_note,) if cov_note else (), ci_method=_CI_METHOD)


def _geometry(w: np.ndarray, h: float, a: float, beta_table: str, a_over_h: float | None,
              contact: str) -> tuple[float, str, str]:
    """Check a/h and the table's range; return (a/h used, kappa source, contact)."""
    if beta_table not in ("paper", "fem"):
        raise ValueError(f"beta_table must be 'paper' or 'fem', got {beta_table!r}")
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
    if beta_table == "fem" and float(np.max(w / h)) > MAX_W_OVER_H + 1e-12:
        raise InputError(f"a press reaches w/h = {float(np.max(w / h)):.3f}, beyond the FEM beta "
                         f"table's w/h <= {MAX_W_OVER_H:g}: drop the deeper presses or use "
                         "beta_table='paper'")
    return ah, kappa_source, contact


def material_fit(c: float, slope: float, cov: np.ndarray, *, depth_mm: np.ndarray,
                 thickness_mm: float, radius_mm: float, a_over_h: float, beta_table: str,
                 contact: str, kappa_source: str, confidence: float, dof: int, rmse_n: float,
                 r_squared: float, effects: tuple[str, ...],
                 effect_params: dict[str, float] | None, a_over_h_given: bool,
                 extra_notes: tuple[str, ...] = (), ci_method: str = _CI_METHOD
                 ) -> IndentationFit:
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

    Returns
    -------
    IndentationFit
    """
    w, h, a, ah = depth_mm, thickness_mm, radius_mm, a_over_h
    ah_exact = a / h
    s = slope
    # the FEM beta read at these very depths (eq. 5 fitted to the FEM's P/w there)
    rel = beta_relation(beta_table, a_over_h=ah, contact=contact,
                        w_over_h=tuple(np.round(w / h, 12)) if beta_table == "fem" else None)
    notes: list[str] = []
    n = w.size
    tq = float(stats.t.ppf(0.5 + confidence / 2, dof)) if dof > 0 else math.nan
    beta = s / c if c != 0 else math.nan

    def interval(est: float, grad: np.ndarray) -> tuple[float, tuple[float, float]]:
        se = float(np.sqrt(grad @ cov @ grad))
        return se, (est - tq * se, est + tq * se)

    beta_se, beta_ci = interval(beta, np.array([-s / c**2, 1 / c])) if c else (math.nan, _NAN2)
    E = nu = C10 = D1 = kap = nu_se = E_se = math.nan
    E_ci = nu_ci = _NAN2
    msg = None
    if not (c > 0 and rel.beta_min <= beta < rel.beta_max):
        msg = (f"c = {c:.4g} N/mm and beta = {beta:.4g} are outside the {beta_table} beta "
               f"table (c > 0, {rel.range_text()}): E and nu not computed")
        notes.append(msg)
    else:
        nu = float(rel.nu(beta))  # eq. (7) or the FEM table, inverted
        line = getattr(rel, "kappa_line_grid", None) is not None
        if line:  # the FEM line at these depths: its intercept, like its beta
            kap, dkap = rel.kappa_line(nu), rel.dkappa_line_dnu(nu)
        else:
            kap = float(kappa(nu, ah, source=kappa_source, contact=contact))
            dkap = _dkappa_dnu(nu, ah, source=kappa_source, contact=contact)
        E = c * (1 - nu**2) / (2 * a * kap)  # eq. (4)
        C10, D1 = neo_hookean_constants(E, nu)
        g_nu = rel.dnu_dbeta(beta) * np.array([-s / c**2, 1 / c])  # d nu / d(c, s)
        dlnE_dnu = (-2 * nu / (1 - nu**2)
                    - dkap / kap)
        nu_se, nu_ci = interval(nu, g_nu)
        E_se, E_ci = interval(E, E * (np.array([1 / c, 0.0]) + dlnE_dnu * g_nu))
        if np.all(np.isfinite(nu_ci)) and not (rel.nu_min <= nu_ci[0] and nu_ci[1] < rel.nu_max):
            notes.append(f"the {confidence:.0%} interval of nu, [{nu_ci[0]:.4f}, "
                         f"{nu_ci[1]:.4f}], reaches outside the beta table "
                         f"({rel.range_text()})")

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
        notes.append(f"kappa read at a/h = {ah:g} as given (exact a/h = {ah_exact:.4f})")
    wh = float(np.max(w)) / h
    if wh > MAX_W_OVER_H + 1e-12:
        text = (f"deepest press has w/h = {wh:.3f} > {MAX_W_OVER_H}: the linear law (2) "
                "may fail there (paper, section VI.1)")
        warnings.warn(text, UserWarning, stacklevel=2)
        notes.append(text)
    cs = float(np.sqrt(cov[0, 0])), float(np.sqrt(cov[1, 1]))
    return IndentationFit(
        E_mpa=E, nu=nu, c_n_per_mm=c, beta=beta, E_ci95_mpa=E_ci, nu_ci95=nu_ci,
        rmse_n=rmse_n, n_presses=n, effects=tuple(effects),
        effect_params=dict(effect_params) if effect_params is not None else {"beta": beta},
        C10_mpa=C10, D1_per_mpa=D1, a_over_h=ah, a_over_h_exact=ah_exact,
        thickness_mm=h, radius_mm=a, kappa=kap, beta_table=beta_table,
        kappa_source=kappa_source, contact=contact, slope_n_per_mm=s,
        c_se_n_per_mm=cs[0], slope_se_n_per_mm=cs[1],
        corr_c_slope=float(cov[0, 1] / (cs[0] * cs[1])) if cs[0] * cs[1] > 0 else math.nan,
        beta_se=beta_se, beta_ci95=beta_ci, nu_se=nu_se, E_se_mpa=E_se, r_squared=r_squared,
        confidence=confidence, ci_method=ci_method, max_w_over_h=wh,
        out_of_table=msg is not None, out_of_table_message=msg, notes=tuple(notes),
    )
