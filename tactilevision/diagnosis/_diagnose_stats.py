"""The statistics of :func:`~tactilevision.diagnosis.diagnose`: residual structure along
each covariate, the replicate noise floor, and cross-validated error.

The search for the missing effect (the candidates, the ladder, the verdict) is in
:mod:`tactilevision.diagnosis._diagnose`; these are the tests it is built on.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy import stats

from ..mechanics import IndentationModel

#: Family-wise level of the covariate structure tests (Bonferroni over columns).
ALPHA = 0.01
#: Columns that are never covariates (``depth_std_mm``: the depth's uncertainty, not physics).
_NOT_COVARIATES = ("force_n", "depth_std_mm", "force_sem_n", "bevel_force_n", "force0_n",
                   "ft_zero_n", "depth_shared_mm", "depth_indenter_std_mm", "force_w0_n",
                   "force_w0_sem_n")
#: Columns that respond to the press rather than set its conditions: a press's tangential
#: forces and its F/T window's scatter grow with its normal force, so structure along them
#: is the force itself. Not scanned as covariates unless asked (``scan``); ``fx_n`` and
#: ``fy_n`` are read by ``force_crosstalk``, the F/T sensor's physics.
RESPONSE_COLUMNS = ("fx_n", "fy_n", "force_std_n")
#: Columns the depth rule computed (products of the certification, not conditions of the
#: press): never covariates, never offered as physics; structure along them is tested
#: apart (:func:`certification_tests`) and reported as a certification problem.
CERTIFICATION_COLUMNS = ("overshoot_mm",)


@dataclass(frozen=True)
class CovariateTest:
    """Residual structure along one covariate.

    Attributes
    ----------
    name : str
    p_value : float
        F test of a smooth function of the column (or one-way ANOVA over its
        values when it has few) against no structure.
    explained_fraction : float
        Fraction of the residual variance that function explains, in [0, 1].
    significant : bool
        ``p_value`` below the Bonferroni level ALPHA / number of covariates.
    n : int
        Presses with a value in this column.
    """

    name: str
    p_value: float
    explained_fraction: float
    significant: bool
    n: int



def _groups(columns: Mapping[str, np.ndarray]) -> np.ndarray:
    """Replicate group of each press: same indenter (if given) and same nominal depth.

    The nominal depth is ``depth_mm`` itself, or, for depths measured by a
    vernier (an ``overshoot_mm`` column), the gauge block's w0 = depth -
    overshoot: the presses of one indenter, each a few microns deeper.
    """
    depth = np.asarray(columns["depth_mm"], np.float64)
    over = np.asarray(columns.get("overshoot_mm", np.full(depth.shape, np.nan)), np.float64)
    nominal = depth - over if np.all(np.isfinite(over)) else depth
    keys = [np.round(nominal, 6)]
    if "indenter" in columns:
        ind = np.asarray(columns["indenter"], np.float64)
        if np.all(np.isfinite(ind)):
            keys.append(ind)
    _, g = np.unique(np.column_stack(keys), axis=0, return_inverse=True)
    return g.ravel()


def _group_means(v: np.ndarray, g: np.ndarray) -> np.ndarray:
    """Mean of `v` (N,) or each column of `v` (N, K) over the groups `g`, per press."""
    G = int(g.max()) + 1
    counts = np.bincount(g, minlength=G)
    if v.ndim == 1:
        return (np.bincount(g, v, G) / counts)[g]
    return (np.stack([np.bincount(g, v[:, j], G) for j in range(v.shape[1])], 1)
            / counts[:, None])[g]


def noise_floor(residuals_n: np.ndarray, columns: Mapping[str, np.ndarray]) -> float:
    """The replicate noise floor: pooled within-group sd of residuals, N.

    Parameters
    ----------
    residuals_n : (N,) ndarray
        Residuals of a model (so anything it explains is taken out).
    columns : mapping
        ``depth_mm`` and, if present, ``indenter`` define the groups of
        repeated presses.

    Returns
    -------
    sd : float
        ``sqrt(sum (r - mean_group r)^2 / (N - G))``; NaN without repeats.
    """
    r = np.asarray(residuals_n, np.float64)
    g = _groups(columns)
    G = int(g.max()) + 1
    if r.size - G < 2:
        return math.nan
    return float(np.sqrt(np.sum((r - _group_means(r, g)) ** 2) / (r.size - G)))


def _covariate_names(columns: Mapping[str, np.ndarray], scan: Sequence[str] = ()
                     ) -> list[str]:
    return [k for k in columns if k not in _NOT_COVARIATES and k not in CERTIFICATION_COLUMNS
            and not k.startswith("_") and (k not in RESPONSE_COLUMNS or k in scan)]


def covariate_tests(residuals_n: np.ndarray, predicted_n: np.ndarray,
                    columns: Mapping[str, np.ndarray], *, n_depth_params: int = 2,
                    alpha: float = ALPHA, scan: Sequence[str] = ()
                    ) -> tuple[CovariateTest, ...]:
    """Does the residual carry structure along each covariate column?

    Parameters
    ----------
    residuals_n, predicted_n : (N,) ndarray
        A model's residuals and predictions.
    columns : mapping of str to (N,) ndarray
        Every column but ``force_n``, the uncertainties and the responses
        (:data:`RESPONSE_COLUMNS`) is a covariate; constant columns are
        skipped.
    n_depth_params : int, default 2
        Parameters of the model that are functions of depth alone (c and
        beta): the lack-of-fit test along ``depth_mm`` has that many fewer
        degrees of freedom.
    alpha : float, default ALPHA
        Family-wise level; each test is significant below alpha / (number of
        covariates tested).
    scan : sequence of str, default ()
        Response columns to test all the same.

    Returns
    -------
    tests : tuple of CovariateTest

    Notes
    -----
    A column with at most 8 distinct values is tested by one-way ANOVA of the
    residuals over its values (along ``depth_mm``: the lack-of-fit test with
    ``K - 1 - n_depth_params`` degrees of freedom). Other columns: an F test
    of the regression of the residual on ``z, z^2, p z, p z^2`` (z the
    standardised column, p the standardised prediction: additive and
    multiplicative structure) within the groups of repeated presses (group
    means taken out of both sides), so that the law's own misfit along
    depth does not show along a column correlated with depth.
    """
    r_all = np.asarray(residuals_n, np.float64)
    p_all = np.asarray(predicted_n, np.float64)
    names = _testable(_covariate_names(columns, scan), r_all, columns)
    m = max(len(names), 1)
    out = []
    for name in names:
        pv, frac, n, _ = _structure(name, r_all, p_all, columns, n_depth_params)
        out.append(CovariateTest(name, pv, frac, pv < alpha / m, n))
    return tuple(out)


def _testable(names: Sequence[str], r_all: np.ndarray, columns: Mapping[str, np.ndarray]
              ) -> list[str]:
    """The columns of `names` with 8 or more values beside a residual, not constant."""
    out = []
    for name in names:
        x = np.asarray(columns[name], np.float64)
        ok = np.isfinite(x) & np.isfinite(r_all)
        if ok.sum() >= 8 and np.ptp(x[ok]) > 0:
            out.append(name)
    return out


def scan_regressors(x: np.ndarray, predicted_n: np.ndarray, groups: np.ndarray
                    ) -> np.ndarray:
    """The scan's regressors along a column of more than 8 values (N, 4): z, z^2, q z,
    q z^2 (z the standardised column, q the standardised prediction), each with its
    replicate groups' means taken out (:func:`covariate_tests`' notes)."""
    z = (x - x.mean()) / x.std()
    q = (predicted_n - predicted_n.mean()) / (predicted_n.std() or 1.0)
    X = np.column_stack([z, z**2, q * z, q * z**2])
    return X - _group_means(X, groups)


def _structure(name: str, r_all: np.ndarray, p_all: np.ndarray,
               columns: Mapping[str, np.ndarray], n_depth_params: int
               ) -> tuple[float, float, int, float]:
    """One column's test (:func:`covariate_tests`' notes): p-value, the fraction of the
    residual variance explained, the presses tested, and the RMS of the structure found
    (the residual's sum of squares it explains, per press, square-rooted), N."""
    x = np.asarray(columns[name], np.float64)
    ok = np.isfinite(x) & np.isfinite(r_all)
    r, xs, p = r_all[ok], x[ok], p_all[ok]
    n = r.size
    values, g = np.unique(xs, return_inverse=True)
    rss0 = float(np.sum((r - r.mean()) ** 2))
    if values.size <= 8:
        G = values.size
        rss1 = float(np.sum((r - _group_means(r, g)) ** 2))
        df1 = G - 1 - (n_depth_params if name == "depth_mm" else 0)
        df2 = n - G
    else:
        # within replicate groups: structure along depth (the law's own) is taken out
        grp = _groups({k: np.asarray(v)[ok] for k, v in columns.items()
                       if k in ("depth_mm", "indenter", "overshoot_mm")})
        G = int(grp.max()) + 1
        r = r - _group_means(r, grp)
        rss0 = float(np.sum(r ** 2))
        X = scan_regressors(xs, p, grp)
        coef, *_ = np.linalg.lstsq(X, r, rcond=None)
        rss1 = float(np.sum((r - X @ coef) ** 2))
        df1 = int(np.linalg.matrix_rank(X))
        df2 = n - G - df1
    if df1 < 1 or df2 < 1 or rss0 <= 0:
        return 1.0, 0.0, n, 0.0
    F = ((rss0 - rss1) / df1) / (rss1 / df2) if rss1 > 0 else math.inf
    return (float(stats.f.sf(F, df1, df2)), float(max(0.0, 1 - rss1 / rss0)), n,
            math.sqrt(max(rss0 - rss1, 0.0) / n))


@dataclass(frozen=True)
class CertificationTest:
    """Residual structure along a column the depth rule computed (a certification
    problem, not physics).

    Attributes
    ----------
    name : str
        The column (:data:`CERTIFICATION_COLUMNS`).
    p_value, explained_fraction : float
        As :class:`CovariateTest`'s (the same test).
    significant : bool
        ``p_value`` below ALPHA / the number of certification columns tested.
    n : int
    size_n : float
        RMS of the structure found along the column, N: how far the forces stray
        with it, the size of the certification problem in force.
    """

    name: str
    p_value: float
    explained_fraction: float
    significant: bool
    n: int
    size_n: float


def certification_tests(residuals_n: np.ndarray, predicted_n: np.ndarray,
                        columns: Mapping[str, np.ndarray], *, alpha: float = ALPHA
                        ) -> tuple[CertificationTest, ...]:
    """Does the residual carry structure along a column the depth rule computed?

    The test of :func:`covariate_tests` on :data:`CERTIFICATION_COLUMNS`
    (``overshoot_mm``: the certified depth less the indenter's w0). Along such a
    column structure is not physics: the depths are off together with what
    certified them (the mark rule's P(w0) crossing, a vernier's unread bands).

    Parameters
    ----------
    residuals_n, predicted_n : (N,) ndarray
        A model's residuals and predictions, N.
    columns : mapping of str to (N,) ndarray
    alpha : float, default ALPHA

    Returns
    -------
    tests : tuple of CertificationTest
        One per certification column the table has (8 values or more, not constant).
    """
    r_all = np.asarray(residuals_n, np.float64)
    p_all = np.asarray(predicted_n, np.float64)
    names = _testable([c for c in CERTIFICATION_COLUMNS if c in columns], r_all, columns)
    m = max(len(names), 1)
    out = []
    for name in names:
        pv, frac, n, size = _structure(name, r_all, p_all, columns, 0)
        out.append(CertificationTest(name, pv, frac, pv < alpha / m, n, size))
    return tuple(out)


def _folds(n: int, k: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.permutation(np.arange(n) % k)


def cross_validated_rmse(model: IndentationModel, columns: Mapping[str, np.ndarray], *,
                         thickness_mm: float, k: int = 10, seed: int = 0,
                         start: Mapping[str, float] | None = None) -> float:
    """K-fold cross-validated RMSE of a model, N.

    Each fold's presses are predicted by the model fitted (robustly) to the
    others. Folds are a seeded random partition, the same for every model
    given the same data and seed.

    Under an error shared within groups of presses (``columns['_group']`` and
    ``columns['_theta']``, as ``diagnose`` sets them for each indenter's shared
    depth error: :func:`tactilevision.mechanics.shared_groups`), the cross-validation
    takes the fits' noise model: each fold is fitted by the same generalized least
    squares (theta recomputed for the group's presses in the fold), and a held-out
    press is predicted with its group's share of the error, the best linear unbiased
    predictor of a random intercept from the group's other presses, B mean(y - f) with
    B = n rho / (1 + n rho), rho = t^2 / s^2 read from theta (Henderson's BLUP;
    Fuller and Battese, J. Econometrics 2, 67, 1974, for theta). Without it the
    held-out error is the shared error itself, which no effect can lower: an effect
    that varies within the groups and passes the BIC was then refused by the folds.

    Parameters
    ----------
    model : IndentationModel
    columns : mapping of str to (N,) ndarray
    thickness_mm : float
    k : int, default 10
    seed : int, default 0
    start : mapping of str to float, optional
        The model's fit to all presses (``ModelFit.params``): each fold's
        fit starts there, and a change point is searched by descent from its
        place in it (:meth:`IndentationModel.fit`), not over every candidate.

    Returns
    -------
    rmse : float
    """
    shared = "_group" in columns and "_theta" in columns
    keys = list(model.columns) + (["_group", "_theta"] if shared else [])
    d = {c: np.asarray(columns[c], np.float64) for c in keys}
    n = d["depth_mm"].size
    k = min(k, n)
    fold = _folds(n, k, seed)
    rho = _shared_ratio(d["_group"], d["_theta"]) if shared else None
    err = np.empty(n)
    for f in range(k):
        test = fold == f
        train = {c: v[~test] for c, v in d.items()}
        if rho is not None:
            train["_theta"] = _fold_theta(train["_group"], rho[~test])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            mf = model.fit(train, thickness_mm=thickness_mm, start=start, identify=False)
        td = {c: v[test] for c, v in d.items()}
        err[test] = model.predict(mf.params, td, thickness_mm) - td["force_n"]
        if rho is not None:
            r_train = train["force_n"] - model.predict(mf.params, train, thickness_mm)
            err[test] += _group_share(train["_group"], r_train, rho[~test],
                                      td["_group"])
    return float(np.sqrt(np.mean(err**2)))


def _shared_ratio(group: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """rho = t^2 / s^2 of each press's group from its theta = 1 - 1 / sqrt(1 + n rho)
    (n the group's presses in the table)."""
    n_g = np.array([np.count_nonzero(group == g) for g in group], np.float64)
    lam = np.clip(1.0 - np.nan_to_num(theta), 1e-12, 1.0)
    return (1.0 / lam**2 - 1.0) / n_g


def _fold_theta(group: np.ndarray, rho: np.ndarray) -> np.ndarray:
    """theta of each press's group among the presses of a fold."""
    n_g = np.array([np.count_nonzero(group == g) for g in group], np.float64)
    return 1.0 - 1.0 / np.sqrt(1.0 + n_g * rho)


def _group_share(group: np.ndarray, resid: np.ndarray, rho: np.ndarray,
                 test_group: np.ndarray) -> np.ndarray:
    """Each held-out press's predicted share of its group's error (BLUP): B times the
    mean of the group's training residuals y - f, B = n rho / (1 + n rho); 0 for a
    group with no training press."""
    out = np.zeros(test_group.size)
    for i, g in enumerate(test_group):
        same = group == g
        if same.any():
            nr = same.sum() * float(rho[same][0])
            out[i] = nr / (1.0 + nr) * float(np.mean(resid[same]))
    return out
