"""``diagnose``, and what its verdict rules out.

:func:`diagnose` runs the ladder (:func:`~tactilevision.diagnosis._diagnose.diagnose_core`)
and, when it names nothing, says what that rules out: the smallest size of each catalogue
effect that this very table would have named (the plan's effect-size replay,
:func:`~tactilevision.diagnosis.table_sensitivity`, on the measured presses at the noise
the diagnosis tested against), so that "none" reads "none larger than ...".
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import replace

import numpy as np

from .._checks import InputError
from ..mechanics import kappa_n_nu_range
from ._budget import law_slope
from ._crossings import (
    CROSSING_UNITS,
    CrossingScan,
    CrossingTest,
    crossing_measurements,
    crossing_sizes,
    crossing_step_places,
    crossing_tests,
)
from ._diagnose import CURVATURE, Diagnosis, diagnose_core
from ._holds import HOLDS_POWER, HoldsFinding, holds_finding
from ._replay import EffectSensitivity, table_sensitivity

__all__ = ["ABSORBED_BY_MARK", "DEPTH_ONLY", "RULES_OUT_DRAWS", "crossing_sensitivity",
           "diagnose", "indenter_shared"]

#: Effects that change the force between the presses of one indenter: under the mark
#: rule (w = w0 + (P - P(w0)) / (dP/dw)) such a change is read as depth, so a table of
#: mark-certified presses hardly shows them, and no size of them is ruled out.
ABSORBED_BY_MARK = ("force_drift", "viscoelastic_relaxation", "incomplete_recovery",
                    "aging", "spatial_nonuniformity", "force_crosstalk")

#: What the message says of a table certified by the mark rule.
MARK_SENTENCE = (
    "These depths were certified by the mark rule: each depth past w0 is read from the "
    "press's own force (w = w0 + (P - P(w0)) / (dP/dw)), so a force effect that changes "
    "the force between one indenter's presses (along time, press, position, hold, wait, "
    "the tangential forces) is read as depth and largely absorbed; this table shows "
    "mainly what moves each indenter's crossing force P(w0) (a force or depth offset, the law's "
    "shape). A bevel read as a vernier certifies depth apart from the force.")

#: Why an effect the mark rule absorbs is not ruled out.
MARK_WHY = ("not ruled out: the mark rule reads the depth past w0 from the force, so this "
            "effect, which changes the force between an indenter's presses, is largely "
            "absorbed")
#: Why an effect along depth alone is not ruled out where each indenter's depths share an
#: error: the replay draws independent presses, and such an effect is what that error
#: looks like from indenter to indenter.
SHARED_WHY = ("not ruled out: along depth alone it is what the depth error each indenter's "
              "presses share looks like, which the replay of independent presses leaves out")

#: Sessions replayed to find what a verdict rules out (the sizes' Monte Carlo error is
#: about 5 % at 400; :func:`effect_sensitivity` plans with 1000).
RULES_OUT_DRAWS = 400


def diagnose(columns: Mapping[str, np.ndarray], *, thickness_mm: float, radius_mm: float,
             base: str = "paper", effects: Sequence[str] = (), beta_table: str = "fem",
             max_steps: int = 3, cv_folds: int = 10, seed: int = 0,
             progress: bool = False, curvature: str = CURVATURE,
             candidates: Sequence = (), scan: Sequence[str] = (),
             rules_out: bool = True, depth_rule: str | None = None,
             holds: Mapping[str, np.ndarray] | HoldsFinding | None = None) -> Diagnosis:
    """Compare a model with the measurements and find the missing effect.

    Parameters
    ----------
    columns : mapping of str to (N,) array_like
        A measurements table (formats.md §2): ``depth_mm``, ``force_n`` and
        any covariates. Text columns must be left out.
    thickness_mm, radius_mm : float
        h and a, mm.
    base : {'paper', 'layer', 'fem'}, default 'paper'
        The paper's eq. (5), the small-strain layer alone, or the FEM's
        finite-strain law (:class:`~tactilevision.mechanics.FemLaw`, read at
        a/h; E and nu are its c and nu). With 'fem' the law's departures, a
        ``(w/h)^2`` curvature and eq. (5)'s own ``large_deformation`` (a gel
        that follows eq. 5 rather than the FEM), are rungs of the ladder,
        never verdicts, and depth effects must beat the better of them
        (`curvature`). See docs/diagnose_power.md for what it gains and
        costs.
    effects : sequence of str
        Effects already in the model diagnosed.
    beta_table : {'fem', 'paper'}, default 'fem'
        For E and nu at each step only: the residuals do not depend on it.
    max_steps : int, default 3
        Most effects added, greedily.
    cv_folds : int, default 10
    seed : int, default 0
        Seeds the cross-validation folds.
    progress : bool, default False
        A progress bar over the candidate fits.
    candidates : sequence of str, Effect subclass or Effect instance
        Effects of your own tried at every step beside the catalogue's, as
        named physics: each can be the verdict, is tested
        against its counterpart of the other kind along its columns, and is
        reported untestable when its columns are missing or constant. Specs
        as for :class:`IndentationModel` (``'package.module:ClassName'``,
        ``'path/to/file.py:ClassName'``, a registered name, a class or an
        instance; docs/custom_effects.md).
    scan : sequence of str, default ()
        Response columns (:data:`RESPONSE_COLUMNS`: ``fx_n``, ``fy_n``,
        ``force_std_n``) to scan as covariates all the same. By default they
        are not: they follow the force, so a trend along them is the force
        itself (a stiffness trend along ``fx_n`` is the normal force's).
        ``fx_n`` and ``fy_n`` are still read by ``force_crosstalk``. The
        columns scanned are in :attr:`Diagnosis.scanned_columns`.
    curvature : {'gate', 'nuisance'}, default :data:`CURVATURE`
        How eq. (5)'s own misfit to the finite-strain law (a ``(w/h)^2``
        curvature of P/w, :class:`LawCurvature`) is kept from being read as
        an effect. 'gate': the curvature is a candidate like the effects (a
        rung of the ladder, never a verdict) and a depth effect
        (``depth_offset``, ``force_offset``) must beat it by
        ``CURVATURE_BIC``. 'nuisance': the curvature enters the model before
        any effect is tried when it lowers the BIC by more than
        ``NUISANCE_BIC`` (with 4 or more distinct depths), and every effect
        is then judged against that model alike.
    rules_out : bool, default True
        With no missing effect and no unexplained covariate, replay the
        decisions on this table at its noise (:func:`table_sensitivity`) to
        say what the verdict rules out: for each catalogue effect, the
        smallest size the table would have named (``Diagnosis.rules_out``).
        On the paper's base only.
    depth_rule : str, optional
        How the depths were certified (``calibrate``'s rule; the table's sidecar
        ``[certification] depth_rule``). ``'mark'``: the depth past w0 is read
        from each press's force, so a force effect that varies between an
        indenter's presses is read as depth and absorbed; the message says so and
        such effects are not ruled out (:data:`ABSORBED_BY_MARK`).
    holds : mapping of str to (K,) ndarray or HoldsFinding, optional
        The force over each press's hold (``holds.csv``'s columns, or
        :func:`holds_finding`'s result): a decay at the depth the stage keeps names
        ``viscoelastic_relaxation`` where the ladder named nothing (a table read at
        one time of every hold cannot show it; :attr:`Diagnosis.holds`).

    Returns
    -------
    Diagnosis

    Raises
    ------
    InputError
        For a missing column of the model, an unknown effect, bad h, a, or
        fewer than two distinct depths.

    Notes
    -----
    At each step every applicable catalogue effect not yet in the model is
    added in turn and the extended model fitted (robust soft_l1 least
    squares, :meth:`IndentationModel.fit`); so are ``stiffness_step:<col>``
    (a change point in stiffness) along ``press``, ``day`` and ``time_s``
    (:data:`STEP_COLUMNS`), ``stiffness_trend:<col>`` for each covariate
    that no named effect reads, and, for each named effect along a column,
    its counterpart of the other kind along the same column
    (``stiffness_trend:time_s`` for ``force_drift``, ``force_trend:day``
    for ``aging``, ...): a stiffness change scales P(w), so its force
    grows with depth, where a force effect adds the same force at every
    depth, and the two compete on the same footing. The best candidate by BIC
    is accepted when its BIC is lower by more than ``DELTA_BIC`` = 10 and its
    10-fold cross-validated RMSE is lower too; an effect seen along depth
    alone (``depth_offset``, ``force_offset``) must also beat, by
    ``CURVATURE_BIC`` = 6, the base law's own curvature (a ``(w/h)^2`` term,
    :class:`LawCurvature`: the FEM's P(w) is not exactly eq. 5, and
    repeatable presses resolve the difference; see `curvature`). Other
    candidates that also pass and come within ``EQUIVALENT_BIC`` = 6 of it,
    or leave an RMSE within ``EQUIVALENT_RMSE`` = 1 % of its, are
    equivalent. A generic trend (``stiffness_trend``, ``force_trend``)
    wins a step only by beating every named effect that passes by
    ``EQUIVALENT_BIC``; else the named effect is taken and the trend is
    listed as its equivalent. A
    ``stiffness_trend`` or ``force_trend`` winner is not a named effect: its
    column is reported as ``unexplained_covariate`` and the trend as
    ``offered_effect``. After
    the last step, a covariate whose residual structure is still
    significant (:func:`covariate_tests`), explains more than 10 % of the
    residual variance and along which an effect (the named one that reads
    the column, else a stiffness or force trend) lowers the BIC by more
    than ``DELTA_BIC`` is reported as unexplained too. A
    counterpart competes only when its named effect passes: alone, it
    raises no alarm. When the base law's
    own curvature wins a step it is added to the ladder as ``law_curvature``
    (eq. 5's limit, not a missing physical effect; no verdict). The noise
    floor is :func:`noise_floor` of the final model's residuals.
    """
    kw = dict(thickness_mm=thickness_mm, radius_mm=radius_mm, base=base, effects=effects,
              beta_table=beta_table, max_steps=max_steps, cv_folds=cv_folds, seed=seed,
              progress=progress, curvature=curvature, candidates=candidates, scan=scan)
    shared = indenter_shared(columns)
    d = _ladder(columns, kw, shared)
    if depth_rule == "mark" and d.missing_effect in DEPTH_ONLY:
        d = _depth_only_checked(d, columns, kw, shared)
    if depth_rule == "mark":
        d = replace(d, message=d.message + " " + MARK_SENTENCE)
    if holds is not None and not isinstance(holds, HoldsFinding):
        holds = holds_finding(holds, columns)
    d = _with_holds(d, holds, depth_rule)
    d = _with_crossings(d, columns, depth_rule)
    if not rules_out or d.missing_effect or d.unexplained_covariate:
        return d
    if base != "paper":
        return replace(d, rules_out_note=f"what the verdict rules out is replayed on the "
                                         f"paper's base only, not on base {base!r}")
    hidden = {e: MARK_WHY for e in ABSORBED_BY_MARK} if depth_rule == "mark" else {}
    if shared is not None:
        hidden.update({e: SHARED_WHY for e in ("depth_offset", "force_offset")})
    own = {**(crossing_sensitivity(_as_scanned(columns, d.crossings))
              if d.crossings is not None else {}), **_holds_entries(holds)}
    return _with_rules_out(d, float(thickness_mm), float(radius_mm), hidden, own)


def crossing_sensitivity(columns: Mapping[str, np.ndarray], *, power: float = 0.95,
                         why: str = "from the crossing forces within indenters at their "
                                    "stated uncertainties (the family-wise tests' power)",
                         sessions: Sequence[tuple[np.ndarray, np.ndarray]] | None = None
                         ) -> dict[str, EffectSensitivity]:
    """The smallest within-indenter changes the crossing forces name, as entries of
    ``rules_out`` and of ``plan``'s ``effect_sizes``.

    Parameters
    ----------
    columns : mapping of str to (N,) array_like
        As for :func:`crossing_sizes` (``indenter``, ``force_w0_n``,
        ``force_w0_sem_n`` and the press's conditions).
    power : float, default 0.95
    why : str
        Each entry's sentence (the step's adds where its size is taken: half-way through
        the presses, and just after each press in ``at_places``).
    sessions : sequence of (keep, sem), optional
        Drawn sessions of the table's design (:func:`crossing_sizes`).

    Returns
    -------
    sizes : dict of str to EffectSensitivity
        :func:`crossing_sizes`'s, ``size`` in the display units of
        :data:`CROSSING_UNITS` (%, %/min, %/mm), ``size_param`` in the catalogue's, ``snr``
        NaN. Empty without crossing forces.
    """
    out = {}
    for name, size in crossing_sizes(columns, power=power, sessions=sessions).items():
        param, unit, factor = CROSSING_UNITS[name]
        places = (tuple((a, factor * s) for a, s in crossing_step_places(
            columns, power=power, sessions=sessions)) if name == "stiffness_step:press"
            else ())
        said = (why + "; a step half-way through the presses, and just after each press "
                "at_places names") if places else why
        out[name] = EffectSensitivity(effect=name, parameter=param, unit=unit,
                                      size=factor * size, size_param=size, power=power,
                                      snr=math.nan, why=said, at_places=places)
    return out


def _as_scanned(columns: Mapping[str, np.ndarray], scan: CrossingScan
                ) -> Mapping[str, np.ndarray]:
    """`columns` with the crossing forces' sds as the scan read them (scaled where the
    stated ones fall short of their scatter: :attr:`CrossingScan.statement_scale`), so
    that what the verdict rules out rests on the noise the tests found."""
    if scan.statement_scale == 1.0:
        return columns
    sem = np.asarray(columns["force_w0_sem_n"], np.float64) * scan.statement_scale
    return {**columns, "force_w0_sem_n": sem}


def _holds_entries(holds: HoldsFinding | None) -> dict[str, EffectSensitivity]:
    """The smallest decay the holds would have named, where they name none."""
    least = math.nan if holds is None else holds.smallest_rate_per_s
    if not math.isfinite(least):
        return {}
    return {"viscoelastic_relaxation": EffectSensitivity(
        effect="viscoelastic_relaxation", parameter="decay rate at the hold's start (holds)",
        unit="%/s", size=100.0 * least, size_param=least, power=HOLDS_POWER, snr=math.nan,
        why=(f"from the holds ({holds.source or 'given'}): the F test's power on "
             f"{holds.relaxation.n_presses} holds, "
             f"{least / holds.relaxation.decay_rate_se_per_s:.3g} standard errors of their "
             "measured rate"))}


#: The ladder's sentences for a table that names nothing, and what they read where a finding
#: beyond the table's columns (the holds, the crossing forces) then names an effect.
_NOTHING_NAMED = (
    ("Nothing is missing: the model explains the data to within its noise.",
     "The table's columns show nothing the model misses beyond their noise; what follows "
     "does."),
    ("No effect of the gel's model is named;", "The table's columns name no effect of the "
     "gel's model;"),
    ("No effect of the gel's model is named, but", "The table's columns name no effect of "
     "the gel's model, but"),
    ("No effect of the gel's model is missing, but", "The table's columns name no missing "
     "effect, but"),
    ("Nothing shows above the noise, but", "Nothing shows in the table's columns above the "
     "noise, but"))


def _named_beyond_table(d: Diagnosis, **verdict) -> Diagnosis:
    """`d` with a verdict found beyond the table's columns, its message no longer saying that
    nothing is named."""
    message = d.message
    for old, new in _NOTHING_NAMED:
        message = message.replace(old, new)
    return replace(d, message=message, **verdict)


#: Ladder verdicts seen along depth alone: under the mark rule they are also what a gel that
#: changes between the indenters' presses looks like (each indenter's depths move with its
#: crossing force P(w0)), so a finding within indenters or in the holds takes their place.
DEPTH_ONLY = ("depth_offset", "force_offset")


def _ladder(columns: Mapping[str, np.ndarray], kw: dict,
            shared: tuple[np.ndarray, np.ndarray] | None) -> Diagnosis:
    """:func:`diagnose_core` on the table, by generalized least squares under the depth
    error each indenter's presses share where the table states it."""
    if shared is None:
        return diagnose_core(columns, **kw)
    d = diagnose_core({**columns, "_group": shared[0], "_theta": shared[1]}, **kw)
    return _with_shared_depth(d, diagnose_core(columns, **{**kw, "progress": False}),
                              shared[1])


def _depth_only_checked(d: Diagnosis, columns: Mapping[str, np.ndarray], kw: dict,
                        shared: tuple[np.ndarray, np.ndarray] | None) -> Diagnosis:
    """Under the mark rule, an effect along depth alone (:data:`DEPTH_ONLY`) that the
    mark's depths name stands only where the crossing forces name it too.

    Each indenter's presses reach it at w0, a depth the frames certify apart from the
    force (:func:`crossing_measurements`); their depths past w0 are read through the force
    with the certification's own slope, so a law whose slope there differs from it looks
    like an offset along depth. On a generated mark session with nothing hidden (seed 8919
    of ``benchmarks/bench_crossings.py``), every indenter's depths within their stated
    uncertainty, the mark's depths named ``depth_offset`` (BIC lower by 26) where the
    crossing forces' own ladder named nothing; with a true depth offset of 10 to 40 um
    added to four such sessions the crossing forces named none either (the law's c and
    beta take it up over five depths). Where the crossing forces do not name it, the ladder
    is run again without the effects along depth alone, which the message lists as not
    identified."""
    try:
        cm = crossing_measurements(columns)
        own = diagnose_core(cm, **{**kw, "effects": (), "candidates": (), "scan": (),
                                   "progress": False})
    except InputError:
        return d
    if {own.missing_effect, *own.equivalent_effects} & set(DEPTH_ONLY):
        return d
    was = d.missing_effect
    why = ("not identified under the mark rule: the mark's depths past w0 are read through "
           "the force, and the crossing forces, at depths the frames certify apart from "
           "it, do not show it")
    again = _ladder(columns, {**kw, "not_tried": dict.fromkeys(DEPTH_ONLY, why)}, shared)
    seen = ", ".join(e for e in (was, *d.equivalent_effects) if e in DEPTH_ONLY)
    return replace(again, message=again.message + (
        f" The mark's depths named {seen} (an offset along depth alone), but the crossing "
        f"forces P(w0), each at a depth the frames certify apart from the force, do not "
        f"({own.missing_effect or 'nothing'} named on their own table): within an indenter "
        f"the mark's depths are read through the force with the certification's own slope, "
        f"and a law whose slope differs from it there looks like an offset along depth. "
        f"{seen} {'is' if ',' not in seen else 'are'} not identified on this table; the "
        f"verdict above is the ladder's "
        f"without the effects along depth alone."))


def _open_verdict(d: Diagnosis, depth_rule: str | None) -> bool:
    """Whether a finding beyond the table's columns may take the verdict: the ladder named
    nothing, or, under the mark rule, only an effect along depth (:data:`DEPTH_ONLY`) or one
    the mark's depths absorb (:data:`ABSORBED_BY_MARK`), which the table shows only through
    each indenter's crossing force."""
    if d.unexplained_covariate:
        return False
    return not d.missing_effect or (depth_rule == "mark" and d.missing_effect in (
        *DEPTH_ONLY, *ABSORBED_BY_MARK))


def _gives_way(d: Diagnosis, **verdict) -> Diagnosis:
    """`d` with a verdict found beyond the table's columns in place of the ladder's (none,
    or a depth-only one under the mark rule, which the message then explains)."""
    if not d.missing_effect:
        return _named_beyond_table(d, **verdict)
    was = d.missing_effect
    why = (f", seen along depth alone, is under the mark rule also what a gel that changes "
           f"between the indenters' presses looks like (each indenter's depths move with its "
           f"crossing force); the finding above, made at depths the frames or the stage keep, "
           f"is the verdict in its place ({was} not ruled out: a tare check or a height gauge "
           "tells)" if was in DEPTH_ONLY else
           " is an effect the mark's depths absorb, which the table shows only through each "
           "indenter's crossing force; the finding above, made at depths the frames or the "
           f"stage keep, is the verdict in its place ({was} not ruled out)")
    return replace(d, **{"equivalent_effects": (), **verdict},
                   message=d.message + f" The ladder's {was}{why}.")


def _with_holds(d: Diagnosis, finding: HoldsFinding | None, depth_rule: str | None = None
                ) -> Diagnosis:
    """`d` with what the holds say (:class:`HoldsFinding`); where the ladder named nothing
    (or, under the mark rule, only an effect along depth) and the holds name the
    relaxation, it is the verdict."""
    if finding is None:
        return d
    d = replace(d, holds=finding, message=d.message + " " + finding.sentence())
    if not finding.named or not _open_verdict(d, depth_rule):
        return d
    return _gives_way(d, missing_effect="viscoelastic_relaxation", fit_data="holds")


def _with_crossings(d: Diagnosis, columns: Mapping[str, np.ndarray],
                    depth_rule: str | None = None) -> Diagnosis:
    """`d` with the crossing forces' tests (:func:`crossing_tests`) and their sentence; where
    the ladder named nothing (or, under the mark rule, only an effect along depth), what
    they find is the verdict: a step or spatial structure as the missing effect, a trend as
    an unexplained covariate with its stiffness trend offered (as the ladder reports a
    trend)."""
    scan = crossing_tests(columns)
    if scan is None:
        return d
    d = replace(d, crossings=scan, message=d.message + " " + scan.sentence())
    found = scan.found
    if found is None or not _open_verdict(d, depth_rule):
        return d
    also = tuple(t.effect for t in scan.equivalent)
    along: dict[str, list[CrossingTest]] = {}
    for t in scan.equivalent:
        along.setdefault(t.column, []).append(t)
    sep = "; ".join(crossing_separating(found, ts, columns) for ts in along.values()) or None
    if sep is not None:
        d = replace(d, message=d.message + f" To tell them apart: {sep}.")
    how = "crossings" if depth_rule == "mark" else "table"
    if how == "crossings":
        d = replace(d, message=d.message + f" Fit {found.effect} on the crossing forces "
                    f"(fit --crossings --effects {found.effect}): the mark's depths, read "
                    "through the force, absorbed part of it, and E fitted to them is biased."
                    + ("" if scan.statement_scale == 1.0 else
                       " The crossing forces' stated sds fall short of their scatter by "
                       f"{scan.statement_scale:.2f}: that fit weighs them by the stated "
                       "ones, and its intervals are too narrow by about as much."))
    if found.kind == "trend" and found.column not in ("x_mm", "y_mm"):
        return _gives_way(d, missing_effect=None, unexplained_covariate=found.column,
                          offered_effect=found.effect, equivalent_effects=also,
                          separating_measurement=sep, fit_data=how)
    return _gives_way(d, missing_effect=found.effect, equivalent_effects=also,
                      separating_measurement=sep, fit_data=how)


def crossing_separating(a: CrossingTest, others: Sequence[CrossingTest],
                        columns: Mapping[str, np.ndarray]) -> str:
    """The presses that would tell changes the crossing forces fit about as well apart.

    Parameters
    ----------
    a : CrossingTest
        The change found.
    others : sequence of CrossingTest
        Changes listed beside it, along one column (a step and a trend along time).
    columns : mapping of str to (N,) array_like
        The measurements table (its columns of the tests, where it has them).

    Returns
    -------
    str
        ``"<a> vs <others>: ..."``: along `a`'s column, more presses along it (a step is a
        jump between neighbours, a trend a steady change); along another, presses that
        vary one with the other held fixed, with their correlation in this table.
    """
    b = others[0]
    head = f"{a.effect} vs {' and '.join(t.effect for t in others)}: "
    if a.column == b.column:
        return head + (f"more presses along {a.column} (a step shows as a jump between "
                       "neighbouring presses, a trend as a steady change)")
    x = np.asarray(columns.get(a.column, ()), np.float64)
    y = np.asarray(columns.get(b.column, ()), np.float64)
    r = math.nan
    if x.shape == y.shape and x.size > 2:
        ok = np.isfinite(x) & np.isfinite(y)
        if ok.sum() > 2 and np.ptp(x[ok]) > 0 and np.ptp(y[ok]) > 0:
            r = float(np.corrcoef(x[ok], y[ok])[0, 1])
    corr = f" (their correlation {r:.2f} in this table)" if math.isfinite(r) else ""
    both = {a.column, b.column}
    if both & {"x_mm", "y_mm"} and both & {"time_s", "press"}:
        return head + (f"presses that separate {a.column} from {b.column}{corr}: one spot "
                       "pressed again at the session's start and end, and spots across the "
                       "pad pressed in an order unrelated to time")
    return head + f"presses that vary {a.column} with {b.column} held fixed{corr}"


def indenter_shared(columns: Mapping[str, np.ndarray]
                    ) -> tuple[np.ndarray, np.ndarray] | None:
    """Each press's group and theta for generalized least squares under the depth error
    each indenter's presses share, from what the table states.

    With ``indenter``, ``depth_indenter_std_mm`` (the shared part u_I of each depth's sd
    u, counted n times over as ``depth_std_mm`` counts it), ``depth_std_mm`` and
    ``force_sem_n`` (s_P) in every row: the presses' own noise s^2 is the mean of
    ``s_P^2 + k^2 (u^2 - u_I^2)``, a group's shared error n_g t_g^2 the mean over its
    presses of ``(k u_I)^2`` (k = dP/dw, a quadratic through the table's P(w)), and
    theta_g = 1 - sqrt(s^2 / (s^2 + n_g t_g^2)): the quasi-demeaning of Fuller and
    Battese (J. Econometrics 2, 67, 1974), under which least squares is generalized
    least squares for a random error per group.

    Returns
    -------
    (group, theta) : two (N,) float64 ndarrays, or None
        None where the table does not state the shared part (or states none), or
        has fewer than two indenters or three depths.
    """
    need = ("indenter", "depth_indenter_std_mm", "depth_std_mm", "force_sem_n")
    if any(c not in columns for c in need):
        return None
    c = {k: np.asarray(columns[k], np.float64) for k in (*need, "depth_mm", "force_n")}
    if not all(np.all(np.isfinite(v)) for v in c.values()) or not np.any(
            c["depth_indenter_std_mm"] > 0):
        return None
    ids, gi = np.unique(c["indenter"], return_inverse=True)
    w = c["depth_mm"]
    if ids.size < 2 or np.unique(w).size < 3:
        return None
    k = law_slope(w, c["force_n"])
    u, ui = c["depth_std_mm"], c["depth_indenter_std_mm"]
    s2 = float(np.mean(c["force_sem_n"] ** 2 + k * k * np.maximum(u * u - ui * ui, 0.0)))
    if not s2 > 0:
        return None
    nt2 = np.bincount(gi, (k * ui) ** 2) / np.bincount(gi)
    theta = 1.0 - np.sqrt(s2 / (s2 + nt2))
    return gi.astype(np.float64), theta[gi]


def _with_shared_depth(d: Diagnosis, plain: Diagnosis, theta: np.ndarray) -> Diagnosis:
    """The diagnosis under the indenters' shared depth error, with what it leaves
    untestable: effects the ladder names with the depths taken as independent but not
    under it."""
    def named(x: Diagnosis) -> set[str]:
        return {e for e in (x.missing_effect, *x.equivalent_effects, x.offered_effect) if e}

    lost = sorted(named(plain) - named(d))
    why = ("the depth error each indenter's presses share (depth_indenter_std_mm) explains "
           "it as well: named with the depths taken as independent, not under that error")
    info = {"theta_min": float(theta.min()), "theta_max": float(theta.max()),
            "not_testable": {e: why for e in lost}}
    s = (f" Every fit weighs the presses by generalized least squares under the depth error "
         f"each indenter's presses share (depth_indenter_std_mm; quasi-demeaning theta "
         f"{theta.min():.2f} to {theta.max():.2f}), so effects that vary within an "
         "indenter keep their power.")
    if lost:
        s += (" Not testable on this table, that shared error explaining as much: "
              + ", ".join(lost) + ".")
    return replace(d, shared_depth=info, message=d.message + s)


def _press_noise(d: Diagnosis) -> tuple[np.ndarray, str]:
    """Each press's force noise, N, as the diagnosis tested against it: the stated part
    (the F/T window's standard error and the certified depth's uncertainty times dP/dw),
    scaled up to the final model's residual RMS where the presses scatter more than it
    says; that RMS alone where nothing is stated."""
    fit, rows = d.fits[-1], d.fit_rows[-1]
    r = np.asarray(fit.residuals_n, np.float64)
    rms = float(np.sqrt(np.mean(r ** 2)))
    cols = {k: np.asarray(v, np.float64)[rows] for k, v in d.columns.items()}
    sem = cols.get("force_sem_n")
    u = cols.get("depth_std_mm")
    parts = []
    stated = np.zeros(r.size)
    if sem is not None and np.all(np.isfinite(sem)):
        stated = stated + sem ** 2
        parts.append("the F/T window's standard error")
    ui = cols.get("depth_indenter_std_mm")
    if u is not None and ui is not None and np.all(np.isfinite(ui)):
        # the part each indenter's presses share moves them together, not press by press
        # (as the noise budget leaves it out)
        u = np.sqrt(np.maximum(u * u - ui * ui, 0.0))
    if u is not None and np.all(np.isfinite(u)):
        # local stiffness from the model's own P(w), as the noise budget takes it
        slope = law_slope(cols["depth_mm"], fit.predicted_n)
        stated = stated + (slope * u) ** 2
        parts.append("the certified depth's uncertainty x dP/dw")
    if parts and np.all(stated > 0):
        sig = np.sqrt(stated)
        k = max(1.0, rms / float(np.sqrt(np.mean(stated))))
        how = (f"{' and '.join(parts)}" + (f", scaled by {k:.3g} to the final model's "
                                           f"residual RMS ({rms * 1e3:.3g} mN)" if k > 1
                                           else ""))
        return sig * k, how
    return np.full(r.size, rms), f"the final model's residual RMS ({rms * 1e3:.3g} mN)"


def _with_rules_out(d: Diagnosis, h: float, a: float, hidden: dict[str, str] | None = None,
                    own: Mapping[str, EffectSensitivity] | None = None) -> Diagnosis:
    """The diagnosis with :attr:`Diagnosis.rules_out` and a sentence under its verdict.

    `own`: sizes found by tests of their own (the holds, the crossing forces), which stand
    where the replay of the table's presses has none (a certification hides the effect, or
    the table cannot carry it) and are said apart."""
    own = dict(own or {})
    cols = {k: np.asarray(v, np.float64)[d.fit_rows[-1]] for k, v in d.columns.items()}
    sigma, how = _press_noise(d)
    E, nu = d.ladder[-1].E_mpa, d.ladder[-1].nu
    if not (math.isfinite(E) and math.isfinite(nu)):
        E, nu = d.E_mpa, d.nu
    if not (math.isfinite(E) and math.isfinite(nu)):
        return _own_sizes(replace(d, rules_out_note="what the verdict rules out was not "
                                  "replayed: the table's E and nu were not derived (the "
                                  "replay's forces are the FEM's at them)"), own)
    untestable = {k: d.untestable_reasons.get(k) or "needs " + ", ".join(v)
                  for k, v in d.untestable.items()}
    nu_fit, edge = nu, ""
    try:
        # a fit at nu = 0.5 (or past the table's floor) is replayed at the table's edge: the
        # sizes are relative changes of the force, which 0.499 and 0.5 shape alike
        nu = float(np.clip(nu, *kappa_n_nu_range()))
        if nu != nu_fit:
            edge = f", the fit's nu = {nu_fit:.4g} taken at the FEM table's edge"
        sizes = table_sensitivity(cols, thickness_mm=h, radius_mm=a, E_mpa=E, nu=nu,
                                  sigma_n=sigma, untestable=untestable, draws=RULES_OUT_DRAWS,
                                  column_effects=d.crossings is None)
    except (InputError, ValueError) as exc:
        return _own_sizes(replace(d, rules_out_note=f"what the verdict rules out was not "
                                                    f"replayed: {exc}"), own)
    note = (f"the smallest size of each effect this table would have named in 95 % of "
            f"{RULES_OUT_DRAWS} replays of its presses (the FEM's forces at E = {E:.4g} MPa, nu = "
            f"{nu:.4g}{edge}) with each press's noise from {how}")
    hidden = {k: v for k, v in (hidden or {}).items() if k in sizes}
    for name, why in hidden.items():     # what the table's certification hides
        sizes[name] = replace(sizes[name], size=math.nan, size_param=math.nan, why=why)
    own = {k: v for k, v in own.items() if k not in sizes or not math.isfinite(sizes[k].size)}
    hidden = {k: v for k, v in hidden.items() if k not in own}
    found = [f"{k} {v.size:.3g}{' ' + v.unit if v.unit else ''}"
             + (f" ({v.places_sentence()})" if v.at_places else "")
             for k, v in sizes.items() if math.isfinite(v.size) and k not in own]
    never = [k for k, v in sizes.items() if v.size == math.inf and k not in own]
    s = []
    if found:
        s.append("None larger than: " + ", ".join(found) + f" ({note}).")
    if never:
        s.append("Not ruled out at any size the parameter allows: " + ", ".join(never) + ".")
    for why in dict.fromkeys(hidden.values()):
        names = ", ".join(k for k, v in hidden.items() if v == why)
        s.append(f"Not ruled out ({why.removeprefix('not ruled out: ')}): {names}.")
    d = replace(d, rules_out=sizes, rules_out_note=note,
                message=d.message + (" " + " ".join(s) if s else ""))
    return _own_sizes(d, own)


def _own_sizes(d: Diagnosis, own: Mapping[str, EffectSensitivity]) -> Diagnosis:
    """`d` with the sizes its own tests found (the holds, the crossing forces) in
    ``rules_out`` and one sentence naming them."""
    if not own:
        return d
    said = ", ".join(f"{k} {v.size:.3g} {v.unit}"
                     + (f" ({v.places_sentence()})" if v.at_places else "")
                     for k, v in own.items())
    return replace(d, rules_out={**d.rules_out, **own},
                   message=d.message + f" From their own tests (the crossing forces within "
                   f"indenters, the holds), none larger than: {said} (each named in 95 % of "
                   "sessions of these presses at their stated uncertainties).")
