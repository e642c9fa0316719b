"""What ``tactilevision validate`` does once its options are parsed
(:mod:`tactilevision.cli._validate`): the paper's FEA check of a calibration (formats.md
§3).

Imported only when the command runs, so that its ``--help`` does not load this stack.
"""

from __future__ import annotations

import argparse
import csv
import sys
import warnings
from pathlib import Path

from .. import InputError
from ..diagnosis import validate_indentation, validate_indenter
from ..io import StagedOutput, check_output_folder, check_overwrite, read_measurements
from ..mechanics import fit_indentation
from ..viz import save_validation_figure
from ._fit_indenter import fit_laws, indenter_of
from ._fit_run import _write_json

__all__ = ["run"]


def _pad_radius(table) -> float | None:
    """The pad's radius the table's sidecar gives (``[sensor] gel_radius_mm``, or a
    rectangular pad's equal-area radius), checked; None without one."""
    value = table.indenter.get("pad_radius_mm")
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float) or value <= 0:
        raise InputError(f"{table.path.parent / 'session.toml'}: [sensor] gel_radius_mm must "
                         "be a positive number")
    return float(value)


def _run_indenter(args: argparse.Namespace, table, path: Path) -> int:
    """``validate`` of a ball's table: the depth its law needs at each measured force."""
    if args.contact == "bonded":
        raise InputError("--contact bonded is a flat punch's; a ball is frictionless or tied")
    ind, contact = indenter_of(table, args)
    if args.E_mpa is None:
        fit, _, why = fit_laws(table, args, None)
        E, nu, law, source = fit.E_mpa, fit.nu, fit.law, f"fit ({why})"
    else:
        law = "neo_hookean" if args.law == "auto" else args.law
        E, nu, source = args.E_mpa, args.nu, "given"
    try:
        res = validate_indenter(table.depth_mm, table.force_n, ind,
                                thickness_mm=table.thickness_mm, E_mpa=E, nu=nu, law=law,
                                contact=contact)
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None
    obj = {"measurements": str(path), "E_nu_source": source, "E_mpa": E, "nu": nu, "law": law,
           "contact": res.contact, "depth_mm": res.depth_mm.tolist(),
           "force_n": res.force_n.tolist(),
           "simulated_depth_mm": [None if v != v else v for v in res.simulated_depth_mm],
           "rel_error": [None if v != v else v for v in res.depth_error],
           "max_abs_rel_error": res.max_abs_error, "mean_abs_rel_error": res.mean_abs_error}
    if args.json is not None:
        _write_json(obj, args.json)
    if args.report is not None:
        with StagedOutput(args.report, overwrite=args.overwrite, what="report folder") as stage:
            save_validation_figure(stage.path / "validation.png", res, title=str(path))
            stage.commit()
    if args.json != "-":
        print(f"{path}: {res.depth_mm.size} presses of a {ind.shape} simulated at E = {E:.4f} "
              f"MPa, nu = {nu:.4g} ({source}); {law} law, {res.contact} contact")
        print("  depth_mm  force_n  simulated_mm  error")
        for d, f, sim, e in zip(res.depth_mm, res.force_n, res.simulated_depth_mm,
                                res.depth_error, strict=True):
            print(f"  {d:8.4f} {f:8.4f} {sim:12.4f} {100 * e:+6.2f}%")
        print(f"  max |error| {100 * res.max_abs_error:.2f}%, mean "
              f"{100 * res.mean_abs_error:.2f}%; a trend of the error with depth is the "
              "missing effect (diagnose)")
    return 0


def run(args: argparse.Namespace) -> int:
    """Run ``validate``; returns 0 (2 through InputError on bad input)."""
    if (args.E_mpa is None) != (args.nu is None):
        raise InputError("give both --E-mpa and --nu, or neither (to use the fitted values)")
    overwrite = args.overwrite
    if args.report is not None:
        check_output_folder(args.report, "report folder")
        check_overwrite(args.report, ("validation.png", "validation.csv"), overwrite=overwrite)
    path = args.measurements
    table = read_measurements(path, thickness_mm=args.thickness_mm, radius_mm=args.radius_mm)
    for note in table.notes:
        print(f"tactilevision validate: warning: {note}", file=sys.stderr)
    if (args.shape or table.indenter.get("shape", "flat_punch")) != "flat_punch":
        return _run_indenter(args, table, path)
    args.contact = args.contact or "bonded"
    if args.contact == "tied":
        raise InputError("--contact tied is a ball's; a flat punch is bonded or frictionless")
    if args.E_mpa is None:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fit = fit_indentation(table.depth_mm, table.force_n,
                                  thickness_mm=table.thickness_mm, radius_mm=table.radius_mm)
        if fit.out_of_table:
            raise InputError(f"{path}: the fit gives no E and nu ({fit.out_of_table_message}); "
                             "pass --E-mpa and --nu")
        E, nu, source = fit.E_mpa, fit.nu, f"fit ({fit.beta_table} beta table)"
    else:
        E, nu, source = args.E_mpa, args.nu, "given"
    pad = args.pad_radius_mm if args.pad_radius_mm is not None else _pad_radius(table)
    try:
        res = validate_indentation(table.depth_mm, table.force_n, E_mpa=E, nu=nu,
                                   thickness_mm=table.thickness_mm, radius_mm=table.radius_mm,
                                   pad_radius_mm=pad, contact=args.contact)
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None
    obj = res.to_json_dict()
    obj.update(measurements=str(path), E_nu_source=source)
    if args.json is not None:
        _write_json(obj, args.json)
    if args.report is not None:
        with StagedOutput(args.report, overwrite=overwrite, what="report folder") as stage:
            save_validation_figure(stage.path / "validation.png", res, title=str(path))
            with (stage.path / "validation.csv").open("w", newline="") as fh:
                wr = csv.writer(fh)
                wr.writerow(["depth_mm", "force_n", "simulated_depth_mm", "rel_error"])
                for d, f, s, e in zip(res.depth_mm, res.force_n, res.simulated_depth_mm,
                                      res.rel_error, strict=True):
                    wr.writerow([f"{d:.5f}", f"{f:.5f}", f"{s:.5f}", f"{e:.5f}"])
            stage.commit()
    if args.json != "-":
        out = sys.stdout
        print(f"{path}: {len(res.depth_mm)} presses simulated at E = {E:.4f} MPa, "
              f"nu = {nu:.4f} ({source}); {args.contact} punch, pad radius "
              f"{res.pad_radius_mm:g} mm", file=out)
        print("  depth_mm  force_n  simulated_mm  error", file=out)
        for d, f, s, e in zip(res.depth_mm, res.force_n, res.simulated_depth_mm, res.rel_error,
                              strict=True):
            print(f"  {d:8.4f} {f:8.4f} {s:12.4f} {100 * e:+6.2f}%", file=out)
        print(f"  max |error| {100 * res.max_abs_rel_error:.2f}%, mean "
              f"{100 * res.mean_abs_rel_error:.2f}% (the paper: within 6%)", file=out)
        for n in res.notes:
            print(f"  note: {n}", file=out)
    return 0
