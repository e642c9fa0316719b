"""The engine of a photometric calibration chosen on presses it did not see: the one
procedure behind ``optics calibrate --model auto`` (the CLI's default) and
``PhotometricCalibration.from_ball_presses(model='auto')`` (the Python default).

The candidates (:func:`~tactilevision.optics.engine_candidates`) are trained on part of
the training presses and scored on the others (:func:`calibration_accuracy`); the tables
are cross-validated over :data:`ENGINE_FOLDS` folds of the pad (:func:`press_folds`), a
network trains once, on the first fold's split. The cost is
:func:`~tactilevision.optics.engine_cost`'s.
"""

from __future__ import annotations

import importlib.util
from collections.abc import Callable
from typing import Any

import numpy as np

from .._checks import InputError
from ._accuracy import calibration_accuracy, edge_cut, press_folds
from ._engine import (
    CAP_DEG,
    UNDECIDED,
    Engine,
    engine_candidates,
    engine_cost,
    engine_margin,
    pooled_cost,
    pooled_presses,
    undecided_choice,
)
from ._reconstructor import DepthReconstructor
from ._training import _checked_presses, _press_circles

__all__ = ["ENGINE_FOLDS", "calibrate_choosing_engine", "choose_engine", "network_unavailable"]

#: Folds the candidate tables are cross-validated over for the engine's choice.
ENGINE_FOLDS = 10

#: ``train(sel, engine, warm=None)``: a calibration of `engine` on the presses `sel`.
Trainer = Callable[..., Any]


def network_unavailable() -> str | None:
    """Why this installation cannot train a network (None: it can)."""
    if importlib.util.find_spec("torch") is None:
        return "torch is not installed (pip install 'tactilevision[torch]')"
    return None


def choose_engine(reference: np.ndarray, frames: np.ndarray,
                  circles: tuple[np.ndarray, np.ndarray], ball_px: np.ndarray,
                  train_idx: np.ndarray, train: Trainer, *, given: bool,
                  detect_edge: str = "contact", progress: bool = False
                  ) -> tuple[Engine, dict, tuple | None]:
    """The engine a calibration keeps, chosen on training presses each candidate did not
    see.

    Parameters
    ----------
    reference : (H, W, 3) uint8 ndarray
        No-contact frame, BGR.
    frames : (N, H, W, 3) uint8 ndarray
        The ball presses.
    circles : ((N, 2) float ndarray, (N,) float ndarray)
        Each press's contact circle (centre x, y and radius, px): given, or detected by no
        calibration (:func:`detect_contact_circles`).
    ball_px : (N,) float ndarray
        Each press's ball radius, px.
    train_idx : (K,) int ndarray
        The presses the choice may train and score on.
    train : callable
        ``train(sel, engine, warm=None)``: a :class:`PhotometricCalibration` of `engine`
        trained on the presses `sel` (their network started from `warm`'s).
    given : bool
        Whether `circles` were given (scored as they are) or detected (a trained press is
        scored on its calibration's refined circle).
    detect_edge : {'contact', 'colour'}, default 'contact'
        The edge detected circles lie on.
    progress : bool, default False
        Print a line per candidate and fold.

    Returns
    -------
    engine : Engine
        The engine kept.
    record : dict
        ``chosen``, ``model``, ``lut_cells``, ``by`` (the rule, in words), ``candidates``
        (each one's pooled cost and per-press scores), ``left_out`` (engine -> why not
        tried), and where a choice was made ``fitted_on``, ``scored_on`` (the first fold's
        presses) and ``margin`` (:func:`engine_margin` against the runner-up, or None).
    first : tuple or None
        ``(calibration, fitted_on, scored_on)`` of the kept candidate on the first fold;
        None where fewer than two training presses lie inside the image (the colour table
        is kept, said so in ``by``).
    """
    centres, radii = circles[0][train_idx], circles[1][train_idx]
    shape = reference.shape[:2]
    n_in = int(np.count_nonzero(~edge_cut(centres, radii, shape)))
    fold = (press_folds(centres, radii, ball_px[train_idx], shape, min(ENGINE_FOLDS, n_in))
            if n_in >= 2 else np.full(train_idx.size, -1))
    if n_in < 2 or np.count_nonzero(fold != 0) < 2:
        why = (f"{n_in} of the {train_idx.size} training presses lie inside the image: too "
               "few to choose an engine on presses it did not see; the colour table")
        return Engine("table", "lut"), {"chosen": "table", "model": "lut", "lut_cells": [1, 1],
                                        "by": why, "candidates": [], "left_out": {}}, None
    fit0, score0 = train_idx[fold != 0], train_idx[fold == 0]
    cands, left = engine_candidates(shape, int(fit0.size), network=network_unavailable())
    rows, first, pooled = [], {}, {}
    for engine in cands:
        folds = [0] if engine.model == "mlp" else range(int(fold.max()) + 1)
        reports = []
        for f in folds:
            if progress:
                print(f"choosing the engine: {engine.label()}, fold {f + 1} of {len(folds)}",
                      flush=True)
            fit_on, score_on = train_idx[fold != f], train_idx[fold == f]
            cal = train(fit_on, engine)
            rep = _score_split(reference, frames, circles, cal, fit_on, score_on, given,
                               ball_px, detect_edge)
            reports.append(rep)
            if f == 0:
                first[engine.name] = (cal, engine_cost(rep))
        pooled[engine.name] = (pooled_presses(reports), pooled_presses(reports[:1]))
        every = pooled[engine.name][0].values()
        rows.append({"engine": engine.name, "label": engine.label(), "model": engine.model,
                     "lut_cells": list(engine.lut_cells), "folds": len(folds),
                     **pooled_cost(reports), "first_fold": first[engine.name][1],
                     "per_press": {"angle_08_deg": [v for a, _ in every for v in a],
                                   "inner_cap": [v for _, c in every for v in c]}})
    chosen = _pick(rows)
    margin = _margin(rows, chosen, pooled)
    by = (f"the lowest angle inside 0.8 of the radius + {CAP_DEG:g} deg x |inner cap| "
          f"(medians over the presses, as the report's) on training presses each "
          f"candidate was not trained on (the tables cross-validated over "
          f"{int(fold.max()) + 1} folds, a network on the first)")
    keep = undecided_choice(chosen, margin)
    if keep != chosen:
        chosen, margin = keep, _margin(rows, keep, pooled)
        by += f"; {UNDECIDED}"
    engine = next(e for e in cands if e.name == chosen)
    return engine, {
        "chosen": chosen, "model": engine.model, "lut_cells": list(engine.lut_cells),
        "by": by, "fitted_on": [int(i) for i in fit0], "scored_on": [int(i) for i in score0],
        "candidates": rows, "left_out": left, "margin": margin}, (
        first[chosen][0], fit0, score0)


def _margin(rows: list[dict], chosen: str, pooled: dict) -> dict | None:
    """The kept engine against the next best candidate scored on the same presses
    (:func:`engine_margin`): the tables on every press their folds scored, a network (one
    fold) against the table of the lowest first-fold cost on that fold's presses; None
    where there is none."""
    net = any(r["model"] == "mlp" for r in rows if r["engine"] == chosen)
    key = (lambda r: r["first_fold"]["cost"]) if net else (lambda r: r["cost"])
    others = sorted((r for r in rows if r["engine"] != chosen and np.isfinite(key(r))
                     and (net or r["model"] != "mlp")), key=key)
    if not others:
        return None
    m = engine_margin(pooled[chosen][int(net)], pooled[others[0]["engine"]][int(net)])
    return None if m is None else {"runner_up": others[0]["engine"], **m,
                                   "ci95": list(m["ci95"])}


def _pick(rows: list[dict]) -> str:
    """The engine kept: the table of the lowest cross-validated cost, unless a network
    scores lower than it on the first fold, where both were scored on the same presses."""
    tables = [r for r in rows if r["model"] == "lut" and np.isfinite(r["cost"])]
    best = min(tables, key=lambda r: r["cost"]) if tables else rows[0]
    for r in rows:
        if (r["model"] == "mlp" and np.isfinite(r["first_fold"]["cost"])
                and not r["first_fold"]["cost"] >= best["first_fold"]["cost"]):
            return r["engine"]
    return best["engine"]


def _score_split(reference: np.ndarray, frames: np.ndarray,
                 circles: tuple[np.ndarray, np.ndarray], cal, fit_on: np.ndarray,
                 score_on: np.ndarray, given: bool, ball_px: np.ndarray,
                 detect_edge: str) -> dict:
    """`cal` (trained on `fit_on`) scored on the presses `score_on` alone, against their
    circles (given, or detected by no calibration)."""
    sel = np.concatenate([fit_on, score_on])
    trained = np.zeros(sel.size, bool)
    trained[:fit_on.size] = True
    if given:
        centres, radii = circles[0][sel], circles[1][sel]
    else:
        centres = np.concatenate([np.asarray(cal.provenance["centers_px"]),
                                  circles[0][score_on]])
        radii = np.concatenate([np.asarray(cal.provenance["radii_px"]), circles[1][score_on]])
    try:
        return calibration_accuracy(DepthReconstructor(cal), frames[sel], centres, radii,
                                    ball_px[sel], trained=trained,
                                    label_fraction=cal.provenance["label_fraction"],
                                    circles="given" if given else "detected",
                                    edge="contact" if given else detect_edge)
    except InputError:
        return {"balls": []}


def calibrate_choosing_engine(cls: type, reference: np.ndarray, frames: np.ndarray,
                              centers_px: np.ndarray | None, radii_px: np.ndarray | None, *,
                              ball_radius_mm: float | np.ndarray, mm_per_px: float,
                              detect_edge: str = "contact", flat_fraction: float = 0.03,
                              detected: bool | None = None,
                              lut_cells: tuple[int, int] = (1, 1), warm_start=None,
                              progress: bool = False, **options: Any):
    """``PhotometricCalibration.from_ball_presses(model='auto')``: the engine chosen by
    :func:`choose_engine` on every press given, then trained on all of them (a network
    starting from the one the choice scored), the choice in ``provenance['engine']``.

    The circles are detected once (none given) and every candidate trains on them, as
    ``optics calibrate`` does; `options` are passed to each training.

    Raises
    ------
    InputError
        For ``lut_cells`` other than (1, 1) or a ``warm_start`` (each names one engine:
        give ``model='lut'`` or ``'mlp'``), and as ``from_ball_presses``.
    """
    if tuple(lut_cells) != (1, 1):
        raise InputError("lut_cells needs model='lut' (model='auto' tries position cells of "
                         "its own)")
    if warm_start is not None:
        raise InputError("warm_start needs model='mlp' (model='auto' chooses the engine)")
    reference, frames, ball_mm = _checked_presses(reference, frames, ball_radius_mm,
                                                  mm_per_px, "lut", detect_edge, flat_fraction)
    none_given = centers_px is None and radii_px is None
    if detected is False and none_given:
        raise InputError("detected=False needs the circles: give centers_px and radii_px")
    centres, radii = _press_circles(frames, reference, centers_px, radii_px, detect_edge)
    as_detected = none_given if detected is None else bool(detected)

    def train(sel: np.ndarray, engine: Engine, warm=None):
        return cls.from_ball_presses(
            reference, frames[sel], centres[sel], radii[sel], detected=as_detected,
            ball_radius_mm=ball_mm[sel], mm_per_px=mm_per_px, model=engine.model,
            lut_cells=engine.lut_cells, detect_edge=detect_edge, flat_fraction=flat_fraction,
            warm_start=warm, progress=progress, **options)

    every = np.arange(len(frames))
    engine, record, first = choose_engine(reference, frames, (centres, radii),
                                          ball_mm / mm_per_px, every, train,
                                          given=not as_detected, detect_edge=detect_edge,
                                          progress=progress)
    cal = train(every, engine, warm=first[0] if first is not None and engine.model == "mlp"
                else None)
    cal.provenance["engine"] = record
    return cal
