"""The noise budget: the scatter the instruments explain against the replicate scatter.

A press's force has two instrument errors: the F/T window's mean (its
standard error, autocorrelation included: ``force_sem_n``) and the certified
depth's uncertainty (``depth_std_mm``) times the local stiffness dP/dw. Their
sum in quadrature is the press's budget. Repeated presses at one depth scatter
about their mean by the budget when nothing else is at work; when they scatter
more, the measurement chain adds noise the table does not record (a depth
certification that lags or wanders, the clock, the force window), whatever
the gel's model. (issue 23, part 1.)
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from scipy import stats

__all__ = ["NoiseBudget", "law_slope", "noise_budget", "stated_weights"]

#: Significance of the budget test (chi-square on the within-group scatter).
BUDGET_ALPHA = 1e-3
#: And by how much the scatter must exceed the budget to be reported (ratio of sds).
BUDGET_RATIO = 1.5
#: Below this p the scatter is not called consistent with the budget, even when it stays
#: below the threshold above (p < BUDGET_ALPHA and ratio > BUDGET_RATIO) that is acted on.
BUDGET_CONSISTENT_P = 0.05


@dataclass(frozen=True)
class NoiseBudget:
    """The replicate scatter against what the instruments explain.

    Attributes
    ----------
    floor_n : float
        Replicate scatter: pooled within-group sd of the residuals, N.
    budget_n : float
        What the instruments explain, pooled over the same presses, N.
    force_window_n, depth_n : float
        Its parts (rms over presses): the F/T window's standard error, and
        the depth uncertainty times dP/dw, N.
    ratio : float
        ``floor_n / budget_n``.
    chi2, dof, p_value : float, int, float
        The test: sum over presses of (residual - its group's mean)^2 over
        the press's budget variance, against chi-square with N - G degrees
        of freedom (G groups of repeated presses).
    exceeds : bool
        ``p_value < BUDGET_ALPHA`` and ``ratio > BUDGET_RATIO``.
    note : str
        What the budget was made of (a missing ``depth_std_mm`` counts as 0).
    """

    floor_n: float
    budget_n: float
    force_window_n: float
    depth_n: float
    ratio: float
    chi2: float
    dof: int
    p_value: float
    exceeds: bool
    note: str

    def to_json_dict(self) -> dict:
        """JSON-ready dict (NaN as None)."""
        def num(v: float) -> float | None:
            return float(v) if math.isfinite(v) else None

        return {"floor_n": num(self.floor_n), "budget_n": num(self.budget_n),
                "force_window_n": num(self.force_window_n), "depth_n": num(self.depth_n),
                "ratio": num(self.ratio), "chi2": num(self.chi2), "dof": self.dof,
                "p_value": num(self.p_value), "exceeds": self.exceeds, "note": self.note}


def law_slope(depth_mm: np.ndarray, force_n: np.ndarray) -> np.ndarray:
    """dP/dw at each depth, N/mm: the slope of a quadratic through P(w) (a line with two
    distinct depths), so that repeated depths, which have no slope of their own, share
    one. Two distinct depths or more."""
    w = np.asarray(depth_mm, np.float64)
    deg = min(2, np.unique(w).size - 1)
    return np.polyval(np.polyder(np.polyfit(w, np.asarray(force_n, np.float64), deg)), w)


def stated_weights(depth_mm: np.ndarray, force_n: np.ndarray, depth_std_mm: np.ndarray,
                   force_sem_n: np.ndarray | None = None) -> np.ndarray | None:
    """Each press's weight in a fit with effects: 1 / sd^2 of its stated force noise.

    The F/T window's standard error and the depth's uncertainty times the local
    stiffness dP/dw (:func:`law_slope`), as eq. (5)'s errors-in-variables fit weighs
    them (effective variance: sigma_i^2 = s_P,i^2 + (dP/dw_i s_w,i)^2).

    Parameters
    ----------
    depth_mm, force_n : (N,) array_like
        Certified depths w, mm, and forces P, N (two distinct depths or more).
    depth_std_mm : (N,) array_like
        Each depth's standard uncertainty, mm.
    force_sem_n : (N,) array_like, optional
        Each force's standard error, N (``force_sem_n``); 0 where absent or NaN.

    Returns
    -------
    weights : (N,) float64 ndarray, 1/N^2, or None
        None where a press's stated noise is zero or the depths are fewer than two
        (nothing to weigh by).
    """
    w = np.asarray(depth_mm, np.float64)
    if np.unique(w).size < 2:
        return None
    sem = np.zeros(w.size) if force_sem_n is None else np.nan_to_num(
        np.asarray(force_sem_n, np.float64))
    var = sem ** 2 + (law_slope(w, force_n) * np.asarray(depth_std_mm, np.float64)) ** 2
    return 1.0 / var if np.all(var > 0) else None


def noise_budget(residuals_n: np.ndarray, predicted_n: np.ndarray,
                 columns: Mapping[str, np.ndarray], groups: np.ndarray
                 ) -> tuple[NoiseBudget | None, str]:
    """Test the replicate scatter against the instruments' budget.

    Parameters
    ----------
    residuals_n, predicted_n : (N,) float ndarray
        A model's residuals and predictions, N.
    columns : mapping
        ``depth_mm`` and ``force_sem_n`` (standard error of each press's F/T
        window mean, N: :func:`tactilevision.contact.window_standard_error`,
        which ``tactilevision calibrate`` writes), optionally
        ``depth_std_mm`` and ``depth_indenter_std_mm`` (the part of it an
        indenter's presses share, left out: it moves a group together).
    groups : (N,) int ndarray
        Groups of repeated presses (0 .. G-1).

    Returns
    -------
    budget : NoiseBudget or None
        None when the table cannot say (no ``force_sem_n``, or no repeats).
    why : str
        Empty, or why there is no budget.
    """
    sem = columns.get("force_sem_n")
    if sem is None:
        why = ("needs force_sem_n, the standard error of each press's F/T window mean "
               "(tactilevision calibrate writes it)")
        if "force_std_n" in columns:
            why += "; force_std_n, the window's sd, does not say how many independent samples"
        return None, why
    r = np.asarray(residuals_n, np.float64)
    w = np.asarray(columns["depth_mm"], np.float64)
    sem = np.asarray(sem, np.float64)
    u = columns.get("depth_std_mm")
    ok = np.isfinite(r) & np.isfinite(sem) & (sem >= 0)
    note = "F/T window standard errors (force_sem_n)"
    if u is not None:
        u = np.asarray(u, np.float64)
        ok &= np.isfinite(u)
        note += " and certified depth uncertainty (depth_std_mm) x dP/dw"
        shared = columns.get("depth_indenter_std_mm")
        if shared is not None:
            # the part an indenter's presses share moves them together: it is not in the
            # scatter within a group of one indenter's presses
            shared = np.nan_to_num(np.asarray(shared, np.float64))
            u = np.sqrt(np.maximum(u * u - shared * shared, 0.0))
            note += (" (less the part each indenter's presses share, "
                     "depth_indenter_std_mm)")
    else:
        u = np.zeros_like(w)
        note += "; no depth_std_mm: the depth's share counted as 0"
    g = np.asarray(groups)[ok]
    r, w, sem, u = r[ok], w[ok], sem[ok], u[ok]
    _, g = np.unique(g, return_inverse=True)
    G = int(g.max()) + 1 if g.size else 0
    dof = int(r.size - G)
    if dof < 2:
        return None, "needs repeated presses at a depth"
    # local stiffness from the model's own P(w): a quadratic through its predictions
    if np.unique(w).size < 2:
        return None, "needs presses at two depths or more (for dP/dw)"
    dpdw = law_slope(w, np.asarray(predicted_n, np.float64)[ok])
    var_f, var_w = sem ** 2, (dpdw * u) ** 2
    var = np.maximum(var_f + var_w, 1e-30)
    means = np.bincount(g, weights=r) / np.bincount(g)
    dev = r - means[g]
    # a group of n shares one mean: n - 1 of its n deviations are free
    chi2 = float(np.sum(dev ** 2 / var))
    floor = float(np.sqrt(np.sum(dev ** 2) / dof))
    n_g = np.bincount(g)[g]
    budget = float(np.sqrt(np.sum(var * (n_g - 1) / n_g) / dof))
    p_value = float(stats.chi2.sf(chi2, dof))
    ratio = floor / budget if budget > 0 else math.inf
    return NoiseBudget(floor_n=floor, budget_n=budget,
                       force_window_n=float(np.sqrt(np.mean(var_f))),
                       depth_n=float(np.sqrt(np.mean(var_w))), ratio=ratio, chi2=chi2,
                       dof=dof, p_value=p_value,
                       exceeds=bool(p_value < BUDGET_ALPHA and ratio > BUDGET_RATIO),
                       note=note), ""
