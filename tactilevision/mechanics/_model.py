"""Indentation models made of named effects (formats.md §4), fitted by robust least squares.

A model is the base indentation law plus a list of effects from the
catalogue. The base is the paper's eq. (5), ``P = c w (1 + beta w / h)``
(``base='paper'``: the layer with ``large_deformation``), or the small-strain
layer ``P = c w`` (``base='layer'``, eq. 2). Each effect is one small class
(in the manner of lmfit's composable models): its parameters with bounds and
units, the columns it needs, and how it changes the depth the law sees or the
force it predicts. The effects and their registry are in
:mod:`tactilevision.mechanics._catalogue`; this module is the engine that composes
and fits them.

Effects act in a fixed order: depth effects first (``depth_offset``), then the
law, then multiplicative stiffness effects, then additive force effects
(``force_offset``, ``force_drift``).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from .._checks import InputError
from . import _catalogue as _cat
from ._catalogue import (  # noqa: F401  (the catalogue's names, also read from here)
    COLUMN_EFFECTS,
    EFFECTS,
    Effect,
    Param,
    effect_name,
    is_registered,
    make_effect,
    register_effect,
)

__all__ = ["EFFECTS", "Effect", "IndentationModel", "ModelFit", "Param", "make_effect"]


@dataclass(frozen=True)
class ModelFit:
    """Result of :meth:`IndentationModel.fit`.

    Attributes
    ----------
    model : IndentationModel
    params : dict of str to float
        ``c_n_per_mm`` and every effect's parameters (``effect.param``).
    stderr : dict of str to float
        Standard errors from the Jacobian at the solution (NaN where a
        parameter sits on a bound or is not identified).
    correlation, covariance : (K, K) float64 ndarray
        Parameter correlations and covariance, in the order of ``params``.
    predicted_n, residuals_n : (N,) float64 ndarray
    weights : (N,) float64 ndarray
    rmse_n : float
        Unweighted root-mean-square residual.
    bic, aic : float
        From the (weighted) residual sum of squares, Gaussian likelihood. A
        parameter found by search (:meth:`Effect.profile`: a change point)
        counts twice in the BIC: the best of K candidate places gains about
        2 ln K of likelihood on noise alone (about 8 for 50 presses), which
        one ln n (4 for 60 presses) does not pay for.
    n_presses, n_params : int
    loss : str
    outliers : (N,) bool ndarray
        Presses the robust loss weights below one half (for 'soft_l1':
        |residual| > sqrt(3) times the loss scale).
    success : bool
    message : str
    unidentified : tuple of str
        Parameters the data cannot determine: they lie along a null direction
        of the (column-normalised) Jacobian, e.g. ``c_n_per_mm`` and
        ``viscoelastic_relaxation.g`` when the fitted tau is far below the
        shortest hold, so that only c (1 - g) is measured; or that the fit
        only seems to determine because it stopped on a bound in a corner
        where another parameter is undetermined (g = 0 leaves tau free): such
        a bounded parameter is held a quarter of its range inwards while the
        others are refitted, and if the cost hardly rises it is flagged, with
        every parameter that moved. Their standard
        errors are infinite and their covariance rows NaN (infinite on the
        diagonal), so any interval derived from them is not finite.
    """

    model: IndentationModel
    params: dict[str, float]
    stderr: dict[str, float]
    correlation: np.ndarray
    covariance: np.ndarray
    predicted_n: np.ndarray
    residuals_n: np.ndarray
    weights: np.ndarray
    rmse_n: float
    bic: float
    aic: float
    n_presses: int
    n_params: int
    loss: str
    outliers: np.ndarray
    success: bool
    message: str
    unidentified: tuple[str, ...] = ()

    @property
    def beta(self) -> float:
        """The stiffening beta of eq. (5) (NaN without ``large_deformation``)."""
        return self.params.get("large_deformation.beta", math.nan)


@dataclass(frozen=True)
class IndentationModel:
    """The base indentation law plus catalogue effects and effects of your own.

    Parameters
    ----------
    base : {'paper', 'layer', 'fem'}, default 'paper'
        ``'paper'``: eq. (5) (the layer with ``large_deformation``);
        ``'layer'``: the small-strain law P = c w (eq. 2); ``'fem'``: the
        FEM's finite-strain law (:class:`FemLaw`: c and nu), which needs
        `a_over_h`.
    effects : tuple of (str, Effect subclass or Effect instance)
        Effects added to the base: catalogue names, ``<kind>:<column>``
        column effects, names registered by :func:`register_effect`, import
        specs ``'package.module:ClassName'`` or ``'path/to/file.py:ClassName'``,
        or :class:`Effect` subclasses or instances. Stored as names: user
        effects are registered and replaced by their names (one str or
        effect alone is taken as a tuple of one).
    a_over_h : float, optional
        Indenter radius over layer thickness; needed by ``base='fem'``
        (0.2 to 2.0, the FEM table's range), unused otherwise.

    Raises
    ------
    InputError
        For a base not 'paper' or 'layer', an unknown effect, an invalid
        user effect or import spec (:func:`register_effect`,
        :func:`make_effect`), or an effect given twice.

    Examples
    --------
    >>> m = IndentationModel().with_effect("incomplete_recovery")
    >>> m.names
    ('large_deformation', 'incomplete_recovery')
    >>> m.columns
    ('depth_mm', 'force_n', 'wait_s')
    """

    base: str = "paper"
    effects: tuple[str, ...] = field(default=())
    a_over_h: float | None = None

    def __post_init__(self) -> None:
        if self.base not in ("paper", "layer", "fem"):
            raise InputError(f"base must be 'paper', 'layer' or 'fem', got {self.base!r}")
        if self.base == "fem":
            r = self.a_over_h
            if r is None or not (isinstance(r, int | float) and 0.2 <= r <= 2.0):
                raise InputError("base 'fem' needs a_over_h (indenter radius / layer "
                                 f"thickness) within the FEM table's 0.2 to 2.0, got {r!r}")
        effects = self.effects
        if isinstance(effects, str | Effect | type):
            effects = (effects,)
        # names are the model's currency: user effects and import specs are registered
        object.__setattr__(self, "effects", tuple(effect_name(e) for e in effects))
        if len(set(self.names)) != len(self.names):
            raise InputError(f"an effect appears twice in {self.names}")

    @property
    def names(self) -> tuple[str, ...]:
        """Effect names including the base's ``large_deformation``."""
        law = {"paper": ("large_deformation",), "fem": ("fem_law",)}.get(self.base, ())
        return law + tuple(self.effects)

    def _effects(self) -> list[Effect]:
        return [make_effect(n) for n in self.names]

    @property
    def columns(self) -> tuple[str, ...]:
        """Columns the model needs."""
        cols = ["depth_mm", "force_n"]
        for e in self._effects():
            cols += [c for c in e.columns if c not in cols]
        return tuple(cols)

    def with_effect(self, name: str | Effect | type[Effect]) -> IndentationModel:
        """The model with one more effect.

        Parameters
        ----------
        name : str, Effect subclass or Effect instance
            As an item of `effects` (a name, an import spec
            ``'package.module:ClassName'``, or a user effect).

        Returns
        -------
        IndentationModel

        Raises
        ------
        InputError
            For an unknown or invalid effect or one already in the model.
        """
        return IndentationModel(self.base, (*self.effects, name), self.a_over_h)

    def missing_columns(self, columns: Sequence[str]) -> tuple[str, ...]:
        """Columns the model needs that `columns` lacks."""
        return tuple(c for c in self.columns if c not in columns)

    def param_names(self) -> tuple[str, ...]:
        """``c_n_per_mm`` then ``<effect>.<param>`` of every effect."""
        own = [f"{e.name}.{q.name}" for e in self._effects() for q in e.params]
        return ("c_n_per_mm", *own)

    def predict(self, params: Mapping[str, float], data: Mapping[str, np.ndarray],
                thickness_mm: float) -> np.ndarray:
        """Predicted force, N.

        Parameters
        ----------
        params : mapping
            As :meth:`param_names`.
        data : mapping of str to (N,) ndarray
            The model's columns.
        thickness_mm : float
            h.

        Returns
        -------
        force_n : (N,) float64 ndarray
        """
        return self._predict(self._effects(), params, data, thickness_mm, self.a_over_h)

    @staticmethod
    def _predict(effects: Sequence[Effect], params: Mapping[str, float],
                 data: Mapping[str, np.ndarray], thickness_mm: float,
                 a_over_h: float | None = None) -> np.ndarray:
        names = ("c_n_per_mm", *(f"{e.name}.{q.name}" for e in effects for q in e.params))
        x = [float(params[q]) for q in names]
        d = dict(data)
        d["_h"] = float(thickness_mm)
        d["_a_over_h"] = a_over_h
        return _forward(_plan(effects), x, d)

    @staticmethod
    def _search(resid, fixed: np.ndarray, searched: dict[int, np.ndarray], x0: np.ndarray,
                bounds: tuple[np.ndarray, np.ndarray], max_first: int = 16,
                near: Mapping[int, float] | None = None, jac="2-point") -> None:
        """Set the searched parameters in `fixed` (in place: `resid` reads it), one at a
        time, the others at their best: least squares at up to `max_first` evenly spaced
        candidates, then at every candidate next to the best (each solve starting from
        the last one's solution). A parameter with a value in `near` (a fit of the same
        model to the same or nearly the same presses) is found by descent instead: from
        the candidate nearest that value, step to a neighbour while it lowers the cost
        (3 to 5 solves instead of about 20). `jac` is least_squares' (a callable:
        :meth:`_Residuals.jac`)."""
        start = [np.asarray(x0, np.float64)]
        near = near or {}
        for i, vals in searched.items():
            cost: dict[int, float] = {}

            def at(j: int, i: int = i, vals: np.ndarray = vals,
                   cost: dict[int, float] = cost) -> float:
                if j not in cost:
                    fixed[i] = vals[j]
                    sol = least_squares(resid, start[0], jac=jac, bounds=bounds,
                                        x_scale="jac", method="trf")
                    start[0] = np.clip(sol.x, bounds[0] + 1e-12, bounds[1] - 1e-12)
                    cost[j] = float(sol.cost)
                return cost[j]

            if i in near and np.isfinite(near[i]):
                best = int(np.argmin(np.abs(vals - near[i])))
                while True:
                    nb = [j for j in (best - 1, best + 1) if 0 <= j < vals.size]
                    j = min(nb, key=at, default=best)
                    if at(j) >= at(best):
                        break
                    best = j
                fixed[i] = vals[best]
                continue
            first = np.unique(np.linspace(0, vals.size - 1, min(max_first, vals.size)
                                          ).round().astype(int))
            best = min(first, key=at)
            pos = int(np.searchsorted(first, best))
            lo_j = first[pos - 1] if pos > 0 else 0
            hi_j = first[pos + 1] if pos + 1 < first.size else vals.size - 1
            best = min(range(lo_j, hi_j + 1), key=at)
            fixed[i] = vals[best]

    def fit(self, data: Mapping[str, np.ndarray], *, thickness_mm: float,
            weights: np.ndarray | None = None, loss: str = "soft_l1",
            f_scale: float | None = None,
            start: Mapping[str, float] | None = None,
            identify: bool = True, stated_noise: bool = False) -> ModelFit:
        """Fit the model by (weighted, robust) least squares.

        Parameters
        ----------
        data : mapping of str to (N,) array_like
            At least the model's :attr:`columns` (a measurements table's
            ``columns``).
        thickness_mm : float
            h.
        weights : (N,) array_like, optional
            Per-press weights; default equal (least squares on P, efficient
            for a force noise that does not grow with depth). E and nu read
            through :func:`fit_model` do not depend on the weighting: it
            fits the same model, with the same weights, to the FEM's P(w).
        loss : {'soft_l1', 'linear', 'huber', 'cauchy'}, default 'soft_l1'
            Robust loss of :func:`scipy.optimize.least_squares`. 'soft_l1'
            behaves as least squares for residuals below `f_scale` and grows
            linearly beyond, so one or two outlier presses pull the fit by
            their scale, not its square.
        f_scale : float, optional
            Residual scale of the robust loss. Default: 2.5 times the robust
            (MAD) residual sd of a first least-squares fit.
        start : mapping of str to float, optional
            Parameter values to start from (e.g. ``ModelFit.params`` of this
            model, or of one effect fewer, on the same or nearly the same
            presses); names the model lacks are ignored. Only change points
            read it: one given here is searched by descent from it, not over
            all its candidates: faster, and the same answer unless the cost has
            another minimum farther off. The other parameters start at their
            catalogue values (:attr:`Param.value`). Default: a full search.
        identify : bool, default True
            Check the corners of the model for parameters that only seem
            identified (:attr:`ModelFit.unidentified`): a few more fits when a
            parameter ends on its bound while another is undetermined. False
            keeps the local (Jacobian) check only, for a caller that reads
            costs and predictions of many candidate fits (:func:`diagnose`'s
            search and cross-validation folds).
        stated_noise : bool, default False
            The `weights` are ``1 / sigma_i^2`` of the forces' stated standard
            uncertainties (N^-2): the covariance's scale is then at least that
            noise's (chi-square per degree of freedom floored at one), raised
            to the residuals' own scatter only where they scatter more (a Birge
            ratio above one), as ``absolute_sigma`` of
            :func:`scipy.optimize.curve_fit` with the scatter as a check. False:
            the scale is the residuals' own (relative weights).

        Returns
        -------
        ModelFit

        Raises
        ------
        InputError
            For a missing column (named), NaN in a needed column, or fewer
            presses than parameters + 1.
        """
        names = self.param_names()
        d, sw, wts = self._checked(data, weights, len(names))
        n = d["depth_mm"].size
        effects = self._effects()
        x0, lo, hi = [float(np.median(d["force_n"] / d["depth_mm"]))], [0.0], [math.inf]
        for e in effects:
            for q in e.params:
                x0.append(q.value)
                lo.append(q.lower)
                hi.append(q.upper)
        P = d["force_n"]
        # parameters found by search (change points): fixed in each least-squares fit
        dh = {**d, "_h": float(thickness_mm), "_a_over_h": self.a_over_h}
        searched: dict[int, np.ndarray] = {}
        for e in effects:
            for q, vals in e.profile(dh).items():
                vals = np.asarray(vals, np.float64)
                if vals.size == 0:
                    raise InputError(f"{e.name}: too few presses with distinct {e.columns[0]} "
                                     "to place the change point")
                searched[names.index(f"{e.name}.{q}")] = vals
        free = np.array([i for i in range(len(names)) if i not in searched], int)
        lo_f, hi_f = np.array(lo)[free], np.array(hi)[free]
        x0_f = np.clip(np.array(x0)[free], lo_f + 1e-12, hi_f - 1e-12)
        fixed = np.array(x0, np.float64)

        resid = _Residuals(effects, fixed, free, dh, sw, P, lo_f, hi_f,
                           shared=shared_groups(data, n))

        near: dict[int, float] = {}
        if start is not None:
            for i, q in enumerate(names):
                if q in start and i in searched:
                    near[i] = float(start[q])
        if searched:
            self._search(resid, fixed, searched, x0_f, (lo_f, hi_f), near=near,
                         jac=resid.jac)
        sol, scale = _solve(resid, x0_f, (lo_f, hi_f), loss=loss, f_scale=f_scale)
        r = sol.fun
        k = len(names)
        J = np.zeros((n, k))
        J[:, free] = sol.jac
        x_full = fixed.copy()
        x_full[free] = sol.x
        active = np.zeros(k, int)
        active[free] = sol.active_mask
        rho_w = _robust_weights(r, scale, loss)
        cov, bad, s2 = _covariance(J * np.sqrt(rho_w)[:, None], r, rho_w,
                                   # the weights are normalised to mean one: sigma^2 = 1 / w
                                   floor=1.0 / float(wts.mean()) if stated_noise else 0.0)
        srch = np.zeros(k, bool)
        srch[list(searched)] = True
        bad &= ~srch                # found by search: no standard error, but identified
        if identify and bad.any() and np.any(active != 0):
            bad |= _off_bound_alias(resid, sol, free, x_full, active, bad, cov,
                                    loss=loss, f_scale=scale, s2=s2)
        cov[bad, :] = np.nan
        cov[:, bad] = np.nan
        cov[bad, bad] = np.inf
        cov[srch, :] = np.nan
        cov[:, srch] = np.nan
        se = np.sqrt(np.clip(np.diag(cov), 0, None))
        on_bound = active != 0
        se[on_bound & ~bad] = np.nan
        with np.errstate(invalid="ignore", divide="ignore"):
            corr = cov / np.outer(se, se)
        params = dict(zip(names, map(float, x_full), strict=True))
        pred = self.predict(params, d, thickness_mm)
        res = P - pred
        rss = float(np.sum(resid.transform(sw * res) ** 2))
        ll_term = n * math.log(max(rss / n, 1e-300))
        return ModelFit(
            model=self, params=params, stderr=dict(zip(names, map(float, se), strict=True)),
            correlation=corr, covariance=cov, predicted_n=pred, residuals_n=res, weights=wts,
            rmse_n=float(np.sqrt(np.mean(res ** 2))),
            bic=ll_term + (k + len(searched)) * math.log(n),
            aic=ll_term + 2 * k, n_presses=n, n_params=k, loss=loss,
            outliers=rho_w < 0.5, success=bool(sol.success), message=str(sol.message),
            unidentified=tuple(q for q, b in zip(names, bad, strict=True) if b))

    def _checked(self, data: Mapping[str, np.ndarray], weights: np.ndarray | None,
                 n_params: int) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray]:
        """The model's columns as float arrays, the square roots of the normalised
        weights, and the weights, after the checks :meth:`fit` documents."""
        missing = self.missing_columns(list(data))
        if missing:
            raise InputError(f"the model {self.names} needs the column(s) {', '.join(missing)}")
        d = {c: np.asarray(data[c], np.float64) for c in self.columns}
        n = d["depth_mm"].size
        for c, v in d.items():
            if v.shape != (n,):
                raise InputError(f"column {c} has {v.size} values, depth_mm {n}")
            if c != "wait_s" and not np.all(np.isfinite(v)):
                row = int(np.argmax(~np.isfinite(v)))
                raise InputError(f"column {c} holds NaN or inf (row {row})")
        if n < n_params + 1:
            raise InputError(f"{n} presses are too few for {n_params} parameters")
        wts = np.ones(n) if weights is None else np.asarray(weights, np.float64)
        if wts.shape != (n,) or not np.all(np.isfinite(wts) & (wts > 0)):
            raise InputError("weights must be positive and finite, one per press")
        return d, np.sqrt(wts / wts.mean()), wts


def shared_groups(data: Mapping[str, np.ndarray], n: int) -> np.ndarray | None:
    """The operator of the quasi-demeaning (Fuller and Battese, J. Econometrics 2, 67,
    1974) that makes least squares on the transformed residuals generalized least squares
    under an error shared within groups of presses: ``data['_group']`` (each press's
    group) and ``data['_theta']`` (its group's theta = 1 - sqrt(s^2 / (s^2 + n_g t_g^2)),
    s the presses' own noise, t_g the error the group shares, in force), which
    ``diagnose`` sets. The (N, N) matrix S with ``S f = theta_g mean_g(f)``, or None."""
    if "_group" not in data or "_theta" not in data:
        return None
    g = np.asarray(data["_group"], np.float64)
    th = np.asarray(data["_theta"], np.float64)
    if g.shape != (n,) or th.shape != (n,) or not np.any(th > 0):
        return None
    same = (g[:, None] == g[None, :]).astype(np.float64)
    return th[:, None] * same / same.sum(axis=1, keepdims=True)


def _solve(resid: _Residuals, x0: np.ndarray, bounds: tuple[np.ndarray, np.ndarray], *,
           loss: str, f_scale: float | None):
    """Least squares from `x0`, then, for a robust `loss`, again from there with that loss
    at `f_scale` (default 2.5 times the MAD residual sd of the first fit); the solution
    (:class:`scipy.optimize.OptimizeResult`) and the scale (NaN for 'linear')."""
    first = least_squares(resid, x0, jac=resid.jac, bounds=bounds, x_scale="jac",
                          method="trf")
    if loss == "linear":
        return first, math.nan
    r0 = first.fun
    mad = 1.4826 * float(np.median(np.abs(r0 - np.median(r0))))
    scale = f_scale if f_scale is not None else 2.5 * max(mad, 1e-12)
    sol = least_squares(resid, first.x, jac=resid.jac, bounds=bounds, x_scale="jac",
                        method="trf", loss=loss, f_scale=scale)
    return sol, scale


def _robust_weights(r: np.ndarray, scale: float, loss: str) -> np.ndarray:
    """The weights rho'(z) of the robust `loss` at the residuals `r` (z = (r / scale)^2;
    1 for least squares), as scipy.optimize.least_squares defines the losses."""
    if loss == "linear":
        return np.ones(r.size)
    z = (r / scale) ** 2
    if loss == "huber":
        return 1 / np.sqrt(np.maximum(z, 1.0))
    if loss == "cauchy":
        return 1 / (1 + z)
    if loss == "arctan":
        return 1 / (1 + z ** 2)
    return 1 / np.sqrt(1 + z)


def _covariance(Jw: np.ndarray, r: np.ndarray, rho_w: np.ndarray, floor: float = 0.0
                ) -> tuple[np.ndarray, np.ndarray, float]:
    """The parameters' covariance s2 (Jw' Jw)^+ from the weighted Jacobian `Jw` (N, K),
    the parameters in a null direction of its column-normalised form (unidentified:
    pinv alone would give them a finite, too small, error), and s2 (at least `floor`: the
    stated noise's, in the normalised weights' units)."""
    k = Jw.shape[1]
    s2 = max(float(np.sum(rho_w * r ** 2)) / max(float(np.sum(rho_w)) - k, 1.0), floor)
    try:
        cov = np.linalg.pinv(Jw.T @ Jw) * s2
        norm = np.linalg.norm(Jw, axis=0)
        _, sv, vt = np.linalg.svd(Jw / np.where(norm > 0, norm, 1.0), full_matrices=False)
        null = vt[sv < 1e-7 * sv[0]] if sv.size and sv[0] > 0 else vt
        bad = (np.any(np.abs(null) > 1e-3, axis=0) if null.size else np.zeros(k, bool))
        bad |= norm == 0
    except np.linalg.LinAlgError:  # pragma: no cover
        cov, bad = np.full((k, k), np.nan), np.ones(k, bool)
    return cov, bad, s2


def _off_bound_alias(resid: _Residuals, sol, free: np.ndarray, x_full: np.ndarray,
                     active: np.ndarray, bad: np.ndarray, cov: np.ndarray, *, loss: str,
                     f_scale: float, s2: float) -> np.ndarray:
    """Parameters that a fit ending on a bound only seems to identify.

    When a parameter sits on its bound and another is already unidentified, the fit
    may have stopped in a corner of the model where one effect switches the other off
    (a relaxation of strength g = 0 has no time constant; one far faster than every hold
    has no visible g, which then trades with c). The local Jacobian sees the corner
    only. Each bounded parameter is therefore moved a quarter of its range inwards and
    held there while the others are refitted, starting with every unidentified
    parameter at either of its bounds; if the best refit's cost rises by less than one
    unit of chi-square (s2), the data do not pin the bounded parameter, and it is
    unidentified, with every parameter that moved by more than three of its standard
    errors between the two fits (a profile-likelihood check; Raue et al.,
    Bioinformatics 25(15), 2009, on structurally non-identifiable parameters).

    Returns
    -------
    (k,) ndarray of bool
        The parameters found unidentified by this check (all ``False`` if none).
    """
    k = x_full.size
    out = np.zeros(k, bool)
    se = np.sqrt(np.clip(np.diag(cov), 0, None))
    lo_all = np.full(k, -np.inf)
    hi_all = np.full(k, np.inf)
    lo_all[free], hi_all[free] = resid.lower, resid.upper
    kw = {} if loss == "linear" else {"loss": loss, "f_scale": f_scale}
    for j in np.flatnonzero(active != 0):
        lo, hi = lo_all[j], hi_all[j]
        if not (np.isfinite(lo) and np.isfinite(hi)):
            continue
        trial = x_full.copy()
        trial[j] = lo + 0.25 * (hi - lo) if active[j] < 0 else hi - 0.25 * (hi - lo)
        rest = np.array([i for i in free if i != j], int)
        if rest.size == 0:
            continue
        keep = np.isin(free, rest)
        sub = resid.with_free(trial, rest, resid.lower[keep], resid.upper[keep])
        starts = [trial[rest]]
        for i in np.flatnonzero(bad[rest]):
            for edge in (sub.lower[i], sub.upper[i]):
                if np.isfinite(edge):
                    x = trial[rest].copy()
                    x[i] = edge
                    starts.append(x)
        best = min((least_squares(sub, np.clip(x0, sub.lower + 1e-12, sub.upper - 1e-12),
                                  jac=sub.jac, bounds=(sub.lower, sub.upper), x_scale="jac",
                                  method="trf", **kw) for x0 in starts),
                   key=lambda r: r.cost)
        if 2.0 * (best.cost - sol.cost) >= s2:
            continue
        out[j] = True
        moved = np.abs(best.x - x_full[rest]) > 3.0 * se[rest]
        out[rest[moved & np.isfinite(se[rest])]] = True
    return out


def _plan(effects: Sequence[Effect]) -> tuple[tuple[Effect, str, tuple], ...]:
    """The effects in the order they act (depth, then stiffness, then force; the order
    of `effects` within a kind), each with its parameters' names and their places in the
    parameter vector (``c_n_per_mm`` first, then every effect's in the order of
    `effects`, as :meth:`IndentationModel.param_names`)."""
    places, i = [], 1
    for e in effects:
        places.append(tuple((q.name, i + j) for j, q in enumerate(e.params)))
        i += len(e.params)
    return tuple((e, kind, p) for kind in ("depth", "stiffness", "force")
                 for e, p in zip(effects, places, strict=True) if e.kind == kind)


def _forward(plan: Sequence[tuple[Effect, str, tuple]], x: Sequence[float],
             d: dict[str, np.ndarray]) -> np.ndarray:
    """Predicted force at the parameter values `x` (floats, in the order of
    :func:`_plan`'s places) on the data `d` (with ``_h`` and ``_a_over_h``; its
    ``depth_mm`` is replaced by the depth the law sees)."""
    w = np.asarray(d["depth_mm"], np.float64)
    force = None
    for e, kind, places in plan:
        p = {q: x[i] for q, i in places}
        if kind == "depth":
            w = e.apply(p, d, w)
            continue
        if force is None:
            d["depth_mm"] = w
            force = x[0] * w
        if kind == "stiffness":
            force = force * e.apply(p, d, force)
        else:
            force = e.apply(p, d, force)
    if force is None:
        d["depth_mm"] = w
        force = x[0] * w
    return force


#: Catalogue effects whose ``apply`` broadcasts parameters given as (K, 1) columns
#: against the (N,) columns (element by element the operations of scalar parameters);
#: not FemLaw (it reads nu as one float), nor effects of one's own.
_BROADCASTING = (_cat.LargeDeformation, _cat.DepthOffset, _cat.ForceOffset, _cat.ForceDrift,
                 _cat.ForceCrosstalk, _cat.ViscoelasticRelaxation, _cat.IncompleteRecovery,
                 _cat.Aging, _cat.SpatialNonuniformity, _cat.StiffnessTrend,
                 _cat.StiffnessStep, _cat.ForceTrend, _cat.LawCurvature)

#: The relative step of scipy's '2-point' finite differences for float64
#: (``scipy.optimize._numdiff._eps_for_method``).
_REL_STEP = float(np.finfo(np.float64).eps ** 0.5)


class _Residuals:
    """The weighted residuals ``sw (P_model - P)`` of one fit as a function of its free
    parameters (the others read from `fixed`, which a search changes in place), and
    their Jacobian for :func:`scipy.optimize.least_squares`.

    The effects' order, the parameters' places and the data dict are prepared once per
    fit, not at every evaluation. :meth:`jac` takes the forward differences of
    least_squares' default ``jac='2-point'`` with its step rule (step sqrt(eps) max(1,
    |x|) signed as x, turned back or shortened at a bound, as
    ``scipy.optimize._numdiff.approx_derivative``), so that the Jacobian, and every
    fit, are the same to the last bit, without approx_derivative's overhead; the
    residual at the point itself is the last one evaluated (least_squares asks for the
    Jacobian where it has just evaluated the residuals).
    """

    def __init__(self, effects: Sequence[Effect], fixed: np.ndarray, free: np.ndarray,
                 data: Mapping[str, np.ndarray], sw: np.ndarray, force_n: np.ndarray,
                 lower: np.ndarray, upper: np.ndarray,
                 shared: np.ndarray | None = None) -> None:
        self.shared = shared          # (N, N): theta times each press's group mean, or None
        self.plan = _plan(effects)
        self.fixed, self.free = fixed, free
        self.data = dict(data)
        self.sw, self.force_n = sw, force_n
        self.lower, self.upper = lower, upper
        self.bounded = not np.all((lower == -np.inf) & (upper == np.inf))
        self.lower_l, self.upper_l = lower.tolist(), upper.tolist()
        self.free_l = np.asarray(free).tolist()
        self.batch = all(type(e) in _BROADCASTING for e in effects)
        self._x: np.ndarray | None = None
        self._f: np.ndarray | None = None

    def with_free(self, fixed: np.ndarray, free: np.ndarray, lower: np.ndarray,
                  upper: np.ndarray) -> _Residuals:
        """The same residuals with other parameters held (`fixed`) and freed (`free`,
        bounded by `lower` and `upper`): the effects and data are shared, not rebuilt."""
        other = copy.copy(self)
        other.fixed, other.free, other.free_l = fixed, free, np.asarray(free).tolist()
        other.lower, other.upper = lower, upper
        other.lower_l, other.upper_l = lower.tolist(), upper.tolist()
        other.bounded = not np.all((lower == -np.inf) & (upper == np.inf))
        other._x = other._f = None
        return other

    def transform(self, f: np.ndarray) -> np.ndarray:
        """The residuals quasi-demeaned within the groups that share an error
        (:func:`shared_groups`): ``f - theta_g mean_g(f)``; `f` itself without groups."""
        return f if self.shared is None else f - f @ self.shared.T

    def _full(self, x: np.ndarray) -> np.ndarray:
        full = self.fixed.copy()
        full[self.free] = x
        return full

    def __call__(self, x: np.ndarray) -> np.ndarray:
        full = self._full(x)
        f = self.transform(
            self.sw * (_forward(self.plan, full.tolist(), dict(self.data)) - self.force_n))
        # the last point, all parameters (a search changes the fixed ones between solves)
        self._x, self._f = full, f
        return f

    def jac(self, x: np.ndarray) -> np.ndarray:
        x0 = np.asarray(x, np.float64)
        full = self._full(x0)
        f0 = (self._f if self._x is not None and np.array_equal(full, self._x)
              else self(x0))
        # scipy's step rule (_compute_absolute_step, then _adjust_scheme_to_bounds for a
        # one-sided scheme of one step), on floats: a few parameters, so faster than on
        # arrays, and the same IEEE operations
        base = full.tolist()
        jt = np.empty((x0.size, f0.size))
        steps: list[float] = []
        for i, (xi, lb, ub, k) in enumerate(zip(x0.tolist(), self.lower_l, self.upper_l,
                                                self.free_l, strict=True)):
            h = _REL_STEP * (1.0 if xi >= 0 else -1.0) * max(1.0, abs(xi))
            if self.bounded:
                lower_dist, upper_dist = xi - lb, ub - xi
                xh = xi + h
                if abs(h) <= max(lower_dist, upper_dist):
                    if xh < lb or xh > ub:
                        h = -h
                elif upper_dist >= lower_dist:
                    h = upper_dist
                else:
                    h = -lower_dist
            if self.batch:
                steps.append(xi + h)
            else:
                p = base.copy()
                p[k] = xi + h
                f = self.transform(
                    self.sw * (_forward(self.plan, p, dict(self.data)) - self.force_n))
                jt[i] = (f - f0) / ((xi + h) - xi)
        if self.batch:
            # all the shifted points in one evaluation: parameter j is a column holding
            # its own shifted value in row j and its value elsewhere (the effects' arrays
            # broadcast to one row per point; element by element the same operations)
            p = list(base)
            for i, k in enumerate(self.free_l):
                col = np.full((x0.size, 1), base[k])
                col[i, 0] = steps[i]
                p[k] = col
            f = self.transform(np.broadcast_to(
                self.sw * (_forward(self.plan, p, dict(self.data)) - self.force_n), jt.shape))
            dx = (np.array(steps) - x0)[:, None]
            jt[:] = (np.broadcast_to(f, jt.shape) - f0) / dx
        return jt.T
