"""What ``tactilevision forces`` does once its options are parsed
(:mod:`tactilevision.cli._forces`): frames -> height maps -> contact force maps and totals.

Imported only when the command runs, so that its ``--help`` does not load this stack.
"""

from __future__ import annotations

import argparse
import csv
import sys
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

from .. import InputError
from ..fem import AUTO_BIN_MAX, ForceEstimator
from ..io import FrameSource, StagedOutput, check_output_folder, check_overwrite, open_source
from ..optics import DepthReconstructor
from ..viz import save_force_image
from ._inputs import beta_from_args, material_from_args, optics_calibration
from ._options import binning_from_args

__all__ = ["run"]

_COLUMNS = ["frame", "t_s", "fx_n", "fy_n", "fz_n", "max_pressure_kpa", "contact_area_mm2",
            "ft_fz_n"]


def run(args: argparse.Namespace) -> int:
    """Run ``forces``; returns 0, or 2 on bad input (nothing written then)."""
    source: Path = args.source
    default_out = (source.with_name(f"{source.stem}_forces") if source.is_file()
                   else source / "forces")
    out = args.out if args.out is not None else default_out
    check_output_folder(out)
    src = open_source(source, reference=args.reference)
    session = src.session
    if args.thickness_mm is None and session is None:
        raise InputError("a frames folder or video needs --thickness-mm (the gel thickness h)")
    h = args.thickness_mm if args.thickness_mm is not None else session.config.gel_thickness_mm
    cal, cal_path, optics_note = optics_calibration(args, src)
    reference = src.reference(cal.shape)
    mm_per_px = src.mm_per_px if src.mm_per_px is not None else cal.mm_per_px
    if args.every < 1:
        raise InputError(f"--every must be >= 1, got {args.every}")
    picks = range(0, src.n_frames, args.every)
    images = args.images and not args.no_images
    names = (["forces.csv"] + [f"{src.frame_stem(i)}_pressure_kpa.npy" for i in picks]
             + ([f"{src.frame_stem(i)}_force.png" for i in picks] if images else []))
    check_overwrite(out, names, overwrite=args.overwrite)
    E, nu, material_source, fit_obj = material_from_args(args, source if session else None)
    beta, beta_source = beta_from_args(args, fit_obj, material_source)
    try:
        grid = tuple(int(v) for v in args.grid.split(","))
    except ValueError:
        raise InputError(f"--grid must be NX,NY, got {args.grid!r}") from None
    binning = binning_from_args(args.binning)
    est = ForceEstimator(cal.shape, mm_per_px, thickness_mm=h, E_mpa=E, nu=nu, grid=grid,
                         method=args.method, contact=args.contact,
                         threshold_mm=args.threshold_mm, beta=beta, binning=binning)
    recon = DepthReconstructor(
        cal, reference="calibration" if reference is None else reference,
        boundary="contact" if args.level == "contact" else "neumann",
        level="median" if args.level == "contact" else args.level,
        flat_reference=args.flat_reference,
        binning=est.blocks if args.level == "contact" else 1)
    ft, ft_note = _ft_log(src, fit_obj)
    # written whole into a hidden folder in out, moved into place at the end (Ctrl-C:
    # nothing)
    with StagedOutput(out, overwrite=args.overwrite) as stage:
        rows, skipped, at_edge = _force_rows(src, picks, recon, est, ft, stage.path, args,
                                             cal.shape, mm_per_px,
                                             cal.provenance.get("credit"))
        with (stage.path / "forces.csv").open("w", newline="") as fh:
            writer = csv.DictWriter(fh, fieldnames=_COLUMNS)
            writer.writeheader()
            writer.writerows(rows)
        stage.commit()
    level = {"contact": "zero outside the contact region",
             "far_field": "levelled at the far field", "median": "the frame's median at zero"}
    contact = (f"footprint above {args.threshold_mm:g} mm" if args.contact == "footprint"
               else "field")
    blocks = est.blocks
    if blocks != 1:
        contact += (f", solved on blocks of up to {AUTO_BIN_MAX} x {AUTO_BIN_MAX} pixels (auto)"
                    if blocks == "auto" else f", solved on blocks of {blocks} x {blocks} pixels")
    elif args.contact == "footprint" and args.method == "spectral":
        contact += ", solved on every pixel"
    blocks_note = ", integrated on blocks as the force solve"
    print(f"force maps of {len(rows)} frame(s) from {source} into {out}{ft_note}\n"
          f"  optics: {cal_path} ({optics_note})\n"
          f"  heights: {level[args.level]}"
          f"{blocks_note if recon.binning != 1 else ''}"
          f"{', flat reference' if args.flat_reference else ''}\n"
          f"  forces: {args.method}, {contact}; E {E:.4g} MPa, nu {nu:.4g} from "
          f"{material_source}; beta {beta:.3g} from {beta_source}; h {h:g} mm")
    if at_edge:
        shown = ", ".join(at_edge[:5]) + (f" and {len(at_edge) - 5} more" if len(at_edge) > 5
                                          else "")
        print(f"tactilevision forces: warning: the footprint reaches the image's edge in "
              f"{len(at_edge)} frame(s) ({shown}): what lies beyond is not measured, and "
              "their totals may be low",
              file=sys.stderr)
    for msg in skipped:
        print(f"tactilevision forces: error: {msg}", file=sys.stderr)
    return 2 if skipped else 0


def _ft_log(src: FrameSource, fit_obj: dict) -> tuple[tuple | None, str]:
    """A session's F/T fz on the camera's clock (times, fz), and a note when the clock offset
    is unknown (the F/T column then stays empty rather than misaligned)."""
    session = src.session
    if session is None or not session.forces_n.size:
        return None, ""
    # the clock offset: the session's, else the one calibrate estimated
    offset = session.config.clock_offset_s
    if offset is None:
        offset = fit_obj.get("clock_offset_s")
    if offset is None:
        return None, ("; ft_fz_n left empty: the clock offset between frames and F/T log is "
                      "unknown (no [force_sensor] clock_offset_s, no fit.json from calibrate)")
    return (session.force_times_s - float(offset), session.forces_n[:, 2]), ""


def _force_rows(src: FrameSource, picks, recon, est, ft, tmp: Path, args, shape,
                mm_per_px: float, credit) -> tuple[list[dict], list[str], list[str]]:
    """Each picked frame's force map (its image into `tmp`) and forces.csv row; the frames
    skipped (their errors) and those whose footprint reaches the image's edge."""
    rows, skipped, at_edge = [], [], []
    with ThreadPoolExecutor(max_workers=1) as writer:
        pending = None
        frames = tqdm(_ahead(src.frames_at(picks, shape)), total=len(picks), desc="forces",
                      unit="frame", file=sys.stderr, mininterval=1.0, disable=args.no_progress)
        for i, pressure in _force_maps(frames, src, recon, est, ft, args, mm_per_px,
                                       credit, tmp, rows, skipped, at_edge):
            # the map written while the next frame is worked on; a failed write raises here
            if pending is not None:
                pending.result()
            pending = writer.submit(np.save, tmp / f"{src.frame_stem(i)}_pressure_kpa.npy",
                                    pressure)
        if pending is not None:
            pending.result()
    return rows, skipped, at_edge


def _ahead(items: Iterator) -> Iterator:
    """The items of `items`, each read while the one before is worked on (one thread: a
    frame's decoding overlaps the last frame's force map)."""
    with ThreadPoolExecutor(max_workers=1) as pool:
        nxt = pool.submit(next, items, None)
        while True:
            item = nxt.result()
            if item is None:
                return
            nxt = pool.submit(next, items, None)
            yield item


def _force_maps(frames, src: FrameSource, recon, est, ft, args, mm_per_px: float, credit,
                tmp: Path, rows: list, skipped: list, at_edge: list) -> Iterator:
    """Each readable frame's force map: its forces.csv row appended to `rows` (the skipped
    frames' errors to `skipped`, those whose footprint reaches the edge to `at_edge`), its
    image written into `tmp`; yields ``(i, pressure map (float32))``."""
    for i, frame in frames:
        if isinstance(frame, InputError):
            skipped.append(str(frame))
            continue
        name = src.frame_name(i)
        height = recon(frame)     # float32: the estimator's single-precision path
        fm = est(height)
        # the contact area: the footprint the traction acts on (pixels, or FEM nodes, above
        # --threshold-mm that push: each node's area is its force over its pressure); with
        # 'field', the colour change above the noise level
        if fm.contact is None:
            area = float(recon.contact_mask(frame).sum()) * mm_per_px ** 2
        else:
            c = fm.contact
            area = float(np.sum(fm.forces_n[..., 2][c] / fm.pressure_kpa[c])) * 1e3
            if c[0].any() or c[-1].any() or c[:, 0].any() or c[:, -1].any():
                at_edge.append(name)     # the force beyond the image is not seen
        t = float(src.times_s[i])
        row = {"frame": name, "t_s": "" if not np.isfinite(t) else f"{t:.4f}",
               "fx_n": f"{fm.total_n[0]:.5f}", "fy_n": f"{fm.total_n[1]:.5f}",
               "fz_n": f"{fm.total_n[2]:.5f}",
               "max_pressure_kpa": f"{float(fm.pressure_kpa.max()):.3f}",
               "contact_area_mm2": f"{area:.3f}", "ft_fz_n": ""}
        if ft is not None and np.isfinite(t):
            row["ft_fz_n"] = f"{float(np.interp(t, ft[0], ft[1])):.5f}"
        rows.append(row)
        if args.images and not args.no_images:
            save_force_image(tmp / f"{src.frame_stem(i)}_force.png", fm, mm_per_px=mm_per_px,
                             frame=frame, title=name, credit=credit)
        yield i, np.asarray(fm.pressure_kpa, np.float32)
