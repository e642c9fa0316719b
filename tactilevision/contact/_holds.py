"""Holds in the F/T log: where a press's approach starts, where its hold starts and ends.

:func:`hold_start`, :func:`hold_end` and :func:`approach_start` read the normal
force alone (F/T clock); two straight lines meeting at a knee, fitted by least
squares (:func:`_knee_fits`), place each instant.
"""

from __future__ import annotations

import numpy as np

__all__ = ["approach_start", "hold_end", "hold_start"]


def hold_start(force_times_s: np.ndarray, fz_n: np.ndarray, t0_s: float, t1_s: float, *,
               smooth_s: float = 0.05, span_s: float = 0.15) -> float | None:
    """When a press stops going deeper, from its force: the start of its hold, F/T clock, s.

    Parameters
    ----------
    force_times_s : (M,) float64 ndarray
    fz_n : (M,) float64 ndarray
        The F/T log's normal force.
    t0_s, t1_s : float
        The press, F/T clock (its first frame in contact to its last).
    smooth_s : float, default 0.05
        Length of the moving average and half-span of the central difference
        that locate the end of the rise roughly.
    span_s : float, default 0.15
        Half-width of the window of the exact fit around it.

    Returns
    -------
    t_hold : float or None
        None when the log holds too few samples or no rising approach.

    Notes
    -----
    A press approaches at about constant speed (Fz rising by P / approach
    time: several N/s), then holds: the rise stops at once, where a gel's
    relaxation bends Fz only slowly. The steepest rise of the smoothed force
    and the first point after it rising at under a fifth of that place the
    stop roughly; then two straight lines meeting at t_hold (rise, hold) are
    fitted by least squares to the samples within `span_s`, t_hold on a
    grid of the sampling interval. Single 1 kHz samples of an ATI-class
    sensor (1/80 N) are too noisy to differentiate: the smoothing is needed.
    """
    sel = (force_times_s >= t0_s) & (force_times_s <= t1_s)
    t, f = force_times_s[sel], fz_n[sel]
    if t.size < 20:
        return None
    dt = float(np.median(np.diff(t)))
    k = max(1, round(smooth_s / dt))
    if t.size < 4 * k:
        return None
    fs = np.convolve(f, np.ones(k) / k, mode="same")
    d = np.full(t.size, 0.0)
    d[k:-k] = (fs[2 * k:] - fs[:-2 * k]) / (t[2 * k:] - t[:-2 * k])
    d[: 2 * k] = 0.0
    d[-2 * k:] = 0.0
    peak = int(np.argmax(d))
    if d[peak] <= 0:
        return None
    after = np.flatnonzero(d[peak:] < 0.2 * d[peak])
    if not after.size:
        return None
    # an approach is a rise that stands out of the samples' noise (robust sd of the first
    # differences, which a trend does not move): ten times it, from the lowest force before
    # the steepest rise to the stop; a falling force or noise alone has none
    df = np.diff(f)
    noise = 1.4826 * float(np.median(np.abs(df - np.median(df)))) / np.sqrt(2.0)
    if fs[peak + after[0]] - float(np.min(fs[k:peak + 1])) <= 10 * noise:
        return None
    guess = float(t[peak + after[0]])
    win = (t >= guess - span_s) & (t <= guess + span_s)
    tw, fw = t[win], f[win]
    if tw.size < 5:
        return guess
    rss, _ = _knee_fits(tw, fw, tw[2:-2], slope_before=True)
    return float(tw[2:-2][int(np.argmin(rss))])


def _knee_fits(t: np.ndarray, f: np.ndarray, knees: np.ndarray, *, slope_before: bool
               ) -> tuple[np.ndarray, np.ndarray]:
    """Two straight lines meeting at each candidate knee, fitted by least squares at once.

    The design at knee k is ``[1, min(t - k, 0), max(t - k, 0)]`` (a line on each side,
    `slope_before`) or ``[1, max(t - k, 0)]`` (flat, then a line). Returns the residual
    sum of squares (K,) and the coefficients (K, p) of every knee, from the normal
    equations of all knees solved together (each knee strictly inside `t`, so every
    design has full rank).
    """
    d = t[None, :] - knees[:, None]                                      # (K, n)
    cols = [np.ones_like(d)]
    if slope_before:
        cols.append(np.minimum(d, 0.0))
    cols.append(np.maximum(d, 0.0))
    X = np.stack(cols, axis=-1)                                          # (K, n, p)
    coef = np.linalg.solve(np.einsum("kni,knj->kij", X, X),
                           np.einsum("kni,n->ki", X, f)[..., None])[..., 0]      # (K, p)
    rss = np.sum((f[None, :] - np.einsum("kni,ki->kn", X, coef)) ** 2, axis=1)
    return rss, coef


def hold_end(force_times_s: np.ndarray, fz_n: np.ndarray, t_hold_s: float, *,
             max_hold_s: float = 600.0) -> float | None:
    """When a press's hold ends (the release begins), from its force, F/T clock, s.

    Parameters
    ----------
    force_times_s : (M,) float64 ndarray
    fz_n : (M,) float64 ndarray
        The F/T log's normal force.
    t_hold_s : float
        The hold's start (:func:`hold_start`), F/T clock.
    max_hold_s : float, default 600
        Longest hold searched.

    Returns
    -------
    t_release : float or None
        None when the force never falls below half its value at the hold's
        start within `max_hold_s`, or the log is too short.

    Notes
    -----
    The release is the mirror image of the approach: the force falls at
    about constant speed from the held level. The first sample after the
    hold's start below half the force held over its first 50 ms brackets
    it; :func:`hold_start` on the time-reversed log, between that sample
    (plus 50 ms) and the hold's start, finds where the fall begins. A
    relaxing gel loses force slowly during the hold (a fifth of it, say):
    that is not a release.
    """
    t = np.asarray(force_times_s, np.float64)
    f = np.asarray(fz_n, np.float64)
    start = (t >= t_hold_s) & (t <= t_hold_s + 0.05)
    if start.sum() < 3:
        return None
    held = float(np.mean(f[start]))
    if held <= 0:
        return None
    later = np.flatnonzero((t > t_hold_s + 0.05) & (t <= t_hold_s + max_hold_s)
                           & (f < 0.5 * held))
    if not later.size:
        return None
    t_half = float(t[later[0]])
    sel = (t >= t_hold_s) & (t <= t_half + 0.05)
    tr, fr = -t[sel][::-1], f[sel][::-1]
    back = hold_start(tr, fr, -(t_half + 0.05), -t_hold_s)
    return None if back is None else min(-back, t_half)


def approach_start(force_times_s: np.ndarray, fz_n: np.ndarray, t_hold_s: float, *,
                   max_ramp_s: float = 10.0, smooth_s: float = 0.01) -> float | None:
    """When a press's force began to rise: the start of its approach, F/T clock, s.

    Parameters
    ----------
    force_times_s : (M,) float64 ndarray
    fz_n : (M,) float64 ndarray
        The F/T log's normal force.
    t_hold_s : float
        The hold's start (:func:`hold_start`), F/T clock.
    max_ramp_s : float, default 10
        Longest approach searched.
    smooth_s : float, default 0.01
        The log is averaged in blocks of this length first.

    Returns
    -------
    t_start : float or None
        The knee of a flat-then-rising line fitted by least squares to the
        force before `t_hold_s`, over three times the time the force took to
        rise from half its held value; None when the log holds too few
        samples there or the force never rose.

    Notes
    -----
    ``t_hold_s - t_start`` is the loading time of the press, which a
    viscoelastic gel's hold curve depends on
    (:func:`~tactilevision.mechanics.fit_relaxation`). A threshold on the
    force would be thrown by the rest level's own wanderings (a relaxing
    gel's force undershoots after each release and recovers over tau); the
    two lines fit the level just before the rise, whatever it is.
    """
    t = np.asarray(force_times_s, np.float64)
    f = np.asarray(fz_n, np.float64)
    sel = np.flatnonzero((t >= t_hold_s - max_ramp_s) & (t <= t_hold_s))
    if sel.size < 20:
        return None
    tt, ff = t[sel], f[sel]
    dt = float(np.median(np.diff(tt)))
    k = max(1, round(smooth_s / dt))
    m = tt.size // k
    if m < 10:
        return None
    cut = tt.size - m * k                      # keep the samples next to the hold
    ts = tt[cut:].reshape(m, k).mean(1)
    fs = ff[cut:].reshape(m, k).mean(1)
    top = float(fs[-1])
    below = np.flatnonzero(fs < top - 0.5 * (top - float(fs.min())))
    if not below.size or top - float(fs.min()) <= 0:
        return None
    span = 3.0 * (t_hold_s - float(ts[below[-1]]))
    w = ts >= t_hold_s - span
    tw, fw = ts[w], fs[w]
    if tw.size < 6:
        return None
    knees = tw[1:-2]
    rss, coef = _knee_fits(tw, fw, knees, slope_before=False)
    rss = np.where(coef[:, 1] > 0, rss, np.inf)          # the force must rise after it
    return float(knees[int(np.argmin(rss))]) if np.isfinite(rss).any() else None
