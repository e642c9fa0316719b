"""g and tau refined on the whole F/T log: each hold carries the memory of the presses before.

:func:`~tactilevision.mechanics.fit_relaxation` fits each hold as if the gel had been
at rest before its press. A gel whose tau is a good part of the rests between presses
has not recovered from the previous press when the next begins: each hold then also
recovers from the last release while it relaxes from its own loading, which flattens
it, and g comes out low (0.288 for 0.334 at tau 2.1 s, with rests of 1.5 to 2.5 s:
``benchmarks/bench_relaxation_identified.py``).

The log knows the whole history. By Boltzmann superposition the elastic force behind
it, P = (1 - a z^-1) / (1 - b z^-1) F (:func:`~tactilevision.mechanics.elastic_force`),
follows the depth at every instant, whatever came before: during a hold the depth
stands still, so P must too. :func:`refine_relaxation` finds the (g, tau) that make
the elastic force behind the log flattest over every hold, from the holds' own fit as
the start; its covariance is the sandwich of the residuals clustered by hold (the
samples of one hold are not independent, the holds are).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from scipy import optimize, stats

from .._checks import InputError, check_array
from ._relaxation import RelaxationFit, elastic_force

__all__ = ["refine_relaxation"]


def _hold_residuals(t: np.ndarray, f: np.ndarray, holds: list[np.ndarray], g: float,
                    tau: float, n_points: int) -> list[np.ndarray]:
    """The elastic force behind the log, less its mean, over each hold (block means)."""
    p = elastic_force(t, f, g, tau)
    out = []
    for sel in holds:
        v = p[sel]
        k = max(1, v.size // n_points)
        m = (v.size // k) * k
        b = v[:m].reshape(-1, k).mean(axis=1)
        out.append(b - b.mean())
    return out


def refine_relaxation(force_times_s: np.ndarray, fz_n: np.ndarray, holds_s: np.ndarray,
                      relax: RelaxationFit, *, n_points: int = 100, n_draws: int = 200,
                      seed: int = 0) -> RelaxationFit:
    """Refine a relaxing gel's g and tau on the whole F/T log (module docstring).

    Parameters
    ----------
    force_times_s : (M,) float ndarray
        F/T sample times, evenly spaced, s.
    fz_n : (M,) float ndarray
        Normal force, N, with the F/T's zero taken off (the filter's gain at
        rest is 1 / (1 - g)).
    holds_s : (K, 2) float ndarray
        Start and end of each hold on the F/T clock, s (the presses' arrival
        at depth and the start of their release).
    relax : RelaxationFit
        The holds' own fit (:func:`~tactilevision.mechanics.fit_relaxation`);
        returned unchanged unless it is ``resolved``.
    n_points : int, default 100
        Each hold's elastic force is averaged in blocks down to this many
        points.
    n_draws : int, default 200
        Draws of (g, tau) from the refined covariance, kept as ``boot`` for
        :func:`~tactilevision.mechanics.relaxed_moduli`.
    seed : int, default 0

    Returns
    -------
    RelaxationFit
        `relax` with g, tau, their intervals (from the clustered sandwich
        covariance, normal in g and log tau) and ``boot`` replaced, and a
        note; `relax` itself when the refinement fails or moves nothing.

    Raises
    ------
    ShapeError
        For arrays of the wrong shape or with NaNs.
    InputError
        For fewer than three holds of 10 samples.
    """
    t = check_array(force_times_s, "force_times_s", [("M",)], dtype=np.number,
                    finite=True).astype(np.float64)
    f = check_array(fz_n, "fz_n", [(t.shape[0],)], dtype=np.number,
                    finite=True).astype(np.float64)
    hs = check_array(holds_s, "holds_s", [("K", 2)], dtype=np.number, finite=True)
    if not relax.resolved:
        return relax
    holds = [np.flatnonzero((t >= a) & (t <= b)) for a, b in hs]
    holds = [h for h in holds if h.size >= 10]
    if len(holds) < 3:
        raise InputError(f"need at least 3 holds of 10 samples in the log, got {len(holds)}")

    def resid(x: np.ndarray) -> np.ndarray:
        g, tau = float(x[0]), float(np.exp(x[1]))
        return np.concatenate(_hold_residuals(t, f, holds, g, tau, n_points))

    x0 = np.array([min(max(relax.g, 0.01), 0.95), math.log(relax.tau_s)])
    sol = optimize.least_squares(resid, x0, bounds=([0.0, math.log(1e-3)], [0.99, math.log(1e5)]),
                                 x_scale=[0.1, 1.0], diff_step=1e-4)
    if not sol.success:
        return relax
    g, tau = float(sol.x[0]), float(np.exp(sol.x[1]))
    # sandwich covariance, the residuals clustered by hold
    J = sol.jac
    sizes = [r.size for r in _hold_residuals(t, f, holds, g, tau, n_points)]
    r = sol.fun
    bread = np.linalg.pinv(J.T @ J)
    meat = np.zeros((2, 2))
    start = 0
    for n in sizes:
        s = J[start:start + n].T @ r[start:start + n]
        meat += np.outer(s, s)
        start += n
    k = len(sizes)
    cov = bread @ meat @ bread * k / max(k - 1, 1)
    tq = float(stats.t.ppf(0.5 + relax.confidence / 2, max(k - 2, 1)))
    se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    g_ci = (max(g - tq * se[0], 0.0), min(g + tq * se[0], 0.99))
    tau_ci = (tau * math.exp(-tq * se[1]), tau * math.exp(tq * se[1]))
    rng = np.random.default_rng(seed)
    draws = rng.multivariate_normal(sol.x, cov, size=n_draws)
    boot = np.column_stack([np.clip(draws[:, 0], 0.0, 0.99), np.exp(draws[:, 1])])
    note = (f"g and tau refined on the whole F/T log (the elastic force behind it held flat "
            f"over every hold, each hold's memory of the presses before it included): "
            f"g {relax.g:.4f} -> {g:.4f}, tau {relax.tau_s:.4g} -> {tau:.4g} s; intervals from "
            f"the sandwich covariance clustered by hold ({k} holds)")
    return replace(relax, g=g, tau_s=tau, g_ci=g_ci, tau_ci_s=tau_ci, boot=boot,
                   notes=(*relax.notes, note))
