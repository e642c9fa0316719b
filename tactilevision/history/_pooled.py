"""Every press of a gel's calibrations in one table, diagnosed along the day.

The weighted line of :mod:`._trend` reads each calibration's E; this pools the
presses themselves (each calibration's ``measurements.csv`` with a ``day``
column, days since the first) and hands them to the diagnosis machinery
(:func:`tactilevision.diagnosis.diagnose`), which tells a gradual change
(``aging``, P (1 + k day)) from a sudden one (``stiffness_step:day``) or none,
and fits the named effect: a rate k with its interval from all the presses at
once, with one nu for the gel.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .._checks import InputError
from ..diagnosis import diagnose
from ..io import read_measurements
from ..mechanics import fit_model
from ..pipeline import CalibrationResult
from ._read import CalibrationRecord

__all__ = ["PooledDiagnosis", "pooled_diagnosis", "pooled_measurements"]

#: Numeric columns pooled when every calibration has them (``day`` is added).
_COLUMNS = ("depth_mm", "force_n", "depth_std_mm", "x_mm", "y_mm", "time_s", "wait_s",
            "hold_s", "press")


def pooled_measurements(records: Sequence[CalibrationRecord]) -> dict[str, np.ndarray]:
    """The presses of every calibration in one table, with ``day`` (days since the first).

    Parameters
    ----------
    records : sequence of CalibrationRecord
        One gel's calibrations (:func:`~tactilevision.history.gather`), in date order.

    Returns
    -------
    columns : dict of str to (N,) float64 ndarray
        ``depth_mm``, ``force_n``, ``day`` and the other numeric columns that
        every calibration's ``measurements.csv`` holds.

    Raises
    ------
    InputError
        If a calibration folder has no readable ``measurements.csv`` (named).
    """
    day0 = records[0].date
    tables = []
    for r in records:
        path = r.folder / "measurements.csv"
        if not path.is_file():
            raise InputError(f"{path} does not exist: the pooled diagnosis needs each "
                             "calibration's measurements")
        m = read_measurements(path)
        cols = {k: np.asarray(v, np.float64) for k, v in m.columns.items() if k in _COLUMNS}
        cols["day"] = np.full(cols["depth_mm"].size, float((r.date - day0).days))
        tables.append(cols)
    keys = [k for k in (*_COLUMNS, "day") if all(k in t for t in tables)]
    return {k: np.concatenate([t[k] for t in tables]) for k in keys}


@dataclass(frozen=True)
class PooledDiagnosis:
    """The pooled presses of one gel, diagnosed (:func:`pooled_diagnosis`).

    Attributes
    ----------
    n_presses, n_calibrations : int
    missing_effect : str or None
        The diagnosis's verdict: ``'aging'``, ``'stiffness_step:day'``,
        another catalogue effect, or None (nothing missing).
    rate_per_day, rate_ci_per_day : float, (float, float)
        With ``aging``: k of P (1 + k day), the relative stiffness change per
        day, and its 95 % interval (+- 1.96 standard errors); else NaN.
    step, step_day : float
        With ``stiffness_step:day``: the relative change s and the day it
        falls after (the change point's midpoint); else NaN.
    E0_mpa, nu : float
        E on day 0 and nu, from the pooled fit with the named effect.
    message : str
        The diagnosis's own message.
    """

    n_presses: int
    n_calibrations: int
    missing_effect: str | None
    rate_per_day: float
    rate_ci_per_day: tuple[float, float]
    step: float
    step_day: float
    E0_mpa: float
    nu: float
    message: str

    def summary(self) -> str:
        """One sentence: what the pooled presses say."""
        head = (f"Pooled, the {self.n_presses} presses of {self.n_calibrations} calibrations "
                "(diagnose, along the day)")
        gel = f"E on day 0 = {self.E0_mpa:.4f} MPa, nu = {self.nu:.3f}"
        if self.missing_effect is None:
            return f"{head} show no missing effect: no change of the gel found; {gel}"
        if self.missing_effect == "aging":
            lo, hi = self.rate_ci_per_day
            return (f"{head} name aging: the stiffness changes {100 * self.rate_per_day:+.3f} "
                    f"%/day [{100 * lo:+.3f}, {100 * hi:+.3f}]; {gel}")
        if self.missing_effect == "stiffness_step:day":
            return (f"{head} name a step: the stiffness changes {100 * self.step:+.1f} % after "
                    f"day {self.step_day:g}; {gel} (before the step)")
        return (f"{head} name {self.missing_effect}, not a change along the day: see "
                f"'tactilevision diagnose' on the pooled table; {gel}")

    def to_json_dict(self) -> dict:
        def clean(v):
            if isinstance(v, float):
                return v if math.isfinite(v) else None
            if isinstance(v, tuple):
                return [clean(x) for x in v]
            return v

        return {k: clean(v) for k, v in vars(self).items()}


def _geometry(records: Sequence[CalibrationRecord]) -> tuple[float, float]:
    hs, as_ = set(), set()
    for r in records:
        obj = CalibrationResult.load(r.folder, tables=False).fit
        hs.add(obj.get("thickness_mm"))
        as_.add(obj.get("radius_mm"))
    if len(hs) != 1 or len(as_) != 1 or None in hs or None in as_:
        raise InputError("the calibrations differ in layer thickness or indenter radius (or a "
                         "fit.json lacks them): their presses cannot be pooled")
    return float(hs.pop()), float(as_.pop())


def pooled_diagnosis(records: Sequence[CalibrationRecord]) -> PooledDiagnosis:
    """Diagnose one gel's pooled presses along the day (module docstring).

    Parameters
    ----------
    records : sequence of CalibrationRecord
        At least two calibrations on different days, in date order.

    Returns
    -------
    PooledDiagnosis

    Raises
    ------
    InputError
        Fewer than two days, calibrations with different h or a, or a
        missing measurements table.
    """
    if len({r.date for r in records}) < 2:
        raise InputError("a pooled diagnosis needs calibrations on at least two days")
    h, a = _geometry(records)
    cols = pooled_measurements(records)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = diagnose(cols, thickness_mm=h, radius_mm=a)
    effect = d.missing_effect
    rate, rate_ci, step, step_day = math.nan, (math.nan, math.nan), math.nan, math.nan
    E0, nu = d.ladder[0].E_mpa, d.ladder[0].nu          # nothing missing: the base model's
    if effect is not None:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fit, mf = fit_model(cols, effect, thickness_mm=h, radius_mm=a)
        E0, nu = fit.E_mpa, fit.nu
        if effect == "aging":
            k = float(mf.params["aging.k_per_day"])
            se = float(mf.stderr.get("aging.k_per_day", math.nan))
            rate, rate_ci = k, (k - 1.96 * se, k + 1.96 * se)
        elif effect == "stiffness_step:day":
            step = float(mf.params["stiffness_step:day.s"])
            step_day = float(mf.params["stiffness_step:day.at"])
    return PooledDiagnosis(n_presses=int(cols["depth_mm"].size), n_calibrations=len(records),
                           missing_effect=effect, rate_per_day=rate, rate_ci_per_day=rate_ci,
                           step=step, step_day=step_day, E0_mpa=float(E0), nu=float(nu),
                           message=d.message)
