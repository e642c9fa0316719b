"""The crossing forces read as the brackets they are: a likelihood for changes within indenters.

Each press's crossing force is bracketed, not measured: the land crossed w0 at a moment
within the frame period before its mark first showed, while fz ran from ``lo`` to ``hi``
(``force_w0_n -+ sqrt(3) force_w0_sem_n``: the certification states the crossing as uniform
over that period). Within one indenter every press crossed the same w0, so with nothing
changing one force P_g lies in all of its presses' brackets; with a stiffness changed by
the relative amount ``delta z_i`` at press i, ``P_g (1 + delta z_i)`` lies in bracket i.
With each crossing uniform over its bracket (density 1 / width where the bracket holds the
force) and P_g integrated out over log P_g (a force's scale is what is unknown, so no size
of change is favoured for scaling a whole indenter), an indenter's likelihood of delta is
the length of the intersection of its brackets in log force, each shifted back by
``log(1 + delta z_i)``, over the product of their widths; the session's is the product
over indenters. (Integrated over P_g itself, an indenter whose presses all lie on the
changed side would gain ``-log(1 + delta)`` from nothing: 0.68 at the grid's -49 %.)

A bracket's edges are not exact (the 10 ms smoothing of fz, the clock offset's error, a
frame's timing): each intersection's length ``l`` is softened to ``s log(1 + exp(l / s))``,
``s`` :data:`BRACKET_SOFTNESS` of the indenter's mean bracket width (in log force), so a
bracket a little off lowers the likelihood instead of zeroing it, and the null below
jitters the edges by that much.

A test's statistic is the log-likelihood's gain at its best delta (a grid,
:data:`BRACKET_DELTAS`) over delta = 0. Its distribution with nothing changing comes from
brackets drawn from the same model: each press's crossing at a uniform place in a bracket
of its own width (relative to its indenter's force), the edges jittered by ``s``. One noise
model: what the certification states (a uniform crossing over a frame period) is what the
tests read and what their null draws.

Why not the brackets' midpoints with sd width / sqrt(12): that reading spends what the
intervals say. n brackets at random places pin a common force to about 2 / (n + 1) of one
bracket's width (their intersection), their midpoints' mean to about 1 / sqrt(3 n). On
two mark sessions rendered by Taxim (20 presses each, 10 and 15 frames/s, brackets 7 to 29
% of the force), a 10 % stiffness step half-way, a 10 % softening over the session and a
gradient of 1 %/mm across the pad were named at the family-wise 1 % by this likelihood in
6 of 6, where the midpoints' least squares named 1 of 6; on four sessions rendered after
it was written, in 9 of 12 (the three misses a gradient below what those sessions' own
brackets can see; docs/guide/diagnose.md).
"""

from __future__ import annotations

import numpy as np

__all__ = ["BRACKET_DELTAS", "BRACKET_SOFTNESS", "bracket_draws", "bracket_gains",
           "residual_scatter", "worst_residual"]

#: The softness of a bracket's edges, a fraction of its width (module docstring).
BRACKET_SOFTNESS = 0.02
#: The relative changes the likelihood is profiled over: a step's size, or a trend's change
#: over the column's range in the table (its shape is scaled to a range of 1). Geometric,
#: 0.1 % to 49 % each way in steps of 20 % of the size: as fine for a design whose brackets
#: are 1 % wide as for one whose are 30 %.
BRACKET_DELTAS = np.r_[-1e-3 * 1.2 ** np.arange(34, -1, -1), 0.0, 1e-3 * 1.2 ** np.arange(35)]
#: Log-likelihoods within this of each other are a tie (a plateau of the maximum).
_TIE = 1e-12
#: Draws per block when the gains are computed for many draws at once (memory).
_BLOCK = 256


def bracket_gains(lo: np.ndarray, hi: np.ndarray, groups: np.ndarray, shapes: np.ndarray,
                  deltas: np.ndarray = BRACKET_DELTAS) -> tuple[np.ndarray, np.ndarray]:
    """Each shape's log-likelihood gain at its best size over none, for each set of brackets.

    Parameters
    ----------
    lo, hi : (D, N) float ndarray
        D sets of N brackets, each relative to its indenter's force (``hi > lo``).
    groups : (N,) int ndarray
        Each press's indenter, 0 to G - 1.
    shapes : (K, N) float ndarray
        Each test's shape z (a press's relative change is ``delta z_i``), ``|z| <= 1``.
        A shape of zeros and ones (a step) is computed from its two sides' intersections
        alone; identical shapes once.
    deltas : (M,) float ndarray, default :data:`BRACKET_DELTAS`
        The sizes tried (0 among them), each above -1.

    Returns
    -------
    gain : (D, K) float64 ndarray
        ``max over delta of log L(delta) - log L(0)`` (>= 0), delta on `deltas`.
    delta : (D, K) float64 ndarray
        The delta that reaches it.
    """
    lo, hi = np.atleast_2d(lo), np.atleast_2d(hi)
    order = np.argsort(groups, kind="stable")
    g = np.asarray(groups)[order]
    starts = np.flatnonzero(np.r_[True, g[1:] != g[:-1]])
    # in log force: a change shifts a bracket by -log(1 + delta z) (lo kept above 0)
    lo = np.log(np.maximum(lo[:, order], 1e-9))
    hi = np.log(np.maximum(hi[:, order], 2e-9))
    z_all = np.asarray(shapes, np.float64)[:, order]
    width = np.mean(hi - lo, axis=0)
    soft = BRACKET_SOFTNESS * np.add.reduceat(width, starts) / np.diff(np.r_[starts, g.size])
    deltas = np.asarray(deltas, np.float64)
    zero = int(np.argmin(np.abs(deltas)))
    n_draws = lo.shape[0]
    gain = np.empty((n_draws, z_all.shape[0]))
    best = np.empty((n_draws, z_all.shape[0]))
    unique, back = np.unique(z_all, axis=0, return_inverse=True)
    is_step = np.all((unique == 0) | (unique == 1), axis=1)
    if np.any(is_step):
        g_s, d_s = _step_search(lo, hi, unique[is_step], starts, deltas, soft, zero)
        for i, k in enumerate(np.flatnonzero(is_step)):
            cols = np.flatnonzero(back.ravel() == k)
            gain[:, cols], best[:, cols] = g_s[i][:, None], d_s[i][:, None]
    for k in np.flatnonzero(~is_step):
        zk, cols = unique[k], np.flatnonzero(back.ravel() == k)
        for a in range(0, n_draws, _BLOCK):
            b = min(a + _BLOCK, n_draws)
            low, high = _bounds(lo[a:b], hi[a:b], zk, starts, deltas)
            ll = np.sum(_log_softplus((high - low) / soft) + np.log(soft), axis=2)
            j = np.argmax(ll, axis=1)
            gain[a:b, cols] = (ll[np.arange(b - a), j] - ll[:, zero])[:, None]
            best[a:b, cols] = deltas[j][:, None]
    return gain, best


def _log_softplus(x: np.ndarray) -> np.ndarray:
    """``log(log(1 + exp(x)))``, without underflow far below 0 (where it is x).

    The softplus as ``max(x, 0) + log1p(exp(-|x|))``: the same to 4e-15 as
    ``np.logaddexp(0, x)`` on (256, 70, 5) arrays of x ~ N(0, 10), and faster: a
    ``crossing_tests`` call on a 20-press table with a 10 % step took 0.248 and 0.289 s
    against 0.278 and 0.346 s with ``logaddexp`` (alternating in one run, this project's
    2-core machine under load), where the profile had put a third of its time here."""
    soft = np.maximum(x, 0.0) + np.log1p(np.exp(-np.abs(x)))
    with np.errstate(divide="ignore"):
        out = np.log(soft)
    return np.where(x < -30.0, x, out)


def _bounds(lo: np.ndarray, hi: np.ndarray, z: np.ndarray, starts: np.ndarray,
            deltas: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each indenter's intersection ends (B, M, G) in log force at every delta, any shape z
    (`lo`, `hi` in log force)."""
    shift = np.log1p(deltas[:, None] * z[None, :])                        # (M, N)
    return (np.maximum.reduceat(lo[:, None, :] - shift, starts, axis=2),
            np.minimum.reduceat(hi[:, None, :] - shift, starts, axis=2))


def _step_search(lo: np.ndarray, hi: np.ndarray, z: np.ndarray, starts: np.ndarray,
                 deltas: np.ndarray, soft: np.ndarray, zero: int
                 ) -> tuple[np.ndarray, np.ndarray]:
    """The gains (K, D) and their deltas (K, D) for K shapes of zeros and ones (K, N), by
    bisection.

    Each side's intersection is taken once, the side that changes shifted by ``-s``,
    ``s = log(1 + delta)``: an indenter's intersection length ``min(hi0, hi1 - s) -
    max(lo0, lo1 - s)`` is concave in s (a minimum of lines less a maximum of lines), the
    log of the softplus is concave and increasing, so the log-likelihood, their sum over
    indenters, is concave in s and unimodal along the sorted grid of deltas. Its maximum
    is found by bisection on the sign of the forward difference: about 4 log2(M)
    evaluations of a (K, D, G) array where the grid's is M. The gains equal the grid's
    (``np.argmax``) to rounding (1e-13 on random brackets); where the maximum is a plateau
    (within :data:`_TIE`), the delta of the plateau nearest 0 is taken (the least change
    that explains the brackets as well; ``np.argmax`` took whichever rounding favoured).
    """
    one = (z == 1)[:, None, :]                                            # (K, 1, N)
    k, d, g = z.shape[0], lo.shape[0], starts.size
    ends = [np.maximum.reduceat(np.where(one, -np.inf, lo), starts, axis=2),
            np.minimum.reduceat(np.where(one, np.inf, hi), starts, axis=2),
            np.maximum.reduceat(np.where(one, lo, -np.inf), starts, axis=2),
            np.minimum.reduceat(np.where(one, hi, np.inf), starts, axis=2)]
    lo0, hi0, lo1, hi1 = (e.reshape(k * d, g) for e in ends)            # a row per (shape, draw)
    grid = np.unique(deltas)                     # sorted, each size once (no false flat)
    s = np.log1p(grid)
    log_soft = float(np.sum(np.log(soft)))

    def ll(j: np.ndarray, rows: np.ndarray | slice = slice(None)) -> np.ndarray:
        shift = s[j][:, None]
        length = (np.minimum(hi0[rows], hi1[rows] - shift)
                  - np.maximum(lo0[rows], lo1[rows] - shift))
        return np.sum(_log_softplus(length / soft), axis=1) + log_soft

    top = s.size - 1
    zero_at = np.full(k * d, int(np.searchsorted(grid, deltas[zero])))
    first = _bisect(ll, np.zeros_like(zero_at), np.full_like(zero_at, top), _TIE)
    # a plateau only where the next size is as likely: bisect for its end there alone
    last = first.copy()
    flat = np.flatnonzero(ll(np.minimum(first + 1, top)) - ll(first) >= -_TIE)
    if flat.size:
        last[flat] = _bisect(lambda j: ll(j, flat), first[flat],
                             np.full(flat.size, top), -_TIE)
    j = np.clip(zero_at, first, last)
    return (ll(j) - ll(zero_at)).reshape(k, d), grid[j].reshape(k, d)


def _bisect(f, a: np.ndarray, b: np.ndarray, rise: float) -> np.ndarray:
    """Per row, the first index j in [a, b] where ``f(j + 1) - f(j) > rise`` fails, for f
    unimodal along the index (vectorised bisection: f takes an index per row)."""
    top = int(b.max())
    while np.any(a < b):
        mid = (a + b) // 2
        up = f(np.minimum(mid + 1, top)) - f(mid) > rise
        a, b = np.where(up & (a < b), mid + 1, a), np.where(up, b, mid)
    return a


def bracket_draws(width: np.ndarray, n_draws: int, rng: np.random.Generator
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Brackets with nothing changing: each press's crossing at a uniform place in a bracket
    of its width about a force of 1, the edges jittered by the softness.

    Parameters
    ----------
    width : (N,) or (n_draws, N) float ndarray
        Each bracket's width relative to its indenter's force (per draw where 2-D).
    n_draws : int
    rng : numpy.random.Generator

    Returns
    -------
    lo, hi : (n_draws, N) float64 ndarray
    """
    w = np.asarray(width, np.float64)
    u = rng.random((n_draws, w.shape[-1]))
    jitter = rng.standard_normal((n_draws, w.shape[-1])) * (BRACKET_SOFTNESS * w)
    lo = 1.0 - u * w + jitter
    return lo, lo + w


def residual_scatter(r: np.ndarray, groups: np.ndarray, w: np.ndarray, shape: np.ndarray,
                     n_draws: int, rng: np.random.Generator) -> tuple[float, int, float]:
    """The crossing forces' scatter about a fitted change, against what their brackets state.

    Parameters
    ----------
    r : (N,) float ndarray
        Each press's crossing force relative to its indenter's (the brackets' midpoints,
        less 1).
    groups : (N,) array_like
        Each press's indenter.
    w : (N,) float ndarray
        Inverse relative variances (12 / width**2: a uniform crossing over its bracket).
    shape : (N,) float ndarray
        The change fitted beside a mean per indenter (a trend's column, a step's 0/1).
    n_draws : int
    rng : numpy.random.Generator

    Returns
    -------
    chi2 : float
        The weighted residual sum of squares of `r` about a mean per indenter and `shape`
        (weighted least squares).
    dof : int
        N less the fit's rank.
    p_value : float
        The share of `n_draws` sets of brackets drawn from the stated model
        (:func:`bracket_draws`: uniform crossings, the edges jittered) whose midpoints
        scatter as much after the same fit, (hits + 1) / (n_draws + 1): small where the
        forces scatter beyond their statement even with the change.

    Notes
    -----
    The statistic is linear least squares, so its null does not depend on the change's
    size. A step's place, chosen as the one the brackets prefer, is held fixed in the
    draws: the observed scatter after a chosen place is if anything smaller than the
    draws', so the p-value errs large (a statement is less often called too narrow).
    """
    sw, q = _fit_basis(groups, w, shape)

    def chi2(res: np.ndarray) -> np.ndarray:
        rw = res * sw
        return np.sum(rw * rw, axis=1) - np.sum((rw @ q) ** 2, axis=1)

    observed = float(chi2(np.asarray(r, np.float64)[None])[0])
    lo, hi = bracket_draws(np.sqrt(12.0 / sw ** 2), n_draws, rng)
    drawn = chi2(0.5 * (lo + hi) - 1.0)
    return observed, int(sw.size - q.shape[1]), float((np.sum(drawn >= observed) + 1)
                                                       / (n_draws + 1))


def worst_residual(r: np.ndarray, groups: np.ndarray, w: np.ndarray, shape: np.ndarray | None,
                   n_draws: int, rng: np.random.Generator) -> tuple[int, float, float]:
    """The crossing force farthest from its indenter's about a fitted change, against what
    the brackets state.

    Parameters
    ----------
    r, groups, w, n_draws, rng
        As for :func:`residual_scatter`.
    shape : (N,) float ndarray or None
        The change fitted beside a mean per indenter; None for none.

    Returns
    -------
    index : int
        The press whose studentized residual (the weighted least-squares residual over its
        sd, ``sqrt((1 - h) / w)``, h its leverage) is largest in size.
    z : float
        That residual, in its sds.
    p_value : float
        The share of `n_draws` sets of brackets drawn from the stated model whose largest
        studentized residual is as large, (hits + 1) / (n_draws + 1). A uniform crossing
        puts a midpoint within sqrt(3) sds of the force, so a press far beyond that is a
        bracket that does not hold its crossing (a mark's onset misread), whatever changed.
    """
    sw, q = _fit_basis(groups, w, np.zeros(np.asarray(w).size) if shape is None else shape)
    lev = np.clip(1.0 - np.sum(q * q, axis=1), 1e-12, None)

    def stud(res: np.ndarray) -> np.ndarray:
        rw = res * sw
        return (rw - (rw @ q) @ q.T) / np.sqrt(lev)

    z = stud(np.asarray(r, np.float64)[None])[0]
    k = int(np.argmax(np.abs(z)))
    lo, hi = bracket_draws(np.sqrt(12.0 / sw ** 2), n_draws, rng)
    drawn = np.abs(stud(0.5 * (lo + hi) - 1.0)).max(axis=1)
    return k, float(z[k]), float((np.sum(drawn >= abs(z[k])) + 1) / (n_draws + 1))


def _fit_basis(groups: np.ndarray, w: np.ndarray, shape: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
    """sqrt(w) (N,) and an orthonormal basis (N, K) of the weighted fit of a mean per group
    and `shape` (a zero shape adds nothing)."""
    w = np.asarray(w, np.float64)
    _, gid = np.unique(np.asarray(groups), return_inverse=True)
    sw = np.sqrt(w)
    X = np.column_stack([np.eye(int(gid.max()) + 1)[gid], np.asarray(shape, np.float64)])
    u, s, _ = np.linalg.svd(X * sw[:, None], full_matrices=False)
    return sw, u[:, s > s[0] * 1e-10]
