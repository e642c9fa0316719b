"""Viscoelastic relaxation from the force over each press's hold.

A gel held at a fixed depth loses force as it relaxes. With one Prony term
(a standard linear solid) the relaxation function is

    G(t) / G(0) = 1 - g (1 - exp(-t / tau)),

and by Boltzmann superposition the force is the elastic force's history
through it: F(t) = (1 - g) P(t) + g int_0^t exp(-(t - s) / tau) dP(s), with
P the force an elastic gel of the instantaneous modulus E_0 would push back
with (quasi-linear viscoelasticity: Fung 1993, *Biomechanics: Mechanical
Properties of Living Tissues*, 2nd ed., ch. 7). A press loaded by a ramp of
duration T in which P rises linearly to P_0, then held, reads over its hold
(t from the end of the ramp)

    F(t) = P_0 [(1 - g) + g phi(T / tau) exp(-t / tau)],
    phi(x) = (1 - exp(-x)) / x,

the ramp-and-hold solution (the ramp correction of Mattice, Lau, Oyen and
Kent 2006, J. Mater. Res. 21(8), 2003-2010, in this form). At the hold's
start F = P_0 [1 - g (1 - phi)]: a ramp of T ~ tau already loses part of the
relaxation, which a fit of exp(-t/tau) alone would miss. Then E_0 is what
the layer law gives for the forces P_0 (the table's force_n divided by
F(hold_s) / P_0), and the relaxed modulus is E_inf = (1 - g) E_0 (every
press relaxes by the same factor, so nu is unchanged).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from scipy import optimize, stats
from scipy.optimize import least_squares
from scipy.signal import lfilter

from .._checks import InputError

#: tau is identified only up to this many times the longest hold (the holds must show its
#: curvature).
TAU_HOLD_RATIO = 2.0
#: ... and down to this fraction of the shortest hold: a faster relaxation is spent within
#: the hold's first blocks (and mostly during the loading ramp), where its shape is not
#: resolved (an elastic gel's first samples fitted tau = 31 ms, g = 0.04, p = 0.0009:
#: benchmarks/bench_relaxation_identified.py).
TAU_MIN_HOLD_FRACTION = 0.1
#: Level of the tests of a decay (against flat holds) and of its curvature (against a
#: straight decay).
RELAX_ALPHA = 1e-3

__all__ = ["RelaxationFit", "elastic_force", "fit_relaxation", "instantaneous_forces",
           "ramp_factor", "relaxed_moduli"]


def ramp_factor(ramp_s: np.ndarray | float, tau_s: float) -> np.ndarray:
    """phi(T / tau) = (1 - exp(-T / tau)) / (T / tau), 1 for an instant load.

    Parameters
    ----------
    ramp_s : float or ndarray
        Loading time T, s (>= 0).
    tau_s : float
        Relaxation time, s (> 0).

    Returns
    -------
    phi : float64 ndarray
        The share of the relaxing term's amplitude left at the end of a
        linear ramp (module docstring).
    """
    x = np.asarray(ramp_s, np.float64) / float(tau_s)
    small = x < 1e-6
    return np.where(small, 1.0 - x / 2, -np.expm1(-np.where(small, 1.0, x))
                    / np.where(small, 1.0, x))


@dataclass(frozen=True)
class RelaxationFit:
    """A standard linear solid fitted to hold curves (:func:`fit_relaxation`).

    Attributes
    ----------
    g : float
        Relaxing share of the modulus: E_inf = (1 - g) E_0.
    tau_s : float
        Relaxation time, s.
    g_ci, tau_ci_s : (float, float)
        Intervals at `confidence`, from a bootstrap over presses (NaN when
        the F test finds no relaxation: no bootstrap is run then).
    confidence : float
    elastic_force_n : dict of int to float
        Per press, P_0: the force at the hold's depth of an elastic gel of
        modulus E_0 (the fitted amplitude).
    ramp_s : dict of int to float
        Per press, the loading time used.
    rmse_n : float
        RMS residual of the fit over every sample, N.
    n_presses, n_samples : int
    resolved : bool
        Whether the gel is found to relax (``verdict == 'relaxing'``): the
        holds decay (an F test against a constant force per press, p <
        0.001), g and tau are both identified (``identified``), g's interval
        excludes 0, and the decay is not the stiffness trend between the
        presses. Only then are g and tau reported as the gel's.
    p_value : float
        The F test's p-value (decay against a constant force per press).
    notes : tuple of str
    boot : (B, 2) float64 ndarray
        The bootstrap's (g, tau_s) draws, for propagating the uncertainty.
    verdict : {'relaxing', 'softening', 'decay not identified', 'flat'}
        What the holds say: the gel relaxes; the holds fall as the
        stiffness falls between presses over the session (a softening gel,
        not relaxation, which recovers between presses); they fall, but tau
        is not identified (only the initial decay rate is); or they hold
        their force.
    why : str
        One sentence with the numbers behind `verdict`.
    identified : bool
        Whether tau (and so g) is pinned by the holds: the decay's curvature
        is seen (a straight decay, tau much longer than the holds, is
        rejected at p < 0.001 against the best fit: the profile of tau is
        bounded above) and tau lies from :data:`TAU_MIN_HOLD_FRACTION` of the
        shortest hold to :data:`TAU_HOLD_RATIO` times the longest.
    tau_profile_ci_s : (float, float)
        Profile-likelihood interval of tau at `confidence`, s (inf above
        when the profile never rises enough: tau not identified).
    curvature_p_value : float
        p-value of the straight decay (tau at the top of the profile's grid)
        against the best fit.
    longest_hold_s : float
        The longest hold, s.
    decay_rate_per_s, decay_rate_se_per_s : float
        The force's relative rate of change over the holds, 1/s (negative
        when it falls), from a straight line through each hold (its slope
        over its value at the hold's start), averaged over the presses, and
        its standard error: what a hold identifies when tau does not (for
        tau much longer than the hold, ``-g phi(T / tau) / tau``).
    trend_per_s, trend_se_per_s : float
        The relative rate at which the presses' forces at the hold's start
        change over the session, 1/s, with each depth (``press_group``)
        apart, and its standard error; NaN without ``press_time_s``.
    """

    g: float
    tau_s: float
    g_ci: tuple[float, float]
    tau_ci_s: tuple[float, float]
    confidence: float
    elastic_force_n: dict[int, float]
    ramp_s: dict[int, float]
    rmse_n: float
    n_presses: int
    n_samples: int
    resolved: bool
    p_value: float = float("nan")
    notes: tuple[str, ...] = ()
    boot: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)), repr=False)
    verdict: str = "flat"
    why: str = ""
    identified: bool = False
    tau_profile_ci_s: tuple[float, float] = (float("nan"), float("nan"))
    curvature_p_value: float = float("nan")
    longest_hold_s: float = float("nan")
    decay_rate_per_s: float = float("nan")
    decay_rate_se_per_s: float = float("nan")
    trend_per_s: float = float("nan")
    trend_se_per_s: float = float("nan")

    def factor(self, hold_s: np.ndarray | float, ramp_s: np.ndarray | float,
               g: float | None = None, tau_s: float | None = None) -> np.ndarray:
        """F(hold_s) / P_0: how much of the instantaneous force is left at a time of the hold.

        Parameters
        ----------
        hold_s : float or ndarray
            Time since the end of the ramp, s.
        ramp_s : float or ndarray
            Loading time, s.
        g, tau_s : float, optional
            Other parameters than the fit's (bootstrap draws).

        Returns
        -------
        factor : float64 ndarray
            ``(1 - g) + g phi(ramp / tau) exp(-hold / tau)``, in (1 - g, 1].
        """
        g = self.g if g is None else g
        tau = self.tau_s if tau_s is None else tau_s
        return (1.0 - g) + g * ramp_factor(ramp_s, tau) * np.exp(-np.asarray(hold_s) / tau)

    def to_json_dict(self) -> dict:
        """The fit as plain JSON types (the bootstrap draws left out; NaN as None)."""
        def clean(v: float) -> float | None:
            return float(v) if np.isfinite(v) else None

        shown = self.identified      # g and tau are the gel's only when identified
        return {"model": "standard linear solid, linear ramp then hold (Boltzmann "
                         "superposition)",
                "g": clean(self.g) if shown else None,
                "g_ci": [clean(v) for v in self.g_ci] if shown else [None, None],
                "tau_s": clean(self.tau_s) if shown else None,
                "tau_ci_s": [clean(v) for v in self.tau_ci_s] if shown else [None, None],
                "confidence": self.confidence, "resolved": self.resolved,
                "verdict": self.verdict, "why": self.why, "identified": self.identified,
                "tau_profile_ci_s": [clean(v) if not np.isposinf(v) else "inf"
                                     for v in self.tau_profile_ci_s],
                "curvature_p_value": clean(self.curvature_p_value),
                "longest_hold_s": clean(self.longest_hold_s),
                "decay_rate_per_s": clean(self.decay_rate_per_s),
                "decay_rate_se_per_s": clean(self.decay_rate_se_per_s),
                "trend_per_s": clean(self.trend_per_s),
                "trend_se_per_s": clean(self.trend_se_per_s),
                "p_value": clean(self.p_value), "rmse_n": clean(self.rmse_n),
                "n_presses": self.n_presses, "n_samples": self.n_samples,
                "notes": list(self.notes)}


def elastic_force(force_times_s: np.ndarray, forces_n: np.ndarray, g: float, tau_s: float
                  ) -> np.ndarray:
    """The elastic force history behind a relaxing gel's F/T log (the inverse filter).

    Parameters
    ----------
    force_times_s : (M,) float ndarray
        Sample times, s, increasing and evenly spaced (the median step is
        used).
    forces_n : (M,) or (M, C) float ndarray
        Measured forces, N (one or several channels).
    g, tau_s : float
        The standard linear solid (:func:`fit_relaxation`): 0 <= g < 1,
        tau_s > 0.

    Returns
    -------
    elastic_n : float64 ndarray, shape of `forces_n`
        P(t): the force a gel of the instantaneous modulus E_0 would read at
        the same depths, which follows the depth at every instant.

    Raises
    ------
    InputError
        For g outside [0, 1), a non-positive tau, fewer than 2 samples or
        non-increasing times.

    Notes
    -----
    Sampled, the Boltzmann superposition of the module docstring is the
    recursion q_n = a q_(n-1) + (P_n - P_(n-1)), F_n = (1 - g) P_n + g q_n
    with a = exp(-dt / tau): in z, F = (1 - b z^-1) / (1 - a z^-1) P with
    b = (1 - g) a + g, so P = (1 - a z^-1) / (1 - b z^-1) F, a stable
    first-order filter (:func:`scipy.signal.lfilter`). The log's first value
    is taken as its rest level (a tared sensor at rest): it is removed before
    the filter and added back, so that a constant offset is not amplified by
    the filter's 1 / (1 - g) gain at rest.
    """
    t = np.asarray(force_times_s, np.float64)
    f = np.asarray(forces_n, np.float64)
    if not (0.0 <= float(g) < 1.0 and np.isfinite(tau_s) and tau_s > 0):
        raise InputError(f"need 0 <= g < 1 and tau_s > 0, got g = {g!r}, tau_s = {tau_s!r}")
    if t.ndim != 1 or t.size < 2 or f.shape[0] != t.size:
        raise InputError(f"need matching times and forces with at least 2 samples, got "
                         f"{t.shape} and {f.shape}")
    dt = np.diff(t)
    if not np.all(dt > 0):
        raise InputError("force_times_s must increase")
    a = float(np.exp(-float(np.median(dt)) / float(tau_s)))
    b = (1.0 - float(g)) * a + float(g)
    rest = f[: min(50, f.shape[0])].mean(axis=0)
    return lfilter([1.0, -a], [1.0, -b], f - rest, axis=0) + rest


def hold_blocks(t: np.ndarray, f: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """A hold's samples averaged in consecutive blocks to about `n` points, as
    :func:`fit_relaxation` averages them: (times (m,), forces (m,)), m <= n."""
    k = max(1, -(-t.size // n))
    m = t.size // k
    return t[: m * k].reshape(m, k).mean(1), f[: m * k].reshape(m, k).mean(1)


def _solve(curves: list[tuple[np.ndarray, np.ndarray, float]], start: tuple[float, float]
           ) -> tuple[float, float, np.ndarray, float]:
    """Least squares over (g, log tau), each press's amplitude profiled out."""
    def amplitudes_and_residuals(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        g, tau = p[0], np.exp(p[1])
        amps, res = [], []
        for t, f, ramp in curves:
            b = (1.0 - g) + g * ramp_factor(ramp, tau) * np.exp(-t / tau)
            a = float(b @ f / (b @ b))
            amps.append(a)
            res.append(f - a * b)
        return np.array(amps), np.concatenate(res)

    r = least_squares(lambda p: amplitudes_and_residuals(p)[1], np.array(start, np.float64),
                      bounds=([0.0, np.log(1e-3)], [0.99, np.log(1e5)]), x_scale=[0.1, 1.0])
    amps, res = amplitudes_and_residuals(r.x)
    return float(r.x[0]), float(np.exp(r.x[1])), amps, float(np.sqrt(np.mean(res ** 2)))


def fit_relaxation(press: np.ndarray, t_s: np.ndarray, fz_n: np.ndarray,
                   ramp_s: np.ndarray | None = None, *, confidence: float = 0.95,
                   n_boot: int = 200, points_per_press: int = 100,
                   seed: int = 0, press_time_s: Mapping[int, float] | None = None,
                   press_group: Mapping[int, object] | None = None) -> RelaxationFit:
    """Fit a standard linear solid to the force over each press's hold.

    Parameters
    ----------
    press : (K,) int ndarray
        Press of each sample (``holds.csv``'s ``press``).
    t_s : (K,) float ndarray
        Time since the hold's start (the end of the ramp), s.
    fz_n : (K,) float ndarray
        Normal force, N.
    ramp_s : (K,) float ndarray, optional
        The press's loading time on each of its samples, s; NaN where not
        known (the median of the known ones is used, or 0: an instant load,
        when none is known). Default: all unknown.
    confidence : float, default 0.95
        Level of the intervals.
    n_boot : int, default 200
        Bootstrap resamples of the presses (with replacement) behind the
        intervals; the samples of one press are not independent (the F/T
        noise is coloured, the gel's memory spans them), the presses are.
    points_per_press : int, default 100
        Each hold is averaged in blocks down to this many points first.
    seed : int, default 0
        For the bootstrap.
    press_time_s : mapping of int to float, optional
        Each press's time in the session (the measurements' ``time_s``), s:
        with it, the presses' forces at the hold's start are tested for a
        trend over the session (a gel that softens does not recover between
        presses; a relaxing one does).
    press_group : mapping of int to object, optional
        Each press's depth group (its indenter): the trend compares presses
        of one group only. Default: one group (the forces then mix depths,
        and the trend is blurred by them).

    Returns
    -------
    RelaxationFit

    Raises
    ------
    InputError
        For arrays of different lengths, non-finite times or forces, fewer
        than 3 presses, a hold with fewer than 5 samples, or holds of
        non-positive force.

    Notes
    -----
    The model (module docstring): F_i(t) = P_i [(1 - g) + g phi(T_i / tau)
    exp(-t / tau)], one P_i per press, g and tau shared. For given (g, tau)
    the P_i are linear and solved for; (g, log tau) by
    :func:`scipy.optimize.least_squares` from the best of a grid.

    What the holds identify (issue 39: a gel that only softened over a
    session was reported relaxing with g 0.99 and tau 997 s):

    1. A decay at all: the fit against a constant force per press (F test,
       2 and n - P - 2 degrees of freedom on the block means, p <
       :data:`RELAX_ALPHA`); else ``'flat'``.
    2. tau: only by the decay's curvature. A hold much shorter than tau
       shows a straight line, F_i = A_i (1 + r t), along which g and tau
       trade off with g / tau fixed; the fit must beat that straight decay
       (F test, 1 degree of freedom, p < :data:`RELAX_ALPHA`), which bounds
       tau's profile above, and tau must lie within :data:`TAU_HOLD_RATIO`
       times the longest hold. The profile interval of tau (g and the P_i
       refitted at each tau, within the F quantile at `confidence`) is
       reported either way (``tau_profile_ci_s``). tau must also reach
       :data:`TAU_MIN_HOLD_FRACTION` of the shortest hold: a faster decay
       is spent in the hold's first instants, its shape not resolved.
    3. Softening, not relaxation: relaxation recovers between presses, so
       the presses start from the same force at the same depth; a gel that
       softens over the session starts each press lower. With
       `press_time_s`, the presses' forces at the hold's start (a line
       through each hold) are regressed, in logarithm, on the session's
       time with a level per `press_group`; a trend beyond three standard
       errors, of the holds' sign, and agreeing with the holds' own rate
       within three standard errors of their difference, explains the holds
       when they do not show a curvature (2): ``'softening'``.
    4. Otherwise a decay whose tau is not identified: ``'decay not
       identified'``; only the initial rate is (``decay_rate_per_s``).

    ``resolved`` (and g and tau reported as the gel's) only for
    ``'relaxing'``: identified (2), g's bootstrap interval above 0.
    """
    press, t, f, ramp, ids = _check_holds(press, t_s, fz_n, ramp_s, confidence)
    notes = []
    curves, ramps = _hold_curves(press, t, f, ramp, ids, points_per_press, notes)
    span = float(np.median([c[0][-1] for c in curves]))
    g, tau, amps, rmse = _fit_shared(curves, span)
    tests = _hold_tests(curves, tau, rmse, confidence)
    boot, g_ci, tau_ci = _bootstrap(curves, g, tau, confidence, n_boot, seed,
                                    tests.identified)
    # relaxation recovers between presses, softening does not: the presses' forces at the
    # hold's start, against the session's time, each depth apart
    r_w, se_w, starts = _decay_rate(curves)
    r_b, se_b = _trend(ids, starts, press_time_s, press_group)
    verdict, why = _verdict(tests, g_ci[0], tau, r_w, se_w, r_b, se_b)
    notes.append(why)
    if verdict == "relaxing" and span < 0.3 * tau:
        notes.append(f"the holds last {span:.3g} s, under a third of tau = {tau:.3g} s: the "
                     "relaxed level is extrapolated; a longer hold pins it down")
    return RelaxationFit(g=g, tau_s=tau, g_ci=g_ci, tau_ci_s=tau_ci, confidence=confidence,
                         elastic_force_n={int(i): float(a) for i, a in zip(ids, amps,
                                                                         strict=True)},
                         ramp_s=ramps, rmse_n=rmse, n_presses=int(ids.size),
                         n_samples=int(t.size), resolved=verdict == "relaxing",
                         p_value=tests.p_value, notes=tuple(notes), boot=boot, verdict=verdict,
                         why=why, identified=tests.identified,
                         tau_profile_ci_s=tests.profile_ci,
                         curvature_p_value=tests.curv_p, longest_hold_s=tests.longest,
                         decay_rate_per_s=r_w, decay_rate_se_per_s=se_w, trend_per_s=r_b,
                         trend_se_per_s=se_b)


def _check_holds(press: np.ndarray, t_s: np.ndarray, fz_n: np.ndarray,
                 ramp_s: np.ndarray | None, confidence: float
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Check :func:`fit_relaxation`'s inputs; return press, t, f, ramp and the press ids."""
    press = np.asarray(press)
    t = np.asarray(t_s, np.float64)
    f = np.asarray(fz_n, np.float64)
    if not (press.shape == t.shape == f.shape) or press.ndim != 1:
        raise InputError(f"press, t_s and fz_n must be 1-D of one length, got {press.shape}, "
                         f"{t.shape} and {f.shape}")
    ramp = (np.full(t.shape, np.nan) if ramp_s is None
            else np.asarray(ramp_s, np.float64))
    if ramp.shape != t.shape:
        raise InputError(f"ramp_s must have the length of t_s, got {ramp.shape}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(f))):
        raise InputError("t_s and fz_n must be finite")
    if np.any(ramp[np.isfinite(ramp)] < 0):
        raise InputError("ramp_s must not be negative")
    if not 0 < confidence < 1:
        raise InputError(f"confidence must be in (0, 1), got {confidence!r}")
    ids = np.unique(press)
    if ids.size < 3:
        raise InputError(f"need the holds of at least 3 presses, got {ids.size}")
    return press, t, f, ramp, ids


def _hold_curves(press: np.ndarray, t: np.ndarray, f: np.ndarray, ramp: np.ndarray,
                 ids: np.ndarray, points_per_press: int, notes: list[str]
                 ) -> tuple[list[tuple[np.ndarray, np.ndarray, float]], dict[int, float]]:
    """Each press's hold in block means, with its loading time; notes on missing ones."""
    known = {int(i): float(np.nanmedian(ramp[press == i])) for i in ids
             if np.any(np.isfinite(ramp[press == i]))}
    if known:
        fill = float(np.median(list(known.values())))
        if len(known) < ids.size:
            notes.append(f"{ids.size - len(known)} presses have no loading time: the median "
                         f"of the others, {fill:.3g} s, is used")
    else:
        fill = 0.0
        notes.append("no loading times (ramp_s): the presses are taken as loaded at once, "
                     "which underestimates g when the ramp lasts a good part of tau")
    curves, ramps = [], {}
    for i in ids:
        sel = press == i
        ti, fi = t[sel], f[sel]
        order = np.argsort(ti)
        ti, fi = ti[order], fi[order]
        if ti.size < 5:
            raise InputError(f"the hold of press {int(i)} has {ti.size} samples, fewer than 5")
        if np.mean(fi) <= 0:
            raise InputError(f"the hold of press {int(i)} has a mean force of "
                             f"{np.mean(fi):.3g} N: a press pushes into the gel (fz_n > 0)")
        r = known.get(int(i), fill)
        ramps[int(i)] = r
        curves.append((*hold_blocks(ti, fi, points_per_press), r))
    return curves, ramps


def _fit_shared(curves: list[tuple[np.ndarray, np.ndarray, float]], span: float
                ) -> tuple[float, float, np.ndarray, float]:
    """g, tau, the presses' amplitudes and the rmse, from the best start of a grid."""
    # the start: the best of a grid (tau from a tenth of the hold to ten holds)
    best = (np.inf, 0.1, np.log(max(span, 1e-3)))
    for tau in np.geomspace(max(span, 1e-3) / 10, max(span, 1e-3) * 10, 5):
        gs, ls, _, rm = _solve(curves, (0.2, np.log(tau)))
        if rm < best[0]:
            best = (rm, gs, np.log(ls))
    return _solve(curves, best[1:])


@dataclass(frozen=True)
class _HoldTests:
    """What the holds identify (:func:`fit_relaxation`, Notes 1 and 2)."""

    p_value: float
    curv_p: float
    profile_ci: tuple[float, float]
    identified: bool
    longest: float
    shortest: float


def _hold_tests(curves: list[tuple[np.ndarray, np.ndarray, float]], tau: float, rmse: float,
                confidence: float) -> _HoldTests:
    """The F tests of a decay and of its curvature, and tau's profile interval."""
    # seen at all? an F test of the fit against a constant force per press (g = 0), on the
    # block means (which whiten the F/T noise); the bootstrap's interval alone is not enough:
    # on a flat hold the fit can park tau at a few ms and g anywhere
    n_pts = sum(c[0].size for c in curves)
    rss1 = rmse ** 2 * n_pts
    rss0 = float(sum(np.sum((c[1] - c[1].mean()) ** 2) for c in curves))
    dof = max(n_pts - len(curves) - 2, 1)
    s2 = max(rss1 / dof, 1e-300)
    p_value = float(stats.f.sf(max(rss0 - rss1, 0.0) / 2 / s2, 2, dof))
    # identified? a straight decay (tau -> infinity at a fixed g / tau) against the fit:
    # the decay's curvature is what pins tau; then the profile of tau at `confidence`
    longest = float(max(c[0][-1] for c in curves))
    shortest = float(min(c[0][-1] for c in curves))
    _, rss_line = straight_decay(curves)
    curv_p = float(stats.f.sf(max(rss_line - rss1, 0.0) / s2, 1, dof))
    crit = s2 * float(stats.f.ppf(confidence, 1, dof))
    profile_ci = _tau_profile(curves, tau, rss1, crit, rss_line, rss0, longest)
    span_ok = TAU_MIN_HOLD_FRACTION * shortest <= tau <= TAU_HOLD_RATIO * longest
    identified = bool(p_value < RELAX_ALPHA and curv_p < RELAX_ALPHA and span_ok)
    return _HoldTests(p_value=p_value, curv_p=curv_p, profile_ci=profile_ci,
                      identified=identified, longest=longest, shortest=shortest)


def _bootstrap(curves: list[tuple[np.ndarray, np.ndarray, float]], g: float, tau: float,
               confidence: float, n_boot: int, seed: int, identified: bool
               ) -> tuple[np.ndarray, tuple[float, float], tuple[float, float]]:
    """Bootstrap draws of (g, tau) over the presses and their percentile intervals."""
    q = [(1 - confidence) / 2 * 100, (1 + confidence) / 2 * 100]
    draws = []
    if identified:                        # intervals only for a relaxation that is there
        rng = np.random.default_rng(seed)
        for _ in range(int(n_boot)):
            pick = rng.integers(0, len(curves), len(curves))
            gb, taub, _, _ = _solve([curves[j] for j in pick], (g, np.log(tau)))
            draws.append((gb, taub))
    boot = np.array(draws, np.float64).reshape(-1, 2)
    if boot.shape[0]:
        g_ci = tuple(float(v) for v in np.percentile(boot[:, 0], q))
        tau_ci = tuple(float(v) for v in np.percentile(boot[:, 1], q))
    else:
        g_ci, tau_ci = (np.nan, np.nan), (np.nan, np.nan)
    return boot, g_ci, tau_ci


def _verdict(tests: _HoldTests, g_lo: float, tau: float, r_w: float, se_w: float, r_b: float,
             se_b: float) -> tuple[str, str]:
    """The verdict on the holds and why (:func:`fit_relaxation`, Notes 1 to 4)."""
    p_value, curv_p = tests.p_value, tests.curv_p
    shortest, longest = tests.shortest, tests.longest
    softening = bool(np.isfinite(r_b) and abs(r_b) > 3.0 * se_b and r_b * r_w > 0
                     and abs(r_w - r_b) <= 3.0 * math.hypot(se_w, se_b))
    pct = f"{100 * r_w:+.3g} %/s (se {100 * se_w:.2g})"
    trend = (f"{100 * r_b:+.3g} %/s (se {100 * se_b:.2g}) over the session"
             if np.isfinite(r_b) else "")
    if p_value >= RELAX_ALPHA:
        verdict = "flat"
        why = (f"the holds are as flat as their noise allows (F test against a constant force "
               f"per press, p = {p_value:.2g}): no relaxation")
    elif tests.identified and g_lo > 0.0:
        verdict = "relaxing"
        why = (f"the holds relax with a curvature that pins tau (a straight decay is rejected, "
               f"p = {curv_p:.2g}; tau = {tau:.3g} s lies within the span the holds resolve, "
               f"{TAU_MIN_HOLD_FRACTION:g} of the shortest hold to {TAU_HOLD_RATIO:g} times the "
               f"longest: {TAU_MIN_HOLD_FRACTION * shortest:.3g} to "
               f"{TAU_HOLD_RATIO * longest:.3g} s)")
        if softening:
            why += (f"; the presses' forces also trend between presses ({trend}): a gel that "
                    "softens too")
    elif softening:
        verdict = "softening"
        why = (f"the holds fall at {pct}, as the presses' forces at the same depth fall "
               f"between presses ({trend}): the gel softens over the session, which does not "
               "recover between presses as relaxation would; not relaxation (the stiffness "
               "trend along time_s explains the holds"
               + (f": a straight decay fits them as well, p = {curv_p:.2g})"
                  if curv_p >= RELAX_ALPHA else ")"))
    else:
        verdict = "decay not identified"
        why = _not_identified_why(curv_p, tau, shortest, longest, pct, trend,
                                  r_w, se_w, r_b, se_b)
    return verdict, why


#: What ``E_mpa`` is where the holds decay but g and tau are not identified (``headline_E``
#: of fit.json): the force windows sit somewhere on the decay, so E is neither E_0 nor
#: E_inf; E_0 is at least it. (A gel that has not recovered between presses starts each
#: one low: with g 0.3, tau 60 s and rests of 4 to 5 s, E read 0.1398 MPa where E_inf was
#: 0.14, so no lower bound is claimed.)
APPARENT_E_WHY = ("the modulus the force windows read, neither the instantaneous E_0 nor "
                  "the relaxed E_inf: the holds decay, but g and tau are not identified; E_0 "
                  "is at least this")
APPARENT_E = f"E_mpa is {APPARENT_E_WHY}"


def _not_identified_why(curv_p: float, tau: float, shortest: float, longest: float, pct: str,
                        trend: str, r_w: float, se_w: float, r_b: float, se_b: float) -> str:
    """Why a decay's tau is not identified (the verdict 'decay not identified')."""
    reason = (f"the decay is straight within the noise (p = {curv_p:.2g} against the fit)"
              if curv_p >= RELAX_ALPHA else
              f"tau = {tau:.3g} s lies beyond {TAU_HOLD_RATIO:g} times the longest hold "
              f"({longest:.3g} s)" if tau > TAU_HOLD_RATIO * longest else
              f"tau = {tau:.3g} s lies under {TAU_MIN_HOLD_FRACTION:g} of the shortest "
              f"hold ({shortest:.3g} s): a drop in the hold's first instants, its shape "
              "not resolved")
    return (f"the holds fall at {pct} (a line through each), but tau is not identified: "
            f"{reason}; only that rate is (g phi / tau = {-r_w:.3g} 1/s for a slow "
            "relaxation): g and tau are not reported and the gel is not called relaxing; "
            "longer holds, or holds of different lengths, would tell"
            + ("" if not trend else
               f" (the presses' forces at one depth move by {trend} between presses"
               + ("; the same rate as the holds', too weak alone to name a softening gel "
                  "(3 se): diagnose's structure along time_s tells"
                  if abs(r_w - r_b) <= 3.0 * math.hypot(se_w, se_b) and r_b * r_w > 0
                  else "") + ")"))


def straight_decay(curves: list[tuple[np.ndarray, np.ndarray, float]]) -> tuple[float, float]:
    """F_i(t) = A_i (1 + r t), r shared: the limit of the model as tau -> infinity at a
    fixed g / tau (``r = -g phi / tau``). Returns r (1/s) and the residual sum of squares
    (the A_i profiled out in closed form)."""
    def rss(r: float) -> float:
        total = 0.0
        for t, f, _ in curves:
            b = 1.0 + r * t
            a = float(b @ f / (b @ b))
            total += float(np.sum((f - a * b) ** 2))
        return total

    longest = max(float(c[0][-1]) for c in curves)
    res = optimize.minimize_scalar(rss, bounds=(-0.9 / max(longest, 1e-9), 10.0),
                                   method="bounded", options={"xatol": 1e-10})
    return float(res.x), float(res.fun)


def _tau_profile(curves: list[tuple[np.ndarray, np.ndarray, float]], tau: float, rss1: float,
                 crit: float, rss_line: float, rss_flat: float, longest: float
                 ) -> tuple[float, float]:
    """The interval of tau whose profile (g and the amplitudes refitted) stays within
    `crit` of the best fit: an end is 0 or inf when the flat hold (tau -> 0) or the straight
    decay (tau -> infinity) is itself within `crit`."""
    def prof(tt: float) -> float:
        def rss_g(g: float) -> float:
            total = 0.0
            for t, f, ramp in curves:
                b = (1.0 - g) + g * ramp_factor(ramp, tt) * np.exp(-t / tt)
                a = float(b @ f / (b @ b))
                total += float(np.sum((f - a * b) ** 2))
            return total

        return float(optimize.minimize_scalar(rss_g, bounds=(0.0, 0.99), method="bounded",
                                              options={"xatol": 1e-6}).fun)

    def last_inside(factor: float) -> float:
        """Walk out from tau by up to `factor` until the profile leaves the interval."""
        inside = tau
        for tt in tau * np.geomspace(1.0, factor, 25)[1:]:
            if prof(tt) - rss1 > crit:
                break
            inside = tt
        return float(inside)

    lo = 0.0 if rss_flat - rss1 <= crit else last_inside(1e-3)
    hi = np.inf if rss_line - rss1 <= crit else last_inside(max(1e3, 100 * longest / tau))
    return float(lo), float(hi)


def _decay_rate(curves: list[tuple[np.ndarray, np.ndarray, float]]
                ) -> tuple[float, float, np.ndarray]:
    """A straight line through each hold: the mean over presses of its slope over its value
    at the hold's start (1/s), that mean's standard error, and each press's start value."""
    rates, starts = [], []
    for t, f, _ in curves:
        slope, start = np.polyfit(t, f, 1)
        rates.append(slope / start)
        starts.append(start)
    rates = np.array(rates)
    se = float(np.std(rates, ddof=1) / math.sqrt(rates.size)) if rates.size > 1 else np.inf
    return float(np.mean(rates)), se, np.array(starts)


def _trend(ids: np.ndarray, starts: np.ndarray, press_time_s: Mapping | None,
           press_group: Mapping | None) -> tuple[float, float]:
    """Relative change per second of the presses' start forces over the session, each group
    (depth) with its own level: least squares of log(start) on time with a dummy per group;
    (NaN, NaN) without times or with too few presses."""
    nan = (float("nan"), float("nan"))
    if press_time_s is None:
        return nan
    keep = [k for k, i in enumerate(ids) if int(i) in press_time_s and starts[k] > 0
            and np.isfinite(press_time_s[int(i)])]
    if len(keep) < 4:
        return nan
    tt = np.array([float(press_time_s[int(ids[k])]) for k in keep])
    y = np.log(starts[keep])
    groups = ([press_group.get(int(ids[k]), -1) for k in keep] if press_group is not None
              else [0] * len(keep))
    levels = sorted(set(groups), key=str)
    X = np.column_stack([tt - tt.mean()] + [[1.0 if gr == lv else 0.0 for gr in groups]
                                            for lv in levels])
    dof = X.shape[0] - X.shape[1]
    if dof < 2 or np.ptp(tt) <= 0:
        return nan
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    r = y - X @ coef
    cov = np.linalg.pinv(X.T @ X) * float(r @ r) / dof
    return float(coef[0]), float(np.sqrt(cov[0, 0]))


def _row_ramps(relax: RelaxationFit, n: int, press: np.ndarray | None) -> np.ndarray:
    fill = float(np.median(list(relax.ramp_s.values()))) if relax.ramp_s else 0.0
    if press is None:
        return np.full(n, fill)
    return np.array([relax.ramp_s.get(int(p), fill) if np.isfinite(p) else fill
                     for p in np.asarray(press, np.float64)])


def instantaneous_forces(force_n: np.ndarray, hold_s: np.ndarray, relax: RelaxationFit,
                         press: np.ndarray | None = None) -> np.ndarray:
    """Forces at the instant of loading: each press's force at its hold time, undone.

    Parameters
    ----------
    force_n : (N,) float ndarray
        The table's forces, N, each the mean of a window centred ``hold_s``
        after the press reached its depth.
    hold_s : (N,) float ndarray
        The table's ``hold_s``, s.
    relax : RelaxationFit
    press : (N,) ndarray, optional
        The table's ``press``: each row's loading time is its press's
        (``relax.ramp_s``), else the median of them.

    Returns
    -------
    force0_n : (N,) float64 ndarray
        ``force_n / relax.factor(hold_s, ramp)``: what a gel of the
        instantaneous modulus E_0 pushes back with at those depths.

    Raises
    ------
    InputError
        If the lengths differ or a ``hold_s`` is missing or negative.
    """
    f = np.asarray(force_n, np.float64)
    h = np.asarray(hold_s, np.float64)
    if f.shape != h.shape:
        raise InputError(f"force_n and hold_s must have one length, got {f.shape}, {h.shape}")
    if not np.all(np.isfinite(h)) or np.any(h < 0):
        raise InputError("hold_s must be a non-negative number in every row to undo the "
                         "relaxation")
    return f / relax.factor(h, _row_ramps(relax, f.size, press))


def relaxed_moduli(E0_mpa: float, E0_ci_mpa: tuple[float, float], relax: RelaxationFit,
                   hold_s: np.ndarray, press: np.ndarray | None = None) -> dict[str, object]:
    """E_0 and the relaxed E_inf = (1 - g) E_0, with intervals that carry g's and tau's.

    Parameters
    ----------
    E0_mpa : float
        The modulus fitted to :func:`instantaneous_forces`, MPa.
    E0_ci_mpa : (float, float)
        Its interval from that fit.
    relax : RelaxationFit
    hold_s : (N,) float ndarray
        The table's ``hold_s``.
    press : (N,) ndarray, optional
        The table's ``press``.

    Returns
    -------
    moduli : dict
        ``E0_mpa``, ``E0_ci_mpa``, ``E_inf_mpa``, ``E_inf_ci_mpa`` (an
        interval's end that cannot be computed, e.g. from a fit without an
        interval of E, is None).

    Notes
    -----
    E scales with the forces, so a bootstrap draw (g_b, tau_b) moves E_0 by
    the mean of the rows' factors F(hold)/P_0 under the fit over that under
    the draw, and E_inf by (1 - g_b) on top. The spread of the draws
    (percentiles at ``relax.confidence``, taken relative to the point
    values) and the fit's own interval are added in quadrature on each side:
    a first-order combination of independent errors.
    """
    h = np.asarray(hold_s, np.float64)
    ramps = _row_ramps(relax, h.size, press)
    base = float(np.mean(relax.factor(h, ramps)))
    e_inf = (1.0 - relax.g) * E0_mpa
    q = [(1 - relax.confidence) / 2 * 100, (1 + relax.confidence) / 2 * 100]
    if relax.boot.shape[0]:
        e0_b = np.array([E0_mpa * base / float(np.mean(relax.factor(h, ramps, g, tau)))
                         for g, tau in relax.boot])
        einf_b = (1.0 - relax.boot[:, 0]) * e0_b
    else:
        e0_b = einf_b = np.array([E0_mpa])

    def combine(point: float, draws: np.ndarray) -> tuple[float, float]:
        lo_d, hi_d = (float(v) for v in np.percentile(draws, q))
        lo_f = (E0_ci_mpa[0] - E0_mpa) / E0_mpa * point
        hi_f = (E0_ci_mpa[1] - E0_mpa) / E0_mpa * point
        return (point - float(np.hypot(point - lo_d, lo_f)),
                point + float(np.hypot(hi_d - point, hi_f)))

    def clean(v: tuple[float, float]) -> tuple[float | None, float | None]:
        return tuple(float(x) if np.isfinite(x) else None for x in v)

    return {"E0_mpa": E0_mpa, "E0_ci_mpa": clean(combine(E0_mpa, e0_b)),
            "E_inf_mpa": e_inf, "E_inf_ci_mpa": clean(combine(e_inf, einf_b))}
