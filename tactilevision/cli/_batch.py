"""``tactilevision batch``: many frame folders, videos or sessions on a Dask cluster."""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path

from ._options import add_material_options, add_optics_options

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


def run(args: argparse.Namespace) -> int:
    """Run ``batch``: :func:`~tactilevision.cli._batch_run.run`, imported only now (``--help``
    reads the options without the command's stack)."""
    return importlib.import_module("._batch_run", __package__).run(args)
