"""``tactilevision forces``: frames -> height maps -> contact force maps and totals."""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path

from ._options import add_contact_options, add_material_options, add_optics_options
from ._out import add_overwrite_argument

__all__ = ["add_parser", "run"]


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Register the ``forces`` sub-command."""
    p = sub.add_parser(
        "forces",
        help="contact pressure maps (.npy, kPa) and total forces per frame (forces.csv; "
        "images with --images)",
        description="Photometric stereo on every frame, then the contact force distribution "
        "(tactilevision.fem.ForceEstimator): writes <frame>_pressure_kpa.npy (float32, kPa), "
        "with --images <frame>_force.png (pressure in kPa with a colour bar, arrows for the "
        "tangential part), and forces.csv (frame, t_s, fx_n, fy_n, "
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
    add_optics_options(p)
    add_material_options(p)
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
    add_contact_options(p)
    p.add_argument("--beta", type=float, default=None,
                   help="large-deformation stiffening of eq. (5), forces x (1 + beta w/h); "
                   "default: the fit JSON's beta, else 0")
    p.add_argument("--every", type=int, default=1, metavar="N", help="every N-th frame")
    p.add_argument("--images", action="store_true",
                   help="also write <frame>_force.png (the force map drawn): pictures are "
                   "opt-in, <frame>_pressure_kpa.npy and forces.csv are the output")
    p.add_argument("--no-images", action="store_true",
                   help="(the default now; kept so that older scripts run)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_overwrite_argument(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run ``forces``: :func:`~tactilevision.cli._forces_run.run`, imported only now (``--help``
    reads the options without the command's stack)."""
    return importlib.import_module("._forces_run", __package__).run(args)
