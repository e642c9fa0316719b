"""``tactilevision optics calibrate``: ball presses -> photometric calibration file."""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path

from ._out import add_overwrite_argument

__all__ = ["add_parser", "run_calibrate"]


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Register ``optics`` and its ``calibrate`` sub-command."""
    p = sub.add_parser("optics", help="photometric calibration of a sensor",
                       description="Photometric calibration: colour -> surface normal.")
    osub = p.add_subparsers(dest="optics_command", metavar="SUBCOMMAND", required=True)
    c = osub.add_parser(
        "calibrate",
        help="calibrate colour -> normal from ball presses",
        description="Fit a photometric calibration from frames of a ball pressed into the gel. "
        "BALL_PRESSES is a folder (reference.png or ref.jpg, the press frames, optionally "
        "circles.csv with frame,x_px,y_px,radius_px) or an .npz (reference, frames[, "
        "centers_px, radii_px], or taxim's dataPack.npz; 'taxim:gelsight' names the one "
        "inside the installed taxim package), or a gs_sdk calibration folder "
        "(background.png, catalog.csv with each press's ball diameter, "
        "<diameter>mm/<i>/gelsight.png and label.npz circles; several ball sizes in one "
        "calibration). A supplied circle is the contact circle: its radius is where the "
        "ball leaves the gel, not the visible colour edge, which lies a little outside it. "
        "Circles are detected when not given: at the contact edge (the shoulder where the "
        "colour change stops growing, see --detect-edge). Pixels within --label-fraction "
        "of the radius are trained on. The accuracy report (printed, and saved as "
        "<name>_accuracy.json beside the calibration) never scores a press the scoring "
        "calibration was trained on: by default one press in four (--holdout), spread over "
        "the pad and the ball sizes, is held out, a calibration trained on the rest is "
        "scored on them, and the calibration saved is then trained on every press. "
        "--presses trains on the presses it names and scores the rest; --holdout 0 scores "
        "the training presses, and the report says it is in sample.",
    )
    c.add_argument("ball_presses", metavar="BALL_PRESSES", type=Path,
                   help="folder, .npz, or taxim:gelsight")
    c.add_argument("--ball-radius-mm", type=float, default=None,
                   help="ball radius R (mm); needed unless BALL_PRESSES is a gs_sdk folder, "
                   "whose catalog.csv gives each press's ball diameter")
    c.add_argument("--mm-per-px", type=float, required=True, help="image scale (mm per px)")
    c.add_argument("--model", choices=("auto", "lut", "mlp"), default="auto",
                   help="the engine: 'auto' (default) cross-validates the colour table and "
                   "the table with position cells over the training presses, trains the "
                   "position-aware network (8 presses or more, the torch extra) on the first "
                   "fold, scores each on presses it was not trained on (normal angle inside "
                   "0.8 of the radius, inner cap) and keeps the best; 'lut' (binned colour "
                   "table, with --lut-cells) or 'mlp' (the network) forces one")
    c.add_argument("--out", metavar="OPTICS", type=Path, required=True,
                   help="calibration file to write (.npz)")
    c.add_argument("--presses", metavar="SEL", default=None,
                   help="presses to calibrate on: slice '0::2' or list '0,2,4' (default all); "
                   "the others are scored")
    c.add_argument("--holdout", metavar="SHARE", type=float, default=0.25,
                   help="without --presses: the share of the presses held out for the "
                   "accuracy report, spread over the pad and the ball sizes, 0 <= SHARE < 1 "
                   "(default 0.25); the calibration saved is trained on every press. 0: the "
                   "training presses are scored (in sample, and said so)")
    c.add_argument("--epochs", type=int, default=30, help="MLP training epochs (default 30)")
    c.add_argument("--hidden", type=int, default=128,
                   help="MLP units per hidden layer (default 128)")
    c.add_argument("--bins", type=int, default=32, help="LUT cells per channel (default 32)")
    c.add_argument("--lut-cells", metavar="NX,NY", default="1,1",
                   help="LUT: position cells along x and y, one colour table each, for a pad "
                   "lit unevenly (default 1,1: colour only; e.g. 8,6 with presses that reach "
                   "the image's edges)")
    c.add_argument("--detect-circles", action="store_true",
                   help="ignore given circles and detect them")
    c.add_argument("--detect-edge", choices=("contact", "colour"), default="contact",
                   help="detected circles: at the contact edge, where the colour change "
                   "levels off before it falls (default), or at the colour edge, its "
                   "steepest fall, outside the contact (then trained to 0.85 of it)")
    c.add_argument("--label-fraction", metavar="F", type=float, default=None,
                   help="train on the pixels within F x the circle's radius, 0 < F <= 1 "
                   "(default 1.0; 0.85 with --detect-edge colour; lower it for circles "
                   "drawn on the colour edge)")
    c.add_argument("--flat-fraction", metavar="F", type=float, default=0.03,
                   help="fraction of each press's pixels beyond twice the contact radius "
                   "trained on as flat gel, 0 < F <= 1 (default 0.03). Lower: gentle slopes "
                   "read less shallow, the flat gel's colour noise passes into the gradients "
                   "(docs: guide/optics.md, 'Flat samples')")
    c.add_argument("--no-progress", action="store_true", help="no progress bar")
    c.add_argument("--seed", type=int, default=0)
    add_overwrite_argument(c, "folder of the calibration file")
    c.add_argument("--credit", default=None,
                   help="attribution of the frames, stored with the calibration and printed on "
                   "depth images")
    c.set_defaults(func=run_calibrate)


def run_calibrate(args: argparse.Namespace) -> int:
    """Run ``optics calibrate``: :func:`~tactilevision.cli._optics_run.run_calibrate`, imported
    only now (``--help`` reads the options without the command's stack)."""
    return importlib.import_module("._optics_run", __package__).run_calibrate(args)
