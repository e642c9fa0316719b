"""The force of a certified press: a window of F/T samples at the certification instant."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._checks import InputError, check_array

__all__ = ["ForceWindow", "force_window", "window_standard_error"]


@dataclass(frozen=True)
class ForceWindow:
    """Mean and scatter of the F/T samples around one instant.

    Attributes
    ----------
    t_center_s : float
        Centre of the window on the F/T clock, s.
    start, stop : int
        Sample indices of the window, ``forces[start:stop]``.
    fx_n, fy_n, fz_n : float
        Mean force components, N (fz positive into the gel).
    fz_std_n : float
        Standard deviation of fz over the window (ddof = 1), N.
    fz_sem_n : float
        Standard error of the window's mean fz, the samples' autocorrelation
        included (:func:`window_standard_error`), N.
    tangential_ratio : float
        |(fx, fy)| / fz of the means: the press is aligned when small.
    """

    t_center_s: float
    start: int
    stop: int
    fx_n: float
    fy_n: float
    fz_n: float
    fz_std_n: float
    tangential_ratio: float
    fz_sem_n: float = float("nan")


def force_window(times_s: np.ndarray, forces_n: np.ndarray, t_center_s: float,
                 window_samples: int) -> ForceWindow:
    """Average `window_samples` F/T samples centred on `t_center_s`.

    Parameters
    ----------
    times_s : (M,) array_like of float
        F/T sample times, strictly increasing, s.
    forces_n : (M, 3) array_like of float
        (fx, fy, fz), N.
    t_center_s : float
        The certification instant on the F/T clock (frame time plus the clock
        offset), s.
    window_samples : int
        Samples averaged (the paper: 200 at 1 kHz), >= 2.

    Returns
    -------
    ForceWindow

    Raises
    ------
    ShapeError
        For arrays of the wrong shape or with NaNs.
    InputError
        For `window_samples` < 2 or more than the log holds, or a window that
        does not fit inside the log around `t_center_s` (the message gives the
        log's time span).

    Notes
    -----
    The window is the `window_samples` consecutive samples whose middle is
    the sample nearest to `t_center_s`. The paper averages 200 samples per
    press (method.md, "Measurement procedure").
    """
    t = check_array(times_s, "times_s", [("M",)], dtype=np.number, finite=True).astype(float)
    f = check_array(forces_n, "forces_n", [(t.size, 3)], dtype=np.number,
                    finite=True).astype(float)
    if isinstance(window_samples, bool) or int(window_samples) != window_samples or \
            window_samples < 2:
        raise InputError(f"window_samples must be an integer >= 2, got {window_samples!r}")
    n = int(window_samples)
    if n > t.size:
        raise InputError(f"window_samples = {n} is more than the {t.size} samples of the F/T log")
    mid = int(np.argmin(np.abs(t - t_center_s)))
    start = mid - n // 2
    stop = start + n
    if start < 0 or stop > t.size or not t[0] <= t_center_s <= t[-1]:
        raise InputError(f"a window of {n} F/T samples around t = {t_center_s:.4f} s does not fit "
                         f"in the F/T log ({t[0]:.4f} to {t[-1]:.4f} s): check the clock offset")
    w = f[start:stop]
    mean = w.mean(axis=0)
    ratio = float(np.hypot(mean[0], mean[1]) / mean[2]) if mean[2] > 0 else float("inf")
    return ForceWindow(t_center_s=float(t_center_s), start=start, stop=stop,
                       fx_n=float(mean[0]), fy_n=float(mean[1]), fz_n=float(mean[2]),
                       fz_std_n=float(w[:, 2].std(ddof=1)), tangential_ratio=ratio,
                       fz_sem_n=window_standard_error(w[:, 2]))


def window_standard_error(x: np.ndarray) -> float:
    """Standard error of a window's mean, with the samples' autocorrelation.

    ``sd / sqrt(n_eff)``, ``n_eff = n / (1 + 2 sum_k rho_k)``, the sum of the
    sample autocorrelations up to the first lag where it turns negative
    (the integrated autocorrelation time with Geyer's initial positive
    sequence cut-off, simplified: Geyer 1992, Statistical Science 7, 473).

    Parameters
    ----------
    x : (n,) float ndarray
        The window's samples (at least 3).

    Returns
    -------
    sem : float
        Same unit as `x`; NaN for fewer than 3 samples.
    """
    x = np.asarray(x, np.float64)
    n = x.size
    if n < 3:
        return math.nan
    d = x - x.mean()
    var = float(d @ d) / n
    if var == 0:
        return 0.0
    tau = 1.0
    for k in range(1, n // 2):      # lag by lag: white noise stops at the first (O(n k))
        rho = float(d[:-k] @ d[k:]) / (n * var)
        if rho <= 0:
            break
        tau += 2 * rho
    return float(np.std(x, ddof=1) * math.sqrt(min(tau, n) / n))
