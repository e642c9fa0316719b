"""``tactilevision live``: a camera, video or frame folder through the live pipeline."""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path

from ._options import add_contact_options, add_material_options, add_optics_options

__all__ = ["CSV_COLUMNS", "add_parser", "run"]

#: The columns of ``--csv``, the per-frame totals.
CSV_COLUMNS = ["frame", "t_s", "latency_ms", "dropped", "max_depth_mm", "contact_area_mm2",
            "fx_n", "fy_n", "fz_n", "process_ms"]


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Register the ``live`` sub-command."""
    p = sub.add_parser(
        "live",
        help="a camera, video or frame folder through the live pipeline: annotated video, CSV",
        description="Run tactilevision.live.Pipeline on SOURCE (a camera index such as 0, a "
        "video file or a frame folder): capture on its own thread, one result per frame "
        "(height map, contact, force map and total force with E and nu), the latency from "
        "capture to result. Writes an annotated video (the frame beside its height map, "
        "force arrows, the total force) and a CSV of per-frame totals. Ctrl-C stops it "
        "cleanly, keeping what was written.",
    )
    p.add_argument("source", metavar="SOURCE",
                   help="camera index (0, 1, ...), video file, or folder of frames")
    add_optics_options(p, required=True, reference=False)
    p.add_argument("--reference", metavar="REF", default="auto",
                   help="no-contact frame (image file), 'auto' (default: from the first "
                   "--reference-frames frames) or 'calibration'")
    p.add_argument("--reference-frames", type=int, default=10,
                   help="frames the automatic reference is taken from (default 10)")
    add_material_options(p, fit=False)
    p.add_argument("--method", choices=("spectral", "fem"), default="spectral",
                   help="force method: spectral (every pixel, the default) or fem (the "
                   "inverse FEM on 40 x 30 nodes, faster a frame)")
    p.add_argument("--policy", choices=("latest", "every"), default=None,
                   help="drop stale frames when slower than the camera (latest, the default "
                   "for a camera) or process every frame (every, the default for files)")
    p.add_argument("--max-frames", type=int, default=None, help="stop after N frames")
    p.add_argument("--level", choices=("contact", "median", "far_field"), default=None,
                   help="the height's zero (default: contact with forces, the accurate "
                   "footprint; median with --contact field, several times faster, for "
                   "camera rate)")
    add_contact_options(p, note="; field with --level median or far_field is the camera-rate "
                        "choice")
    p.add_argument("--out", metavar="VIDEO", type=Path, default=None,
                   help="annotated video to write (.mp4 or .avi)")
    p.add_argument("--csv", metavar="FILE", type=Path, default=None,
                   help="per-frame totals: " + ", ".join(CSV_COLUMNS))
    p.add_argument("--depth-range-mm", type=float, default=None,
                   help="height of the colour map's top, mm (default: the first results' "
                   "deepest point)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--overwrite", action="store_true",
                   help="replace --out and --csv even when tactilevision did not write them")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run ``live``: :func:`~tactilevision.cli._live_run.run`, imported only now (``--help`` reads
    the options without the command's stack)."""
    return importlib.import_module("._live_run", __package__).run(args)
