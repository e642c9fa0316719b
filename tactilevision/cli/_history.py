"""``tactilevision history``: calibration folders in, each gel's history over days out."""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path

from ._out import add_overwrite_argument

__all__ = ["add_parser", "run"]

_DESCRIPTION = """\
Reads the output folders of tactilevision calibrate (fit.json, rejected.csv;
formats.md section 3), from any days and sensors, and gives one history per
sensor: date, E, nu, c, beta with their 95% intervals, certified and rejected
presses, clock offset; the trend of E over days (weighted least squares, each
calibration weighted by its interval); and whether E has left the first
calibration's interval ("recalibrate", with the date from which a session
using the first E used a stale one). The date of each calibration is
fit.json's session_date ([session] date of the session.toml), else --date.
With --report DIR: history_<sensor>.csv, E_<sensor>.png, nu_<sensor>.png and
report.html. Exit status 2 on bad input."""


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Register the ``history`` sub-command.

    Parameters
    ----------
    sub : argparse._SubParsersAction
    """
    p = sub.add_parser("history", help="calibration folders over days -> each gel's E and nu "
                       "history, trend, recalibrate or not", description=_DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("folders", metavar="CALIBRATION_DIR", type=Path, nargs="+",
                   help="output folders of tactilevision calibrate")
    p.add_argument("--sensor", metavar="NAME",
                   help="only the calibrations of this sensor ([sensor] name)")
    p.add_argument("--report", type=Path, metavar="DIR",
                   help="write history_<sensor>.csv, E_<sensor>.png, nu_<sensor>.png and "
                        "report.html into DIR")
    p.add_argument("--json", metavar="FILE",
                   help="write the result as JSON to FILE ('-' for standard output)")
    p.add_argument("--date", action="append", default=[], metavar="FOLDER=YYYY-MM-DD",
                   help="the date of a calibration folder whose fit.json has no session_date "
                        "(repeatable)")
    p.add_argument("--no-pooled", action="store_true",
                   help="skip the pooled diagnosis (every press of a sensor's calibrations "
                        "diagnosed along the day: aging or a step; seconds per sensor)")
    add_overwrite_argument(p, "report folder")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run ``history``: :func:`~tactilevision.cli._history_run.run`, imported only now (``--help``
    reads the options without the command's stack)."""
    return importlib.import_module("._history_run", __package__).run(args)
