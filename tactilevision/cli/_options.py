"""The option groups the frame commands share (``reconstruct``, ``forces``, ``view``,
``live``, ``batch``): one definition and one help text each."""

from __future__ import annotations

import argparse
from pathlib import Path

from .. import KNOWN_SENSORS, InputError, default_calibration_path
from ..io import FrameSource
from ..optics import PhotometricCalibration

__all__ = ["add_material_options", "add_optics_options", "optics_calibration"]

_REFERENCE_HELP = ("no-contact frame (default: the session's own, else reference.png, ref.jpg, "
                   "gs_sdk's background.png or <video stem>_reference.png beside the frames, "
                   "else the calibration's own reference)")


def add_optics_options(p: argparse.ArgumentParser, *, required: bool = False,
                       reference: bool = True) -> None:
    """``--calibration OPTICS`` or ``--sensor NAME`` (one of them; `required` or not), and
    ``--reference REF`` unless `reference` is False."""
    src = p.add_mutually_exclusive_group(required=required)
    src.add_argument("--calibration", metavar="OPTICS", type=Path,
                     help="photometric calibration file (.npz from 'optics calibrate'); "
                     "a session's own by default")
    src.add_argument("--sensor", metavar="NAME", choices=KNOWN_SENSORS,
                     help=f"the shipped calibration of a sensor: {', '.join(KNOWN_SENSORS)}")
    if reference:
        p.add_argument("--reference", metavar="REF", type=Path, default=None,
                       help=_REFERENCE_HELP)


def add_material_options(p: argparse.ArgumentParser, *, fit: bool = True) -> None:
    """``--fit FIT.json`` (unless `fit` is False), ``--E-mpa``, ``--nu`` and
    ``--thickness-mm``: the gel a force map needs."""
    if fit:
        p.add_argument("--fit", metavar="FIT.json", type=Path, default=None,
                       help="E_mpa, nu (and beta) from a calibration folder or its fit.json "
                       "(calibrate, fit --json)")
    p.add_argument("--E-mpa", type=float, default=None, help="Young's modulus E, MPa")
    p.add_argument("--nu", type=float, default=None, help="Poisson's ratio nu")
    p.add_argument("--thickness-mm", type=float, default=None,
                   help="gel layer thickness h, mm (a session's own by default)")


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
