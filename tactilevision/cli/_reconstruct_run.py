"""What ``tactilevision reconstruct`` does once its options are parsed
(:mod:`tactilevision.cli._reconstruct`): a folder of frames -> height maps and depth images.

Imported only when the command runs, so that its ``--help`` does not load this stack.
"""

from __future__ import annotations

import argparse
import csv
import sys

import numpy as np
from tqdm.auto import tqdm

from .. import InputError
from ..io import StagedOutput, check_output_folder, check_overwrite, open_source
from ..optics import DepthReconstructor
from ..viz import save_depth_image
from ._inputs import optics_calibration

__all__ = ["run"]


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
