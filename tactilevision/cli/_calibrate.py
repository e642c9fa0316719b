"""``tactilevision calibrate``: a session folder in, E and nu with a report out (formats.md §3)."""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path

from ._out import add_overwrite_argument

__all__ = ["add_parser", "run"]

_DESCRIPTION = """\
The main job. Reads a session folder (session.toml, reference.png, frames/,
frames.csv, forces.csv, optional presses.csv; formats.md section 1), finds
every press in the frames, synchronises the F/T clock, certifies each press
(footprint circle of radius a, indenter, first frame where the bevel shows,
window_samples F/T samples from that instant, |Fxy| << Fz), lists the
rejected presses with their reasons, fits E and nu (eq. 5 with the FEM beta
and kappa tables) and writes a report folder: measurements.csv, fit.json,
rejected.csv, figures and report.html. Exit status 2 on bad input.

A ball ([indenter] shape = "sphere", no [gauge_block]): each press's depth is
read from the ball's contact circle through the sphere's a(w) at --nu and
--law, its force from the F/T log over the hold; E (nu where the presses
identify it) is fitted by the sphere's force law and the folder holds
measurements.csv with its sidecar session.toml, circles.csv, rejected.csv and
fit.json (docs/guide/ball.md). A folder with weights.csv (frame,mass_kg[,
mass_std_kg]) and no forces.csv holds dead weights: one frame of the ball at
rest under each mass, P = m g."""


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Register the ``calibrate`` sub-command.

    Parameters
    ----------
    sub : argparse._SubParsersAction
    """
    p = sub.add_parser("calibrate", help="session of frames and forces -> certified presses, "
                       "E, nu, report", description=_DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("session", metavar="SESSION_DIR", type=Path)
    p.add_argument("--out", type=Path, metavar="DIR",
                   help="report folder (default: SESSION_DIR/calibration)")
    p.add_argument("--json", metavar="FILE",
                   help="write the fit.json object to FILE too ('-' for standard output)")
    p.add_argument("--depth-rule", choices=("auto", "vernier", "mark", "nominal", "land"),
                   default="auto",
                   help="certified depth: 'vernier' (w0 plus the overshoot read on a machined "
                        "bevel, less the gel's bulge there; the default when [gauge_block] "
                        "bevel_angle_deg > 0), 'mark' (w0 plus the depth past it that the "
                        "force reads from the frame before the mark first shows to the force "
                        "window; the default for a bevel mark), 'nominal' (the paper's w = w0; "
                        "for a mark, the overshoot it leaves out widens E's and nu's "
                        "intervals), or 'land' (where the bulging gel meets a flat block land; "
                        "FEM at the fitted nu; ill-conditioned)")
    p.add_argument("--beta-table", choices=("fem", "paper"), default="fem")
    add_overwrite_argument(p)
    p.add_argument("--relaxation", choices=("auto", "off"), default="auto",
                   help="auto (default): fit a standard linear solid to the force over each "
                        "hold; for a gel seen to relax, synchronise the clock on the elastic "
                        "force and report E as the instantaneous E_0 with the relaxed E_inf "
                        "beside it. off: the forces as measured")
    p.add_argument("--bevel-threshold", type=_threshold, default="auto", metavar="SNR|auto",
                   help="for a bevel mark (bevel_angle_deg = 0): when the mark is seen. auto "
                        "(default): from the session's own frames (a frame 2.5 sd of the "
                        "no-contact frames' score noise above its press's approach, the next 3 "
                        "averaging with it 2 sd above); a number: the fixed rule, two "
                        "consecutive frames above it or one above twice it (rejected.csv gives "
                        "each press's best)")
    p.add_argument("--ft-zero", choices=("auto", "constant", "drift", "off"), default="auto",
                   help="the F/T's zero, read between the presses once each release has "
                        "settled: constant takes its mean off fz (a sensor tared before the "
                        "gauge block was mounted reads the block's weight); drift takes off its "
                        "line over the session at each sample; auto (default): drift when the "
                        "zero is seen to drift, else constant; off keeps the forces as the F/T "
                        "read them. fit.json's ft_zero reports it either way")
    b = p.add_argument_group("a ball session ([indenter] shape = \"sphere\")")
    b.add_argument("--nu", type=float, default=0.5,
                   help="nu of the ball's a(w), and E's nu when the presses do not identify "
                        "it (default 0.5)")
    b.add_argument("--law", choices=("neo_hookean", "linear"), default="neo_hookean",
                   help="the sphere's force law and a(w): finite strain (default) or small "
                        "strain")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--no-report", action="store_true",
                   help="write measurements.csv, fit.json and rejected.csv only")
    p.set_defaults(func=run)


def _threshold(text: str) -> float | str:
    """``--bevel-threshold``: 'auto' or a number (checked by calibrate_session)."""
    if text == "auto":
        return text
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number or 'auto', got {text!r}") from None


def run(args: argparse.Namespace) -> int:
    """Run ``calibrate``: :func:`~tactilevision.cli._calibrate_run.run`, imported only now
    (``--help`` reads the options without the command's stack)."""
    return importlib.import_module("._calibrate_run", __package__).run(args)
