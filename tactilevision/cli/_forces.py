"""``tactilevision forces``: frames -> height maps -> contact force maps and totals."""

from __future__ import annotations

import argparse
import csv
import json
import sys
from pathlib import Path

import numpy as np

from .. import KNOWN_SENSORS, InputError, default_calibration_path
from ._out import StagedOutput, add_overwrite_argument, check_output_folder, check_overwrite

__all__ = ["add_parser", "run"]

_COLUMNS = ["frame", "t_s", "fx_n", "fy_n", "fz_n", "max_pressure_kpa", "contact_area_mm2",
            "ft_fz_n"]


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Register the ``forces`` sub-command."""
    p = sub.add_parser(
        "forces",
        help="contact force maps (images, kPa) and total forces per frame (forces.csv)",
        description="Photometric stereo on every frame, then the contact force distribution "
        "(tactilevision.fem.ForceEstimator): writes <frame>_force.png (pressure in kPa with a "
        "colour bar, arrows for the tangential part) and forces.csv (frame, t_s, fx_n, fy_n, "
        "fz_n, max_pressure_kpa, contact_area_mm2, and for a session ft_fz_n, the F/T "
        "sensor's fz at the frame's time). E and nu come from --E-mpa/--nu, --fit FIT.json, "
        "or a session's calibration/fit.json.",
    )
    p.add_argument("source", metavar="SESSION_DIR|FRAMES_DIR|VIDEO", type=Path,
                   help="a session folder (session.toml), a folder of frames, or a video "
                   "file (frames named <stem>_<index>, t_s from its frame rate)")
    p.add_argument("--out", metavar="DIR", type=Path, default=None,
                   help="output folder (default: SOURCE/forces; for a video <stem>_forces "
                   "beside it)")
    src = p.add_mutually_exclusive_group()
    src.add_argument("--calibration", metavar="OPTICS", type=Path,
                     help="photometric calibration (.npz); a session's own by default")
    src.add_argument("--sensor", metavar="NAME", choices=KNOWN_SENSORS,
                     help=f"shipped calibration: {', '.join(KNOWN_SENSORS)}")
    p.add_argument("--reference", metavar="REF", type=Path, default=None,
                   help="no-contact frame of a frames folder (default: found beside it)")
    p.add_argument("--fit", metavar="FIT.json", type=Path, default=None,
                   help="E_mpa and nu from a fit/calibrate JSON")
    p.add_argument("--E-mpa", type=float, default=None, help="Young's modulus, MPa")
    p.add_argument("--nu", type=float, default=None, help="Poisson's ratio")
    p.add_argument("--thickness-mm", type=float, default=None,
                   help="gel thickness h, mm (a session's own by default)")
    p.add_argument("--method", choices=("spectral", "fem"), default="spectral",
                   help="spectral layer model at full resolution (default) or inverse FEM")
    p.add_argument("--grid", metavar="NX,NY", default="40,30",
                   help="FEM surface nodes along x and y (default 40,30)")
    p.add_argument("--level", choices=("contact", "far_field", "median"), default="contact",
                   help="the height's zero: pinned outside the contact region, heights "
                   "integrated over the contact only (default; DepthReconstructor(boundary="
                   "'contact')), a surface fitted to the gel outside the contact, or the "
                   "frame's median (DepthReconstructor's default)")
    p.add_argument("--flat-reference", action="store_true",
                   help="subtract the optics model's gradient on the reference (right for "
                   "simulated frames; on real GelSight frames it adds background)")
    p.add_argument("--contact", choices=("footprint", "field"), default="footprint",
                   help="traction only on the footprint, the pixels whose height exceeds "
                   "--threshold-mm, zero elsewhere (default), or the height map trusted "
                   "everywhere (every error beyond the contact then pushes or pulls)")
    p.add_argument("--threshold-mm", type=float, default=0.02,
                   help="footprint: height above which a pixel is in contact (default 0.02)")
    p.add_argument("--beta", type=float, default=None,
                   help="large-deformation stiffening of eq. (5), forces x (1 + beta w/h); "
                   "default: the fit JSON's beta, else 0")
    p.add_argument("--every", type=int, default=1, metavar="N", help="every N-th frame")
    p.add_argument("--no-images", action="store_true", help="write forces.csv only")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_overwrite_argument(p)
    p.set_defaults(func=run)


def _material(args: argparse.Namespace, session_dir: Path | None
              ) -> tuple[float, float, str, dict]:
    """E, nu, where they came from, and the fit JSON object (empty without one)."""
    if args.E_mpa is not None or args.nu is not None:
        if args.E_mpa is None or args.nu is None:
            raise InputError("give both --E-mpa and --nu (or --fit FIT.json)")
        return float(args.E_mpa), float(args.nu), "command line", {}
    path = args.fit
    if path is None and session_dir is not None:
        path = session_dir / "calibration" / "fit.json"
        if not path.is_file():
            raise InputError(f"no E and nu: {path} does not exist (run 'tactilevision "
                             "calibrate' first) and neither --E-mpa/--nu nor --fit was given")
    if path is None:
        raise InputError("no E and nu: give --E-mpa and --nu, or --fit FIT.json")
    try:
        obj = json.loads(Path(path).read_text())
        E, nu = float(obj["E_mpa"]), float(obj["nu"])
    except FileNotFoundError:
        raise InputError(f"{path} does not exist") from None
    except (json.JSONDecodeError, KeyError, TypeError, ValueError) as exc:
        raise InputError(f"{path} has no numeric E_mpa and nu ({exc})") from None
    if not (np.isfinite(E) and np.isfinite(nu)):
        raise InputError(f"{path} has E_mpa = {E} and nu = {nu}: not a usable fit")
    return E, nu, str(path), obj


def _beta(args: argparse.Namespace, fit_obj: dict, material_source: str
          ) -> tuple[float, str]:
    """Eq. (5)'s beta and where it came from: --beta, the fit JSON's, else 0."""
    if args.beta is not None:
        if not (np.isfinite(args.beta) and args.beta >= 0):
            raise InputError(f"--beta must be finite and >= 0, got {args.beta}")
        return float(args.beta), "command line"
    value = fit_obj.get("beta")
    if value is None:
        return 0.0, "default (no fit JSON with a beta: linear layer)"
    try:
        beta = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{material_source} has a beta of {value!r}, not a number") from None
    if not (np.isfinite(beta) and beta >= 0):
        raise InputError(f"{material_source} has beta = {beta}: give --beta")
    return beta, material_source


def run(args: argparse.Namespace) -> int:
    """Run ``forces``; returns 0, or 2 on bad input (nothing written then)."""
    from ..fem import ForceEstimator
    from ..io import (
        VideoFrames,
        find_reference,
        find_video_reference,
        is_video,
        list_frames,
        read_frame,
        read_reference,
        read_session,
    )
    from ..optics import DepthReconstructor, PhotometricCalibration
    from ..viz import save_force_image
    from ._reconstruct import _checked, _VideoFrame

    source: Path = args.source
    video = VideoFrames(source) if source.is_file() and is_video(source) else None
    if video is None and not source.is_dir():
        raise InputError(f"{source} is not a folder nor a video file")
    default_out = (source.with_name(f"{source.stem}_forces") if video is not None
                   else source / "forces")
    check_output_folder(args.out if args.out is not None else default_out)
    overwrite = args.overwrite
    session = None
    if video is None and (source / "session.toml").is_file():
        session = read_session(source)
        frames = list(session.frame_paths)
        times = np.asarray(session.frame_times_s, np.float64)
        cfg = session.config
        h = args.thickness_mm if args.thickness_mm is not None else cfg.gel_thickness_mm
        cal_path = args.calibration or (default_calibration_path(args.sensor) if args.sensor
                                        else cfg.calibration)
        optics_note = ("--calibration" if args.calibration else
                       f"shipped '{args.sensor}'" if args.sensor else "the session's own")
        if cal_path is None and cfg.sensor_name in KNOWN_SENSORS:
            cal_path = default_calibration_path(cfg.sensor_name)
            optics_note = (f"shipped '{cfg.sensor_name}' (the session names no [optics] "
                           "calibration of its own)")
        reference = session.reference
        mm_per_px = cfg.mm_per_px
    else:
        if video is not None:
            frames = [_VideoFrame(source, i) for i in range(video.n_frames)]
            times = np.arange(video.n_frames) / video.fps
        else:
            frames = list_frames(source)
            times = np.full(len(frames), np.nan)
        cal_path = args.calibration or (default_calibration_path(args.sensor) if args.sensor
                                        else None)
        optics_note = "--calibration" if args.calibration else f"shipped '{args.sensor}'"
        if args.thickness_mm is None:
            raise InputError("a frames folder or video needs --thickness-mm (the gel "
                             "thickness h)")
        h = args.thickness_mm
        reference = None
        mm_per_px = None
    if cal_path is None:
        raise InputError("no photometric calibration: give --calibration OPTICS or --sensor")
    cal = PhotometricCalibration.load(cal_path)
    if session is None:
        ref_path = args.reference or (find_video_reference(source) if video is not None
                                      else find_reference(source))
        if args.reference is not None and not args.reference.is_file():
            raise InputError(f"reference {args.reference} does not exist")
        reference = read_reference(ref_path, cal.shape) if ref_path else None
        mm_per_px = cal.mm_per_px
    if not frames:
        raise InputError(f"{source} holds no frames")
    if args.every < 1:
        raise InputError(f"--every must be >= 1, got {args.every}")
    names = ["forces.csv"] + ([] if args.no_images else
                              [f"{frames[i].stem}_force.png"
                               for i in range(0, len(frames), args.every)])
    check_overwrite(args.out if args.out is not None else default_out, names,
                    overwrite=overwrite)
    E, nu, material_source, fit_obj = _material(args, source if session else None)
    beta, beta_source = _beta(args, fit_obj, material_source)
    try:
        grid = tuple(int(v) for v in args.grid.split(","))
    except ValueError:
        raise InputError(f"--grid must be NX,NY, got {args.grid!r}") from None
    recon = DepthReconstructor(
        cal, reference="calibration" if reference is None else reference,
        boundary="contact" if args.level == "contact" else "neumann",
        level="median" if args.level == "contact" else args.level,
        flat_reference=args.flat_reference)
    est = ForceEstimator(cal.shape, mm_per_px, thickness_mm=h, E_mpa=E, nu=nu, grid=grid,
                         method=args.method, contact=args.contact,
                         threshold_mm=args.threshold_mm, beta=beta)
    out = args.out if args.out is not None else default_out
    ft = None
    ft_note = ""
    if session is not None and session.forces_n.size:
        # the clock offset: the session's, else the one calibrate estimated; unknown, the F/T
        # column stays empty rather than misaligned
        offset = session.config.clock_offset_s
        if offset is None:
            offset = fit_obj.get("clock_offset_s")
        if offset is None:
            ft_note = ("; ft_fz_n left empty: the clock offset between frames and F/T log is "
                       "unknown (no [force_sensor] clock_offset_s, no fit.json from calibrate)")
        else:
            ft = (session.force_times_s - float(offset), session.forces_n[:, 2])
    # written whole into a hidden folder in out, moved into place at the end (Ctrl-C:
    # nothing)
    with StagedOutput(out, overwrite=overwrite) as stage:
        tmp = stage.path
        credit = cal.provenance.get("credit")
        picks = list(range(0, len(frames), args.every))
        it = picks
        if not args.no_progress:
            from tqdm.auto import tqdm

            it = tqdm(picks, desc="forces", unit="frame", file=sys.stderr, mininterval=1.0)
        rows, skipped, at_edge = [], [], []
        decoded = video.iter(0, video.n_frames) if video is not None else None
        at = 0                        # the next frame the video decoder gives
        for i in it:
            path = frames[i]
            try:
                if decoded is None:
                    frame = read_frame(path, cal.shape)
                else:                 # decoded in order: skip to frame i
                    while at <= i:
                        frame, at = next(decoded), at + 1
                    frame = _checked(frame, cal.shape, path.name)
            except InputError as exc:
                skipped.append(str(exc))
                continue
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
                    at_edge.append(path.name)     # the force beyond the image is not seen
            t = float(times[i])
            row = {"frame": path.name, "t_s": "" if not np.isfinite(t) else f"{t:.4f}",
                   "fx_n": f"{fm.total_n[0]:.5f}", "fy_n": f"{fm.total_n[1]:.5f}",
                   "fz_n": f"{fm.total_n[2]:.5f}",
                   "max_pressure_kpa": f"{float(fm.pressure_kpa.max()):.3f}",
                   "contact_area_mm2": f"{area:.3f}",
                   "ft_fz_n": ""}
            if ft is not None and np.isfinite(t):
                row["ft_fz_n"] = f"{float(np.interp(t, ft[0], ft[1])):.5f}"
            rows.append(row)
            if not args.no_images:
                save_force_image(tmp / f"{path.stem}_force.png", fm, mm_per_px=mm_per_px,
                                 frame=frame, title=path.name, credit=credit)
        with (tmp / "forces.csv").open("w", newline="") as fh:
            writer = csv.DictWriter(fh, fieldnames=_COLUMNS)
            writer.writeheader()
            writer.writerows(rows)
        stage.commit()
    level = {"contact": "zero outside the contact region",
             "far_field": "levelled at the far field", "median": "the frame's median at zero"}
    contact = (f"footprint above {args.threshold_mm:g} mm" if args.contact == "footprint"
               else "field")
    print(f"force maps of {len(rows)} frame(s) from {source} into {out}{ft_note}\n"
          f"  optics: {cal_path} ({optics_note})\n"
          f"  heights: {level[args.level]}"
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
