"""What ``tactilevision diagnose`` does once its options are parsed
(:mod:`tactilevision.cli._diagnose`): model against measurement (formats.md §3, §4).

Imported only when the command runs, so that its ``--help`` does not load this stack.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from .. import InputError
from ..diagnosis import HoldsFinding, diagnose, diagnose_indenter, holds_finding
from ..io import (
    Measurements,
    StagedOutput,
    check_output_folder,
    check_overwrite,
    read_holds,
    read_measurements,
)
from ..mechanics import effect_names, fit_indentation, model_label
from ..viz import (
    diagnosis_figures,
    indenter_figure,
    write_diagnosis_report,
    write_indenter_report,
)
from ._fit_indenter import depth_shared, force_sd, indenter_of
from ._fit_run import _write_json, depth_uncertainty
from ._fit_specimens import table_specimens

__all__ = ["run"]


def _run_indenter(args: argparse.Namespace, table, path: Path) -> int:
    """``diagnose`` of a ball's table: the ladder of :func:`diagnose_indenter`."""
    ind, contact = indenter_of(table, args)
    depth_std, std_message = depth_uncertainty(table, ignore=False,
                                               effects=("large_deformation",))
    if std_message is not None:
        print(f"tactilevision diagnose: warning: {path}: {std_message}", file=sys.stderr)
    try:
        diag = diagnose_indenter(table.depth_mm, table.force_n, ind,
                                 thickness_mm=table.thickness_mm, contact=contact, nu=args.nu,
                                 depth_std_mm=depth_std, force_std_n=force_sd(table),
                                 depth_shared_mm=depth_shared(table, depth_std))
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None
    obj = diag.to_json_dict()
    obj["measurements"] = str(path)
    if args.json is not None:
        _write_json(obj, args.json)
    if args.report is not None:
        with StagedOutput(args.report, overwrite=args.overwrite, what="report folder") as stage:
            fig = indenter_figure(diag, stage.path / "error_ladder.png", title=str(path))
            write_indenter_report(diag, stage.path, {"error ladder": fig}, source=str(path))
            stage.commit()
    if args.json != "-":
        lines = [f"{path}: {diag.depth_mm.size} presses of a {ind.shape} (R = "
                 f"{ind.radius_mm:g} mm, h = {table.thickness_mm:g} mm), models at nu = "
                 f"{diag.nu:g}", "  model                             law          contact"
                 "        E (MPa)  RMSE (mN)   drift"]
        for r in diag.ladder:
            lines.append(f"  {' + '.join(('base', *r.effects)):33s} {r.law:12s} {r.contact:13s}"
                         f"  {r.E_mpa:7.4f}  {r.rmse_n * 1e3:9.4g}  {100 * r.drift:+6.1f} %")
        lines.append(f"  {diag.message}")
        print("\n".join(lines))
    return 0


def _verdict_words(diag) -> str:
    """The verdict in words: the effect named (and those equivalent to it), or that none
    is, and a covariate the residuals follow that no effect explains."""
    if diag.missing_effect is None:
        words = "no missing effect named"
    else:
        words = f"missing effect {diag.missing_effect}"
        if diag.equivalent_effects:
            words += f" (equivalent: {', '.join(diag.equivalent_effects)})"
    if diag.unexplained_covariate is not None:
        words += f"; unexplained covariate {diag.unexplained_covariate}"
    return words


def _summary(diag, path: Path) -> str:
    def mn(v: float) -> str:
        return f"{v * 1e3:.3f} mN" if math.isfinite(v) else "-"


    lines = [f"{path}: {diag.fits[0].n_presses} presses, model {model_label(diag.model)}"]
    lines.append("  covariate          p-value   explained")
    for t in diag.covariates:
        flag = "  <- structure" if t.significant else ""
        lines.append(f"  {t.name:16s} {t.p_value:9.2g}   {t.explained_fraction:6.1%}{flag}")
    for t in diag.certification:
        flag = "  <- certification problem" if t.significant else ""
        lines.append(f"  {t.name:16s} {t.p_value:9.2g}   {t.explained_fraction:6.1%}  (the depth "
                     f"rule's product, not scanned as physics; {t.size_n * 1e3:.2f} mN RMS)"
                     f"{flag}")
    lines.append("  candidate                       delta BIC   CV RMSE")
    for c in diag.candidates:
        lines.append(f"  {c.effect:30s} {c.delta_bic:9.1f}   {mn(c.cv_rmse_n)}")
    lines.append(f"  error ladder (noise floor {mn(diag.noise_floor_n)}):")
    for s in diag.ladder:
        e = (f"E = {s.E_mpa:.4f} MPa, nu = {s.nu:.4f}" if math.isfinite(s.E_mpa)
             else "E, nu not derived")
        lines.append(f"    {'base' if s.added is None else '+ ' + s.added:28s} "
                     f"RMSE {mn(s.rmse_n)}, CV {mn(s.cv_rmse_n)}; {e}")
    lines.append(f"  verdict: {_verdict_words(diag)}")
    lines.append(f"  {diag.message}")
    if diag.misfit is not None and diag.misfit.warning:
        lines.append(f"  WARNING (the final model's fit): {diag.misfit.warning}")
    return "\n".join(lines)


def _holds(args: argparse.Namespace, table: Measurements, path: Path) -> HoldsFinding | None:
    """What the holds say (``--holds``, else holds.csv beside the table): None without them.

    A file named by ``--holds`` that cannot be read or fitted is an error naming it; a
    holds.csv found beside the table is read the same way, but where it fails the table is
    diagnosed without it, with a warning naming the file and why."""
    if args.no_holds:
        return None
    given = args.holds is not None
    hpath = args.holds if given else path.parent / "holds.csv"
    if not given and not hpath.is_file():
        return None
    try:
        return holds_finding(read_holds(hpath), table.columns, labels=table.labels,
                             source=str(hpath))
    except InputError as exc:
        if given:
            raise InputError(f"--holds: {exc}") from None
        print(f"tactilevision diagnose: warning: {exc}; the table is diagnosed without its "
              "holds (--holds names another file, --no-holds reads none)", file=sys.stderr)
        return None


def run(args: argparse.Namespace) -> int:
    """Run ``diagnose``; returns 0 (2 through InputError on bad input)."""
    overwrite = args.overwrite
    if args.report is not None:
        check_output_folder(args.report, "report folder")
        check_overwrite(args.report, ("residuals_by_covariate.png", "error_ladder.png",
                                      "report.html"), overwrite=overwrite)
    path = args.measurements
    requested = [e.strip() for e in args.effects.split(",") if e.strip()]
    # names checked (and effects of the user's own imported) before the table is read
    effects = [e for e in effect_names(requested)
               if not (args.base == "paper" and e == "large_deformation")]
    candidates = effect_names([e.strip() for e in args.candidates.split(",") if e.strip()])
    table = read_measurements(path, thickness_mm=args.thickness_mm, radius_mm=args.radius_mm)
    for note in table.notes:
        print(f"tactilevision diagnose: warning: {note}", file=sys.stderr)
    if (args.shape or table.indenter.get("shape", "flat_punch")) != "flat_punch":
        return _run_indenter(args, table, path)
    holds = _holds(args, table, path)
    try:
        diag = diagnose(table.columns, thickness_mm=table.thickness_mm,
                        radius_mm=table.radius_mm, base=args.base, effects=effects,
                        candidates=candidates, beta_table=args.beta_table,
                        scan=[c.strip() for c in args.scan.split(",") if c.strip()],
                        depth_rule=table.certification.get("depth_rule"), holds=holds,
                        progress=not args.no_progress and args.json != "-")
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None
    obj = diag.to_json_dict()
    obj["measurements"] = str(path)
    obj["depth_rule"] = table.certification.get("depth_rule")
    spec, spec_lines = _specimens(table, args)
    obj["specimens"] = spec
    if args.json is not None:
        _write_json(obj, args.json)
    if args.report is not None:
        with StagedOutput(args.report, overwrite=overwrite, what="report folder") as stage:
            figs = diagnosis_figures(diag, stage.path)
            write_diagnosis_report(diag, stage.path, figs, source=str(path))
            stage.commit()
    if args.json != "-":
        print(_summary(diag, path), file=sys.stdout)
        if spec_lines:
            print("  specimens (the specimen column): " + "\n  ".join(spec_lines))
    return 0


def _specimens(table, args: argparse.Namespace) -> tuple[dict | None, list[str]]:
    """A table with a specimen column: each specimen's base fit (eq. 5 with its depth
    uncertainties) and the batch's E with the spread between them."""
    def fit_flat(t):
        std = t.columns.get("depth_std_mm")
        return fit_indentation(t.depth_mm, t.force_n, thickness_mm=t.thickness_mm,
                               radius_mm=t.radius_mm, beta_table=args.beta_table,
                               depth_std_mm=None if std is None or np.any(np.isnan(std))
                               else std)

    args.ignore_depth_std = getattr(args, "ignore_depth_std", False)
    return table_specimens(table, args, fit_flat)
