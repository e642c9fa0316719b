"""The option groups several commands share (the frames' ``reconstruct``, ``forces``,
``view``, ``live``, ``batch``; a domed gel's ``fit`` and ``diagnose``): one definition and
one help text each. What they name (a calibration, E and nu) is read by
:mod:`tactilevision.cli._inputs`, imported only when a command runs."""

from __future__ import annotations

import argparse
from pathlib import Path

from .. import KNOWN_SENSORS, InputError

__all__ = ["add_contact_options", "add_dome_argument", "add_material_options",
           "add_optics_options", "binning_from_args"]

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


def add_contact_options(p: argparse.ArgumentParser, *, note: str = "") -> None:
    """``--contact {footprint,field}`` and ``--threshold-mm``: the forces' traction region,
    with one default wherever forces are mapped (``ForceEstimator``'s); `note` ends the
    ``--contact`` help."""
    p.add_argument("--contact", choices=("footprint", "field"), default="footprint",
                   help="traction only on the footprint, the pixels whose height exceeds "
                   "--threshold-mm, zero elsewhere (default), or the height map trusted "
                   "everywhere (every error beyond the contact then pushes or pulls)" + note)
    p.add_argument("--threshold-mm", type=float, default=0.02,
                   help="footprint: height above which a pixel is in contact (default 0.02)")
    p.add_argument("--binning", metavar="K", default="auto",
                   help="footprint (spectral): the contact-pinned heights and the "
                   "footprint's solve on K x K blocks of pixels; 'auto' (default) takes per "
                   "frame the largest K up to 8 with K pixels at most the footprint's width "
                   "over 20 (the contact region's over 40 for the heights); 1: every pixel")


def binning_from_args(text: str) -> int | str:
    """``--binning``'s value: 'auto' or a whole number (checked further by the estimator).

    Raises
    ------
    InputError
        For anything else, naming the option.
    """
    if text == "auto":
        return text
    try:
        return int(text)
    except ValueError:
        raise InputError(f"--binning must be 'auto' or a positive integer, got {text!r}"
                         ) from None


def add_dome_argument(g) -> None:
    """``--dome-radius-mm``: a domed gel's top (fit, diagnose)."""
    g.add_argument("--dome-radius-mm", type=float, metavar="RD",
                   help="a domed gel: its top's radius of curvature, mm, the depth counted "
                        "from the apex (default: session.toml [sensor] gel_dome_radius_mm, "
                        "else a flat top); needs the pad's radius; one FEM sweep per nu")
