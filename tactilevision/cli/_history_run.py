"""What ``tactilevision history`` does once its options are parsed
(:mod:`tactilevision.cli._history`): calibration folders in, each gel's history over days
out.

Imported only when the command runs, so that its ``--help`` does not load this stack.
"""

from __future__ import annotations

import argparse
import datetime
import math
from pathlib import Path

from .. import InputError
from ..history import (
    assess,
    gather,
    history_figures,
    history_rows,
    pooled_diagnosis,
    sensor_file_name,
    write_history_csv,
    write_history_report,
)
from ..io import StagedOutput, check_output_folder, check_overwrite
from ._fit_run import _write_json

__all__ = ["parse_dates", "run", "sensor_dict"]


def parse_dates(items: list[str]) -> dict[Path, datetime.date]:
    """``--date FOLDER=YYYY-MM-DD`` arguments as a mapping.

    Parameters
    ----------
    items : list of str

    Returns
    -------
    dates : dict of Path to datetime.date

    Raises
    ------
    InputError
        For an item without ``=`` or with a date that is not YYYY-MM-DD.
    """
    out = {}
    for item in items:
        folder, sep, text = item.rpartition("=")
        if not sep or not folder:
            raise InputError(f"--date {item!r}: give FOLDER=YYYY-MM-DD")
        try:
            out[Path(folder)] = datetime.date.fromisoformat(text.strip())
        except ValueError:
            raise InputError(f"--date {item!r}: {text!r} is not a date YYYY-MM-DD") from None
    return out


def _clean(v):
    if isinstance(v, float):
        return v if math.isfinite(v) else None
    if isinstance(v, tuple | list):
        return [_clean(x) for x in v]
    return v


def sensor_dict(records, assessment, rows, csv_name: str | None) -> dict:
    """The JSON object of one sensor's history (formats.md, "Calibration history").

    Parameters
    ----------
    records : list of CalibrationRecord
    assessment : Assessment
    rows : list of dict
        :func:`~tactilevision.history.history_rows`.
    csv_name : str or None
        The CSV written for it, if any.

    Returns
    -------
    obj : dict
    """
    a = assessment
    tr = a.trend
    trend = None
    if tr is not None:
        trend = _clean({
            "method": "weighted least squares of E against days, weights 1/E_se^2",
            "intercept_mpa": tr.intercept, "slope_mpa_per_day": tr.slope,
            "slope_ci_mpa_per_day": list(tr.slope_ci()), "rate_per_day": a.rate_per_day,
            "rate_ci_per_day": list(a.rate_ci_per_day), "chi2": tr.chi2, "dof": tr.dof,
            "scaled": tr.scaled})
    return {
        "sensor": a.sensor, "n_calibrations": len(records),
        "first_date": records[0].date.isoformat(), "last_date": records[-1].date.isoformat(),
        "calibrations": rows,
        "E_change": _clean(a.change), "E_change_ci": _clean(list(a.change_ci)),
        "recalibrate": a.recalibrate,
        "stale_from": a.stale_from.isoformat() if a.stale_from is not None else None,
        "trend": trend, "nu_beyond": a.nu_beyond, "message": a.message, "csv": csv_name,
    }


def _print(records, a) -> None:
    head = a.message.split("\n")[0]
    print(head if len(records) == 1 else f"{head}, {records[0].date} to {records[-1].date}")
    print(f"  {'date':10} {'day':>4}  {'E MPa [95% CI]':27} {'nu [95% CI]':22} presses "
          "rejected clock_s")
    for r, d, b in zip(records, a.days, a.beyond, strict=True):
        clock = f"{r.clock_offset_s:.4f}" if math.isfinite(r.clock_offset_s) else "-"
        E = f"{r.E_mpa:.4f} [{r.E_ci95_mpa[0]:.4f}, {r.E_ci95_mpa[1]:.4f}]" + ("*" if b else "")
        nu = f"{r.nu:.3f} [{r.nu_ci95[0]:.3f}, {r.nu_ci95[1]:.3f}]"
        print(f"  {r.date.isoformat():10} {int(d):>4}  {E:27} {nu:22} {r.n_presses:>7} "
              f"{r.n_rejected:>8} {clock:>7}")
    for line in a.message.split("\n")[1:]:
        print(f"  {line.strip()}")


def run(args: argparse.Namespace) -> int:
    """Run ``history``.

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
        Naming the folder, file or key at fault: a folder without fit.json,
        a fit.json without E (or its interval), a calibration without a date
        (add ``[session] date`` or pass ``--date FOLDER=YYYY-MM-DD``), a
        ``--sensor`` no folder has, or a report folder that cannot be written.
        Every input is read before anything is written.
    """
    if args.report is not None:
        check_output_folder(args.report, "report folder")
    by_sensor = gather(args.folders, dates=parse_dates(args.date))
    if args.sensor is not None:
        if args.sensor not in by_sensor:
            raise InputError(f"--sensor {args.sensor}: no calibration of that sensor among the "
                             f"folders (sensors: {', '.join(sorted(by_sensor))})")
        by_sensor = {args.sensor: by_sensor[args.sensor]}
    results, pooled = {}, {}
    for sensor, records in by_sensor.items():
        a = assess(records)
        results[sensor] = (records, a, history_rows(records, a.beyond))
    names = {s: sensor_file_name(s) for s in results}
    if len(set(names.values())) < len(names):
        raise InputError("two sensor names give the same file name "
                         f"({', '.join(sorted(names))}); filter with --sensor")
    if args.report is not None:                # refused at once, before the slow part
        stems = [names[s][len("history_"):-len(".csv")] for s in names]
        files = (["report.html"] + list(names.values()) + [f"E_{t}.png" for t in stems]
                 + [f"nu_{t}.png" for t in stems])
        check_overwrite(args.report, files, overwrite=args.overwrite)
    for sensor, (records, _, _) in results.items():
        if not args.no_pooled and len({r.date for r in records}) >= 2:
            try:
                pooled[sensor] = pooled_diagnosis(records)
            except InputError as exc:          # the weighted line stands without it
                pooled[sensor] = str(exc)
    if args.report is not None:
        with StagedOutput(args.report, overwrite=args.overwrite, what="report folder") as stage:
            pages = {}
            for s, (records, a, rows) in results.items():
                write_history_csv(stage.path / names[s], rows)
                figs = history_figures(records, a, stage.path)
                pages[s] = (records, a, rows, figs)
            write_history_report(stage.path, pages, pooled={
                s: p.summary() if not isinstance(p, str) else f"No pooled diagnosis: {p}"
                for s, p in pooled.items()})
            stage.commit()
    obj = {"confidence": 0.95, "sensors": {
        s: sensor_dict(records, a, rows, names[s] if args.report is not None else None)
        for s, (records, a, rows) in results.items()}}
    for s, p in pooled.items():
        d = obj["sensors"][s]
        d["pooled_diagnosis"] = None if isinstance(p, str) else p.to_json_dict()
        d["pooled_note"] = p if isinstance(p, str) else p.summary()
    if args.json is not None:
        _write_json(obj, args.json)
    if args.json != "-":
        for s, (records, a, _) in results.items():
            _print(records, a)
            if s in pooled:
                p = pooled[s]
                print(f"  {p.summary() if not isinstance(p, str) else 'no pooled diagnosis: ' + p}")
        if args.report is not None:
            print(f"report: {args.report / 'report.html'}")
    return 0
