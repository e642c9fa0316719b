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

from dataclasses import dataclass, field

import numpy as np

from .._checks import InputError

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
        Whether relaxation is seen: the interval of g excludes 0 and the fit
        beats a constant force per press (F test, p < 0.001).
    p_value : float
        That F test's p-value.
    notes : tuple of str
    boot : (B, 2) float64 ndarray
        The bootstrap's (g, tau_s) draws, for propagating the uncertainty.
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

        return {"model": "standard linear solid, linear ramp then hold (Boltzmann "
                         "superposition)",
                "g": clean(self.g), "g_ci": [clean(v) for v in self.g_ci],
                "tau_s": clean(self.tau_s), "tau_ci_s": [clean(v) for v in self.tau_ci_s],
                "confidence": self.confidence, "resolved": self.resolved,
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
    from scipy.signal import lfilter

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


def _blocks(t: np.ndarray, f: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    k = max(1, -(-t.size // n))
    m = t.size // k
    return t[: m * k].reshape(m, k).mean(1), f[: m * k].reshape(m, k).mean(1)


def _solve(curves: list[tuple[np.ndarray, np.ndarray, float]], start: tuple[float, float]
           ) -> tuple[float, float, np.ndarray, float]:
    """Least squares over (g, log tau), each press's amplitude profiled out."""
    from scipy.optimize import least_squares

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
                   seed: int = 0) -> RelaxationFit:
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
    :func:`scipy.optimize.least_squares` from the best of a grid. tau is only
    determined by holds that last a good part of it: a hold much shorter
    than tau shows a straight line, along which g and tau trade off (wide
    intervals say so).
    """
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
    notes = []
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
        curves.append((*_blocks(ti, fi, points_per_press), r))
    span = float(np.median([c[0][-1] for c in curves]))
    # the start: the best of a grid (tau from a tenth of the hold to ten holds)
    best = (np.inf, 0.1, np.log(max(span, 1e-3)))
    for tau in np.geomspace(max(span, 1e-3) / 10, max(span, 1e-3) * 10, 5):
        gs, ls, _, rm = _solve(curves, (0.2, np.log(tau)))
        if rm < best[0]:
            best = (rm, gs, np.log(ls))
    g, tau, amps, rmse = _solve(curves, best[1:])
    # seen at all? an F test of the fit against a constant force per press (g = 0), on the
    # block means (which whiten the F/T noise); the bootstrap's interval alone is not enough:
    # on a flat hold the fit can park tau at a few ms and g anywhere
    from scipy.stats import f as f_dist

    n_pts = sum(c[0].size for c in curves)
    rss1 = rmse ** 2 * n_pts
    rss0 = float(sum(np.sum((c[1] - c[1].mean()) ** 2) for c in curves))
    dof = max(n_pts - len(curves) - 2, 1)
    f_stat = max(rss0 - rss1, 0.0) / 2 / max(rss1 / dof, 1e-300)
    p_value = float(f_dist.sf(f_stat, 2, dof))
    q = [(1 - confidence) / 2 * 100, (1 + confidence) / 2 * 100]
    draws = []
    if p_value < 1e-3:                   # intervals only for a relaxation that is there
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
    resolved = bool(p_value < 1e-3 and g_ci[0] > 0.0)
    if not resolved:
        notes.append(f"no relaxation resolved: the holds are as flat as their noise allows "
                     f"(F test against a constant force, p = {p_value:.2g})")
    if span < 0.3 * tau:
        notes.append(f"the holds last {span:.3g} s, under a third of tau = {tau:.3g} s: the "
                     "relaxed level is extrapolated; a longer hold pins it down")
    return RelaxationFit(g=g, tau_s=tau, g_ci=g_ci, tau_ci_s=tau_ci, confidence=confidence,
                         elastic_force_n={int(i): float(a) for i, a in zip(ids, amps,
                                                                         strict=True)},
                         ramp_s=ramps, rmse_n=rmse, n_presses=int(ids.size),
                         n_samples=int(t.size), resolved=resolved, p_value=p_value,
                         notes=tuple(notes),
                         boot=boot)


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
