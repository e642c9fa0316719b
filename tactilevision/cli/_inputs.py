"""What the shared options name (:mod:`tactilevision.cli._options`): the photometric
calibration, E and nu, and eq. (5)'s beta a force map needs. Imported only when a command
runs, so that ``--help`` does not load the optics and the pipeline."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from .. import KNOWN_SENSORS, InputError, default_calibration_path
from ..io import FrameSource
from ..optics import PhotometricCalibration
from ..pipeline import read_material

__all__ = ["beta_from_args", "material_from_args", "optics_calibration"]


def optics_calibration(args: argparse.Namespace, source: FrameSource | None = None,
                       *, required: bool = True
                       ) -> tuple[PhotometricCalibration | None, Path | None, str]:
    """The photometric calibration the options (or the source) name.

    ``--calibration``, else ``--sensor``'s shipped one, else a session's
    ``[optics] calibration``, else the shipped one of the session's sensor.

    Returns
    -------
    calibration : PhotometricCalibration or None
        None when none is named and `required` is False.
    path : Path or None
    note : str
        Where it came from, for the run's summary.

    Raises
    ------
    InputError
        None named (when `required`), or a file that does not exist or is not
        a calibration (named).
    """
    path, note = None, ""
    if getattr(args, "calibration", None) is not None:
        path, note = Path(args.calibration), "--calibration"
    elif getattr(args, "sensor", None):
        path, note = default_calibration_path(args.sensor), f"shipped '{args.sensor}'"
    elif source is not None and source.session is not None:
        cfg = source.session.config
        if cfg.calibration is not None:
            path, note = Path(cfg.calibration), "the session's own"
        elif cfg.sensor_name in KNOWN_SENSORS:
            path = default_calibration_path(cfg.sensor_name)
            note = (f"shipped '{cfg.sensor_name}' (the session names no [optics] calibration "
                    "of its own)")
    if path is None:
        if required:
            raise InputError("no photometric calibration: give --calibration OPTICS or --sensor")
        return None, None, ""
    if not Path(path).is_file():
        raise InputError(f"calibration {path} does not exist")
    return PhotometricCalibration.load(path), Path(path), note


def material_from_args(args: argparse.Namespace, session_dir: Path | None
              ) -> tuple[float, float, str, dict]:
    """E, nu, where they came from, and the fit JSON object (empty without one): --E-mpa and
    --nu, else --fit, else a session's calibration/fit.json (`session_dir`)."""
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
    E, nu, obj = read_material(path)
    return E, nu, str(path), obj


def beta_from_args(args: argparse.Namespace, fit_obj: dict, material_source: str
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
