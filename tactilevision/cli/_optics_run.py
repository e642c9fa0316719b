"""What ``tactilevision optics calibrate`` does once its options are parsed
(:mod:`tactilevision.cli._optics`): ball presses -> photometric calibration file.

Imported only when the command runs, so that its ``--help`` does not load this stack.
"""

from __future__ import annotations

import argparse
import json
import re
from dataclasses import replace
from pathlib import Path

import numpy as np

from .. import InputError
from ..io import (
    StagedOutput,
    check_output_folder,
    check_overwrite,
    read_ball_presses,
    taxim_datapack,
)
from ..optics import (
    CIRCLE_ERROR,
    MIN_MARGIN_PRESSES,
    NON_BALL_RATIO,
    DepthReconstructor,
    Engine,
    PhotometricCalibration,
    calibration_accuracy,
    choose_engine,
    detect_contact_circles,
    holdout_presses,
    non_ball_presses,
)

__all__ = ["parse_presses", "run_calibrate"]

def parse_presses(text: str | None, n: int) -> np.ndarray:
    """Press selection: a Python slice ``start:stop:step`` or a comma list.

    Parameters
    ----------
    text : str or None
        e.g. ``"0::2"`` or ``"0,3,5"``; None selects all.
    n : int
        Number of presses available.

    Returns
    -------
    indices : (K,) int ndarray

    Raises
    ------
    InputError
        For malformed text or indices out of range.
    """
    if text is None:
        return np.arange(n)
    bad = InputError(f"--presses '{text}' is neither a slice like 0::2 nor a list like 0,3,5")
    if text.count(":") > 2:
        raise bad
    try:
        if ":" in text:
            parts = [int(p) if p.strip() else None for p in text.split(":")]
            idx = np.arange(n)[slice(*parts)]
        else:
            idx = np.array([int(p) for p in text.split(",")])
    except ValueError:
        raise bad from None
    if idx.size == 0 or idx.min() < -n or idx.max() >= n:
        raise InputError(f"--presses '{text}' selects no press or one outside 0..{n - 1}")
    return idx % n


def _accuracy_text(report: dict, mm: float) -> str:
    """The accuracy report as printed: a line per ball size."""
    which = ("training presses (in sample: every press was trained on; --holdout 0.25 "
             "holds one in four out)" if report["in_sample"] else "held-out presses")
    if report["circles"] == "given":
        circles = "circles given (contact circles)"
    elif report.get("edge") == "colour":
        circles = (f"circles detected at the colour edge, scored at "
                   f"{report['label_fraction']:g} of their radius")
    else:
        circles = "circles detected at the contact edge"
    lines = [f"{circles}; trained to {report['label_fraction']:.2f} x their radius"]
    for b in report["balls"]:
        radius = b["ball_radius_px"] * mm
        cut = f"; {b['n_edge_cut']} cut by the image edge, left out" if b["n_edge_cut"] else ""
        head = f"{which} ({b['n_scored']}{cut}), ball radius {radius:g} mm"
        if not b["n_scored"]:
            lines.append(f"{head}: none to score")
            continue
        trained = (f"slopes trained up to {b['trained_tilt_deg']:.1f} deg"
                   if b["trained_tilt_deg"] is not None else "no press of this ball trained on")
        lines.append(
            f"{head}: normal angle {b['normal_angle_deg']:.2f} deg (median; "
            f"{b['normal_angle_08_deg']:.2f} inside 0.8 of the radius), inner cap "
            f"{100 * b['inner_cap']:+.1f} % (centre against 0.8 of the radius), deepest "
            f"point {100 * b['deepest_point']:+.1f} %, shape RMS "
            f"{b['shape_rms_px'] * mm * 1000:.1f} "
            f"um, fitted ball radius {b['fitted_radius_px'] * mm:.3f} +- "
            f"{b['fitted_radius_std_px'] * mm:.3f} mm (true {radius:g}); {trained}, these "
            f"rims reach {b['rim_tilt_deg']:.1f} deg")
        ex = b.get("inner_cap_expected")
        if ex:
            lines.append(
                f"  a new press's inner cap, from these {ex['n']}: {100 * ex['mean']:+.1f} % "
                f"expected, {100 * ex['confidence']:.0f} % of presses within "
                f"[{100 * ex['low']:+.1f}, {100 * ex['high']:+.1f}] %")
        cu = b.get("circle_uncertainty")
        if cu:
            a, c, e = cu["normal_angle_08_deg"], cu["inner_cap"], report["circle_error"]
            lines.append(
                f"  the scoring circles' own error (centre {e['centre_sd_r']:g} r, radius "
                f"{100 * e['radius_sd']:g} % per press; {e['centre_bias_r']:g} r and "
                f"{100 * e['radius_bias']:g} % shared): angle inside 0.8 "
                f"+- {a['random_sd']:.2f} deg random, up to {a['systematic']:.2f} deg shared; "
                f"inner cap +- {100 * c['random_sd']:.1f} % random, up to "
                f"{100 * c['systematic']:.1f} % shared")
    return "\n".join(lines)


def run_calibrate(args: argparse.Namespace) -> int:
    """Run ``optics calibrate``."""
    cells = _check_calibrate_options(args)
    out = Path(args.out)
    if out.is_dir():
        raise InputError(f"--out {out} is a folder; give the calibration file to write (.npz)")
    check_output_folder(out.parent, "folder of the calibration file")
    name = out.name if out.suffix == ".npz" else out.name + ".npz"
    report_name = Path(name).stem + "_accuracy.json"
    check_overwrite(out.parent, [name, report_name], overwrite=args.overwrite)
    ps, ball_mm = _read_presses(args, cells)
    idx = parse_presses(args.presses, len(ps.frames))
    given = ps.centers_px is not None and ps.radii_px is not None and not args.detect_circles
    mm = args.mm_per_px
    ps, ball_mm, idx, refused, origin, circles = _screen_presses(args, ps, ball_mm, idx,
                                                                 given)
    held = _held_out(args, ps, circles, ball_mm / mm)
    train = _trainer(args, ps, given, ball_mm, circles)
    # the report's calibration never sees the presses it is scored on, nor did the choice
    # of its engine
    train_idx = idx if held is None else np.flatnonzero(~held)
    engine, choice, inner = _choose_engine(args, ps, given, circles, ball_mm / mm,
                                           train_idx, cells, train)
    for key in ("fitted_on", "scored_on"):          # the folder's numbering, and the files
        if key in choice:
            choice[f"{key}_files"] = [ps.names[i] for i in choice[key]]
            choice[key] = [int(origin[i]) for i in choice[key]]
    # the network saved starts from the one scored (trained on most of these presses):
    # a quarter of the steps (MLP_WARM_FRACTION)
    scoring = (None if engine.model != "mlp" else inner[0] if inner is not None
               else None if held is None else train(train_idx, engine))
    cal = train(idx, engine, warm=scoring)
    cal.provenance.update(engine=choice, presses=[int(origin[i]) for i in idx],
                          files=[ps.names[i] for i in idx],
                          command="tactilevision " + " ".join(args.argv))
    if refused:
        cal.provenance["refused"] = refused
    if args.credit:
        cal.provenance["credit"] = args.credit
    report = _report(args, ps, cal, idx, train_idx, inner, engine, train, given, held,
                     circles, ball_mm / mm, origin, scoring)
    report.update(engine=choice, refused=refused)
    # one press's cap scatter on presses the calibration did not see, for the ball
    # sessions' cap cross-check (pipeline.ball_press_caps' press_sd): the largest over balls
    sds = [] if report.get("in_sample", True) else [
        b["inner_cap_expected"]["sd"] for b in report.get("balls", [])
        if b.get("inner_cap_expected")]
    cal.provenance["inner_cap_sd"] = float(max(sds)) if sds else None
    # into place only when complete; the folder's manifest records it (a rerun may replace it)
    with StagedOutput(out.parent, overwrite=args.overwrite,
                      what="folder of the calibration file") as stage:
        cal.save(stage.path / name)
        (stage.path / report_name).write_text(json.dumps(report, indent=2) + "\n")
        stage.commit()
    if args.model == "auto":
        print(_engine_text(choice))
    print(f"wrote {engine.model} calibration from {len(idx)} presses to {out.parent / name} "
          f"({engine.label()})")
    if held is not None:
        trained_on = (inner[1].size if inner is not None else np.count_nonzero(~held))
        print(f"held out for the report: presses "
              f"{', '.join(str(origin[i]) for i in np.flatnonzero(held))}"
              f" ({np.count_nonzero(held)} of {len(ps.frames)}, spread over the pad and the "
              f"ball sizes among the presses whose contact lies inside the image), scored by "
              f"a calibration trained on {trained_on} of the others"
              + (" (the first fold's others scored the engines)" if inner is not None
                 else "")
              + f"; the calibration saved is trained on all {len(ps.frames)}"
              + (" (its network started from the scored one's)"
                 if cal.provenance.get("warm_start") else ""))
    print(report["error"] if "error" in report else _accuracy_text(report, mm))
    print(f"accuracy report: {out.parent / report_name}")
    return 0


def _read_presses(args: argparse.Namespace, cells: tuple[int, int]):
    """The ball presses and each one's ball radius (mm), the options checked against them."""
    src = str(args.ball_presses)
    ps = read_ball_presses(taxim_datapack(src.split(":", 1)[1]) if src.startswith("taxim:")
                           else args.ball_presses)
    if cells != (1, 1) and args.model != "lut":
        raise InputError("--lut-cells needs --model lut (the network takes the position "
                         "itself; --model auto tries position cells of its own)")
    if ps.ball_radius_mm is not None and args.ball_radius_mm is not None:
        raise InputError(f"{args.ball_presses} lists each press's ball diameter (catalog.csv); "
                         "leave out --ball-radius-mm")
    if ps.ball_radius_mm is None and args.ball_radius_mm is None:
        raise InputError(f"--ball-radius-mm is needed: {args.ball_presses} does not say the "
                         "ball's size")
    ball_mm = (ps.ball_radius_mm if ps.ball_radius_mm is not None
               else np.full(len(ps.frames), args.ball_radius_mm))
    return ps, ball_mm


def _trainer(args: argparse.Namespace, ps, given: bool, ball_mm: np.ndarray, circles):
    """``train(sel, engine, warm=None)``: a calibration of `engine` on the presses `sel`
    (their circles given, else the ones detected once for all: `circles`), its network
    started from `warm`'s; an error about one of them names its file."""
    def train(sel: np.ndarray, engine: Engine,
              warm: PhotometricCalibration | None = None) -> PhotometricCalibration:
        try:
            return PhotometricCalibration.from_ball_presses(
                ps.reference, ps.frames[sel], circles[0][sel], circles[1][sel],
                detected=not given,
                ball_radius_mm=ball_mm[sel], mm_per_px=args.mm_per_px, model=engine.model,
                bins=args.bins, lut_cells=engine.lut_cells, epochs=args.epochs,
                hidden=args.hidden, seed=args.seed, source=str(args.ball_presses),
                label_fraction=args.label_fraction, progress=not args.no_progress,
                detect_edge=args.detect_edge, flat_fraction=args.flat_fraction,
                warm_start=warm,
            )
        except InputError as exc:
            raise InputError(_name_press(str(exc), [ps.names[i] for i in sel])) from None
    return train


def _name_press(text: str, names: list[str]) -> str:
    """`text` with a leading ``press K`` or ``frames[K]`` (K: a position among the presses
    given) replaced by that press's file name."""
    m = re.match(r"(press |frames\[)(\d+)\]?(.*)", text, re.S)
    if m is None or int(m.group(2)) >= len(names):
        return text
    return f"{names[int(m.group(2))]}{m.group(3)}"


def _subset(ps, keep: np.ndarray):
    """The ball-press set of the presses `keep` (indices, in order)."""
    keep = np.asarray(keep, np.int64)
    return replace(
        ps, frames=ps.frames[keep], names=[ps.names[i] for i in keep],
        centers_px=None if ps.centers_px is None else ps.centers_px[keep],
        radii_px=None if ps.radii_px is None else ps.radii_px[keep],
        ball_radius_mm=None if ps.ball_radius_mm is None else ps.ball_radius_mm[keep])


def _report(args: argparse.Namespace, ps, cal, idx, train_idx, inner, engine, train,
            given: bool, held, circles, ball_px: np.ndarray, origin: np.ndarray,
            scoring=None) -> dict:
    """The accuracy report (:func:`_accuracy_report`). With an engine chosen on held-out
    training presses, the calibration scored is the chosen candidate's (trained on the
    presses the choice trained on), and the presses the choice scored are not scored;
    else `scoring` (trained on `train_idx`; None: trained here)."""
    if inner is None:
        if scoring is None and held is not None:
            scoring = train(train_idx, engine)
        return _accuracy_report(args, ps, scoring if scoring is not None else cal, train_idx,
                                given, held, circles, ball_px, origin)
    scoring, fit_on, score_on = inner
    if held is None and args.presses is None:        # --holdout 0: in sample, said so
        return _accuracy_report(args, ps, cal, idx, given, None, None, ball_px, origin)
    keep = np.setdiff1d(np.arange(len(ps.frames)), score_on)
    pos = np.searchsorted(keep, fit_on)
    view = _subset(ps, keep)
    return _accuracy_report(args, view, scoring, pos, given,
                            None if held is None else held[keep],
                            (circles[0][keep], circles[1][keep]),
                            ball_px[keep], origin[keep])


def _check_calibrate_options(args: argparse.Namespace) -> tuple[int, int]:
    """Refuse an out-of-range option of ``optics calibrate`` (named); the LUT's cells."""
    if (args.ball_radius_mm is not None and args.ball_radius_mm <= 0) or args.mm_per_px <= 0:
        raise InputError("--ball-radius-mm and --mm-per-px must be positive")
    for name, value, low in (("--bins", args.bins, 2), ("--epochs", args.epochs, 1),
                             ("--hidden", args.hidden, 1)):
        if value < low:
            raise InputError(f"{name} must be at least {low}, got {value}")
    if args.label_fraction is not None and not 0 < args.label_fraction <= 1:
        raise InputError(f"--label-fraction must be in (0, 1], got {args.label_fraction}")
    if not 0 < args.flat_fraction <= 1:
        raise InputError(f"--flat-fraction must be in (0, 1], got {args.flat_fraction}")
    if not 0 <= args.holdout < 1:
        raise InputError(f"--holdout must be at least 0 and under 1, got {args.holdout:g}")
    try:
        cells = tuple(int(v) for v in args.lut_cells.split(","))
    except ValueError:
        cells = ()
    if len(cells) != 2 or min(cells) < 1:
        raise InputError(f"--lut-cells '{args.lut_cells}' must be two positive integers NX,NY "
                         "(e.g. 8,6)")
    return cells


def _held_out(args: argparse.Namespace, ps, circles, ball_px: np.ndarray):
    """The presses held out for the accuracy report (None: none), spread over the pad by
    their circles ((centres, radii): given, or detected by no calibration)."""
    if args.presses is not None or args.holdout <= 0:
        return None
    held = holdout_presses(circles[0], circles[1], ball_px, ps.reference.shape[:2],
                           args.holdout)
    if not held.any() or np.count_nonzero(~held) < 2:
        return None
    return held


def _accuracy_report(args: argparse.Namespace, ps, scoring, train_idx: np.ndarray,
                     given: bool, held, circles, ball_px: np.ndarray, origin: np.ndarray
                     ) -> dict:
    """The accuracy report: held-out presses (else the training ones, said so), by ball."""
    trained = np.zeros(len(ps.frames), bool)
    trained[train_idx] = True
    try:
        if given:
            centres, radii = ps.centers_px, ps.radii_px
        else:
            # the trained presses' circles are the scoring calibration's own (its refined
            # centres); the held-out presses' are detected, by no calibration
            centres = np.zeros((len(ps.frames), 2))
            radii = np.zeros(len(ps.frames))
            centres[train_idx] = scoring.provenance["centers_px"]
            radii[train_idx] = scoring.provenance["radii_px"]
            others = np.flatnonzero(~trained)
            centres[others], radii[others] = circles[0][others], circles[1][others]
        report = calibration_accuracy(DepthReconstructor(scoring), ps.frames, centres, radii,
                                      ball_px, trained=trained,
                                      label_fraction=scoring.provenance["label_fraction"],
                                      circles="given" if given else "detected",
                                      edge="contact" if given else args.detect_edge,
                                      circle_error=(CIRCLE_ERROR if not given
                                                    and args.detect_edge == "contact"
                                                    else None))
    except InputError as exc:      # the calibration stands; only its report is missing
        report = {"error": f"no accuracy report: {exc}"}
    for b in report.get("balls", []):           # the folder's numbering, and the files
        b["files"] = [ps.names[i] for i in b.get("presses", [])]
        b["presses"] = [int(origin[i]) for i in b.get("presses", [])]
    report["held_out"] = None if held is None else {
        "presses": [int(origin[i]) for i in np.flatnonzero(held)],
        "files": [ps.names[i] for i in np.flatnonzero(held)], "share": float(args.holdout),
        "scored_by": f"a calibration trained on the other {int(np.count_nonzero(~held))} "
                     "presses",
        "saved_calibration_trained_on": "every press"}
    report["mm_per_px"] = args.mm_per_px
    return report


def _choose_engine(args: argparse.Namespace, ps, given: bool, circles, ball_px: np.ndarray,
                   train_idx: np.ndarray, cells: tuple[int, int], train
                   ) -> tuple[Engine, dict, tuple | None]:
    """The engine the calibration keeps, the record of the choice, and ``(calibration,
    fitted_on, scored_on)`` of the candidate kept on the first fold (None where no choice
    was made): ``--model lut|mlp`` as named, ``--model auto`` by :func:`choose_engine`
    (the Python API's default procedure)."""
    if args.model != "auto":
        engine = (Engine("network", "mlp") if args.model == "mlp" else
                  Engine("table_cells" if cells != (1, 1) else "table", "lut", cells))
        return engine, {"chosen": engine.name, "model": engine.model,
                        "lut_cells": list(engine.lut_cells), "by": f"--model {args.model}",
                        "candidates": [], "left_out": {}}, None
    return choose_engine(ps.reference, ps.frames, circles, ball_px, train_idx, train,
                         given=given, detect_edge=args.detect_edge,
                         progress=not args.no_progress)


def _engine_text(choice: dict) -> str:
    """How the engine was chosen, as printed."""
    if not choice["candidates"]:
        return f"engine: {choice['chosen']} ({choice['by']})"
    lines = [f"engine chosen by {choice['by']}:"]
    for r in choice["candidates"]:
        mark = "  <- kept" if r["engine"] == choice["chosen"] else ""
        f0 = r["first_fold"]
        score = ("not scored" if not r["n_scored"] else
                 f"{r['angle_08_deg']:.2f} deg inside 0.8, inner cap "
                 f"{100 * r['inner_cap']:+.1f} % over {r['n_scored']} presses"
                 + (f" (first fold {f0['angle_08_deg']:.2f} deg, {100 * f0['inner_cap']:+.1f} %)"
                    if r["folds"] > 1 and f0["n_scored"] else ""))
        lines.append(f"  {r['label']}: {score}{mark}")
    for name, why in choice["left_out"].items():
        lines.append(f"  {name}: not tried ({why})")
    m = choice.get("margin")
    if m:
        lo, hi = m["ci95"]
        other = next(r["label"] for r in choice["candidates"] if r["engine"] == m["runner_up"])
        lines.append(
            f"  the {other} costs {m['cost_difference']:+.2f} deg more on these "
            f"{m['n_presses']} presses (95 % interval [{lo:+.2f}, {hi:+.2f}], paired "
            "bootstrap over them): " + (
                "the presses tell the two apart" if m["told_apart"] else
                "the presses cannot tell the two apart; either may read better on new "
                "presses" + (f" (fewer than {MIN_MARGIN_PRESSES} presses cannot)"
                             if m["n_presses"] < MIN_MARGIN_PRESSES else "")))
    return "\n".join(lines)


def _screen_presses(args: argparse.Namespace, ps, ball_mm: np.ndarray, idx: np.ndarray,
                    given: bool):
    """Refuse what is not a press of the stated ball before anything trains on it or scores
    it: a frame with no contact found, or whose contact does not read as the ball's
    (:func:`~tactilevision.optics.non_ball_presses`). Each is printed with its file.

    Returns ``(ps, ball_mm, idx, refused, origin, circles)``: the presses kept, their
    balls, the training selection among them, the refused (``press``, ``file``,
    ``reason``), each kept press's index in the folder, and the kept presses' circles
    ``(centres, radii)``: given, or detected by no calibration."""
    n = len(ps.frames)
    alive = np.ones(n, bool)
    refused: list[dict] = []
    ball_px = ball_mm / args.mm_per_px
    if given:
        centres, radii = ps.centers_px, ps.radii_px
    else:
        centres, radii = np.zeros((n, 2)), np.zeros(n)
        while True:
            live = np.flatnonzero(alive)
            try:
                centres[live], radii[live] = detect_contact_circles(
                    ps.frames[live], ps.reference, edge=args.detect_edge)
                break
            except InputError as exc:
                m = re.match(r"frames\[(\d+)\]: (.*)", str(exc), re.S)
                if m is None or live.size <= 2:
                    raise InputError(f"{args.ball_presses}: {exc}") from None
                k = int(live[int(m.group(1))])
                alive[k] = False
                refused.append({"press": k, "file": ps.names[k], "reason": m.group(2)})
    over = np.flatnonzero(alive & (radii >= ball_px))
    if given and over.size:
        k = int(over[0])
        raise InputError(f"{ps.names[k]}: contact radius {radii[k]:.1f} px is not smaller than "
                         f"the ball radius {ball_px[k]:.1f} px: check --ball-radius-mm and "
                         "--mm-per-px, or its circle")
    for k in over:
        alive[k] = False
        refused.append({"press": int(k), "file": ps.names[k], "reason": (
            f"its detected circle ({radii[k]:.1f} px) is not smaller than the ball "
            f"({ball_px[k]:.1f} px)")})
    live = np.flatnonzero(alive)
    if live.size >= 3:
        bad, ang, thr = non_ball_presses(ps.reference, ps.frames[live], centres[live],
                                         radii[live], ball_px[live])
        for j in np.flatnonzero(bad):
            k = int(live[j])
            alive[k] = False
            read = ("cannot be read by the others' colours" if not np.isfinite(ang[j]) else
                    f"reads {ang[j]:.1f} deg off the ball's normals inside 0.8 of its circle "
                    f"by a colour table of the other presses, above {thr:.1f} deg "
                    f"({NON_BALL_RATIO:g} times their median)")
            refused.append({"press": k, "file": ps.names[k], "reason": (
                f"its contact is not the {ball_mm[k]:g} mm ball's: it {read}; another "
                "object, two contacts, or a circle off its contact")})
    if not refused:
        return ps, ball_mm, idx, refused, np.arange(n), (centres, radii)
    for r in refused:
        print(f"refused press {r['press']} ({r['file']}): {r['reason']}")
    keep = np.flatnonzero(alive)
    pos = {int(k): i for i, k in enumerate(keep)}
    idx = np.array([pos[int(i)] for i in idx if alive[i]], np.int64)
    if idx.size < 2:
        raise InputError(f"{args.ball_presses}: {idx.size} of the presses to train on left "
                         f"after refusing {', '.join(r['file'] for r in refused)}; at least "
                         "two are needed")
    return (_subset(ps, keep), ball_mm[keep], idx, refused, keep,
            (centres[keep], radii[keep]))
