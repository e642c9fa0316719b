"""``tactilevision reconstruct``: a folder of frames -> height maps and depth images."""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path

from ._options import add_optics_options
from ._out import add_overwrite_argument

__all__ = ["add_parser", "run"]


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Register the ``reconstruct`` sub-command."""
    p = sub.add_parser(
        "reconstruct",
        help="height maps (.npy, mm) and heights.csv from a folder of frames or a video "
        "(depth images with --images)",
        description="Photometric stereo on every frame of FRAMES_DIR: writes <frame>_height.npy "
        "(float32, mm, positive into the gel) and heights.csv (one row per frame); with "
        "--images also <frame>_depth.png (frame beside its coloured height map, colour bar in "
        "mm, scale bar).",
    )
    p.add_argument("frames_dir", metavar="FRAMES_DIR", type=Path,
                   help="folder of .png/.jpg frames (sorted by name), or a video file (.mp4, "
                   ".avi, ...: its frames named <video stem>_<index>)")
    add_optics_options(p, required=True)
    p.add_argument("--out", metavar="DIR", type=Path, default=None,
                   help="output folder (default: <FRAMES_DIR>_reconstruct beside the frames "
                   "folder, <stem>_reconstruct beside a video; never the current folder "
                   "unless the source is there)")
    p.add_argument("--images", action="store_true",
                   help="also write <frame>_depth.png (the frame beside its coloured height "
                   "map): pictures are opt-in, the arrays and heights.csv are the output")
    p.add_argument("--no-images", action="store_true",
                   help="(the default now; kept so that older scripts run)")
    p.add_argument("--level", choices=("median", "far_field", "contact"), default="median",
                   help="the height's zero: the frame's median (default, camera rate), a "
                   "surface fitted to the gel outside the contact, or zero outside the "
                   "contact region with the heights integrated over it (what 'forces' uses; "
                   "absolute heights: docs/absolute_depth.md)")
    p.add_argument("--boundary", choices=("neumann", "dirichlet", "contact"), default=None,
                   help="Poisson boundary condition: 'neumann' (default, whole image, camera "
                   "rate), 'dirichlet' (zero height on the image border), or 'contact' (zero "
                   "outside the frame's contact region, integrated over it only; slower, and "
                   "the same as --level contact)")
    p.add_argument("--engine", choices=("table", "onnx"), default="table",
                   help="how an MLP calibration runs: 'table' (default: tabulated once, one "
                   "lookup per pixel) or 'onnx' (the network on every pixel: exact, much "
                   "slower); a LUT calibration runs only as 'table'")
    p.add_argument("--flat-reference", action="store_true",
                   help="subtract the optics model's gradient on the reference")
    p.add_argument("--zero-background", action="store_true",
                   help="zero the gradients outside each frame's contact region before "
                   "integrating, so the flat gel's noise stays out of the height map; meant "
                   "for calibrations made with a small --flat-fraction such as 0.003 (no "
                   "effect with --boundary contact)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_overwrite_argument(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run ``reconstruct``: :func:`~tactilevision.cli._reconstruct_run.run`, imported only now
    (``--help`` reads the options without the command's stack)."""
    return importlib.import_module("._reconstruct_run", __package__).run(args)
