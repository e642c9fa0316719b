"""A second reading of a drawn mark's depths: the stage's speed times the time it travelled.

The mark rule (:func:`~tactilevision.contact.mark_depths`) reads each press's depth past
w0 from the force: the rise from its indenter's P(w0) (the intersection of the presses'
crossing brackets) to the force window, over dP/dw from eq. (5). This reading shares
none of that: no force magnitude, no P(w0) shared between presses, no dP/dw. A stage
approaches at a steady speed v over a press, so its depth at a time t of the approach is
``v (t - t_touch)``, where ``t_touch`` is when the punch face met the gel (the F/T force
leaves its rest), and the depth stops growing at the hold's start. The press's own
crossing of w0, between the instants of its bracket (:attr:`CertifiedPress.onset_span_s`),
gives its speed: ``v = w0 / (t_c - t_touch)``. So the depth over the force window is

    w = w0 (t_window - t_touch) / (t_c - t_touch),

``t_window`` the window's mean instant with t held at the hold's start. Its uncertainty is
mostly the crossing's place in its bracket (uniform): ``w sd(t_c) / (t_c - t_touch)``,
some 5 to 40 um, several times the mark rule's: a check against gross misreadings (a
misread onset, a wrong intersection), not a second estimate to average with.

What it shares with the mark rule: the frames' times, the clock offset between them and
the F/T log, and which frame first shows the mark (the bracket). What it assumes instead:
a steady speed over each approach, from the touch (a stage's acceleration lasts a few ms
at these speeds), and a gel surface at w = 0 when the force leaves its rest.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._checks import InputError, check_array

__all__ = ["STAGE_Z", "StageReading", "stage_depths", "touch_time"]

#: Two readings of a press's depth disagree where they differ by more than this many sds
#: of their difference (each reading's own uncertainty, and the shared parts' bounds as
#: uniform sds): the press is flagged and left out of the fit.
STAGE_Z = 3.0
#: The share of the crossing's force over which the touch's rise is fitted.
_TOUCH_FROM, _TOUCH_TO = 0.05, 0.6


def touch_time(force_times_s: np.ndarray, fz_n: np.ndarray, t0_s: float, t1_s: float
               ) -> tuple[float, float]:
    """When a press's punch face met the gel: where its force left the rest, F/T clock, s.

    Parameters
    ----------
    force_times_s : (M,) float64 ndarray
        F/T clock, s (increasing).
    fz_n : (M,) float64 ndarray
        Normal force, N, its zero taken off (the rest reads about 0).
    t0_s, t1_s : float
        A span from before the touch (in the rest) to an instant of the approach well
        past it (the crossing of w0), F/T clock, s.

    Returns
    -------
    t_touch, sd : float
        The instant, and its standard uncertainty from the fit, s: a quadratic in time
        (eq. 5's P(w) at a constant speed is one) fitted by least squares to fz where it
        rises from :data:`_TOUCH_FROM` to :data:`_TOUCH_TO` of its value at `t1_s`, its root
        nearest that rise's start; ``(nan, nan)`` where the span holds too few samples or
        no rise.
    """
    tf = np.asarray(force_times_s, np.float64)
    fz = np.asarray(fz_n, np.float64)
    i0, i1 = np.searchsorted(tf, [t0_s, t1_s])
    if i1 - i0 < 20:
        return math.nan, math.nan
    t, f = tf[i0:i1], fz[i0:i1]
    dt = float(np.median(np.diff(t)))
    k = max(1, round(0.01 / dt))
    smooth = np.convolve(f, np.ones(k) / k, mode="same")
    top = float(np.median(f[-k:]))
    rest = float(np.median(f[:max(k, 5)]))
    rise = top - rest
    noise = 1.4826 * float(np.median(np.abs(np.diff(f)))) / math.sqrt(2.0)
    if rise <= 10 * noise / math.sqrt(k):
        return math.nan, math.nan
    above = np.flatnonzero(smooth - rest > _TOUCH_FROM * rise)
    if above.size == 0:
        return math.nan, math.nan
    j0 = int(above[0])
    upto = np.flatnonzero(smooth[j0:] - rest > _TOUCH_TO * rise)
    j1 = j0 + (int(upto[0]) if upto.size else t.size - j0)
    if j1 - j0 < 8:
        return math.nan, math.nan
    tc = t[j0:j1] - t[j0]
    X = np.column_stack([np.ones_like(tc), tc, tc * tc])
    coef = np.linalg.lstsq(X, f[j0:j1] - rest, rcond=None)[0]
    a, b, c = (float(v) for v in coef)
    if abs(c) * tc[-1] ** 2 < 1e-9 * max(abs(b) * tc[-1], 1e-12):
        roots = np.array([-a / b]) if b else np.zeros(0)
    else:
        disc = b * b - 4 * a * c
        roots = (np.array([(-b - math.sqrt(disc)) / (2 * c), (-b + math.sqrt(disc)) / (2 * c)])
                 if disc >= 0 else np.zeros(0))
    roots = roots[np.isfinite(roots)]
    if roots.size == 0:
        return math.nan, math.nan
    r = float(roots[np.argmin(np.abs(roots))])
    slope = b + 2 * c * r
    if slope <= 0:
        return math.nan, math.nan
    # the root's sd from the fit's covariance (the residuals' variance)
    dof = max(len(tc) - 3, 1)
    s2 = float(np.sum((f[j0:j1] - rest - X @ coef) ** 2)) / dof
    cov = s2 * np.linalg.pinv(X.T @ X)
    g = np.array([1.0, r, r * r]) / slope          # d root / d (a, b, c)
    sd = math.sqrt(max(float(g @ cov @ g), 0.0))
    # the rest's level is read from samples too: its error moves the root by noise / slope
    sd = math.hypot(sd, noise / math.sqrt(max(k, 5)) / slope)
    return float(t[j0] + r), sd


@dataclass(frozen=True)
class StageReading:
    """The stage reading of a session's mark-certified presses.

    Attributes
    ----------
    depth_mm, depth_std_mm : (N,) float64 ndarray
        Each press's depth over its force window (module docstring) and its sd; NaN
        where the press was not read (no touch in the F/T log, or no bracket).
    speed_mm_s : (N,) float64 ndarray
        Each press's approach speed, w0 over the time from its touch to its crossing's
        bracket's middle, mm/s (NaN where not read).
    note : str
        Why no press could be read (empty where one was).
    """

    depth_mm: np.ndarray
    depth_std_mm: np.ndarray
    speed_mm_s: np.ndarray
    note: str = ""


#: The hold's start's sd, s (:func:`~tactilevision.contact.hold_start`: two lines fitted
#: on a grid of the sampling interval), where a force window reaches the hold.
_HOLD_SD_S = 0.002


def stage_depths(w0_mm: np.ndarray, spans_s: np.ndarray, touch_s: np.ndarray,
                 touch_sd_s: np.ndarray, hold_start_s: np.ndarray, windows_s: np.ndarray
                 ) -> StageReading:
    """The stage reading of each press's depth (module docstring).

    Parameters
    ----------
    w0_mm : (N,) float ndarray
        Each press's indenter protrusion, mm (> 0).
    spans_s : (N, 2) float ndarray
        The instants between which each press crossed w0, F/T clock, s
        (:attr:`CertifiedPress.onset_span_s`); the crossing uniform between them.
    touch_s, touch_sd_s : (N,) float ndarray
        When each press touched the gel and its sd, s (:func:`touch_time`; NaN: not read).
    hold_start_s : (N,) float ndarray
        Each press's hold's start, F/T clock, s (NaN: the log shows none; the window is
        then taken as on the ramp).
    windows_s : (N, 2) float ndarray
        Each press's force window, F/T clock, s.

    Returns
    -------
    StageReading

    Raises
    ------
    ShapeError
        For arrays of different lengths.
    InputError
        For a w0 that is not positive.
    """
    w0 = check_array(w0_mm, "w0_mm", [("N",)], dtype=np.number).astype(np.float64)
    n = w0.shape[0]
    spans = check_array(spans_s, "spans_s", [(n, 2)], dtype=np.number).astype(np.float64)
    win = check_array(windows_s, "windows_s", [(n, 2)], dtype=np.number).astype(np.float64)
    touch = check_array(touch_s, "touch_s", [(n,)], dtype=np.number).astype(np.float64)
    tsd = check_array(touch_sd_s, "touch_sd_s", [(n,)], dtype=np.number).astype(np.float64)
    hold = check_array(hold_start_s, "hold_start_s", [(n,)], dtype=np.number).astype(
        np.float64)
    if np.any(w0 <= 0):
        raise InputError("w0_mm must be positive")
    t_c = spans.mean(axis=1)
    tc_sd = (spans[:, 1] - spans[:, 0]) / math.sqrt(12.0)
    rise = t_c - touch                              # touch to crossing, s
    ok = np.isfinite(rise) & (rise > 0)
    nan = np.full(n, np.nan)
    if not ok.any():
        return StageReading(nan, nan, nan, "no press with a touch before its crossing")
    # the window's mean instant on the ramp, t held at the hold's start
    t = np.linspace(0.0, 1.0, 41)
    tt = win[:, :1] + (win[:, 1:] - win[:, :1]) * t[None, :]
    stop = np.where(np.isfinite(hold), hold, np.inf)[:, None]
    reach = np.any(tt > stop, axis=1)
    run = np.minimum(tt, stop).mean(axis=1) - touch        # touch to the window, s
    with np.errstate(invalid="ignore", divide="ignore"):
        depth = np.where(ok, w0 * run / rise, np.nan)
        # d depth / d t_c = -depth / rise; d / d t_touch = depth (1 / rise - 1 / run);
        # d / d t_hold = w0 / rise x the share of the window past it
        share = np.mean(tt > stop, axis=1)
        sd = np.sqrt((depth * tc_sd / rise) ** 2
                     + (depth * (1 / rise - 1 / run) * tsd) ** 2
                     + np.where(reach, (w0 / rise * share * _HOLD_SD_S) ** 2, 0.0))
    return StageReading(depth, np.where(ok, sd, np.nan), np.where(ok, w0 / rise, np.nan))
