"""``tactilevision reconstruct``: a folder of frames -> height maps and depth images."""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

from .. import KNOWN_SENSORS, InputError, default_calibration_path
from ._out import StagedOutput, add_overwrite_argument, check_output_folder, check_overwrite

__all__ = ["add_parser", "run"]


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Register the ``reconstruct`` sub-command."""
    p = sub.add_parser(
        "reconstruct",
        help="height maps (.npy, mm) and depth images (.png) from a folder of frames or a video",
        description="Photometric stereo on every frame of FRAMES_DIR: writes <frame>_height.npy "
        "(float32, mm, positive into the gel), <frame>_depth.png (frame beside its coloured "
        "height map, colour bar in mm, scale bar) and heights.csv (one row per frame).",
    )
    p.add_argument("frames_dir", metavar="FRAMES_DIR", type=Path,
                   help="folder of .png/.jpg frames (sorted by name), or a video file (.mp4, "
                   ".avi, ...: its frames named <video stem>_<index>)")
    p.add_argument("--reference", metavar="REF", type=Path, default=None,
                   help="no-contact frame; default FRAMES_DIR/reference.png (or ref.jpg, or "
                   "gs_sdk's background.png, or in the parent folder), else the "
                   "calibration's own reference; a file of one of these names is never read "
                   "as a frame")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--calibration", metavar="OPTICS", type=Path,
                     help="photometric calibration file (.npz from 'optics calibrate')")
    src.add_argument("--sensor", metavar="NAME", choices=KNOWN_SENSORS,
                     help=f"use the shipped default calibration: {', '.join(KNOWN_SENSORS)}")
    p.add_argument("--out", metavar="DIR", type=Path, default=Path("out/reconstruct"),
                   help="output folder (default: out/reconstruct)")
    p.add_argument("--no-images", action="store_true", help="write only the .npy height maps")
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
    from ..io import (
        VideoFrames,
        find_reference,
        find_video_reference,
        is_video,
        list_frames,
        read_frame,
        read_reference,
    )
    from ..optics import DepthReconstructor, PhotometricCalibration
    from ..viz import save_depth_image

    boundary, level = _boundary_and_level(args.boundary, args.level)
    out = check_output_folder(args.out)    # before any work: a bad --out fails at once
    overwrite = args.overwrite
    cal_path = args.calibration or default_calibration_path(args.sensor)
    cal = PhotometricCalibration.load(cal_path)
    video = None
    if args.frames_dir.is_file() and is_video(args.frames_dir):
        video = VideoFrames(args.frames_dir)
        frames = [_VideoFrame(args.frames_dir, i) for i in range(video.n_frames)]
    else:
        frames = list_frames(args.frames_dir)
    names = ["heights.csv"] + [f"{p.stem}_height.npy" for p in frames]
    if not args.no_images:
        names += [f"{p.stem}_depth.png" for p in frames]
    check_overwrite(out, names, overwrite=overwrite)
    ref_path = args.reference or (find_video_reference(args.frames_dir) if video is not None
                                  else find_reference(args.frames_dir))
    if args.reference is not None and not args.reference.is_file():
        raise InputError(f"reference {args.reference} does not exist")
    reference = read_reference(ref_path, cal.shape) if ref_path else None
    recon = DepthReconstructor(cal, reference="calibration" if reference is None else reference,
                               boundary=boundary, level=level, engine=args.engine,
                               flat_reference=args.flat_reference,
                               zero_background=args.zero_background)
    credit = cal.provenance.get("credit")
    rows, skipped = [], []
    # written whole into a hidden folder in out, moved into place at the end (Ctrl-C: nothing)
    with StagedOutput(out, overwrite=overwrite) as stage:
        tmp = stage.path
        decoded = video.iter(0, video.n_frames) if video is not None else None
        for path in tqdm(frames, desc="reconstruct", unit="frame", file=sys.stderr,
                         disable=args.no_progress):
            try:
                frame = (read_frame(path, cal.shape) if decoded is None
                         else _checked(next(decoded), cal.shape, path.name))
            except InputError as exc:
                skipped.append(str(exc))
                continue
            height = recon(frame)
            np.save(tmp / f"{path.stem}_height.npy", height)
            if not args.no_images:
                save_depth_image(tmp / f"{path.stem}_depth.png", height,
                                 mm_per_px=cal.mm_per_px, frame=frame, title=path.name,
                                 credit=credit)
            contact = recon.contact_mask(frame)
            rows.append({"frame": path.name, "max_depth_mm": f"{float(height.max()):.4f}",
                         "contact_area_mm2": f"{contact.sum() * cal.mm_per_px ** 2:.3f}",
                         "out_of_range_px": int(recon.out_of_range(frame).sum())})
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
    ref_note = str(ref_path) if ref_path else "the calibration's reference"
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


class _VideoFrame:
    """A video's frame named as a file would be: ``<video stem>_<index>``."""

    def __init__(self, video: Path, index: int) -> None:
        self.stem = f"{video.stem}_{index:05d}"
        self.name = f"{video.name}#{index}"



def _checked(frame, shape: tuple[int, int], name: str):
    if frame.shape[:2] != tuple(shape):
        raise InputError(f"{name} is {frame.shape[1]} x {frame.shape[0]}, the calibration "
                         f"{shape[1]} x {shape[0]}")
    return frame
