"""What ``tactilevision live`` does once its options are parsed
(:mod:`tactilevision.cli._live`): a camera, video or frame folder through the live pipeline.

Imported only when the command runs, so that its ``--help`` does not load this stack.
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

import cv2
import numpy as np
from tqdm.auto import tqdm

from .. import InputError, default_calibration_path
from ..io import (
    check_output_file,
    check_output_folder,
    output_folder,
    read_reference,
    record_output,
)
from ..live import Pipeline
from ._live import CSV_COLUMNS
from ._options import binning_from_args

__all__ = ["annotate", "run"]


def annotate(frame: np.ndarray, height_mm: np.ndarray, *, depth_range_mm: float,
             forces=None, total_force_n: np.ndarray | None = None, cell_px: int = 24
             ) -> np.ndarray:
    """The frame beside its coloured height map, tangential force arrows and the total force.

    Parameters
    ----------
    frame : (H, W, 3) uint8 ndarray
        BGR.
    height_mm : (H, W) float ndarray
        mm, positive into the gel.
    depth_range_mm : float
        The height at the top of the colour map (viridis), mm.
    forces : ForceMap, optional
        Arrows of the tangential force, scaled to the largest: per-pixel forces
        (spectral) summed over cells of `cell_px` pixels, node forces (inverse
        FEM) at their nodes.
    total_force_n : (3,) ndarray, optional
        Written as text.
    cell_px : int, default 24

    Returns
    -------
    image : (H, 2 W, 3) uint8 ndarray
        BGR.
    """
    h, w = height_mm.shape
    z = np.clip(np.nan_to_num(height_mm) / max(depth_range_mm, 1e-9), 0.0, 1.0)
    colour = cv2.applyColorMap((255 * z).astype(np.uint8), cv2.COLORMAP_VIRIDIS)
    arrows = []                       # (x0, y0, fx, fy, length of the largest) in px
    if forces is not None and np.ndim(forces.forces_n) == 3:
        f = np.asarray(forces.forces_n, np.float64)
        if f.shape[:2] == (h, w):         # per pixel: summed over cells
            rows, cols = h // cell_px, w // cell_px
            if rows and cols:
                cells = f[:rows * cell_px, :cols * cell_px, :2].reshape(
                    rows, cell_px, cols, cell_px, 2).sum(axis=(1, 3))
                arrows = [(j * cell_px + cell_px // 2, i * cell_px + cell_px // 2,
                           *cells[i, j], 0.9 * cell_px)
                          for i in range(rows) for j in range(cols)]
        elif len(forces.x_mm) == f.shape[1] and len(forces.y_mm) == f.shape[0]:
            # per node (the inverse FEM): at the nodes, scaled to their spacing
            px = float(forces.x_mm[-1] - forces.x_mm[0]) / max(w - 1, 1)
            step = float(forces.x_mm[1] - forces.x_mm[0]) / px if f.shape[1] > 1 else cell_px
            arrows = [(round(x / px), round(y / px), *f[i, j, :2], 0.9 * step)
                      for i, y in enumerate(forces.y_mm) for j, x in enumerate(forces.x_mm)]
    big = max((abs(a[2]) for a in arrows), default=0.0)
    big = max([big, *(abs(a[3]) for a in arrows)])
    if big > 0:
        for x0, y0, fx, fy, length in arrows:
            fx, fy = fx / big * length, fy / big * length
            if abs(fx) + abs(fy) < 1.0:
                continue
            cv2.arrowedLine(colour, (x0, y0), (int(x0 + fx), int(y0 + fy)),
                            (255, 255, 255), 1, tipLength=0.3)
    out = np.concatenate([frame, colour], axis=1)
    scale = max(h / 480.0, 0.35)
    cv2.putText(out, f"0-{depth_range_mm:.2f} mm", (w + 5, int(18 * scale) + 4),
                cv2.FONT_HERSHEY_SIMPLEX, 0.5 * scale, (255, 255, 255), 1, cv2.LINE_AA)
    if total_force_n is not None:
        fx, fy, fz = (float(v) for v in total_force_n)
        cv2.putText(out, f"Fz {fz:.3f} N  Fx {fx:+.3f}  Fy {fy:+.3f}",
                    (5, h - 8), cv2.FONT_HERSHEY_SIMPLEX, 0.5 * scale, (255, 255, 255), 1,
                    cv2.LINE_AA)
    return out


def run(args: argparse.Namespace) -> int:
    """Run ``live``; returns 0 (130 on Ctrl-C, with the outputs so far closed and kept)."""
    cal_path = args.calibration or default_calibration_path(args.sensor)
    source: int | Path = int(args.source) if str(args.source).isdigit() else Path(args.source)
    if isinstance(source, Path) and not source.exists():
        raise InputError(f"{source}: no such file or folder")
    _check_outputs(args)
    reference = args.reference
    if reference not in ("auto", "calibration"):
        reference = read_reference(Path(reference))
    pipe = Pipeline(cal_path, reference=reference, n_reference=args.reference_frames,
                    E_mpa=args.E_mpa, nu=args.nu, thickness_mm=args.thickness_mm,
                    level=args.level, method=args.method, contact=args.contact,
                    threshold_mm=args.threshold_mm, binning=binning_from_args(args.binning))
    for p in (args.out, args.csv):
        if p is not None:
            output_folder(p.parent, f"folder of {p.name}")
    mm2 = pipe.calibration.mm_per_px ** 2
    writer = None
    fh = wcsv = None
    bar = None
    n, lat, drops, proc, live = 0, [], 0, [], True
    depth_range = args.depth_range_mm
    try:
        if args.csv is not None:
            fh = args.csv.open("w", newline="")
            record_output(args.csv)
            wcsv = csv.DictWriter(fh, fieldnames=CSV_COLUMNS)
            wcsv.writeheader()
        if not args.no_progress:

            bar = tqdm(desc="live", unit="frame", file=sys.stderr, mininterval=0.5)
        t0 = None
        for r in pipe.stream(source, policy=args.policy, max_frames=args.max_frames):
            t0 = r.t_capture_s if t0 is None else t0
            if depth_range is None:
                depth_range = max(float(np.nanmax(r.height_mm)), 0.05)
            if args.out is not None:
                img = annotate(r.frame, r.height_mm, depth_range_mm=depth_range,
                               forces=r.forces, total_force_n=r.total_force_n)
                if writer is None:
                    fourcc = "mp4v" if args.out.suffix.lower() == ".mp4" else "MJPG"
                    writer = cv2.VideoWriter(str(args.out), cv2.VideoWriter_fourcc(*fourcc),
                                             30.0, (img.shape[1], img.shape[0]))
                    record_output(args.out)
                writer.write(img)
            if wcsv is not None:
                tot = r.total_force_n
                wcsv.writerow({
                    "frame": r.index, "t_s": f"{r.t_capture_s - t0:.4f}",
                    "latency_ms": f"{1e3 * r.latency_s:.2f}",
                    "process_ms": f"{1e3 * r.process_s:.2f}", "dropped": r.dropped,
                    "max_depth_mm": f"{float(np.nanmax(r.height_mm)):.4f}",
                    "contact_area_mm2": f"{float(r.contact.sum()) * mm2:.3f}",
                    **({k: "" for k in ("fx_n", "fy_n", "fz_n")} if tot is None else
                       {k: f"{float(v):.5f}" for k, v in zip(("fx_n", "fy_n", "fz_n"), tot,
                                                            strict=True)})})
            n += 1
            lat.append(r.latency_s)
            proc.append(r.process_s)
            live = r.live
            drops += r.dropped
            if bar is not None:
                bar.update(1)
    finally:
        if bar is not None:
            bar.close()
        if writer is not None:
            writer.release()
        if fh is not None:
            fh.close()
    if n == 0:
        raise InputError(f"{args.source}: no frame was processed")
    print(f"live: {n} frame(s) from {args.source}, {drops} dropped; "
          f"{_timing(lat, proc, live)}"
          + (f"; video {args.out}" if args.out else "") + (f"; CSV {args.csv}" if args.csv
                                                             else ""))
    return 0


def _timing(lat: list[float], proc: list[float], live: bool) -> str:
    """The run's timing in words: on a camera the latency (capture to result); on a file
    or folder, read ahead of the processing, the processing time a frame, the
    capture-to-result figure named as the queue it mostly is."""
    med, pmed = 1e3 * float(np.median(lat)), 1e3 * float(np.median(proc))
    if live:
        return (f"latency median {med:.1f} ms, max {1e3 * max(lat):.1f} ms (processing "
                f"median {pmed:.1f} ms)")
    return (f"processing median {pmed:.1f} ms a frame ({1e3 / pmed:.1f} frames/s), max "
            f"{1e3 * max(proc):.1f} ms; a file is read ahead, so capture to result "
            f"(median {med:.0f} ms) is mostly its queue, not a latency")


def _check_outputs(args: argparse.Namespace) -> None:
    """--out and --csv, before any work: a video's suffix, a file (not a folder) in a
    folder that can be made, and not a file tactilevision did not write (--overwrite)."""
    if args.out is not None and args.out.suffix.lower() not in (".mp4", ".avi"):
        raise InputError(f"--out {args.out}: write a .mp4 or .avi video")
    for p in (args.out, args.csv):
        if p is not None:
            check_output_folder(p.parent, f"folder of {p.name}")
            if p.is_dir():
                raise InputError(f"{p} is a folder: give a file name")
            check_output_file(p, overwrite=args.overwrite)
