"""The F/T sensor's own zero, read from the log where nothing touches the gel.

An F/T sensor tared before the gauge block was mounted reads the block's
weight in every sample, between presses too; a sensor warming up drifts. A
press's force window then holds the indenter's force plus that zero. The log
measures the zero directly: between presses, once each release has settled,
the sensor reads nothing but it. A tare measured there is better than an
offset fitted against the curvature of eq. (5), which it trades with (a
constant force offset and beta are nearly the same function over 4 to 6
depths: ``docs/diagnose_power.md``).

:func:`force_zero` takes the rests between the presses the frames show
(each press's frames in contact, widened by a margin, on the F/T clock),
keeps the settled second half of each, and fits a line to their mean fz
over the session: the zero, its drift, and their standard errors.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import stats

from .._checks import InputError, check_array

__all__ = ["ForceZero", "force_zero"]

#: A rest whose fz moves by more than this (and four standard errors) over its kept half
#: is not settled, N (a relaxing gel's recovery after a release, a contact the frames
#: missed).
SETTLED_N = 0.002
#: The zero drifts when the line's change over the session is significant at this level
#: and larger than :data:`DRIFT_MIN_N`.
DRIFT_ALPHA = 1e-3
#: Smallest drift over the session reported as one, N.
DRIFT_MIN_N = 0.002


@dataclass(frozen=True)
class ForceZero:
    """The F/T's zero, read between presses (:func:`force_zero`).

    Attributes
    ----------
    zero_n : float
        The mean fz with nothing touching, N: the line's value at the mean
        time of the rests (the constant a tare would take off).
    zero_se_n : float
        Its standard error, N.
    drift_n : float
        The line's change from the first rest to the last, N.
    drift_se_n : float
        Its standard error, N (NaN with fewer than three rests).
    drift_p_value : float
        Two-sided p-value of a zero slope (t test on the rests' means; NaN
        with fewer than three rests).
    drifts : bool
        ``drift_p_value < DRIFT_ALPHA`` and ``|drift_n| > DRIFT_MIN_N``.
    slope_n_per_s : float
        The line's slope, N/s (0 with one rest).
    t_ref_s : float
        The time of `zero_n` on the F/T clock, s.
    rest_t_s, rest_fz_n, rest_sem_n : (K,) float64 ndarray
        Middle time (F/T clock, s), mean fz (N) and its standard error (N) of
        each settled rest used.
    n_rests, n_unsettled : int
        Rests used, and rests left out as not settled.
    subtracted : {'constant', 'drift', 'off'}
        What the calibration took off the forces: `zero_n` from every
        sample, the line at each sample's time, or nothing.
    """

    zero_n: float
    zero_se_n: float
    drift_n: float
    drift_se_n: float
    drift_p_value: float
    drifts: bool
    slope_n_per_s: float
    t_ref_s: float
    rest_t_s: np.ndarray = field(repr=False)
    rest_fz_n: np.ndarray = field(repr=False)
    rest_sem_n: np.ndarray = field(repr=False)
    n_rests: int = 0
    n_unsettled: int = 0
    subtracted: str = "constant"

    def at(self, t_s: np.ndarray | float) -> np.ndarray:
        """The zero at F/T times `t_s` (s) on the fitted line, N, float64."""
        return self.zero_n + self.slope_n_per_s * (np.asarray(t_s, np.float64) - self.t_ref_s)

    def taken_off(self, t_s: np.ndarray | float) -> np.ndarray:
        """What the calibration took off the force at F/T times `t_s`, N (0 for 'off')."""
        t = np.asarray(t_s, np.float64)
        if self.subtracted == "off":
            return np.zeros(t.shape)
        if self.subtracted == "drift":
            return self.at(t)
        return np.full(t.shape, self.zero_n)

    @property
    def subtracted_n(self) -> bool:
        """Whether anything was taken off the forces."""
        return self.subtracted != "off"

    def sentence(self) -> str:
        """One sentence for the report: the zero, its drift, what was done."""
        text = (f"the F/T read {1e3 * self.zero_n:+.1f} mN (se {1e3 * self.zero_se_n:.2f}) with "
                f"nothing touching, over {self.n_rests} settled rests between presses")
        if self.n_unsettled:
            text += f" ({self.n_unsettled} unsettled rests left out)"
        if np.isfinite(self.drift_p_value):
            text += (f"; it {'drifts' if self.drifts else 'does not drift measurably'}: "
                     f"{1e3 * self.drift_n:+.1f} mN over the session (se "
                     f"{1e3 * self.drift_se_n:.2f} mN, p = {self.drift_p_value:.2g})")
        text += {"constant": "; its mean was taken off every force",
                 "drift": "; the zero on its line was taken off each force at its time",
                 "off": "; the forces were left as the F/T read them (--ft-zero off)"
                 }[self.subtracted]
        if self.drifts and self.subtracted == "constant":
            text += (" (the drift is left in force_n and listed per press as ft_drift_n: a "
                     "force_drift, measured; calibrate --ft-zero drift takes it off)")
        return text

    def to_json_dict(self) -> dict:
        """Plain JSON types (NaN as None)."""
        def num(v: float) -> float | None:
            return float(v) if math.isfinite(v) else None

        return {"zero_n": num(self.zero_n), "zero_se_n": num(self.zero_se_n),
                "drift_n": num(self.drift_n), "drift_se_n": num(self.drift_se_n),
                "drift_p_value": num(self.drift_p_value), "drifts": self.drifts,
                "slope_n_per_s": num(self.slope_n_per_s), "n_rests": self.n_rests,
                "n_unsettled": self.n_unsettled, "subtracted": self.subtracted}


def _rest_mean(t: np.ndarray, f: np.ndarray) -> tuple[float, float, float, float] | None:
    """Mean, its standard error, and the change of a line over the rest with its standard
    error (on ten block means, which whiten the F/T's coloured noise); None when too few
    samples."""
    if t.size < 20:
        return None
    k = t.size // 10
    m = 10 * k
    tb = t[:m].reshape(10, k).mean(axis=1)
    fb = f[:m].reshape(10, k).mean(axis=1)
    sem = float(np.std(fb, ddof=1) / math.sqrt(fb.size))
    x = tb - tb.mean()
    slope = float(x @ (fb - fb.mean()) / (x @ x))
    r = fb - fb.mean() - slope * x
    se = math.sqrt(float(r @ r) / 8 / float(x @ x))
    span = float(t[-1] - t[0])
    return float(f.mean()), sem, slope * span, se * span


def force_zero(force_times_s: np.ndarray, fz_n: np.ndarray, contact_s: np.ndarray, *,
               margin_s: float = 0.25, min_rest_s: float = 0.2,
               subtracted: str = "constant") -> ForceZero | None:
    """Measure the F/T's zero and its drift from the rests between presses.

    Parameters
    ----------
    force_times_s : (M,) float ndarray
        F/T sample times, increasing, s.
    fz_n : (M,) float ndarray
        Normal force, N.
    contact_s : (P, 2) float ndarray
        Start and end of each press (anything touching the gel), on the F/T
        clock, s, in order: the frames' runs in contact plus the clock
        offset.
    margin_s : float, default 0.25
        Taken off each side of a press before the rest starts (the force
        rises before the frames see contact, and the release takes time).
    min_rest_s : float, default 0.2
        Shortest settled half of a rest that is used, s.
    subtracted : {'constant', 'drift', 'off'}, default 'constant'
        Recorded in the result (what the caller takes off the forces).

    Returns
    -------
    ForceZero or None
        None when no rest is long enough or none is settled.

    Raises
    ------
    ShapeError
        For arrays of the wrong shape or with NaNs.
    InputError
        For an unknown `subtracted` or a negative margin.

    Notes
    -----
    A rest runs from one press's end plus `margin_s` to the next press's
    start less `margin_s` (the log's start and end bound the first and the
    last). Only its second half is kept, and it is used unless its fz
    changes by more than :data:`SETTLED_N` along a fitted line, and by more
    than four standard errors of that change (a relaxing gel
    recovers after a release; the elastic force behind the log is what
    settles). The rests' means are fitted by weighted least squares with a
    line in time; its slope's t test (n - 2 degrees of freedom) says whether
    the zero drifts. With two rests the line is drawn through them and the
    drift is not tested; with one, the zero is that rest's mean.
    """
    t = check_array(force_times_s, "force_times_s", [("M",)], dtype=np.number, finite=True)
    f = check_array(fz_n, "fz_n", [(t.shape[0],)], dtype=np.number, finite=True)
    c = check_array(contact_s, "contact_s", [("P", 2)], dtype=np.number, finite=True)
    if subtracted not in ("constant", "drift", "off"):
        raise InputError(f"subtracted must be 'constant', 'drift' or 'off', got {subtracted!r}")
    if not (margin_s >= 0 and min_rest_s > 0):
        raise InputError(f"margin_s must be >= 0 and min_rest_s > 0, got {margin_s!r}, "
                         f"{min_rest_s!r}")
    t, f, c = t.astype(np.float64), f.astype(np.float64), c.astype(np.float64)
    order = np.argsort(c[:, 0])
    c = c[order]
    edges = np.concatenate([[t[0] - margin_s], c.ravel(), [t[-1] + margin_s]]).reshape(-1, 2)
    rt, rf, rs = [], [], []
    unsettled = 0
    for t_end, t_next in edges:
        a, b = t_end + margin_s, t_next - margin_s
        a = max(a, 0.5 * (a + b))                 # the settled second half
        if b - a < min_rest_s:
            continue
        sel = (t >= a) & (t <= b)
        got = _rest_mean(t[sel], f[sel])
        if got is None:
            continue
        mean, sem, change, change_se = got
        if abs(change) > max(SETTLED_N, 4.0 * change_se):
            unsettled += 1
            continue
        rt.append(0.5 * (a + b))
        rf.append(mean)
        rs.append(max(sem, 1e-9))
    if not rt:
        return None
    rt, rf, rs = np.array(rt), np.array(rf), np.array(rs)
    n = rt.size
    t_ref = float(rt.mean())
    nan = float("nan")
    if n == 1:
        return ForceZero(zero_n=float(rf[0]), zero_se_n=float(rs[0]), drift_n=nan,
                         drift_se_n=nan, drift_p_value=nan, drifts=False, slope_n_per_s=0.0,
                         t_ref_s=t_ref, rest_t_s=rt, rest_fz_n=rf, rest_sem_n=rs, n_rests=1,
                         n_unsettled=unsettled, subtracted=subtracted)
    X = np.column_stack([np.ones(n), rt - t_ref])
    if n == 2:
        coef = np.linalg.solve(X, rf)
        cov = np.diag([float(np.mean(rs ** 2)) / 2, np.nan])
        p, se_slope = nan, nan
    else:
        # the rests' scatter about the line, not only their own noise, sets the errors
        w = 1.0 / rs ** 2
        A = X * np.sqrt(w)[:, None]
        coef, *_ = np.linalg.lstsq(A, rf * np.sqrt(w), rcond=None)
        r = (rf - X @ coef) * np.sqrt(w)
        scale = max(float(r @ r) / (n - 2), 1.0)
        cov = np.linalg.inv(A.T @ A) * scale
        se_slope = float(np.sqrt(cov[1, 1]))
        p = float(2 * stats.t.sf(abs(coef[1]) / max(se_slope, 1e-300), n - 2))
    span = float(rt[-1] - rt[0])
    drift = float(coef[1]) * span
    drift_se = se_slope * span
    drifts = bool(np.isfinite(p) and p < DRIFT_ALPHA and abs(drift) > DRIFT_MIN_N)
    return ForceZero(zero_n=float(coef[0]), zero_se_n=float(np.sqrt(cov[0, 0])), drift_n=drift,
                     drift_se_n=drift_se, drift_p_value=p, drifts=drifts,
                     slope_n_per_s=float(coef[1]), t_ref_s=t_ref, rest_t_s=rt, rest_fz_n=rf,
                     rest_sem_n=rs, n_rests=n, n_unsettled=unsettled, subtracted=subtracted)
