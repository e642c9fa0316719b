"""``tactilevision diagnose``: model against measurement (formats.md §3, §4)."""

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
from ._fit import _write_json, depth_uncertainty
from ._fit_indenter import add_dome_argument, depth_shared, force_sd, indenter_of
from ._fit_specimens import table_specimens
from ._out import add_overwrite_argument

__all__ = ["add_parser", "run"]

_DESCRIPTION = """\
Compare the indentation model with a measurements table: residuals against
every covariate column (a test with a p-value and the fraction of residual
variance explained), the replicate noise floor, the model plus each
applicable catalogue effect compared by BIC and cross-validated RMSE, the
verdict (missing effect, equivalent effects, unexplained covariate) and the
error ladder with E and nu at each step. Columns the depth rule computed
(overshoot_mm) are tested apart as the certification's, never as physics. A
verdict that names nothing says what it rules out: per catalogue effect, the
smallest size this table would have named (its presses replayed at its noise).
A table certified by the mark rule ([certification] depth_rule in its
session.toml) is told to read force effects within an indenter as depth.
The force over each press's hold (calibrate's holds.csv, read from beside the
table unless --holds names another or --no-holds) is tested for a relaxing gel,
which a table read at one time of every hold cannot show. --report DIR writes
the figures and report.html. Exit status 2 on bad input.

A ball's table ([indenter] shape = "sphere"): the ladder starts from the
small-strain law with the stated contact and tries large_deformation (finite
strain), contact_slip (the other contact condition), force_offset and
depth_offset, taking the change that lowers the BIC most until none does; each
rung shows every press's apparent E (flat when the model is right). As fit does,
it weighs the presses by depth_std_mm and force_sem_n and fits the circles'
shared error (depth_shared_mm) within its bound in every rung."""


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Register the ``diagnose`` sub-command."""
    p = sub.add_parser("diagnose", help="find where the model fails and which effect is missing",
                       description=_DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("measurements", metavar="MEASUREMENTS.csv", type=Path)
    p.add_argument("--effects", default="", metavar="E1,E2",
                   help="effects already in the model diagnosed: catalogue names, or an "
                        "Effect subclass of your own as package.module:ClassName or "
                        "path/to/file.py:ClassName (a module not on the Python path is looked "
                        "for in the working directory; docs/custom_effects.md)")
    p.add_argument("--candidates", default="", metavar="E1,E2",
                   help="effects of your own tried beside the catalogue's, as candidates for "
                        "the missing effect (package.module:ClassName or "
                        "path/to/file.py:ClassName; docs/custom_effects.md)")
    p.add_argument("--scan", default="", metavar="COL1,COL2",
                   help="response columns (fx_n, fy_n, force_std_n: they follow the force) to "
                        "scan as covariates all the same; by default they are not, and the "
                        "output names the columns scanned")
    p.add_argument("--base", choices=("paper", "layer", "fem"), default="paper",
                   help="paper: eq. (5), the layer with large_deformation (default); "
                        "layer: the small-strain layer alone; fem: the FEM's finite-strain "
                        "law (E and nu its own parameters; docs/diagnose_power.md)")
    holds = p.add_mutually_exclusive_group()
    holds.add_argument("--holds", metavar="HOLDS.csv", type=Path,
                       help="the force over each press's hold, tested for a relaxing gel "
                            "(default: holds.csv beside the table, where there is one)")
    holds.add_argument("--no-holds", action="store_true",
                       help="do not read the holds (not even holds.csv beside the table)")
    p.add_argument("--thickness-mm", type=float, metavar="H")
    p.add_argument("--radius-mm", type=float, metavar="A")
    p.add_argument("--beta-table", choices=("fem", "paper"), default="fem",
                   help="table for E and nu at each step (the diagnosis does not depend on it)")
    p.add_argument("--json", metavar="FILE", help="write the result as JSON ('-': stdout)")
    p.add_argument("--report", metavar="DIR", type=Path,
                   help="write residuals_by_covariate.png, error_ladder.png, report.html")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--shape", choices=("flat_punch", "sphere"),
                   help="indenter shape (default: session.toml [indenter] shape)")
    p.add_argument("--contact", choices=("frictionless", "tied"),
                   help="a ball's stated contact (default: session.toml [indenter] contact)")
    p.add_argument("--nu", type=float, default=0.5, metavar="NU",
                   help="a ball's models are fitted at this nu (default 0.5)")
    p.add_argument("--pad-radius-mm", type=float, metavar="R",
                   help="a ball's gel pad radius (default: session.toml [sensor] "
                        "gel_radius_mm, else the infinite layer)")
    add_dome_argument(p)
    add_overwrite_argument(p, "report folder")
    p.set_defaults(func=run)


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
