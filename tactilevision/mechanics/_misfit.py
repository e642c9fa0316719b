"""What a fit's residuals say beyond its stated noise, carried into its intervals.

A fit's interval holds the truth only where the model explains the data to within
their noise. Three readings of the residuals tell when it does not, and each widens
the intervals by what it shows:

- the **Birge ratio** R_B = sqrt(chi2 / dof) on the *stated* noise (Birge 1932): the
  residuals' size against what the force and depth uncertainties explain. Above 1 by
  more than chance (chi2's upper tail), the scatter the noise does not explain is in
  the intervals (a fit that scales its covariance by its residual variance, or adds an
  extra variance by Paule and Mandel's rule, already carries it: the factor is then
  named, not applied twice);
- the **serial correlation** of the residuals ordered by depth (lag 1; repeats at one
  depth averaged, since they have no order among them): a law that
  cannot follow the curve leaves long runs of one sign, and n such residuals carry the
  information of n (1 - rho) / (1 + rho) independent ones (an AR(1) process; Bayley and
  Hammersley 1946), so the intervals widen by sqrt((1 + rho) / (1 - rho));
- where depths are repeated, the **lack of fit** of the repeats' mean residuals against
  the repeats' own scatter (an F test): significant, the repeats of a depth share its
  misfit, and the intervals widen by Kish's design effect sqrt(1 + (m - 1) icc), m
  presses per depth, icc = (F - 1) / (F - 1 + m) the share of the residual variance
  between depths;
- the **drift** of each press's apparent E over depth (the deepest quarter's mean over
  the shallowest's, tested by the slope of a straight line of apparent E on depth): a
  law that fits gives a flat profile; a drift says the E the fit reports depends on
  which depths were pressed, and E's interval is widened to hold the apparent E of the
  shallowest and of the deepest quarter of the presses.

Where groups of presses share a stated error (an indenter's P(w0) under the mark
rule, whose depths past w0 are read from the force itself), the structure and the
drift are read on the groups' means: what the stated errors make among a group's
presses, side by side along depth, is not a misfit.

The first two are tested at :data:`MISFIT_ALPHA` (1 %), the drift at :data:`DRIFT_ALPHA`
(5 %), or at :data:`DRIFT_LENIENT` (20 %) where it is :data:`DRIFT_LARGE` (5 %) or more;
what is found is named in one warning (the
factor and the drift) that ``fit``, ``calibrate`` and ``diagnose`` print and write.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import special, stats

from .._checks import check_array

__all__ = ["DRIFT_ALPHA", "DRIFT_LARGE", "DRIFT_LENIENT", "DRIFT_MIN", "MISFIT_ALPHA", "Misfit",
           "assess_misfit", "log_interval", "serial_correlation", "widen_interval"]

#: Level of the tests of the residuals' size (chi2's tail) and serial correlation: 1 %.
MISFIT_ALPHA = 0.01
#: Level of the apparent E's drift test: 5 %, since a table of four or five depths gives the
#: slope's t test few degrees of freedom (FEATS' four points drift 21 % at p = 0.015), and a
#: drift missed is an interval too narrow where one found is only an interval wider.
DRIFT_ALPHA = 0.05
#: A drift this large (5 % of E over the depths pressed) is named and held in E's interval
#: at a lenient level (p below :data:`DRIFT_LENIENT`): four presses cannot make a 13 %
#: drift significant at 5 % when it is curved (a contact point 0.05 mm off on the FEATS
#: geometry: p = 0.06 to 0.07), and an E that moves that much with the depths fitted is not
#: one number.
DRIFT_LARGE = 0.05
#: The lenient level of a large drift.
DRIFT_LENIENT = 0.20
#: A drift smaller than this (1 % of E over the depths pressed) is not named however
#: significant: it moves E less than any calibration's interval.
DRIFT_MIN = 0.01
#: Fewest residuals whose lag-1 correlation is read (fewer: not read).
_MIN_CORRELATED = 8


@dataclass(frozen=True)
class Misfit:
    """The misfit of a fit against its stated noise (:func:`assess_misfit`).

    Attributes
    ----------
    birge_ratio : float
        sqrt(chi2 / dof) of the residuals on the stated noise alone; NaN where no
        noise was stated (nothing to compare the residuals with).
    chi2_p : float
        chi2's upper-tail probability on dof degrees of freedom; NaN without noise.
    correlation : float
        Lag-1 correlation of the residuals ordered by depth (the mean residual of
        each depth where presses repeat it); NaN for fewer than 8 depths.
    correlation_p : float
        Its one-sided p (rho sqrt(n) against the standard normal); NaN likewise.
    drift : float
        The apparent E's relative change over the depths pressed: the deepest
        quarter's mean over the shallowest quarter's, less 1 (-0.21: 21 % lower at
        the deepest presses than at the shallowest).
    drift_p : float
        Two-sided p of the slope of a straight line of apparent E on depth
        (Student t, n - 2 degrees of freedom; a drift below :data:`DRIFT_ALPHA`);
        NaN for fewer than three presses.
    E_shallow_mpa, E_deep_mpa : float
        Mean apparent E of the shallowest and of the deepest quarter of the
        presses (at least one each), MPa.
    factor : float
        What the misfit multiplies the residuals' sd by in the intervals (>= 1),
        before the drift's hull: the serial correlation's, times the Birge
        ratio's where the fit had not carried it already.
    carried : bool
        Whether the fit's own covariance already carried the Birge ratio (a
        residual variance or Paule-Mandel extra variance).
    warning : str or None
        One sentence naming what was found, the factor and the drift; None when
        nothing was.
    """

    birge_ratio: float
    chi2_p: float
    correlation: float
    correlation_p: float
    drift: float
    drift_p: float
    E_shallow_mpa: float
    E_deep_mpa: float
    factor: float
    carried: bool
    warning: str | None

    @property
    def drifts(self) -> bool:
        """The apparent E drifts with depth: by :data:`DRIFT_MIN` or more at its slope's p
        below :data:`DRIFT_ALPHA`, or by :data:`DRIFT_LARGE` or more at p below
        :data:`DRIFT_LENIENT`."""
        return _drifts(self.drift, self.drift_p)

    @property
    def beyond_noise(self) -> bool:
        """The residuals exceed the stated noise (chi2's p below :data:`MISFIT_ALPHA`)."""
        return bool(np.isfinite(self.chi2_p) and self.chi2_p < MISFIT_ALPHA)

    def to_json_dict(self) -> dict[str, Any]:
        """JSON-ready dict (NaN as None), with ``drifts`` and ``beyond_noise``."""
        out: dict[str, Any] = {}
        for k in self.__dataclass_fields__:
            v = getattr(self, k)
            out[k] = (None if isinstance(v, float) and not math.isfinite(v) else v)
        out["drifts"], out["beyond_noise"] = self.drifts, self.beyond_noise
        return out


def _drifts(drift: float, p: float) -> bool:
    if not (math.isfinite(p) and math.isfinite(drift)):
        return False
    return ((p < DRIFT_ALPHA and abs(drift) >= DRIFT_MIN)
            or (abs(drift) >= DRIFT_LARGE and p < DRIFT_LENIENT))


def _quarters(depth: np.ndarray, apparent: np.ndarray) -> tuple[float, float]:
    order = np.argsort(depth, kind="stable")
    k = max(1, depth.size // 4)
    return float(np.mean(apparent[order[:k]])), float(np.mean(apparent[order[-k:]]))


def assess_misfit(depth_mm: np.ndarray, residuals_n: np.ndarray, apparent_E_mpa: np.ndarray,
                  *, noise_sd_n: np.ndarray | None = None, n_params: int = 2,
                  carried: bool = True, structure: bool = True,
                  group: np.ndarray | None = None) -> Misfit:
    """Read a fit's residuals against its stated noise, along depth.

    Parameters
    ----------
    depth_mm : (N,) float ndarray
        Depths of the presses, mm (the order the correlation and drift are read in).
    residuals_n : (N,) float ndarray
        Measured less fitted force, N.
    apparent_E_mpa : (N,) float ndarray
        Each press's own E (its force over the law's at E = 1), MPa.
    noise_sd_n : (N,) float ndarray, optional
        The stated standard uncertainty of each residual, N (the force's and the
        depth's through dP/dw), > 0; None where nothing is stated.
    n_params : int, default 2
        Parameters fitted (the residuals' degrees of freedom are N - n_params).
    carried : bool, default True
        Whether the fit's own covariance already carries the residuals' size (a
        residual variance, or Paule and Mandel's extra variance): the Birge ratio is
        then named but not applied.
    structure : bool, default True
        Whether the residuals' structure along depth (serial correlation, lack of fit)
        is read: False where the residuals are against a curve that only stands for the
        law E is read through (eq. 5's line with effects, whose E the FEM's law at these
        depths gives), so that their shape says nothing of E.
    group : (N,) ndarray, optional
        Where groups of presses share a stated error (an indenter's P(w0) under the
        mark rule, whose depths past w0 are read from the force itself): each press's
        group. The structure and the drift are then read on the groups' mean depths,
        residuals and apparent E (the between-groups estimator), so that what the
        stated errors make within and between a group's presses (side by side along
        depth) is not taken for a misfit; the lack of fit is not read (groups are not
        repeats). The Birge ratio stays the presses'.

    Returns
    -------
    Misfit

    Raises
    ------
    ShapeError
        Where `group` is not (N,).
    """
    w = np.asarray(depth_mm, np.float64)
    r = np.asarray(residuals_n, np.float64)
    e = np.asarray(apparent_E_mpa, np.float64)
    n = w.size
    dof = n - n_params
    birge = chi2_p = math.nan
    if noise_sd_n is not None and dof > 0:
        sd = np.asarray(noise_sd_n, np.float64)
        if np.all(np.isfinite(sd) & (sd > 0)):
            chi2 = float(np.sum((r / sd) ** 2))
            birge, chi2_p = math.sqrt(chi2 / dof), float(stats.chi2.sf(chi2, dof))
    # presses at one depth (repeats) have no order among them: their mean residual is read
    ws, rs, es = w, r, e          # what the structure and the drift are read on
    if group is not None:
        g = check_array(group, "group", [(n,)])
        _, gi = np.unique(g, return_inverse=True)
        cnt = np.bincount(gi)
        ws, rs, es = (np.bincount(gi, v) / cnt for v in (w, r, e))
    _, inv = np.unique(np.round(ws, 9), return_inverse=True)
    r_depth = np.bincount(inv, rs) / np.bincount(inv)
    rho, rho_p, f_corr = (serial_correlation(r_depth) if structure
                          else (math.nan, math.nan, 1.0))
    lof_F, lof_p = (_lack_of_fit(inv, rs, n_params) if structure and group is None
                    else (math.nan, 1.0))
    f_lof = 1.0
    if lof_p < MISFIT_ALPHA and lof_F > 1:
        # the repeats of a depth share its misfit: n presses carry the information of
        # n / (1 + (m - 1) icc) (Kish's design effect, m presses per depth, icc the share
        # of the residual variance between depths), the residual-scaled intervals too few
        m = rs.size / (int(inv.max()) + 1)
        icc = (lof_F - 1) / (lof_F - 1 + m)
        f_lof = math.sqrt(1 + (m - 1) * icc)
    drift = drift_p = math.nan
    shallow, deep = _quarters(ws, es)
    if shallow != 0 and math.isfinite(shallow) and math.isfinite(deep):
        drift = deep / shallow - 1.0
    if ws.size >= 3 and np.ptp(ws) > 0 and np.all(np.isfinite(es)):
        slope, stderr, pvalue = _linregress(ws, es)
        if ws.size - n_params > 0 and math.isfinite(stderr) and stderr > 0:
            drift_p = pvalue
        elif slope == 0:
            drift_p = 1.0
        elif math.isfinite(stderr):   # an exact line: the drift is certain
            drift_p = 0.0
    factor = 1.0
    found = []
    if f_corr > 1 or f_lof > 1:
        factor *= max(f_corr, f_lof)
        why = []
        if f_corr > 1:
            why.append(f"the residuals run in long runs along depth (lag-1 correlation "
                       f"{rho:.2f})")
        if f_lof > 1:
            why.append(f"the repeats' mean residuals lie off the law beyond the repeats' own "
                       f"scatter (lack of fit F = {lof_F:.3g}, p = {lof_p:.2g})")
        found.append(" and ".join(why) + f": the intervals widened x{max(f_corr, f_lof):.2g}")
    if math.isfinite(chi2_p) and chi2_p < MISFIT_ALPHA:
        if carried:
            found.append(f"the residuals are {birge:.3g} times the stated noise (Birge ratio, "
                         f"chi2 p = {chi2_p:.2g}): the intervals carry that scatter")
        else:
            factor *= birge
            found.append(f"the residuals are {birge:.3g} times the stated noise (Birge ratio, "
                         f"chi2 p = {chi2_p:.2g}): the intervals widened x{birge:.3g}")
    if _drifts(drift, drift_p):
        found.append(f"the apparent E drifts {100 * drift:+.1f} % over the depths pressed "
                     f"(p = {drift_p:.2g}; {shallow:.4g} MPa at the shallowest presses, "
                     f"{deep:.4g} MPa at the deepest): E depends on the depths fitted, its "
                     "interval holds both")
    warning = None
    if found:
        warning = ("the model does not explain these data to within their noise: "
                   + "; ".join(found) + ". A missing effect or a wrong geometry is likely: "
                   "`tactilevision diagnose` names it")
    return Misfit(birge_ratio=birge, chi2_p=chi2_p, correlation=rho, correlation_p=rho_p,
                  drift=drift, drift_p=drift_p, E_shallow_mpa=shallow, E_deep_mpa=deep,
                  factor=factor, carried=carried, warning=warning)


def _linregress(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float]:
    """Slope, its standard error and the two-sided p-value of its t test: the arithmetic of
    ``scipy.stats.linregress`` (scipy 1.17) for finite x (3 or more, not all equal), without
    its argument handling, which took 2.7 ms of a 17 ms ``fit_indentation`` (issue 86: the
    planner fits thousands of tables); the same numbers to the last bit on random tables
    (tests/test_misfit.py)."""
    n = x.size
    ssxm, ssxym, _, ssym = np.cov(x, y, bias=1).flat
    if ssxm == 0.0 or ssym == 0.0:
        r = math.nan if ssxym == 0 else 0.0
    else:
        r = min(max(float(ssxym / np.sqrt(ssxm * ssym)), -1.0), 1.0)
    slope = float(ssxym / ssxm)
    if n == 2:
        return slope, 0.0, 1.0 if y[0] == y[1] else 0.0
    df = n - 2
    tiny = 1.0e-20                                           # scipy's TINY
    t = r * np.sqrt(df / ((1.0 - r + tiny) * (1.0 + r + tiny)))
    p = float(2 * special.stdtr(df, -np.abs(t)))
    return slope, float(np.sqrt((1 - r**2) * ssym / ssxm / df)), p


def _lack_of_fit(groups: np.ndarray, r: np.ndarray, n_params: int) -> tuple[float, float]:
    """The lack-of-fit F of residuals `r` whose presses repeat depths (`groups`, the index
    of each press's depth), and its p; (NaN, 1) without two degrees of freedom on each
    side."""
    k = int(groups.max()) + 1 if groups.size else 0
    dof_pure, dof_lack = r.size - k, k - n_params
    if dof_pure < 2 or dof_lack < 1:
        return math.nan, 1.0
    means = np.bincount(groups, r) / np.bincount(groups)
    ss_pure = float(np.sum((r - means[groups]) ** 2))
    ss_lack = float(np.sum(r ** 2)) - ss_pure
    if not ss_pure > 0:
        return math.nan, 1.0
    F = (ss_lack / dof_lack) / (ss_pure / dof_pure)
    return F, float(stats.f.sf(F, dof_lack, dof_pure))


def serial_correlation(residuals: np.ndarray) -> tuple[float, float, float]:
    """The lag-1 correlation of residuals in their order, its one-sided p, and the factor
    it widens an interval by.

    Parameters
    ----------
    residuals : (N,) float ndarray
        In the order they were measured along (depth, travel).

    Returns
    -------
    rho : float
        Lag-1 autocorrelation; NaN for fewer than 8 residuals or all equal.
    p : float
        One-sided p of rho sqrt(N) against the standard normal (no correlation).
    factor : float
        sqrt((1 + rho) / (1 - rho)) where p < :data:`MISFIT_ALPHA` (an AR(1) process's
        inflation of a mean's variance), else 1; capped at sqrt(N) (one independent
        residual left).
    """
    r = np.asarray(residuals, np.float64)
    n = r.size
    if n < _MIN_CORRELATED:
        return math.nan, math.nan, 1.0
    ro = r - np.mean(r)
    den = float(ro @ ro)
    if not den > 0:
        return math.nan, math.nan, 1.0
    rho = float(ro[1:] @ ro[:-1]) / den
    p = float(stats.norm.sf(rho * math.sqrt(n)))
    if p < MISFIT_ALPHA and rho > 0:
        return rho, p, min(math.sqrt((1 + rho) / max(1 - rho, 1e-12)), math.sqrt(n))
    return rho, p, 1.0


def widen_interval(value: float, ci: tuple[float, float], factor: float,
                   limits: tuple[float, float] = (-math.inf, math.inf)
                   ) -> tuple[float, float]:
    """`ci` about `value` with each side's half-width times `factor`, clipped to `limits`."""
    lo, hi = ci
    return (max(limits[0], value - factor * (value - lo)),
            min(limits[1], value + factor * (hi - value)))


#: log of the largest float: math.exp past it raises OverflowError
_LOG_FLOAT_MAX = math.log(sys.float_info.max)


def log_interval(value: float, se: float, quantile: float) -> tuple[float, float]:
    """A positive quantity's interval in log space: value exp(-+ quantile se / value).

    Never reaches zero: a modulus of 1 +- 0.6 (quantile x se) reads [0.55, 1.8], not
    [0.4, 1.6]; for se small against the value it is the symmetric interval. Where
    ``quantile se / value`` is past what a float's exponential holds (about 709), the
    upper end is infinite (nothing pins the value) and the lower end underflows towards
    zero, instead of raising ``OverflowError``.
    """
    if not (value > 0 and math.isfinite(se) and se >= 0):
        return (math.nan, math.nan)
    s = quantile * se / value
    return (value * math.exp(-s), value * math.exp(s) if s < _LOG_FLOAT_MAX else math.inf)
