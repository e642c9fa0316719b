"""E of a batch from several specimens (or repeats) of one gel: a random effect of the specimen.

Each specimen's fit gives its own E with an interval that holds its own noise and misfit.
Specimens of one batch differ by more than that (cure, thickness, mixing): the batch's E
is then the mean of a distribution of specimen moduli, and its interval must hold that
spread. The specimens are pooled on log E (a modulus is positive; its spread is relative)
by the random-effects model of DerSimonian and Laird (1986): each specimen i has
y_i = ln E_i with variance v_i (from its own interval), the specimens' true y_i scatter
about the batch's mu with variance tau^2, estimated by the method of moments from
Cochran's Q. The interval of mu is Hartung and Knapp's (2001; Sidik and Jonkman 2002),
a Student t on k - 1 degrees of freedom with the weighted scatter of the y_i, which
holds its level with few specimens where the plain random-effects z interval does not;
the prediction interval (Higgins, Thompson and Spiegelhalter 2009) is where a new
specimen of the batch would lie. Q's p says whether the specimens disagree beyond their
own intervals, and the result says so in one sentence.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import stats

from .._checks import InputError

__all__ = ["SPECIMEN_ALPHA", "SpecimenPool", "pool_specimens"]

#: Level of Cochran's Q test of the specimens' agreement.
SPECIMEN_ALPHA = 0.05


@dataclass(frozen=True)
class SpecimenPool:
    """The batch's E from its specimens (:func:`pool_specimens`). Units in the names.

    Attributes
    ----------
    labels : tuple of str
        The specimens, in the order given.
    E_mpa : (K,) float64 ndarray
        Each specimen's E, MPa.
    E_ci95_mpa : (K, 2) float64 ndarray
        Each specimen's own interval, MPa.
    E_batch_mpa : float
        exp(mu): the batch's (geometric) mean modulus, MPa.
    E_batch_ci95_mpa : (float, float)
        Its interval (Hartung-Knapp, t on K - 1 degrees of freedom), MPa.
    E_prediction_ci95_mpa : (float, float)
        Where a new specimen of the batch would lie (mu +- t sqrt(tau^2 + se^2)),
        MPa; NaN for fewer than three specimens.
    spread : float
        tau, the specimens' relative sd of E (ln E), DerSimonian-Laird.
    Q, Q_p : float
        Cochran's Q and its chi2 p on K - 1 degrees of freedom.
    I2 : float
        The share of the specimens' scatter their own intervals do not explain,
        (Q - (K - 1)) / Q, at least 0.
    disagree : bool
        Q_p below :data:`SPECIMEN_ALPHA`: the specimens differ beyond their own
        intervals.
    confidence : float
    message : str
        One or two sentences: the batch's E, and whether the specimens disagree.
    """

    labels: tuple[str, ...]
    E_mpa: np.ndarray = field(repr=False)
    E_ci95_mpa: np.ndarray = field(repr=False)
    E_batch_mpa: float
    E_batch_ci95_mpa: tuple[float, float]
    E_prediction_ci95_mpa: tuple[float, float]
    spread: float
    Q: float
    Q_p: float
    I2: float
    disagree: bool
    confidence: float
    message: str

    def to_json_dict(self) -> dict[str, Any]:
        """JSON-ready (NaN as None): the pooled figures and one entry per specimen."""
        def num(v: float) -> float | None:
            return float(v) if math.isfinite(v) else None

        return {"specimens": [{"specimen": s, "E_mpa": num(e), "E_ci95_mpa": [num(a), num(b)]}
                              for s, e, (a, b) in zip(self.labels, self.E_mpa,
                                                      self.E_ci95_mpa, strict=True)],
                "E_batch_mpa": num(self.E_batch_mpa),
                "E_batch_ci95_mpa": [num(v) for v in self.E_batch_ci95_mpa],
                "E_prediction_ci95_mpa": [num(v) for v in self.E_prediction_ci95_mpa],
                "spread": num(self.spread), "Q": num(self.Q), "Q_p": num(self.Q_p),
                "I2": num(self.I2), "disagree": self.disagree, "confidence": self.confidence,
                "message": self.message}


def pool_specimens(labels: Sequence[str], E_mpa: Sequence[float],
                   E_ci_mpa: Sequence[tuple[float, float]], *,
                   confidence: float = 0.95) -> SpecimenPool:
    """Pool the specimens of a batch into the batch's E, the spread between them held.

    Parameters
    ----------
    labels : sequence of str, length K >= 2
        The specimens' names.
    E_mpa : sequence of float
        Each specimen's E, MPa, > 0.
    E_ci_mpa : sequence of (float, float)
        Each specimen's interval at `confidence`, MPa, 0 < lo <= E <= hi.
    confidence : float, default 0.95

    Returns
    -------
    SpecimenPool

    Raises
    ------
    InputError
        For fewer than two specimens, lengths that differ, an E or interval that is
        not positive and finite or does not hold its E (naming the specimen).

    Notes
    -----
    y_i = ln E_i, v_i = ((ln hi_i - ln lo_i) / (2 z))^2 with z the normal quantile
    of `confidence` (each interval read as a normal one on ln E), w_i = 1 / v_i,
    Q = sum w_i (y_i - y_w)^2, tau^2 = max(0, (Q - (K - 1)) / (sum w - sum w^2 /
    sum w)); mu = sum w*_i y_i / sum w*_i with w*_i = 1 / (v_i + tau^2), its
    Hartung-Knapp variance sum w*_i (y_i - mu)^2 / ((K - 1) sum w*_i), the
    interval mu +- t(K - 1) se, the prediction interval mu +- t(K - 2)
    sqrt(tau^2 + 1 / sum w*) (K >= 3).
    """
    labels = tuple(str(s) for s in labels)
    E = np.asarray(E_mpa, np.float64)
    ci = np.asarray(E_ci_mpa, np.float64).reshape(-1, 2)
    k = len(labels)
    if not (E.size == k and ci.shape[0] == k):
        raise InputError(f"{k} specimen labels, {E.size} moduli and {ci.shape[0]} intervals: "
                         "one of each per specimen")
    if k < 2:
        raise InputError(f"{k} specimen: pooling needs two or more")
    if not 0 < confidence < 1:
        raise InputError(f"confidence must be in (0, 1), got {confidence!r}")
    for s, e, (lo, hi) in zip(labels, E, ci, strict=True):
        if not (np.isfinite([e, lo, hi]).all() and 0 < lo <= e <= hi and hi > lo):
            raise InputError(f"specimen {s}: E = {e:g} MPa with interval [{lo:g}, {hi:g}] "
                             "must be positive, finite and inside a non-empty interval")
    z = float(stats.norm.ppf(0.5 + confidence / 2))
    y = np.log(E)
    v = ((np.log(ci[:, 1]) - np.log(ci[:, 0])) / (2 * z)) ** 2
    w = 1 / v
    yw = float(np.sum(w * y) / np.sum(w))
    Q = float(np.sum(w * (y - yw) ** 2))
    Q_p = float(stats.chi2.sf(Q, k - 1))
    tau2 = max(0.0, (Q - (k - 1)) / (float(np.sum(w)) - float(np.sum(w**2) / np.sum(w))))
    ws = 1 / (v + tau2)
    mu = float(np.sum(ws * y) / np.sum(ws))
    se_hk = math.sqrt(float(np.sum(ws * (y - mu) ** 2)) / ((k - 1) * float(np.sum(ws))))
    se_re = math.sqrt(1 / float(np.sum(ws)))
    se = max(se_hk, se_re)        # Hartung-Knapp never narrower than the plain interval
    t = float(stats.t.ppf(0.5 + confidence / 2, k - 1))
    batch = (math.exp(mu - t * se), math.exp(mu + t * se))
    if k >= 3:
        tp = float(stats.t.ppf(0.5 + confidence / 2, k - 2))
        half = tp * math.sqrt(tau2 + se**2)
        pred = (math.exp(mu - half), math.exp(mu + half))
    else:
        pred = (math.nan, math.nan)
    I2 = max(0.0, (Q - (k - 1)) / Q) if Q > 0 else 0.0
    disagree = Q_p < SPECIMEN_ALPHA
    pct = f"{confidence:.0%}"
    msg = (f"{k} specimens pooled as a random effect of the specimen: the batch's E = "
           f"{math.exp(mu):.4g} MPa, {pct} CI [{batch[0]:.4g}, {batch[1]:.4g}] MPa")
    if disagree:
        msg += (f". The specimens disagree beyond their own intervals (Cochran's Q = {Q:.3g} "
                f"on {k - 1} degrees of freedom, p = {Q_p:.2g}; {100 * I2:.0f} % of their "
                f"scatter is specimen to specimen, sd {100 * math.sqrt(tau2):.3g} % of E): "
                "each specimen's own E is in the table, and the batch's interval holds "
                "the spread between them")
        if k >= 3:
            msg += f"; a new specimen would lie in [{pred[0]:.4g}, {pred[1]:.4g}] MPa"
    else:
        msg += (f". The specimens agree within their own intervals (Cochran's Q p = "
                f"{Q_p:.2g})")
    return SpecimenPool(labels=labels, E_mpa=E, E_ci95_mpa=ci, E_batch_mpa=math.exp(mu),
                        E_batch_ci95_mpa=batch, E_prediction_ci95_mpa=pred,
                        spread=math.sqrt(tau2), Q=Q, Q_p=Q_p, I2=I2, disagree=disagree,
                        confidence=confidence, message=msg + ".")
