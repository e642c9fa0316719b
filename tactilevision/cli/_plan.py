"""``tactilevision plan``: what a calibration session's design will measure, before it runs."""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path

__all__ = ["add_parser", "run"]

_DESCRIPTION = """\
Predict, from a design (a session.toml plus a [plan] table: repeats, E_mpa,
nu, frame_rate_hz, stage_speed_mm_s or approach_s (each press's depth reached
in that time), overshoot_um, force_noise_n,
force_zero_n, hold_s or holds_s, waits_s, days, positions or schedule (the
presses the robot will command: a presses.csv or [[indenter, x_mm, y_mm],
...]), depth_std_um), each press's depth uncertainty, the sds of E and nu that
'tactilevision fit' will give over sessions of this design, the biases its
shared errors leave, whether nu is identified at all, and the catalogue
effects 'diagnose' could not test on such a session, the smallest size of each
it names in 95 % of sessions ([plan.detect] effect = size: how often it names
that size), and whether fit_relaxation identifies a planned relaxation.
Nothing is drawn for E and nu: the fit is differentiated on the design's
noise-free table and its E and nu integrated over the predicted spread of eq.
(5)'s line. --from-calibration plans a repeat of a session 'calibrate' ran
(its presses.csv as the schedule). Exit status 2 on a bad design, with one
sentence naming the key."""


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Register the ``plan`` sub-command."""
    p = sub.add_parser("plan", help="predict what a calibration session's design will measure",
                       description=_DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("design", metavar="DESIGN.toml", type=Path, nargs="?",
                   help="the design file (or --from-calibration)")
    p.add_argument("--from-calibration", metavar="DIR", type=Path,
                   help="plan from the session a 'calibrate' folder ran: its h, a, depths, "
                        "repeats, fitted E and nu, overshoots, F/T noise and zero drift (and "
                        "the session folder's scale, bevel, window and frame rate)")
    p.add_argument("--session", metavar="DIR", type=Path,
                   help="with --from-calibration: the session folder (default: the one "
                        "fit.json names)")
    p.add_argument("--write-design", metavar="FILE", type=Path,
                   help="also write the design as a design file (to edit and plan again)")
    p.add_argument("--recommend", action="store_true",
                   help="also rank the changes of the design by predicted gain (each planned "
                        "again: a few seconds)")
    p.add_argument("--target-E-pct", type=float, metavar="PCT",
                   help="find the cheapest design whose total error of E (random and "
                        "systematic, %% of E) is at most PCT (implies --recommend)")
    p.add_argument("--target-nu", type=float, metavar="ERR",
                   help="... and whose total error of nu is at most ERR (implies --recommend)")
    p.add_argument("--write-recommended", metavar="FILE", type=Path,
                   help="write the cheapest design meeting the targets as a design file")
    p.add_argument("--json", metavar="FILE", help="write the prediction as JSON ('-': stdout)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace --json, --write-design and --write-recommended even when "
                   "tactilevision did not write them")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run ``plan``: :func:`~tactilevision.cli._plan_run.run`, imported only now (``--help`` reads
    the options without the command's stack)."""
    return importlib.import_module("._plan_run", __package__).run(args)
