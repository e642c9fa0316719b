"""``tactilevision reconstruct``: a folder of frames -> height maps and depth images."""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

from .. import InputError
from ..io import StagedOutput, check_output_folder, check_overwrite, open_source
from ..optics import DepthReconstructor
from ..viz import save_depth_image
from ._options import add_optics_options, optics_calibration
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
    """Run ``reconstruct``; returns 2 if any frame was skipped."""
    boundary, level = _boundary_and_level(args.boundary, args.level)
    if args.out is None:
        src_path = args.frames_dir
        args.out = src_path.with_name(f"{src_path.stem if src_path.is_file() else src_path.name}"
                                      "_reconstruct")
    out = check_output_folder(args.out)    # before any work: a bad --out fails at once
    src = open_source(args.frames_dir, reference=args.reference)
    cal, cal_path, _ = optics_calibration(args, src)
    stems = [src.frame_stem(i) for i in range(src.n_frames)]
    names = ["heights.csv"] + [f"{s}_height.npy" for s in stems]
    images = args.images and not args.no_images
    if images:
        names += [f"{s}_depth.png" for s in stems]
    check_overwrite(out, names, overwrite=args.overwrite)
    reference = src.reference(cal.shape)
    recon = DepthReconstructor(cal, reference="calibration" if reference is None else reference,
                               boundary=boundary, level=level, engine=args.engine,
                               flat_reference=args.flat_reference,
                               zero_background=args.zero_background)
    credit = cal.provenance.get("credit")
    rows, skipped = [], []
    # written whole into a hidden folder in out, moved into place at the end (Ctrl-C: nothing)
    with StagedOutput(out, overwrite=args.overwrite) as stage:
        tmp = stage.path
        for i, frame in tqdm(src.frames_at(range(src.n_frames), cal.shape), total=src.n_frames,
                             desc="reconstruct", unit="frame", file=sys.stderr,
                             disable=args.no_progress):
            if isinstance(frame, InputError):
                skipped.append(str(frame))
                continue
            name, stem = src.frame_name(i), stems[i]
            height = recon(frame)
            np.save(tmp / f"{stem}_height.npy", height)
            if images:
                save_depth_image(tmp / f"{stem}_depth.png", height, mm_per_px=cal.mm_per_px,
                                 frame=frame, title=name, credit=credit)
            contact, outside = recon.contact_and_out_of_range(frame)
            rows.append({"frame": name, "max_depth_mm": f"{float(height.max()):.4f}",
                         "contact_area_mm2": f"{contact.sum() * cal.mm_per_px ** 2:.3f}",
                         "out_of_range_px": int(outside.sum())})
        if not rows:
            # nothing to show for the run: the output folder is left as it was
            raise InputError(f"no frame of {args.frames_dir} could be reconstructed, nothing "
                             f"written: " + "; ".join(skipped))
        with (tmp / "heights.csv").open("w", newline="") as fh:
            writer = csv.DictWriter(fh, fieldnames=["frame", "max_depth_mm",
                                                    "contact_area_mm2", "out_of_range_px"])
            writer.writeheader()
            writer.writerows(rows)
        stage.commit()
    ref_note = (str(src.reference_path) if src.reference_path else
                "the session's" if src.session is not None else "the calibration's reference")
    print(f"reconstructed {len(rows)} frame(s) from {args.frames_dir} with {cal_path} "
          f"(reference: {ref_note}) into {out}")
    if skipped:
        for msg in skipped:
            print(f"tactilevision reconstruct: error: {msg}", file=sys.stderr)
        return 2
    return 0


def _boundary_and_level(boundary: str | None, level: str) -> tuple[str, str]:
    """The reconstructor's boundary and level from ``--boundary`` and ``--level`` (``--level
    contact`` is ``--boundary contact``; 'far_field' levels a Neumann solve only).

    Raises
    ------
    InputError
        For a combination that asks for two different things (naming both options).
    """
    if level == "contact":
        if boundary not in (None, "contact"):
            raise InputError(f"--level contact is --boundary contact; it cannot go with "
                             f"--boundary {boundary}")
        return "contact", "median"
    boundary = boundary or "neumann"
    if level == "far_field" and boundary != "neumann":
        raise InputError(f"--level far_field levels a Neumann solve; with --boundary {boundary} "
                         "the height's zero is set by the boundary itself (leave out --level)")
    return boundary, level
