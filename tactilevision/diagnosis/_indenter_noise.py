"""One noise model for a ball's diagnosis: the presses' stated uncertainties, the error
they share, and the fits of every rung against them.

The fit (:func:`tactilevision.mechanics.fit_indenter`) weighs each press by its
effective variance, s0^2 + (dP/dw u)^2 + s_P^2 (u the depth's stated sd, s_P the
force's, s0 by the Paule-Mandel rule), and carries a depth error shared by every press
(a ball's contact circles all off by the detector's bias) as a bound. The diagnosis
uses the same: every rung is weighted least squares with those variances, and the
shared error is a nuisance fitted within its bound in every rung (the depths
(w + lambda s)(1 + lambda r), |lambda| <= 1), so a change is named only where the
shared error cannot explain as much.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import optimize

from .._checks import InputError, check_array
from ..mechanics import paule_mandel

__all__: list[str] = []


@dataclass(frozen=True)
class PressNoise:
    """The presses' noise as the fit states it.

    Attributes
    ----------
    var : (N,) float64 ndarray
        Each press's force variance, N^2 (ones: unweighted, no uncertainty stated).
    stated : (N,) float64 ndarray or None
        Its stated part (dP/dw u)^2 + s_P^2, N^2; None when nothing was stated.
    sigma0_n : float
        The force scatter the stated uncertainties leave unexplained (Paule-Mandel), N;
        NaN when nothing was stated.
    shared_mm : (N,) float64 ndarray
        How far each depth moves when the shared error is at its bound, mm (zeros:
        none stated).
    shared_rel : float
        A shared error in proportion to each depth, its bound as a fraction.
    """

    var: np.ndarray
    stated: np.ndarray | None
    sigma0_n: float
    shared_mm: np.ndarray
    shared_rel: float

    @property
    def has_shared(self) -> bool:
        return bool(np.any(self.shared_mm > 0) or self.shared_rel > 0)

    def depths(self, w: np.ndarray, lam: float) -> np.ndarray:
        """The depths with the shared error at `lam` of its bound."""
        return (w + lam * self.shared_mm) * (1.0 + lam * self.shared_rel)


def _optional(arr, name: str, n: int) -> np.ndarray | None:
    if arr is None:
        return None
    a = check_array(arr, name, [(n,)], dtype=np.number, finite=True).astype(np.float64)
    bad = np.flatnonzero(a < 0)
    if bad.size:
        raise InputError(f"press {int(bad[0])}: {name} = {a[bad[0]]:g} must be >= 0")
    return a


def press_noise(w: np.ndarray, P: np.ndarray, g_of, *, depth_std_mm=None, force_std_n=None,
                depth_shared_mm=0.0, depth_shared_rel: float = 0.0) -> PressNoise:
    """The noise model of :func:`fit_indenter` at the base model `g_of` (w -> P at E = 1).

    Raises
    ------
    InputError
        For an uncertainty < 0 or not one per press (naming the press), or a
        `depth_shared_rel` outside [0, 1).
    """
    n = w.size
    u = _optional(depth_std_mm, "depth_std_mm", n)
    f = _optional(force_std_n, "force_std_n", n)
    shared = np.asarray(depth_shared_mm, np.float64)
    shared = _optional(np.broadcast_to(shared, (n,)) if shared.ndim == 0 else shared,
                       "depth_shared_mm", n)
    rel = float(depth_shared_rel)
    if not (math.isfinite(rel) and 0 <= rel < 1):
        raise InputError(f"depth_shared_rel must be within [0, 1), got {depth_shared_rel!r}")
    stated = None
    if (u is not None and np.any(u > 0)) or (f is not None and np.any(f > 0)):
        g = g_of(w)
        E0 = float(g @ P / (g @ g))
        eps = 1e-6 * float(np.max(w))
        dg = (g_of(w + eps) - g_of(np.maximum(w - eps, 1e-12))) / (
            w + eps - np.maximum(w - eps, 1e-12))
        stated = (E0 * dg * (0.0 if u is None else u)) ** 2 + (0.0 if f is None else f ** 2)
        t = paule_mandel(g, P, stated, max(n - 1, 1))
        floor = max((1e-12 * float(np.max(P))) ** 2, np.finfo(float).tiny)
        return PressNoise(np.maximum(t + stated, floor), stated, math.sqrt(t), shared, rel)
    return PressNoise(np.ones(n), None, math.nan, shared, rel)


def weighted_linear(g: np.ndarray, P: np.ndarray, var: np.ndarray, offset: bool
                    ) -> tuple[float, float, float]:
    """Weighted least squares of P = E g (+ F0) with variances `var`: (E, F0, chi2)."""
    sw = 1.0 / np.sqrt(var)
    if offset:
        X = np.column_stack([g, np.ones_like(g)]) * sw[:, None]
        (E, F0), *_ = np.linalg.lstsq(X, P * sw, rcond=None)
    else:
        gw, Pw = g * sw, P * sw
        E, F0 = float(gw @ Pw / (gw @ gw)), 0.0
    r = (P - E * g - F0) * sw
    return float(E), float(F0), float(r @ r)


def best_shift(cost, lo: float, hi: float, n: int = 21) -> float:
    """The argument in [lo, hi] of the smallest `cost`: a grid of `n`, then bounded Brent
    between the best point's neighbours."""
    if not hi > lo:
        return 0.5 * (lo + hi)
    grid = np.linspace(lo, hi, n)
    vals = [cost(x) for x in grid]
    k = int(np.argmin(vals))
    a, b = grid[max(k - 1, 0)], grid[min(k + 1, n - 1)]
    res = optimize.minimize_scalar(cost, bounds=(a, b), method="bounded",
                                   options={"xatol": 1e-6 * (hi - lo)})
    return float(res.x) if res.fun <= vals[k] else float(grid[k])
