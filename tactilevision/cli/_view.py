"""``tactilevision view``: frames, a video or a batch's Zarr group -> one interactive HTML page."""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path

from ._options import add_material_options, add_optics_options

__all__ = ["add_parser", "run"]


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Register the ``view`` sub-command."""
    p = sub.add_parser(
        "view",
        help="an interactive, self-contained HTML viewer (frame, height map, 3D surface, "
        "force map, frame slider)",
        description="Writes one HTML page (Plotly, its JavaScript inline: opens without a "
        "network) with the tactile frame beside its height map (colour bar in mm), a 3D "
        "surface to rotate, the pressure map (kPa) when E, nu and the thickness are given "
        "or the Zarr group holds pressure_kpa, and a slider over the frames.",
    )
    p.add_argument("source", metavar="FRAMES_DIR|VIDEO|ZARR", type=Path,
                   help="a folder of frames, a video file, or a NAME.zarr group written by "
                   "'tactilevision batch'")
    p.add_argument("--out", metavar="HTML", type=Path, default=None,
                   help="the page to write (default: <source>_view.html beside the source; "
                   "a page tactilevision did not write is replaced only with --overwrite)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace --out even when tactilevision did not write it")
    add_optics_options(p)
    p.add_argument("--max-frames", type=int, default=60, metavar="N",
                   help="at most N frames, evenly spaced (default 60)")
    p.add_argument("--max-px", type=int, default=160, metavar="PX",
                   help="long side of the images on the page, px (default 160)")
    add_material_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run ``view``: :func:`~tactilevision.cli._view_run.run`, imported only now (``--help`` reads
    the options without the command's stack)."""
    return importlib.import_module("._view_run", __package__).run(args)
