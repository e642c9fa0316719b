"""``tactilevision batch``: many frame folders, videos or sessions on a Dask cluster."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from .. import InputError, default_calibration_path
from ..batch import BatchSettings, run_batch
from ..io import check_output_folder, write_output_file
from ._options import add_material_options, add_optics_options, beta_from_args, material_from_args

__all__ = ["add_parser", "run"]


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Register the ``batch`` sub-command."""
    p = sub.add_parser(
        "batch",
        help="reconstruct / forces / calibrate over many inputs on Dask (Zarr, Parquet)",
        description="Run 'reconstruct' or 'forces' over frame folders and video files (.mp4, "
        ".avi, ...) in chunks of frames, or 'calibrate' over session folders, on a local Dask "
        "cluster (one worker process per core) or a running scheduler (--scheduler). Writes "
        "OUT/NAME.zarr (height_mm [, force_n, pressure_kpa], float32, readable while it "
        "runs), OUT/NAME.parquet (one row per frame) or OUT/NAME/ (calibrate's outputs), and "
        "OUT/batch.json. A broken input is listed and the others go on; a rerun skips what "
        "is complete. Needs: pip install 'tactilevision[dask]'.",
    )
    p.add_argument("kind", choices=("reconstruct", "forces", "calibrate"))
    p.add_argument("inputs", metavar="INPUT", nargs="+", type=Path,
                   help="frame folders or video files (reconstruct, forces); session "
                   "folders (calibrate)")
    p.add_argument("--out", metavar="DIR", type=Path, required=True, help="output folder")
    p.add_argument("--scheduler", metavar="ADDRESS", default=None,
                   help="a running dask.distributed scheduler (tcp://host:8786); default: a "
                   "local cluster")
    p.add_argument("--workers", type=int, default=None,
                   help="worker processes of the local cluster (default: one per core)")
    p.add_argument("--chunk-frames", type=int, default=32,
                   help="frames per task and per Zarr chunk (default 32)")
    add_optics_options(p, reference=False)
    p.add_argument("--reference", metavar="REF", type=Path, default=None,
                   help="one no-contact frame for every input (default: each input's own "
                   "reference.png / <video>_reference.png, else the calibration's)")
    p.add_argument("--level", choices=("median", "far_field", "contact"), default=None,
                   help="the height's zero, as in reconstruct and forces (default: median "
                   "for reconstruct, contact for forces)")
    p.add_argument("--engine", choices=("table", "onnx"), default="table",
                   help="reconstructor engine (table: built once per worker, fastest per "
                   "frame; onnx: no build)")
    add_material_options(p)
    p.add_argument("--beta", type=float, default=None, help="forces: eq. (5)'s beta")
    p.add_argument("--method", choices=("spectral", "fem"), default="spectral")
    p.add_argument("--grid", metavar="NX,NY", default="40,30")
    p.add_argument("--json", metavar="FILE", default=None,
                   help="also write the batch report as JSON to FILE ('-': standard output)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--overwrite", action="store_true",
                   help="start again inputs an earlier run wrote with other settings")
    p.set_defaults(func=run)


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
