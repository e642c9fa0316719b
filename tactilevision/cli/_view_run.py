"""What ``tactilevision view`` does once its options are parsed
(:mod:`tactilevision.cli._view`): frames, a video or a batch's Zarr group -> one interactive
HTML page.

Imported only when the command runs, so that its ``--help`` does not load this stack.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import warnings
from pathlib import Path

import numpy as np

from .. import InputError
from ..fem import ForceEstimator
from ..io import check_output_file, open_source, record_output
from ..optics import DepthReconstructor, PhotometricCalibration
from ..pipeline import read_material
from ..viz import write_viewer
from ._inputs import optics_calibration

__all__ = ["run"]


def _picks(n: int, k: int) -> np.ndarray:
    """At most `k` indices of ``range(n)``, evenly spaced, first and last included."""
    return np.unique(np.round(np.linspace(0, n - 1, min(n, k))).astype(int))


def _material(args: argparse.Namespace) -> tuple[float, float, float] | None:
    """(E_mpa, nu, thickness_mm) for the force map, or None when none was asked for."""
    asked = (args.E_mpa is not None or args.nu is not None or args.fit is not None
             or args.thickness_mm is not None)
    if not asked:
        return None
    if args.fit is not None:
        E, nu, _ = read_material(args.fit)
        if args.E_mpa is not None:
            E = float(args.E_mpa)
        if args.nu is not None:
            nu = float(args.nu)
    else:
        if args.E_mpa is None or args.nu is None:
            raise InputError("a force map needs both --E-mpa and --nu (or --fit FIT.json)")
        E, nu = float(args.E_mpa), float(args.nu)
    if args.thickness_mm is None:
        raise InputError("a force map needs --thickness-mm (the gel thickness h)")
    if not (np.isfinite(E) and E > 0 and np.isfinite(nu) and -1 < nu < 0.5
            and np.isfinite(args.thickness_mm) and args.thickness_mm > 0):
        raise InputError(f"E_mpa = {E}, nu = {nu}, thickness_mm = {args.thickness_mm}: "
                         "need E > 0, -1 < nu < 0.5, h > 0")
    return E, nu, float(args.thickness_mm)


def _from_zarr(source: Path, args, picks_max: int):
    import zarr  # the dask extra

    try:
        g = zarr.open_group(str(source), mode="r")
    except Exception as exc:  # zarr raises several types for a folder that is no group
        raise InputError(f"{source} is not a readable Zarr group ({exc})") from None
    if "height_mm" not in g:
        raise InputError(f"Zarr group {source} has no 'height_mm' array (not written by "
                         "'tactilevision batch'?)")
    with warnings.catch_warnings():    # groups written before 2026-11-26: Quantize
        warnings.filterwarnings("ignore", "Numcodecs codecs are not in the Zarr")
        h = g["height_mm"]
    if len(h.shape) != 3 or h.shape[0] == 0:
        raise InputError(f"{source}/height_mm has shape {h.shape}, not (N, H, W) with N > 0")
    idx = _picks(h.shape[0], picks_max)
    heights = np.stack([np.asarray(h[int(i)], np.float32) for i in idx])
    pressure = None
    if "pressure_kpa" in g:
        p = g["pressure_kpa"]
        if len(p.shape) == 3 and p.shape[0] == h.shape[0]:
            pressure = np.stack([np.asarray(p[int(i)], np.float32) for i in idx])
    attrs = dict(g.attrs)
    cal, _, _ = optics_calibration(args, required=False)
    if cal is None:
        try:
            cal_path = json.loads(attrs.get("settings", "{}")).get("calibration")
            cal = PhotometricCalibration.load(cal_path) if cal_path else None
        except Exception:  # the batch's calibration moved: axes in px then
            cal = None
    mm_per_px = cal.mm_per_px if cal is not None else None
    frames = None
    src = attrs.get("source")
    labels = [f"frame {int(i)}" for i in idx]
    if src:
        try:
            fs = open_source(src)
            if fs.n_frames == h.shape[0]:
                frames = np.stack([fs.frame(int(i), tuple(h.shape[1:])) for i in idx])
                labels = [fs.frame_name(int(i)) for i in idx]
        except (InputError, OSError):
            frames = None      # the source moved or changed: the height maps alone
    return frames, heights, pressure, mm_per_px, labels


def run(args: argparse.Namespace) -> int:
    """Run ``view``; returns 0, or 2 on bad input (nothing written then)."""
    source: Path = args.source
    if args.out is None:
        args.out = source.with_name(f"{source.stem}_view.html")
    out: Path = args.out
    check_output_file(out, overwrite=args.overwrite)
    if args.max_frames < 1:
        raise InputError(f"--max-frames must be >= 1, got {args.max_frames}")
    if args.max_px < 8:
        raise InputError(f"--max-px must be >= 8, got {args.max_px}")
    if out.is_dir():
        raise InputError(f"--out {out} is a folder: give the .html file to write")
    if not source.exists():
        raise InputError(f"{source} does not exist")
    if importlib.util.find_spec("plotly") is None:   # said before any work
        raise InputError("the viewer needs Plotly: pip install 'tactilevision[view]'")
    material = _material(args)
    is_zarr = source.is_dir() and ((source / "zarr.json").is_file()
                                   or (source / ".zgroup").is_file()
                                   or source.suffix == ".zarr")
    if is_zarr:
        if material is not None:
            raise InputError(f"{source} is a Zarr group: its force maps come from "
                             "'tactilevision batch forces', not --E-mpa/--nu/--fit")
        frames, heights, pressure, mm_per_px, labels = _from_zarr(source, args,
                                                                  args.max_frames)
    else:
        frames, heights, pressure, mm_per_px, labels = _from_frames(source, args, material)
    path = write_viewer(out, frames, heights, mm_per_px=mm_per_px, pressure_kpa=pressure,
                        titles=labels, max_px=args.max_px)
    record_output(path)                 # a rerun may replace it without --overwrite
    size = path.stat().st_size / 1e6
    print(f"wrote {path} ({size:.1f} MB): {len(labels)} frame(s) of {source}"
          + (", with the force map" if pressure is not None else ""))
    return 0


def _from_frames(source: Path, args, material):
    """Frames of a folder, video or session, their height maps and (given E, nu and h) their
    pressure maps, at most --max-frames of them."""
    src = open_source(source, reference=args.reference)
    cal, _, _ = optics_calibration(args, src)
    if src.n_frames == 0:
        raise InputError(f"{source} holds no frames")
    reference = src.reference(cal.shape)
    recon = DepthReconstructor(cal, reference="calibration" if reference is None else reference)
    idx = _picks(src.n_frames, args.max_frames)
    frames = np.stack([src.frame(int(i), cal.shape) for i in idx])
    heights = np.stack([recon(f) for f in frames]).astype(np.float32)
    labels = [src.frame_name(int(i)) for i in idx]
    pressure = None
    if material is not None:
        E, nu, h = material
        est = ForceEstimator(cal.shape, cal.mm_per_px, thickness_mm=h, E_mpa=E, nu=nu,
                             contact="field")
        pressure = np.stack([np.asarray(est(z).pressure_kpa, np.float32) for z in heights])
    return frames, heights, pressure, cal.mm_per_px, labels
