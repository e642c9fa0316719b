"""The trend of a gel's calibrations over days, and whether it has left its calibration.

Pure functions on arrays. The trend is a weighted least-squares straight line
of E against days (:func:`weighted_line`), each calibration weighted by its
own interval; the verdict (:func:`assess`) compares the latest calibration
with the first.

Why a weighted line and not :func:`tactilevision.diagnosis.diagnose` with the
``aging`` effect on the pooled presses: ``aging`` (P (1 + k day)) scales the
stiffness c of eq. (5) at one nu for all presses, and pooling assumes the
calibrations share a depth rule, a clock and a press quality. Each
calibration's E interval already carries its nu's uncertainty (through the
beta table) and its own certification; the weighted line keeps them, and its
inputs are the numbers the user sees in each fit.json.
"""

from __future__ import annotations

import datetime
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy import stats

from .._checks import InputError
from ._read import CalibrationRecord

__all__ = ["Assessment", "LineFit", "assess", "relative_change", "weighted_line"]


@dataclass(frozen=True)
class LineFit:
    """A weighted straight line y = intercept + slope x (:func:`weighted_line`).

    Attributes
    ----------
    intercept, slope : float
        In the units of y, and of y per unit of x.
    cov : (2, 2) ndarray
        Covariance of (intercept, slope), scaled by the Birge ratio squared
        when the scatter exceeds the stated uncertainties (`scaled`).
    chi2 : float
        Sum of squared weighted residuals.
    dof : int
        n - 2.
    scaled : bool
        Whether `cov` was multiplied by chi2 / dof (> 1).
    quantile : float
        The two-sided quantile of the intervals: normal when not scaled,
        Student t with `dof` degrees of freedom when scaled.
    """

    intercept: float
    slope: float
    cov: np.ndarray
    chi2: float
    dof: int
    scaled: bool
    quantile: float

    def at(self, x: np.ndarray | float) -> np.ndarray:
        """The line at `x`, (len(x),) or scalar array."""
        return self.intercept + self.slope * np.asarray(x, dtype=float)

    def band(self, x: np.ndarray | float) -> np.ndarray:
        """Half-width of the line's interval at `x` (quantile times its standard error)."""
        x = np.asarray(x, dtype=float)
        var = self.cov[0, 0] + 2 * x * self.cov[0, 1] + x * x * self.cov[1, 1]
        return self.quantile * np.sqrt(np.maximum(var, 0.0))

    def slope_ci(self) -> tuple[float, float]:
        """Interval of the slope."""
        h = self.quantile * math.sqrt(max(self.cov[1, 1], 0.0))
        return self.slope - h, self.slope + h


def weighted_line(x: np.ndarray, y: np.ndarray, sigma: np.ndarray, *,
                  confidence: float = 0.95) -> LineFit:
    """Fit y = a + b x by weighted least squares with known standard errors.

    Closed form (Bevington and Robinson, *Data Reduction and Error Analysis
    for the Physical Sciences*, 3rd ed., 2003, sections 6.3-6.4): with W =
    diag(1 / sigma^2) and X = [1, x], (a, b) = (X'WX)^-1 X'Wy and cov =
    (X'WX)^-1, the sigmas taken as absolute. When chi2 / (n - 2) > 1 (the
    calibrations scatter more than their intervals say: a trend that is not
    straight, or intervals too narrow) the covariance is multiplied by it
    (the Birge ratio squared, R. T. Birge, Phys. Rev. 40, 207, 1932) and the
    intervals use Student's t with n - 2 degrees of freedom; never narrowed.

    Parameters
    ----------
    x : (n,) ndarray
        Abscissae (days).
    y : (n,) ndarray
        Values (E, MPa).
    sigma : (n,) ndarray
        Standard errors of `y`, positive and finite.
    confidence : float, default 0.95

    Returns
    -------
    fit : LineFit

    Raises
    ------
    InputError
        Fewer than two points, x all equal, or a sigma not positive and finite.
    """

    x, y, s = (np.asarray(v, dtype=float) for v in (x, y, sigma))
    if x.size < 2 or np.ptp(x) == 0:
        raise InputError("a trend needs calibrations on at least two different days")
    if not (np.all(np.isfinite(s)) and np.all(s > 0)):
        raise InputError("every calibration needs a positive, finite uncertainty for the trend")
    w = 1.0 / s ** 2
    X = np.column_stack([np.ones_like(x), x])
    A = X.T @ (w[:, None] * X)
    cov = np.linalg.inv(A)
    a, b = cov @ (X.T @ (w * y))
    chi2 = float(np.sum(w * (y - a - b * x) ** 2))
    dof = x.size - 2
    scaled = dof > 0 and chi2 / dof > 1.0
    if scaled:
        cov = cov * (chi2 / dof)
        q = float(stats.t.ppf(0.5 + confidence / 2, dof))
    else:
        q = float(stats.norm.ppf(0.5 + confidence / 2))
    return LineFit(float(a), float(b), cov, chi2, dof, bool(scaled), q)


def relative_change(first: float, first_se: float, last: float, last_se: float, *,
                    confidence: float = 0.95) -> tuple[float, float, float]:
    """Relative change last / first - 1 with its interval.

    The interval is taken on the log of the ratio (the delta method: se(log E)
    = se(E) / E, the two calibrations independent) and mapped back, so it is
    never below -100 %.

    Parameters
    ----------
    first, last : float
        The two values (E, MPa), positive.
    first_se, last_se : float
        Their standard errors, same unit.
    confidence : float, default 0.95

    Returns
    -------
    change, low, high : float
        Fractions (-0.12 is a 12 % fall).
    """

    r = math.log(last / first)
    se = math.hypot(first_se / first, last_se / last)
    z = float(stats.norm.ppf(0.5 + confidence / 2))
    return math.expm1(r), math.expm1(r - z * se), math.expm1(r + z * se)


@dataclass(frozen=True)
class Assessment:
    """What the calibrations of one gel say (:func:`assess`). Units are in the names.

    Attributes
    ----------
    sensor : str
    days : (n,) ndarray
        Days since the first calibration.
    change, change_ci : float, (float, float)
        E of the latest calibration over the first's, less 1, with its
        interval (fractions); NaN with one calibration.
    beyond : (n,) bool ndarray
        Whether each calibration's E lies outside the first's interval.
    recalibrate : bool
        The latest E lies outside the first calibration's interval and the
        change's interval excludes 0.
    stale_from : datetime.date or None
        When `recalibrate`: the day from which a session using the first
        calibration's E used a stale one (where the trend leaves the first's
        interval, kept between the last calibration inside it and the first
        outside it).
    trend : LineFit or None
        E (MPa) against days; None with fewer than two distinct days.
    rate_per_day, rate_ci_per_day : float, (float, float)
        The trend's slope over the first calibration's E (fraction of it per
        day), with its interval; NaN without a trend.
    nu_beyond : bool
        Whether the latest nu lies outside the first's interval.
    message : str
        The verdict in plain sentences.
    """

    sensor: str
    days: np.ndarray
    change: float
    change_ci: tuple[float, float]
    beyond: np.ndarray
    recalibrate: bool
    stale_from: datetime.date | None
    trend: LineFit | None
    rate_per_day: float
    rate_ci_per_day: tuple[float, float]
    nu_beyond: bool
    message: str


def _pct(v: float) -> str:
    return f"{100 * v:.1f}"


def _day(first: datetime.date, d: datetime.date) -> str:
    return f"{d.isoformat()} (day {(d - first).days})"


def assess(records: Sequence[CalibrationRecord], *, confidence: float = 0.95) -> Assessment:
    """The trend of E over days and whether the gel has left its first calibration.

    Parameters
    ----------
    records : sequence of CalibrationRecord
        One sensor's calibrations, sorted by date (:func:`gather`).
    confidence : float, default 0.95
        Of the change's and the trend's intervals (the calibrations' own
        intervals are at their fit.json's confidence).

    Returns
    -------
    assessment : Assessment
        Its `message` says, for a change beyond the first calibration's
        interval, e.g. "E fell 12.0 % [8.0, 16.0] since 2026-11-02 (day 0)
        ...: recalibrate; the force maps of sessions after 2026-12-10 (day 38)
        used a stale E".

    Raises
    ------
    InputError
        For no records, or records of several sensors.
    """
    if not records:
        raise InputError("no calibrations to assess")
    sensors = {r.sensor for r in records}
    if len(sensors) != 1:
        raise InputError(f"calibrations of several sensors given together: {sorted(sensors)}")
    sensor = records[0].sensor
    first, last = records[0], records[-1]
    days = np.array([(r.date - first.date).days for r in records], dtype=float)
    E = np.array([r.E_mpa for r in records])
    lo0, hi0 = first.E_ci95_mpa
    beyond = (E < lo0) | (E > hi0)
    beyond[0] = False
    trend = None
    rate, rate_ci = math.nan, (math.nan, math.nan)
    if len(records) >= 2 and np.ptp(days) > 0:
        trend = weighted_line(days, E, np.array([r.E_se_mpa for r in records]),
                              confidence=confidence)
        b_lo, b_hi = trend.slope_ci()
        rate, rate_ci = trend.slope / first.E_mpa, (b_lo / first.E_mpa, b_hi / first.E_mpa)
    start = f"{sensor}: {len(records)} calibration{'s' if len(records) > 1 else ''}"
    if len(records) == 1:
        return Assessment(sensor, days, math.nan, (math.nan, math.nan), beyond, False, None,
                          None, rate, rate_ci, False,
                          f"{start} ({first.date.isoformat()}): no history to compare yet")
    change, c_lo, c_hi = relative_change(first.E_mpa, first.E_se_mpa, last.E_mpa,
                                         last.E_se_mpa, confidence=confidence)
    nu_beyond = not first.nu_ci95[0] <= last.nu <= first.nu_ci95[1]
    recal = bool(beyond[-1]) and not c_lo <= 0.0 <= c_hi
    if change < 0:      # a fall and its interval as positive percentages
        verb, size, lo_, hi_ = "fell", -change, -c_hi, -c_lo
    else:
        verb, size, lo_, hi_ = ("rose" if change > 0 else "changed"), change, c_lo, c_hi
    since = _day(first.date, first.date)
    head = (f"E {verb} {_pct(size)} % [{_pct(lo_)}, {_pct(hi_)}] since {since}, to "
            f"{last.E_mpa:.4g} MPa on {_day(first.date, last.date)}")
    lines = [start]
    stale = None
    if recal:
        stale = _stale_from(records, days, beyond, trend, change)
        lines.append(f"{head}, outside day 0's {100 * first.confidence:g}% interval "
                     f"[{lo0:.4g}, {hi0:.4g}] MPa: recalibrate; the force maps of sessions "
                     f"after {_day(first.date, stale)} used a stale E")
    else:
        where = ("inside" if not beyond[-1] else "outside") + (
            f" day 0's {100 * first.confidence:g}% interval [{lo0:.4g}, {hi0:.4g}] MPa")
        why = ("" if not beyond[-1] else
               ", but the change's interval includes 0")
        lines.append(f"{head}, {where}{why}: no recalibration needed yet")
    if trend is not None:
        lines.append(f"trend: {_pct(rate)} %/day [{_pct(rate_ci[0])}, {_pct(rate_ci[1])}] of "
                     f"day 0's E (weighted least squares over {len(records)} calibrations, "
                     f"chi2/dof = {trend.chi2 / trend.dof:.2f})" if trend.dof > 0 else
                     f"trend: {_pct(rate)} %/day [{_pct(rate_ci[0])}, {_pct(rate_ci[1])}] of "
                     "day 0's E (two calibrations: the line through them)")
    if nu_beyond:
        lines.append(f"nu is {last.nu:.3f} on {last.date.isoformat()}, outside day 0's "
                     f"interval [{first.nu_ci95[0]:.3f}, {first.nu_ci95[1]:.3f}]")
    return Assessment(sensor, days, change, (c_lo, c_hi), beyond, recal, stale, trend, rate,
                      rate_ci, nu_beyond, "\n  ".join(lines))


def _stale_from(records: Sequence[CalibrationRecord], days: np.ndarray, beyond: np.ndarray,
                trend: LineFit | None, change: float) -> datetime.date:
    """The day the trend leaves the first calibration's interval, bracketed by the
    calibrations: after the last one inside it and no later than the first outside it."""
    first = records[0]
    k = int(np.flatnonzero(beyond)[0])
    lo_day, hi_day = days[k - 1], days[k]
    t = lo_day
    if trend is not None and trend.slope != 0 and np.sign(trend.slope) == np.sign(change):
        bound = first.E_ci95_mpa[0] if change < 0 else first.E_ci95_mpa[1]
        t = float(np.clip((bound - trend.intercept) / trend.slope, lo_day, hi_day))
    return first.date + datetime.timedelta(days=round(t))
