"""What ``tactilevision calibrate`` does once its options are parsed
(:mod:`tactilevision.cli._calibrate`): a session folder in, E and nu with a report out
(formats.md §3).

Imported only when the command runs, so that its ``--help`` does not load this stack.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
from tqdm import tqdm

from .. import InputError
from ..io import (
    check_output_folder,
    check_overwrite,
    read_dead_weights,
    read_measurements,
    read_session,
)
from ..pipeline import (
    BALL_CALIBRATION_FILES,
    CALIBRATION_FILES,
    calibrate_ball_session,
    calibrate_dead_weights,
    calibrate_session,
    write_ball_calibration,
    write_calibration,
)
from ._fit_indenter import summary_lines
from ._fit_run import _write_json, relaxation_lines, summary

__all__ = ["CALIBRATE_FILES", "run"]

#: The files ``calibrate`` writes into its output folder (figures and report unless
#: --no-report).
CALIBRATE_FILES = CALIBRATION_FILES


def run(args: argparse.Namespace) -> int:
    """Run ``calibrate``.

    Parameters
    ----------
    args : argparse.Namespace

    Returns
    -------
    status : int
        0 on success.

    Raises
    ------
    InputError
        For a broken session (nothing is written) or too few certified presses
        (rejected.csv, the certified presses' measurements.csv, the figures
        and report.html are written first, saying why).
    """
    if _dead_weights(args.session):
        return _run_dead_weights(args)
    session = read_session(args.session)
    out = args.out if args.out is not None else session.path / "calibration"
    check_output_folder(out)               # before the minute of work, not after
    ball = session.config.indenter_shape == "sphere"
    check_overwrite(out, BALL_CALIBRATION_FILES if ball else CALIBRATE_FILES,
                    overwrite=args.overwrite)
    progress = None
    if not args.no_progress:
        def progress(it):
            return tqdm(it, desc="frames", unit="frame", file=sys.stderr, mininterval=1.0)
    if ball:
        return _run_ball(session, out, args, progress)
    cal = calibrate_session(session, depth_rule=args.depth_rule, beta_table=args.beta_table,
                            progress=progress, allow_failure=True,
                            relaxation=args.relaxation, bevel_threshold=args.bevel_threshold,
                            ft_zero=args.ft_zero)
    # written whole into a hidden folder in out, moved into place at the end (or dropped)
    result = write_calibration(cal, out, overwrite=args.overwrite, report=not args.no_report)
    if cal.fit is None:
        # nothing to fit: what certification found is kept, and says why
        raise InputError(f"{cal.failure}; rejected.csv"
                         + ("" if args.no_report else ", the bevel panels and report.html")
                         + f" in {out} say why")
    _print_summary(cal, result, out, args)
    return 0


def _unused_options(args: argparse.Namespace) -> list[str]:
    """Warnings for the gauge-block options a ball's calibration does not use."""
    defaults = {"depth_rule": "auto", "beta_table": "fem", "relaxation": "auto",
                "bevel_threshold": "auto", "ft_zero": "auto"}
    return [f"--{k.replace('_', '-')} {getattr(args, k)} is a gauge block's option; a ball's "
            "calibration does not use it" for k, v in defaults.items()
            if getattr(args, k, v) != v]


def _dead_weights(folder: Path) -> bool:
    """A dead-weight folder: weights.csv and no F/T log."""
    return (folder / "weights.csv").is_file() and not (folder / "forces.csv").exists()


def _run_dead_weights(args: argparse.Namespace) -> int:
    """``calibrate`` of a dead-weight folder: P = m g, depths from the contact circles."""
    session = read_dead_weights(args.session)
    out = args.out if args.out is not None else session.path / "calibration"
    check_output_folder(out)
    check_overwrite(out, BALL_CALIBRATION_FILES, overwrite=args.overwrite)
    cal = calibrate_dead_weights(session, nu=args.nu, law=args.law)
    return _report_ball(cal, write_ball_calibration(cal, out, figure=not args.no_report,
                                                   overwrite=args.overwrite),
                        out, args)


def _run_ball(session, out: Path, args: argparse.Namespace, progress) -> int:
    """``calibrate`` of a ball's session: depths from the contact circles."""
    cal = calibrate_ball_session(session, nu=args.nu, law=args.law, progress=progress)
    return _report_ball(cal, write_ball_calibration(cal, out, figure=not args.no_report,
                                                   overwrite=args.overwrite),
                        out, args)


def _report_ball(cal, paths: dict, out: Path, args: argparse.Namespace) -> int:
    """The summary of a ball's calibration on standard output (and fit.json to --json)."""
    obj = json.loads(paths["fit.json"].read_text())
    if args.json is not None:
        _write_json(obj, args.json)
    if args.json != "-":
        table = read_measurements(paths["measurements.csv"])
        lines = summary_lines(cal.fit, {cal.law: cal.fit}, f"--law {cal.law}", table)
        d = cal.depths
        lines.insert(1, f"  depths from {len(cal.used)} contact circles through a(w): "
                        f"{1e3 * d.depth_mm.min():.1f} to {1e3 * d.depth_mm.max():.1f} um, "
                        f"random error median {1e3 * float(np.median(d.depth_std_mm)):.2f} um,"
                        f" shared up to {1e3 * float(d.depth_shared_mm.max()):.2f} um")
        lines.append(f"  {len(cal.used)} presses fitted, {len(cal.rejected)} rejected"
                     + "".join(f"\n    press {r.press}: {r.reason} ({r.detail})"
                               for r in cal.rejected))
        lines.append((f"  clock offset {cal.presses.clock_offset_s:.4f} s "
                      f"({cal.presses.clock_source}); " if cal.presses is not None else
                      "  dead weights: P = m g; ") + f"{cal.seconds:.1f} s")
        lines += [f"  warning: {w}" for w in cal.warnings + _unused_options(args)]
        lines.append(f"  wrote {', '.join(p.name for p in paths.values())} in {out}")
        print("\n".join(lines))
    return 0


def _print_summary(cal, result, out: Path, args: argparse.Namespace) -> None:
    """The run's summary on standard output (and fit.json to --json)."""
    obj = result.fit
    if args.json is not None:
        _write_json(obj, args.json)
    if args.json != "-":
        c = cal.certification
        print(summary(cal.fit, out / "measurements.csv"))
        if cal.relaxation is not None and cal.relaxation.resolved:
            print("\n".join(relaxation_lines(cal.relaxation, cal.moduli, out / "holds.csv",
                                              e_finite=bool(np.isfinite(cal.fit.E_mpa)))))
        n_in = int(cal.depth_certified.sum())
        tol = 1e3 * cal.session.config.depth_tolerance_mm
        read = (f"{len(c.presses)} presses certified," if n_in == len(c.presses) else
                f"{len(c.presses)} presses fitted: {n_in} certified within +-{tol:.0f} um, "
                f"{len(c.presses) - n_in} only bounded;")
        print(f"  {read} {len(c.rejected)} rejected"
              + "".join(f"\n    press {r.press}: {r.reason} ({r.detail})" for r in c.rejected))
        print(f"  clock offset {c.clock_offset_s:.4f} s ({c.clock_source}); depth rule "
              f"{cal.depth_rule}; {cal.seconds:.1f} s")
        if len(cal.depth_std_mm) and cal.depth_rule != "land":
            over = cal.depth_mm - np.array([q.w0_mm for q in c.presses])
            print(f"  certified depths: overshoot past w0 {1e3 * over.min():.1f} to "
                  f"{1e3 * over.max():.1f} um, standard uncertainty median "
                  f"{1e3 * float(np.median(cal.depth_std_mm)):.2f} um")
        for w in cal.warnings:
            print(f"  warning: {w}")
        n_held = len(np.unique(result.holds["press"]))
        print(f"  holds.csv: the force over the hold of {n_held} of {len(c.presses)} presses"
              + ("" if n_held == len(c.presses) else " (no release found in the log for the "
                 "others)"))
        if not args.no_report:
            print(f"  report: {out / 'report.html'}")
