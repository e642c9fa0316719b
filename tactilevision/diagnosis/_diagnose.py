"""Model against measurement: where the model fails and which effect is missing.

:func:`diagnose` fits a model (formats.md §4), tests its residuals for structure
along every covariate column, fits the model plus each applicable catalogue
effect, compares them by BIC and by cross-validated RMSE, and decides. The
greedy steps form the error ladder. The replicate noise floor is the error no
model of these columns can beat. The statistical tests themselves are in
:mod:`tactilevision.diagnosis._diagnose_stats`.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from tqdm import tqdm

from .._checks import InputError
from ..mechanics import (
    EFFECTS,
    Effect,
    IndentationModel,
    Misfit,
    ModelFit,
    assess_misfit,
    effect_name,
    fit_indentation,
    fit_model,
    kappa_n,
    make_effect,
    model_label,
    shared_groups,
)
from ._budget import (
    BUDGET_ALPHA,
    BUDGET_CONSISTENT_P,
    BUDGET_RATIO,
    NoiseBudget,
    noise_budget,
)
from ._crossings import CrossingScan
from ._diagnose_stats import (  # noqa: F401  (the statistics' names, also read from here)
    _NOT_COVARIATES,
    ALPHA,
    CERTIFICATION_COLUMNS,
    RESPONSE_COLUMNS,
    CertificationTest,
    CovariateTest,
    _covariate_names,
    _folds,
    _group_means,
    _groups,
    certification_tests,
    covariate_tests,
    cross_validated_rmse,
    noise_floor,
)
from ._holds import HoldsFinding

__all__ = [
    "CURVATURE_BIC",
    "DELTA_BIC",
    "EQUIVALENT_BIC",
    "Candidate",
    "CertificationTest",
    "CovariateTest",
    "Diagnosis",
    "LadderStep",
    "certification_tests",
    "covariate_tests",
    "cross_validated_rmse",
    "diagnose_core",
    "noise_floor",
    "untestable_reason",
]

#: Evidence a candidate effect must bring: BIC lower by more than this
#: ("very strong" on the scale of Kass and Raftery, JASA 90:773, 1995).
DELTA_BIC = 10.0
#: Candidates whose BIC is within this of the best explain the data equally well.
EQUIVALENT_BIC = 6.0
#: ... as do candidates whose RMSE is within this fraction of the best's (whatever their
#: number of parameters).
EQUIVALENT_RMSE = 0.01
#: How eq. (5)'s own misfit to the finite-strain law is kept from being read as an effect
#: (:func:`diagnose`'s ``curvature``): 'gate' or 'nuisance'.
CURVATURE = "gate"
#: 'nuisance': the law's curvature enters the model first when it lowers the BIC by this.
NUISANCE_BIC = 2.0
#: 'gate': a depth effect must beat the base law's own curvature (LawCurvature) by this
#: much BIC.
CURVATURE_BIC = 6.0
#: Columns along which a change point in stiffness (``stiffness_step:<column>``) is tried.
STEP_COLUMNS = ("press", "day", "time_s")
#: Generic effects: a winner is reported as an unexplained covariate, not a verdict.
_GENERIC = ("stiffness_trend:", "force_trend:")

# the measurement that separates two effects that look alike on one table
_SEPARATE = {
    frozenset({"depth_offset", "force_offset"}):
        "a tare check with nothing touching the gel (reads a force offset directly) or the "
        "gauge block's step heights measured on a height gauge (a depth offset)",
    frozenset({"force_drift", "aging"}):
        "repeated presses within one session (drift) against sessions on other days (aging)",
    frozenset({"force_drift", "force_offset"}):
        "a tare check at the start and end of the session",
}


@dataclass(frozen=True)
class Candidate:
    """The model plus one catalogue effect.

    Attributes
    ----------
    effect : str
    delta_bic : float
        BIC(model + effect) - BIC(model); negative is better.
    cv_rmse_n : float
        Cross-validated RMSE, N (NaN, ``null`` in JSON, where the BIC does
        not fall by more than ``DELTA_BIC``: not enough evidence to pass, not
        worth the folds).
    rmse_n : float
    params : dict of str to float
        The effect's fitted parameters (``<effect>.<param>``).
    n_presses : int
        Presses the comparison used (rows with the effect's columns).
    """

    effect: str
    delta_bic: float
    cv_rmse_n: float
    rmse_n: float
    params: dict[str, float] = field(hash=False)
    n_presses: int = 0


@dataclass(frozen=True)
class LadderStep:
    """One rung of the error ladder: a model, its errors and its E and nu."""

    model: tuple[str, ...]
    rmse_n: float
    cv_rmse_n: float
    bic: float
    E_mpa: float
    nu: float
    added: str | None


@dataclass(frozen=True)
class Diagnosis:
    """Result of :func:`diagnose`; :meth:`to_json_dict` is ``diagnose --json``.

    Attributes
    ----------
    model : tuple of str
        The model diagnosed: ``'layer'`` then its effects.
    E_mpa, nu : float
        Of that model (NaN without beta or out of the table).
    rmse_n, cv_rmse_n : float
    noise_floor_n : float
        Pooled sd of the final model's residuals within groups of repeated
        presses at one depth (NaN without repeats).
    covariates : tuple of CovariateTest
        Residual structure of the model diagnosed.
    covariates_after : tuple of CovariateTest
        The same after the effects the diagnosis added.
    candidates : tuple of Candidate
        The model plus each applicable effect, best first.
    missing_effect : str or None
    equivalent_effects : tuple of str
    separating_measurement : str or None
        What would tell `missing_effect` from `equivalent_effects`.
    unexplained_covariate : str or None
    offered_effect : str or None
        ``stiffness_trend:<column>`` for the unexplained covariate.
    ladder : tuple of LadderStep
    untestable : dict of str to tuple of str
        Catalogue effects not tried, and the columns that would make them
        testable.
    untestable_reasons : dict of str to str
        Why each was not tried: a column missing, with empty cells, or
        constant (the same value in every row: an effect along it cannot
        show).
    fits : tuple of ModelFit
        The ladder's fits (for the figures).
    fit_rows : tuple of (N,) bool ndarray
        The rows of `columns` each fit used (rows with a needed value
        missing are left out).
    columns : dict of str to ndarray
        The data.
    message : str
        The story in a few sentences.
    noise_budget : NoiseBudget or None
        The final model's replicate scatter against what the instruments
        explain (:func:`~tactilevision.diagnosis.noise_budget`); None when
        the table cannot say.
    noise_budget_missing : str
        Why there is no budget (empty when there is one).
    scanned_columns : tuple of str
        The covariate columns tested for structure (present and not
        constant).
    responses_not_scanned : tuple of str
        Response columns of the table left out of the scan
        (:data:`RESPONSE_COLUMNS`; ``scan`` adds them).
    rules_out : dict of str to EffectSensitivity
        With no missing effect and no unexplained covariate: for each catalogue
        effect, the smallest size this very table would have named in 95 % of
        replays at the noise the diagnosis tested against (``size`` in its
        ``unit``; NaN where the table cannot test it, inf where no size the
        parameter allows would be named; ``why`` says which). Empty otherwise.
    rules_out_note : str
        How those sizes were found, or why there are none.
    shared_depth : dict
        Where the table states the depth error each indenter's presses share
        (``depth_indenter_std_mm``): the fits' generalized least squares under it
        (``theta_min``, ``theta_max`` of the quasi-demeaning) and ``not_testable``,
        the effects named with the depths taken as independent but not under it,
        with the reason. Empty otherwise.
    certification : tuple of CertificationTest
        The base model's residual structure along the columns the depth rule
        computed (:data:`CERTIFICATION_COLUMNS`: ``overshoot_mm``), never scanned
        as covariates nor offered as physics: a significant one is a certification
        problem, reported with its size.
    crossings : CrossingScan or None
        Where the table has each press's force at its crossing of w0
        (``force_w0_n``, ``force_w0_sem_n``): those forces tested for a change
        within indenters (:func:`~tactilevision.diagnosis.crossing_tests`); its
        finding is the verdict where the ladder named nothing.
    holds : HoldsFinding or None
        Where the holds were given: what the force over each press's hold says of a
        relaxing gel (:func:`~tactilevision.diagnosis.holds_finding`); where it names
        ``viscoelastic_relaxation`` and the ladder named nothing, that is the verdict.
    fit_data : {'table', 'crossings', 'holds'}
        What the verdict's effect is fitted to: the table (``fit --effects``), the
        crossing forces where they found it under the mark rule (``fit --crossings
        --effects``: the mark's depths absorbed part of it) or the holds where they named
        the relaxation (``fit --holds``).
    """

    model: tuple[str, ...]
    E_mpa: float
    nu: float
    rmse_n: float
    cv_rmse_n: float
    noise_floor_n: float
    covariates: tuple[CovariateTest, ...]
    covariates_after: tuple[CovariateTest, ...]
    candidates: tuple[Candidate, ...]
    missing_effect: str | None
    equivalent_effects: tuple[str, ...]
    separating_measurement: str | None
    unexplained_covariate: str | None
    offered_effect: str | None
    ladder: tuple[LadderStep, ...]
    untestable: dict[str, tuple[str, ...]] = field(hash=False)
    untestable_reasons: dict[str, str] = field(default_factory=dict, hash=False)
    fits: tuple[ModelFit, ...] = field(default=(), hash=False, repr=False)
    fit_rows: tuple[np.ndarray, ...] = field(default=(), hash=False, repr=False)
    columns: dict[str, np.ndarray] = field(default_factory=dict, hash=False, repr=False)
    message: str = ""
    noise_budget: NoiseBudget | None = None
    noise_budget_missing: str = ""
    scanned_columns: tuple[str, ...] = ()
    responses_not_scanned: tuple[str, ...] = ()
    certification: tuple[CertificationTest, ...] = ()
    rules_out: dict[str, Any] = field(default_factory=dict, hash=False)
    rules_out_note: str = ""
    shared_depth: dict[str, Any] = field(default_factory=dict, hash=False)
    crossings: CrossingScan | None = field(default=None, hash=False)
    holds: HoldsFinding | None = field(default=None, hash=False)
    fit_data: str = "table"
    misfit: Misfit | None = field(default=None, hash=False)

    @property
    def depth_link_coarse(self) -> bool:
        """Whether the certified depths' own uncertainty dominates a noise level that hides
        gel effects (at least :data:`DEPTH_LINK_DOMINANCE` times the F/T window's part of the
        budget, the replicate scatter at least :data:`DEPTH_LINK_SHARE` of the median force);
        the message then says so instead of "nothing is missing"."""
        return bool(_coarse_depth_link(self))

    def to_json_dict(self) -> dict[str, Any]:
        """The ``diagnose --json`` object (formats.md §3), then extra keys.

        Returns
        -------
        obj : dict
            JSON-ready (NaN as None).
        """
        def num(v: float) -> float | None:
            return float(v) if math.isfinite(v) else None

        def cov(t: CovariateTest) -> dict:
            return {"name": t.name, "p_value": num(t.p_value),
                    "explained_fraction": num(t.explained_fraction),
                    "significant": t.significant, "n": t.n}

        return {
            "model": list(self.model),
            "params": {"E_mpa": num(self.E_mpa), "nu": num(self.nu)},
            "rmse_n": num(self.rmse_n), "cv_rmse_n": num(self.cv_rmse_n),
            "noise_floor_n": num(self.noise_floor_n),
            "misfit": None if self.misfit is None else self.misfit.to_json_dict(),
            "covariates": [cov(t) for t in self.covariates],
            "candidates": [{"effect": c.effect, "delta_bic": num(c.delta_bic),
                            "cv_rmse_n": num(c.cv_rmse_n),
                            "params": {k: num(v) for k, v in c.params.items()}}
                           for c in self.candidates],
            "verdict": {"missing_effect": self.missing_effect,
                        "equivalent_effects": list(self.equivalent_effects),
                        "unexplained_covariate": self.unexplained_covariate,
                        "offered_effect": self.offered_effect,
                        "separating_measurement": self.separating_measurement,
                        "fit_data": self.fit_data},
            "ladder": [{"model": list(s.model), "added": s.added, "rmse_n": num(s.rmse_n),
                        "cv_rmse_n": num(s.cv_rmse_n), "bic": num(s.bic),
                        "E_mpa": num(s.E_mpa), "nu": num(s.nu)} for s in self.ladder],
            "covariates_after": [cov(t) for t in self.covariates_after],
            "untestable": {k: list(v) for k, v in self.untestable.items()},
            "untestable_reasons": dict(self.untestable_reasons),
            "message": self.message,
            "noise_budget": (None if self.noise_budget is None
                             else self.noise_budget.to_json_dict()),
            "noise_budget_missing": self.noise_budget_missing or None,
            "depth_link_coarse": self.depth_link_coarse,
            "scanned_columns": list(self.scanned_columns),
            "responses_not_scanned": list(self.responses_not_scanned),
            "certification": [{"name": t.name, "p_value": num(t.p_value),
                               "explained_fraction": num(t.explained_fraction),
                               "significant": t.significant, "n": t.n,
                               "size_n": num(t.size_n)} for t in self.certification],
            "rules_out": {k: v.to_json_dict() for k, v in self.rules_out.items()},
            "rules_out_note": self.rules_out_note or None,
            "shared_depth": self.shared_depth or None,
            "crossings": None if self.crossings is None else self.crossings.to_json_dict(),
            "holds": None if self.holds is None else self.holds.to_json_dict(),
        }


# ----------------------------------------------------------------- pieces


#: A noise budget whose certified-depth term is at least this many times the F/T window's,
#: with a replicate scatter of at least this share of the median force, is the depth link's:
#: the message says so instead of "nothing is missing" (a mark's onset certifies to one
#: frame's travel, tens of um; the vernier to a few um: 0.7 % of the force).
DEPTH_LINK_DOMINANCE, DEPTH_LINK_SHARE = 2.0, 0.03


def _coarse_depth_link(d: Diagnosis) -> str:
    """A sentence when the depth certification's own uncertainty sets a noise level that
    hides gel effects (the budget consistent, but coarse), else ''."""
    b = d.noise_budget
    if b is None or b.exceeds or not np.isfinite(b.depth_n) or not np.isfinite(
            b.force_window_n) or b.depth_n < DEPTH_LINK_DOMINANCE * b.force_window_n:
        return ""
    force = np.abs(np.asarray(d.columns.get("force_n", []), np.float64))
    std = np.asarray(d.columns.get("depth_std_mm", []), np.float64)
    if not force.size or not std.size or b.floor_n < DEPTH_LINK_SHARE * float(np.median(force)):
        return ""
    return (f"the noise is large: {b.floor_n * 1e3:.3g} mN per press, "
            f"{100 * b.floor_n / float(np.median(force)):.0f} % of the median force, and "
            f"most of it is the certified depths' own uncertainty (depth_std_mm median "
            f"{1e3 * float(np.nanmedian(std)):.3g} um; certified depth x dP/dw "
            f"{b.depth_n * 1e3:.3g} mN of the {b.budget_n * 1e3:.3g} mN the instruments "
            "explain). Effects of the gel smaller than that cannot show here, and a depth "
            "lag shared by every press (the stage still moving when the depth is certified) "
            "cannot show at all: the law's curvature takes it up. A finer depth link (the "
            "bevel's vernier, bevel_angle_deg > 0; for a mark's onset, a faster camera or a "
            "slower approach) would show them.")


def _budget_sentence(b: NoiseBudget) -> str:
    """The diagnosis's sentence on a noise budget, its wording following both numbers.

    A small p is never called consistent: "consistent with" only for
    ``p >= BUDGET_CONSISTENT_P`` (0.05). Below it, and while the budget does
    not exceed (``p < BUDGET_ALPHA`` and ``ratio > BUDGET_RATIO``, the
    threshold this diagnosis acts on: :attr:`NoiseBudget.exceeds`), the
    scatter is said to be somewhat above the budget (or, with ``ratio <= 1``,
    larger than some presses' own budgets allow) but below that threshold.
    An exceeded budget gets the sentence that it is above the threshold (the
    diagnosis itself says more, on the measurement chain).

    Parameters
    ----------
    b : NoiseBudget

    Returns
    -------
    sentence : str
        One sentence: scatter and budget in mN (2 decimals), p to 2
        significant digits, the ratio to 2 decimals.
    """
    floor, budget = f"{b.floor_n * 1e3:.2f} mN", f"{b.budget_n * 1e3:.2f} mN"
    threshold = (f"the threshold this diagnosis acts on (p < {BUDGET_ALPHA:g} and a scatter "
                 f"more than {BUDGET_RATIO:g} times the budget)")
    if b.exceeds:
        return (f"The replicate scatter ({floor}) is {b.ratio:.2f} times what the instruments "
                f"explain ({budget}; p = {b.p_value:.2g}), above {threshold}.")
    if not b.p_value < BUDGET_CONSISTENT_P:   # a NaN p has nothing to contradict either
        return (f"The replicate scatter ({floor}) is consistent with what the instruments "
                f"explain ({budget}; p = {b.p_value:.2g}).")
    if b.ratio > 1:
        return (f"The replicate scatter ({floor}) is somewhat above what the instruments "
                f"explain ({budget}, {b.ratio:.2f} times; p = {b.p_value:.2g}), but below "
                f"{threshold}.")
    return (f"The replicate scatter ({floor}) is no larger than what the instruments explain "
            f"({budget}) on average, but larger at some presses than their own budget allows "
            f"(p = {b.p_value:.2g}); it stays below {threshold}.")


def _usable(name: str, columns: Mapping[str, np.ndarray]) -> str | None:
    """Why an effect cannot be tried on these columns (None: it can)."""
    e = make_effect(name)
    for col in e.columns:
        if col not in columns:
            return "missing"
        x = np.asarray(columns[col], np.float64)
        fin = x[np.isfinite(x)]
        if col != "wait_s" and fin.size < x.size:
            return "missing"
        if fin.size < 3 or np.ptp(fin) == 0:
            return "constant"
    return None


def _trend_passes(model: IndentationModel, column: str, d: Mapping[str, np.ndarray],
                  bic: float, h: float) -> bool:
    """Whether an effect along `column` lowers the model's BIC by more than DELTA_BIC:
    the evidence a verdict needs, asked of a covariate left over too. The effect is the
    named one that reads the column (``spatial_nonuniformity`` for ``y_mm``), as on the
    ladder, else a stiffness or force trend along it."""
    if column not in d or not np.all(np.isfinite(d[column])):
        return False
    tries = [n for n in EFFECTS if column in make_effect(n).columns and n not in model.names
             and make_effect(n).columns != ("depth_mm",)]
    if not tries:
        tries = [f"{kind}:{column}" for kind in ("stiffness_trend", "force_trend")]
    for name in tries:
        if name in model.names or any(c not in d for c in make_effect(name).columns):
            continue
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                f = model.with_effect(name).fit(d, thickness_mm=h, identify=False)
        except InputError:
            continue
        if f.bic < bic - DELTA_BIC:
            return True
    return False


def untestable_reason(name: str, columns: Mapping[str, np.ndarray]) -> str | None:
    """Why a table's columns cannot carry a catalogue effect, in words (None: they can).

    Parameters
    ----------
    name : str
        A catalogue effect (formats.md §5).
    columns : mapping of str to (N,) array_like
        The table's columns.

    Returns
    -------
    str or None
        The columns the effect needs that are missing, hold empty cells, fewer than 3
        values, or one value in every row: the test ``diagnose`` makes before it tries
        an effect.
    """
    if _usable(name, columns) is None:
        return None
    return _why(make_effect(name).columns, columns)


def _why(needed: Sequence[str], columns: Mapping[str, np.ndarray]) -> str:
    """Why columns cannot carry an effect, in words: missing, empty cells, or constant."""
    out = []
    for col in needed:
        if col not in columns:
            out.append(f"needs {col}")
            continue
        x = np.asarray(columns[col], np.float64)
        fin = x[np.isfinite(x)]
        if col != "wait_s" and fin.size < x.size:
            out.append(f"{col} has {x.size - fin.size} empty cells")
        elif fin.size < 3:
            out.append(f"{col} has {fin.size} values")
        elif np.ptp(fin) == 0:
            out.append(f"{col} is constant ({fin[0]:g} in every row): an effect along it "
                       "cannot show")
    return "; ".join(out)


# ----------------------------------------------------------------- diagnose


def diagnose_core(columns: Mapping[str, np.ndarray], *, thickness_mm: float,
                  radius_mm: float, base: str = "paper", effects: Sequence[str] = (),
                  beta_table: str = "fem", max_steps: int = 3, cv_folds: int = 10,
                  seed: int = 0, progress: bool = False, curvature: str = CURVATURE,
                  candidates: Sequence = (), scan: Sequence[str] = (),
                  not_tried: Mapping[str, str] | None = None) -> Diagnosis:
    """:func:`tactilevision.diagnosis.diagnose` without what its verdict rules out (the
    effect-size replay on the table): the ladder, the verdicts, the message.
    `not_tried`: catalogue effects left out of the ladder, each with the reason the
    message gives (listed as not testable on this table)."""
    cols = {k: np.asarray(v, np.float64) for k, v in columns.items()}
    h, a = float(thickness_mm), float(radius_mm)
    model = _model_to_diagnose(cols, h, a, base, effects)
    # the base law's own limits: rungs of the ladder, never verdicts, left out of E and nu
    # (on the FEM law, eq. (5)'s beta term is the departure of a gel that follows eq. 5)
    law_rungs = ("law_curvature",) + (("large_deformation",) if base == "fem" else ())
    table = _Table(cols, h, a, beta_table, law_rungs)
    pool = _candidate_pool(cols, base, model, candidates, tuple(scan))
    for n, why in (not_tried or {}).items():
        if n in pool.named and n not in pool.untestable:
            pool.untestable[n] = tuple(make_effect(n).columns)
            pool.why_untestable[n] = why
    if curvature not in ("gate", "nuisance"):
        raise InputError(f"curvature must be 'gate' or 'nuisance', got {curvature!r}")
    scan = pool.scan
    climb = _Climb(table=table, pool=pool, cv_folds=cv_folds, seed=seed, curvature=curvature)
    base_step, cov0 = _first_rungs(climb, model)
    _climb(climb, max_steps, progress)
    cov_after, d_final = _left_over(climb)
    cur_fit = climb.cur_fit
    floor = noise_floor(cur_fit.residuals_n, d_final)
    budget, budget_missing = noise_budget(cur_fit.residuals_n, cur_fit.predicted_n, d_final,
                                          _groups(d_final))
    misfit = _final_misfit(climb)
    separating = None
    if climb.missing_effect and climb.equivalent:
        separating = "; ".join(_separating(climb.missing_effect, e, cols)
                               for e in climb.equivalent)
    diag = Diagnosis(
        model=("layer", *model.names), E_mpa=base_step.E_mpa, nu=base_step.nu,
        rmse_n=base_step.rmse_n, cv_rmse_n=base_step.cv_rmse_n,
        noise_floor_n=floor, covariates=cov0, covariates_after=cov_after,
        candidates=climb.first_candidates, missing_effect=climb.missing_effect,
        equivalent_effects=climb.equivalent, separating_measurement=separating,
        unexplained_covariate=climb.unexplained, offered_effect=climb.offered, misfit=misfit,
        ladder=tuple(climb.ladder), untestable=pool.untestable,
        untestable_reasons=pool.why_untestable, fits=tuple(climb.fits),
        fit_rows=tuple(climb.fit_rows), columns=cols, noise_budget=budget,
        noise_budget_missing=budget_missing,
        scanned_columns=tuple(t.name for t in cov0),
        responses_not_scanned=tuple(c for c in RESPONSE_COLUMNS if c in cols and c not in scan),
        certification=certification_tests(
            _gls(climb.fits[0].residuals_n, climb.table.sub(climb.fit_rows[0])),
            climb.fits[0].predicted_n,
            climb.table.sub(climb.fit_rows[0])))
    return _with_message(diag)


def _final_misfit(climb) -> Misfit | None:
    """The misfit of the model the ladder reached (:func:`~tactilevision.mechanics.
    assess_misfit`): its residuals' serial correlation along depth and its presses'
    apparent E's drift (E P / P_fit, at the last rung's E where it has one)."""
    if not climb.fits:
        return None
    fit, rows = climb.fits[-1], climb.fit_rows[-1]
    d = climb.table.sub(rows)
    pred = np.asarray(fit.predicted_n, np.float64)
    if not np.all(pred > 0):
        return None
    E = climb.ladder[-1].E_mpa if climb.ladder else math.nan
    P = pred + np.asarray(fit.residuals_n, np.float64)
    # where each indenter's presses share a stated depth error (the fits' quasi-demeaning
    # groups), the structure and drift are read on the indenters' means
    group = (np.asarray(d["_group"]) if "_group" in d and "_theta" in d
             and np.any(np.asarray(d["_theta"], np.float64) > 0) else None)
    m = assess_misfit(d["depth_mm"], fit.residuals_n,
                      (E if math.isfinite(E) else 1.0) * P / pred, n_params=fit.n_params,
                      group=group)
    return m if math.isfinite(E) else replace(m, E_shallow_mpa=math.nan, E_deep_mpa=math.nan)


def _gls(residuals_n: np.ndarray, d: Mapping[str, np.ndarray]) -> np.ndarray:
    """A fit's residuals as its generalized least squares sees them: quasi-demeaned within
    the groups that share a depth error (``_group``, ``_theta``, the operator the fits use:
    :func:`~tactilevision.mechanics.shared_groups`), so that the covariate tests
    use the fits' noise model; the residuals themselves without groups."""
    r = np.asarray(residuals_n, np.float64)
    S = shared_groups(d, r.size)
    return r if S is None else r - S @ r


def _model_to_diagnose(cols: Mapping[str, np.ndarray], h: float, a: float, base: str,
                       effects: Sequence[str]) -> IndentationModel:
    """The model as given to :func:`diagnose`, checked against the table."""
    if base == "fem" and not (0.2 <= a / h <= 2.0):
        raise InputError(f"base 'fem' reads the FEM table at a/h = {a / h:.3g}, outside its "
                         "0.2 to 2.0")
    model = IndentationModel(base, tuple(e for e in effects
                                         if not (base == "paper" and e == "large_deformation")),
                             a / h if base == "fem" else None)
    missing = model.missing_columns(list(cols))
    if missing:
        raise InputError(f"the model {model.names} needs the column(s) {', '.join(missing)}")
    n_depths = np.unique(cols["depth_mm"]).size if "depth_mm" in cols else 0
    if n_depths < 2:
        # as fit_indentation: one depth fixes no line, so no verdict can be drawn
        raise InputError(f"depth_mm holds {n_depths} distinct depth(s); comparing eq. (5) with "
                         "the measurements needs presses at two depths or more")
    return model


@dataclass
class _Climb:
    """A diagnosis under way: its table, pool and settings, and the ladder climbed so far
    (its rungs, their fits and rows, the model reached and the verdicts found)."""

    table: _Table
    pool: _Pool
    cv_folds: int
    seed: int
    curvature: str
    ladder: list[LadderStep] = field(default_factory=list)
    fits: list[ModelFit] = field(default_factory=list)
    fit_rows: list[np.ndarray] = field(default_factory=list)
    current: IndentationModel | None = None
    cur_fit: ModelFit | None = None
    cur_cv: float = math.nan
    missing_effect: str | None = None
    equivalent: tuple[str, ...] = ()
    unexplained: str | None = None
    offered: str | None = None
    first_candidates: tuple[Candidate, ...] = ()

    def add_rung(self, model: IndentationModel, fit: ModelFit, cv: float, rows: np.ndarray,
                 d: Mapping[str, np.ndarray], added: str | None) -> LadderStep:
        """Put `model` (fitted on the rows `rows`, the columns `d`) on the ladder."""
        E, nu = self.table.material(model, d, fit)
        step = LadderStep(("layer", *model.names), fit.rmse_n, cv, fit.bic, E, nu, added)
        self.ladder.append(step)
        self.fits.append(fit)
        self.fit_rows.append(rows)
        self.current, self.cur_fit, self.cur_cv = model, fit, cv
        return step


def _first_rungs(c: _Climb, model: IndentationModel
                 ) -> tuple[LadderStep, tuple[CovariateTest, ...]]:
    """Rung 0, the model as given (and the law's curvature as a nuisance, if asked and
    seen); returns rung 0 and the covariate tests of its residuals."""
    table, h = c.table, c.table.h
    ok0 = table.rows_for(model)
    d0 = table.sub(ok0)
    fit0 = model.fit(d0, thickness_mm=h)
    cv0 = cross_validated_rmse(model, d0, thickness_mm=h, k=c.cv_folds, seed=c.seed,
                               start=fit0.params)
    n_depth = 2 if {"large_deformation", "fem_law"} & set(model.names) else 1
    step0 = c.add_rung(model, fit0, cv0, ok0, d0, None)
    cov0 = covariate_tests(_gls(fit0.residuals_n, d0), fit0.predicted_n, d0,
                           n_depth_params=n_depth,
                           scan=c.pool.scan)
    if (c.curvature == "nuisance" and "large_deformation" in model.names
            and "law_curvature" not in model.names
            and np.unique(d0["depth_mm"]).size >= 4):
        # the law's own curvature as a nuisance term, in the model before any effect is
        # tried, when the data show it (BIC lower by more than NUISANCE_BIC)
        mc = model.with_effect("law_curvature")
        fc = mc.fit(d0, thickness_mm=h)
        if fc.bic < fit0.bic - NUISANCE_BIC:
            cvc = cross_validated_rmse(mc, d0, thickness_mm=h, k=c.cv_folds, seed=c.seed,
                                       start=fc.params)
            c.add_rung(mc, fc, cvc, ok0, d0, "law_curvature")
    return step0, cov0


def _climb(c: _Climb, max_steps: int, progress: bool) -> None:
    """The greedy steps: the best passing candidate joins the model, one per rung."""
    pool, law_rungs = c.pool, c.table.law_rungs
    bar = None
    if progress:

        bar = tqdm(desc="diagnose", unit="fit", mininterval=0.5)
    for _step in range(max_steps):
        tried = [n for n in pool.named if n not in c.current.names and n not in pool.untestable]
        tried += [g for g in (*pool.steps, *pool.generic) if g not in c.current.names]
        if c.curvature == "gate" and {"large_deformation", "fem_law"} & set(c.current.names):
            tried += [r for r in law_rungs if r not in c.current.names]
        cands = _score_candidates(c.table, c.current, c.cur_fit, tried, cv_folds=c.cv_folds,
                                  seed=c.seed, bar=bar)
        if _step == 0:
            c.first_candidates = tuple(x for x in cands if x.effect not in law_rungs)
        chosen = _choose(cands, c.cur_cv, pool.partner, law_rungs, c.curvature)
        if chosen is None:
            break
        _take_step(c, *chosen)
    if bar is not None:
        bar.close()


def _take_step(c: _Climb, best: Candidate, eq: tuple[str, ...]) -> None:
    """Add the chosen candidate to the model, as a verdict where it is one, and refit."""
    if best.effect in c.table.law_rungs:
        pass   # the base law's own limit: a rung of the ladder, not a verdict
    elif best.effect.startswith(_GENERIC):
        if c.unexplained is None:
            c.unexplained = best.effect.partition(":")[2]
            c.offered = best.effect
    elif c.missing_effect is None:
        c.missing_effect, c.equivalent = best.effect, eq
    table, h = c.table, c.table.h
    current = c.current.with_effect(best.effect)
    d = table.sub(table.rows_for(current))
    # the start matters only to parameters found by search (the new effect's change
    # point is searched near its place in the candidate's fit): without one, this is
    # the candidate's fit again, now with the identifiability check the search skipped
    dh = {**d, "_h": h, "_a_over_h": current.a_over_h}
    cur_fit = current.fit(d, thickness_mm=h,
                          start=(c.cur_fit.params if not make_effect(best.effect).profile(dh)
                                 else {**c.cur_fit.params, **best.params}))
    c.add_rung(current, cur_fit, best.cv_rmse_n, table.rows_for(current), d, best.effect)


def _left_over(c: _Climb) -> tuple[tuple[CovariateTest, ...], dict[str, np.ndarray]]:
    """What is left: structure along a covariate (an unexplained one, if no step found
    one); returns the final model's covariate tests and columns."""
    current, cur_fit = c.current, c.cur_fit
    d_final = c.table.sub(c.table.rows_for(current))
    n_depth = 2 if {"large_deformation", "fem_law"} & set(current.names) else 1
    cov_after = covariate_tests(_gls(cur_fit.residuals_n, d_final), cur_fit.predicted_n, d_final,
                                n_depth_params=n_depth, scan=c.pool.scan)
    if c.unexplained is None:
        # along depth_mm, eq. (5) itself is not the FEM's exact P(w): depth structure
        # counts only through the named depth effects among the candidates
        left = [t for t in cov_after if t.significant and t.explained_fraction > 0.1
                and t.name not in ("press", "depth_mm", "indenter")
                and _trend_passes(current, t.name, d_final, cur_fit.bic, c.table.h)]
        if left:
            worst = min(left, key=lambda t: t.p_value)
            c.unexplained = worst.name
            c.offered = f"stiffness_trend:{worst.name}"
    return cov_after, d_final


@dataclass
class _Table:
    """A diagnosis's table and constants, with what every rung reads from them: the rows a
    model can use, a subset of the columns, and E and nu of a model (each model on each
    set of presses fitted once)."""

    cols: dict[str, np.ndarray]
    h: float
    a: float
    beta_table: str
    law_rungs: tuple[str, ...]
    materials: dict[tuple, tuple[float, float]] = field(default_factory=dict)

    def rows_for(self, m: IndentationModel) -> np.ndarray:
        """Rows with every column `m` reads finite (``wait_s`` may be NaN: no press before)."""
        ok = np.ones(self.cols["depth_mm"].size, bool)
        for c in m.columns:
            if c != "wait_s":
                ok &= np.isfinite(self.cols[c])
        return ok

    def sub(self, ok: np.ndarray) -> dict[str, np.ndarray]:
        """The columns on the rows `ok`."""
        return {k: v[ok] for k, v in self.cols.items()}

    def material(self, m: IndentationModel, d: Mapping[str, np.ndarray],
                 fit: ModelFit | None = None) -> tuple[float, float]:
        """E and nu of `m` on `d`; `fit`: m's own fit, if made.

        The law's own curvature is a nuisance of the comparison: E and nu are read
        through the model without it (with it, beta trades against its gamma).
        """
        full = m
        m = IndentationModel(m.base, tuple(e for e in m.effects if e not in self.law_rungs),
                             m.a_over_h)
        if m.base == "fem" and fit is not None and m == full:
            return self._material(m, d, fit)     # that fit is this one
        # the same model on the same presses (a law_curvature rung, left out here, adds
        # nothing to the model before it): the same fit, made once
        key = (m, tuple((k, v.tobytes()) for k, v in d.items()))
        if key not in self.materials:
            self.materials[key] = self._material(m, d, None)
        return self.materials[key]

    def _material(self, m: IndentationModel, d: Mapping[str, np.ndarray],
                  fit: ModelFit | None) -> tuple[float, float]:
        """E and nu of `m` (without law rungs) on `d`; `fit`: m's own fit (base 'fem')."""
        h, a = self.h, self.a
        if m.base == "fem":
            # the FEM law's own parameters: nu is its shape's, E from c = 2 a E kappa_0 /
            # (1 - nu^2) (eq. 1-2)
            f = fit
            if f is None:
                try:
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        f = m.fit(d, thickness_mm=h, identify=False)
                except InputError:
                    return math.nan, math.nan
            nu_f = f.params["fem_law.nu"]
            k0 = float(kappa_n(nu_f, a / h, 0.0))
            return f.params["c_n_per_mm"] * (1 - nu_f ** 2) / (2 * a * k0), nu_f
        if m.names == ("large_deformation",):
            # eq. (5) alone: the fit `fit` makes (the paper's, errors in both variables
            # where the table gives depth_std_mm in every row), so both report one E, nu
            u = d.get("depth_std_mm")
            u = u if u is not None and np.all(np.isfinite(u)) else None
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    f = fit_indentation(d["depth_mm"], d["force_n"], thickness_mm=h,
                                        radius_mm=a, beta_table=self.beta_table,
                                        depth_std_mm=u)
                return f.E_mpa, f.nu
            except InputError:
                return math.nan, math.nan
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                fit, _ = fit_model(d, m, thickness_mm=h, radius_mm=a,
                                   beta_table=self.beta_table)
            return fit.E_mpa, fit.nu
        except InputError:
            return math.nan, math.nan


@dataclass(frozen=True)
class _Pool:
    """The effects a diagnosis may try, and why the others cannot be tried."""

    named: list[str]                      # catalogue and user effects
    untestable: dict[str, tuple[str, ...]]
    why_untestable: dict[str, str]
    generic: list[str]                    # trends along covariates, and counterparts
    partner: dict[str, str]               # counterpart -> the named effect it challenges
    steps: list[str]                      # stiffness change points
    scan: tuple[str, ...]


def _candidate_pool(cols: Mapping[str, np.ndarray], base: str, model: IndentationModel,
                    candidates: Sequence, scan: tuple[str, ...]) -> _Pool:
    """The catalogue's effects (and the user's `candidates`) the table can test, the
    generic trends along its other covariates, each named effect's counterpart of the
    other kind along its own column, and the stiffness change points; :class:`_Pool`."""
    named = [n for n in EFFECTS if n != "large_deformation" or base == "layer"]
    # the user's own candidates: registered (import specs, classes) and tried as named physics
    if isinstance(candidates, str | Effect | type):
        candidates = (candidates,)
    own = [effect_name(c) for c in candidates]
    named += [n for n in dict.fromkeys(own) if n not in named and n not in model.names]
    untestable: dict[str, tuple[str, ...]] = {}
    why_untestable: dict[str, str] = {}
    for n in named:
        why = _usable(n, cols)
        if why is not None:
            untestable[n] = tuple(make_effect(n).columns)
            why_untestable[n] = _why(make_effect(n).columns, cols)
    read_by_named = {c for n in (*EFFECTS, *named) for c in make_effect(n).columns}
    bad = [c for c in scan if c not in cols]
    if bad:
        raise InputError(f"scan names columns the table does not have: {', '.join(bad)}")
    bad = [c for c in scan if c in CERTIFICATION_COLUMNS]
    if bad:
        raise InputError(f"scan names {', '.join(bad)}: computed by the depth rule, not a "
                         "condition of the press, it is never scanned as physics (structure "
                         "along it is reported as a certification problem)")
    trend_cols = [c for c in _covariate_names(cols, scan)
                  if c not in read_by_named and c not in ("press", "indenter", "force_std_n")
                  and _usable(f"stiffness_trend:{c}", cols) is None]
    # each named effect's counterpart of the other kind along the same column: a stiffness
    # change (grows with depth) against a force added at every depth
    generic = [f"stiffness_trend:{c}" for c in trend_cols]
    partner: dict[str, str] = {}
    for n in named:
        if n in untestable:
            continue
        e = make_effect(n)
        if e.kind not in ("stiffness", "force") or e.columns == ("depth_mm",):
            continue
        other = "force_trend" if e.kind == "stiffness" else "stiffness_trend"
        for c in e.columns:
            g = f"{other}:{c}"
            if c in RESPONSE_COLUMNS and c not in scan:
                continue            # a stiffness trend along a response is the force itself
            if g not in generic and _usable(g, cols) is None and c != "wait_s":
                generic.append(g)
                partner[g] = n
    steps = [f"stiffness_step:{c}" for c in STEP_COLUMNS if c in cols
             and _usable(f"stiffness_step:{c}", cols) is None
             and np.unique(cols[c][np.isfinite(cols[c])]).size > 1]
    return _Pool(named, untestable, why_untestable, generic, partner, steps, scan)


def _score_candidates(table: _Table, current: IndentationModel, cur_fit: ModelFit,
                      tried: Sequence[str], *, cv_folds: int, seed: int,
                      bar: Any = None) -> list[Candidate]:
    """The current model plus each effect of `tried`, against the current model on the
    same presses, best BIC first (the folds only for a candidate whose BIC can pass)."""
    h = table.h
    cands = []
    refs: dict[bytes, ModelFit] = {}    # the current model on fewer rows, by the rows
    for name in tried:
        m = current.with_effect(name)
        ok = table.rows_for(m)
        d = table.sub(ok)
        # the current model's change points are searched near their place in its fit
        if ok.sum() == cur_fit.n_presses:
            ref = cur_fit
        elif (ref := refs.get(ok.tobytes())) is None:
            ref = refs[ok.tobytes()] = current.fit(d, thickness_mm=h,
                                                   start=cur_fit.params, identify=False)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                mf = m.fit(d, thickness_mm=h, start=cur_fit.params, identify=False)
                # only a candidate that can pass needs its folds
                cv = (cross_validated_rmse(m, d, thickness_mm=h, k=cv_folds, seed=seed,
                                           start=mf.params)
                      if mf.bic < ref.bic - DELTA_BIC else math.nan)
        except InputError:
            continue
        if bar is not None:
            bar.update(1)
        own = {k: v for k, v in mf.params.items() if k.startswith(name + ".")}
        cands.append(Candidate(name, mf.bic - ref.bic, cv, mf.rmse_n, own, int(ok.sum())))
    cands.sort(key=lambda c: c.delta_bic)
    return cands


def _choose(cands: Sequence[Candidate], cur_cv: float, partner: Mapping[str, str],
            law_rungs: tuple[str, ...], curvature: str
            ) -> tuple[Candidate, tuple[str, ...]] | None:
    """The candidate that joins the model and the effects equivalent to it, or None when
    none passes: BIC lower by more than :data:`DELTA_BIC` and a lower cross-validated
    RMSE; a depth effect must also beat the law's own curvature by :data:`CURVATURE_BIC`
    ('gate'); a generic trend must beat every passing named effect by
    :data:`EQUIVALENT_BIC`."""
    # the law's own curvature: the alternative every depth effect must beat
    curv = [c for c in cands if c.effect in law_rungs]
    curv_bic = curv[0].delta_bic if curv else math.inf
    passing = [c for c in cands if c.delta_bic < -DELTA_BIC and c.cv_rmse_n < cur_cv
               and (make_effect(c.effect).columns != ("depth_mm",)
                    or c.effect in law_rungs or curvature == "nuisance"
                    or c.delta_bic < curv_bic - CURVATURE_BIC)]
    # a counterpart competes only with its named effect: it does not raise an alarm
    # of its own (so many more candidates would, by chance, on null tables); nor where a
    # stiffness change point along its own column raises one, where it is only that
    # change's other shape (a softening over the session against a step in time)
    names_passing = {c.effect for c in passing}
    passing = [c for c in passing
               if c.effect not in partner or partner[c.effect] in names_passing
               or _step_along(c.effect) in names_passing]
    if not passing:
        return None
    best = passing[0]
    generic_first = None
    if best.effect.startswith(_GENERIC):
        # a generic trend must beat every named effect that passes by EQUIVALENT_BIC;
        # else the named one (the catalogue's physics) is taken, the trend its equivalent
        named_ok = [c for c in passing if not c.effect.startswith((*_GENERIC, *law_rungs))]
        if named_ok and named_ok[0].delta_bic - best.delta_bic < EQUIVALENT_BIC:
            generic_first, best = best, named_ok[0]
    # equivalent: as good by BIC, or leaving the same residual (a change point between
    # two sessions is aging over their days; the BIC then differs by the step's place)
    eq = tuple(c.effect for c in passing
               if c is not best and (c.delta_bic - best.delta_bic < EQUIVALENT_BIC
                                     or c.rmse_n <= (1 + EQUIVALENT_RMSE) * best.rmse_n)
               and not c.effect.startswith((*_GENERIC, *law_rungs)))
    if generic_first is not None:
        eq = (*eq, generic_first.effect)
    return best, eq


def _step_along(effect: str) -> str | None:
    """The stiffness change point along a stiffness trend's column (None for others)."""
    kind, _, column = effect.partition(":")
    return f"stiffness_step:{column}" if kind == "stiffness_trend" else None


def _separating(a: str, b: str, cols: Mapping[str, np.ndarray]) -> str:
    key = frozenset({a, b})
    if key in _SEPARATE:
        return f"{a} vs {b}: {_SEPARATE[key]}"
    ca, cb = make_effect(a).columns, make_effect(b).columns
    if ca != cb:
        x, y = cols.get(ca[0]), cols.get(cb[0])
        r = math.nan
        if x is not None and y is not None:
            ok = np.isfinite(x) & np.isfinite(y)
            if ok.sum() > 2:
                r = float(np.corrcoef(x[ok], y[ok])[0, 1])
        return (f"{a} vs {b}: presses that vary {ca[0]} with {cb[0]} held fixed "
                f"(correlation {r:.2f} in this table)")
    return f"{a} vs {b}: presses at more depths and forces along {ca[0]}"


def _moduli_text(step: LadderStep) -> str:
    """``E = ... MPa, nu = ...`` of a rung, or that it gives none (a beta outside what the
    FEM gives its model, or a parameter the data do not identify: ``fit`` says which)."""
    if math.isfinite(step.E_mpa) and math.isfinite(step.nu):
        return f"E = {step.E_mpa:.4g} MPa, nu = {step.nu:.4g}"
    return ("no E or nu (its beta lies outside what the FEM gives the model, or a parameter "
            "is not identified: fit with --effects says which)")


def _final_in_table(d: Diagnosis) -> bool:
    """Whether the last rung of the ladder gives E and nu where its model has a beta (the
    small-strain layer alone, ``--base layer``, has none to give them)."""
    last = d.ladder[-1] if d.ladder else None
    return (last is None or "large_deformation" not in last.model
            or (math.isfinite(last.E_mpa) and math.isfinite(last.nu)))


def _with_message(d: Diagnosis) -> Diagnosis:
    floor = d.noise_floor_n
    base = d.ladder[0]
    s = [f"The model {model_label(d.model)} leaves an RMSE of {base.rmse_n * 1e3:.2f} mN "
         f"({base.cv_rmse_n * 1e3:.2f} mN cross-validated)"
         + (f" against a replicate noise floor of {floor * 1e3:.2f} mN." if math.isfinite(floor)
            else "; the table has no repeated depths for a noise floor.")]
    sig = sorted((t for t in d.covariates if t.significant), key=lambda t: t.p_value)
    if sig:
        s.append("Its residuals carry structure along "
                 + ", ".join(f"{t.name} (p = {t.p_value:.1g}, {t.explained_fraction:.0%} of "
                             "the residual variance)" for t in sig[:3]) + ".")
    else:
        s.append("Its residuals carry no significant structure along any covariate.")
    if d.scanned_columns or d.responses_not_scanned:
        s.append(f"Scanned: {', '.join(d.scanned_columns) or 'nothing'}"
                 + (f"; {', '.join(d.responses_not_scanned)} follow the force and are not "
                    "scanned (scan them with --scan; fx_n and fy_n are read by "
                    "force_crosstalk)" if d.responses_not_scanned else "") + ".")
    if d.missing_effect:
        step = next(x for x in d.ladder if x.added == d.missing_effect)
        s.append(f"Missing: {d.missing_effect}. Adding it brings the cross-validated RMSE to "
                 f"{step.cv_rmse_n * 1e3:.2f} mN and gives {_moduli_text(step)} (before: "
                 f"{_moduli_text(base)}).")
        fit = d.fits[d.ladder.index(step)] if len(d.fits) == len(d.ladder) else None
        g = fit.params.get("viscoelastic_relaxation.g") if fit is not None else None
        if (d.missing_effect == "viscoelastic_relaxation" and g is not None
                and math.isfinite(step.E_mpa)):
            s.append(f"That E is the instantaneous modulus E_0 (hold -> 0); the relaxed "
                     f"modulus (hold -> infinity) is E_inf = (1 - g) E_0 = "
                     f"{step.E_mpa * (1 - g):.4g} MPa (g = {g:.3g}). hold_s counts from "
                     "the end of the loading, which took time: E_0 here is the gel's at that "
                     "instant, below that of an instant load by what relaxed during the ramp; "
                     "the hold curves (calibrate's holds.csv, fit --holds) give the latter.")
        at = fit.params.get(f"{d.missing_effect}.at") if fit is not None else None
        if (d.missing_effect.startswith("stiffness_step:") and at is not None
                and math.isfinite(step.E_mpa)):
            sv = fit.params[f"{d.missing_effect}.s"]
            s.append(f"That E is the gel's up to {d.missing_effect.partition(':')[2]} = "
                     f"{at:g}; after it the stiffness is {1 + sv:.4g} times that "
                     f"(E = {step.E_mpa * (1 + sv):.4g} MPa).")
        if d.equivalent_effects:
            s.append(f"{', '.join(d.equivalent_effects)} explain the data equally well; "
                     f"to tell them apart: {d.separating_measurement}.")
    if d.unexplained_covariate:
        s.append(f"Structure along {d.unexplained_covariate} is explained by no named effect; "
                 f"{d.offered_effect} is offered.")
    s += _closing(d)
    b = d.noise_budget
    if b is not None and not b.exceeds:
        s.append(_budget_sentence(b))
    if d.untestable:
        s.append("Not testable on this table: " + "; ".join(
            f"{k} ({d.untestable_reasons.get(k) or 'needs ' + ', '.join(v)})"
            for k, v in d.untestable.items()) + ".")
    return replace(d, message=" ".join(s))


def _closing(d: Diagnosis) -> list[str]:
    """The certification problems, then how to read the verdict: nothing missing, or not
    to be read so (a certification problem, a measurement chain adding noise, a coarse
    depth link)."""
    s: list[str] = []
    b = d.noise_budget
    for t in d.certification:
        if t.significant:
            stated = b is not None and b.depth_n >= t.size_n
            s.append(f"The base model's residuals also follow {t.name}, a product of the "
                     f"depth rule, not a condition of the press (p = {t.p_value:.1g}, "
                     f"{t.explained_fraction:.0%} of the residual variance, "
                     f"{t.size_n * 1e3:.2f} mN RMS): "
                     + (f"the depth rule's own error, within what its stated depth "
                        f"uncertainty explains ({b.depth_n * 1e3:.2f} mN), not physics."
                        if stated else "a certification problem (the depths are off "
                        "together with what certified them), not physics."))
    chain = (f"the replicate scatter ({b.floor_n * 1e3:.2f} mN) is {b.ratio:.1f} times what "
             f"the instruments explain ({b.budget_n * 1e3:.2f} mN: F/T window "
             f"{b.force_window_n * 1e3:.2f} mN, certified depth x dP/dw "
             f"{b.depth_n * 1e3:.2f} mN; p = {b.p_value:.1g}): the measurement chain adds "
             "noise the table does not record. Check the depth certification (a lag or "
             "scatter of the certified depth), the clock offset and the force window."
             ) if b is not None and b.exceeds else ""
    coarse = _coarse_depth_link(d)
    cert = max((t.size_n for t in d.certification if t.significant), default=0.0)
    if not d.missing_effect and not d.unexplained_covariate:
        if cert > 0 and b is not None and b.depth_n >= cert:
            s.append(f"No effect of the gel's model is named; the certified depths' stated "
                     f"error ({cert * 1e3:.2f} mN RMS along the depth rule's products) would "
                     "hide an effect of that size.")
        elif cert > 0:
            s.append(f"No effect of the gel's model is named, but that certification problem "
                     f"({cert * 1e3:.2f} mN RMS) is not the model's noise: an effect of that "
                     "size would hide in it. Check the depth rule before reading this verdict.")
            if chain or coarse:
                s.append("Also, " + (chain or coarse))
        elif chain:
            s.append("No effect of the gel's model is missing, but " + chain)
        elif coarse:
            s.append("Nothing shows above the noise, but " + coarse)
        elif not _final_in_table(d):
            s.append("Nothing shows above the noise, but the model gives no E or nu here (its "
                     "beta lies outside what the FEM gives it: `fit` says OUT OF TABLE): the "
                     "model does not describe these presses, so it cannot be said to explain "
                     "them.")
        elif not math.isfinite(d.noise_floor_n) and b is None:
            s.append("Nothing shows above the residuals' own scatter, but the table has no "
                     "noise floor (no repeated depths, no stated force or depth uncertainty): "
                     "a misfit of the model cannot be told from noise here. Repeat depths, or "
                     "give force_sem_n and depth_std_mm, before reading this as nothing "
                     "missing.")
        else:
            s.append("Nothing is missing: the model explains the data to within its noise.")
    elif coarse:
        s.append("Also, " + coarse)
    elif chain:
        s.append("Also, " + chain)
    return s
