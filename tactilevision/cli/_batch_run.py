"""What ``tactilevision batch`` does once its options are parsed
(:mod:`tactilevision.cli._batch`): many frame folders, videos or sessions on a Dask cluster.

Imported only when the command runs, so that its ``--help`` does not load this stack.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from .. import InputError, default_calibration_path
from ..batch import BatchSettings, run_batch
from ..io import check_output_folder, write_output_file
from ._inputs import beta_from_args, material_from_args

__all__ = ["run"]


def _settings(args: argparse.Namespace):
    cal = args.calibration or (default_calibration_path(args.sensor) if args.sensor else None)
    if cal is None:
        raise InputError(f"batch {args.kind} needs --calibration OPTICS or --sensor NAME")
    if not Path(cal).is_file():
        raise InputError(f"--calibration {cal} does not exist")
    if args.reference is not None and not args.reference.is_file():
        raise InputError(f"--reference {args.reference} does not exist")
    if args.chunk_frames < 1:
        raise InputError(f"--chunk-frames must be >= 1, got {args.chunk_frames}")
    level = args.level or ("contact" if args.kind == "forces" else "median")
    kw = {}
    if args.kind == "forces":
        E, nu, source, fit_obj = material_from_args(args, None)
        beta, _ = beta_from_args(args, fit_obj, source)
        if args.thickness_mm is None:
            raise InputError("batch forces needs --thickness-mm (the gel thickness h)")
        try:
            grid = tuple(int(v) for v in args.grid.split(","))
        except ValueError:
            raise InputError(f"--grid must be NX,NY, got {args.grid!r}") from None
        kw = {"E_mpa": E, "nu": nu, "thickness_mm": float(args.thickness_mm), "beta": beta,
              "method": args.method, "grid": grid}
    return BatchSettings(kind=args.kind, calibration=str(cal),
                         reference=str(args.reference) if args.reference else None,
                         level=level, engine=args.engine, chunk_frames=args.chunk_frames, **kw)


def run(args: argparse.Namespace) -> int:
    """Run ``batch``; returns 0, or 2 when an input failed (listed) or on bad options."""
    out = check_output_folder(args.out)
    settings = None if args.kind == "calibrate" else _settings(args)
    report = run_batch(args.kind, args.inputs, out, settings=settings, scheduler=args.scheduler,
                       n_workers=args.workers, overwrite=args.overwrite,
                       progress=not args.no_progress)
    d = report.to_json_dict()
    if args.json == "-":
        print(json.dumps(d, indent=2))
    else:
        if args.json:
            write_output_file(args.json, json.dumps(d, indent=2) + "\n", overwrite=True)
        for o in report.inputs:
            extra = (f" ({o.chunks_run} chunk(s) run, {o.chunks_skipped} already done)"
                     if args.kind != "calibrate" and o.status == "done" else "")
            print(f"{o.input}: {o.status}{extra}" + (f": {o.error}" if o.error else ""))
        print(f"batch {args.kind}: {len(report.inputs) - len(report.failed)} of "
              f"{len(report.inputs)} input(s) complete, {report.frames_run} frame(s) run on "
              f"{report.workers} worker(s) in {report.seconds:.1f} s; outputs in {out}")
    for o in report.failed:
        print(f"tactilevision batch: error: {o.input}: {o.error}", file=sys.stderr)
    return 2 if report.failed else 0
