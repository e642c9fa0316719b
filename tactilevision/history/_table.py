"""One sensor's calibrations as a table (``history_<sensor>.csv``)."""

from __future__ import annotations

import csv
import math
import re
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ._read import CalibrationRecord

__all__ = ["HISTORY_COLUMNS", "history_rows", "sensor_file_name", "write_history_csv"]

#: The columns of ``history_<sensor>.csv`` (formats.md, "Calibration history"), in order.
HISTORY_COLUMNS = (
    "date", "day", "folder", "E_mpa", "E_lo_mpa", "E_hi_mpa", "nu", "nu_lo", "nu_hi",
    "c_n_per_mm", "c_lo_n_per_mm", "c_hi_n_per_mm", "beta", "beta_lo", "beta_hi",
    "n_presses", "n_rejected", "clock_offset_s", "beyond_day0_ci", "date_source",
)


def history_rows(records: Sequence[CalibrationRecord],
                 beyond: np.ndarray | None = None) -> list[dict]:
    """The table's rows, one per calibration, in the order given (by date).

    Parameters
    ----------
    records : sequence of CalibrationRecord
        One sensor's calibrations, sorted by date.
    beyond : (n,) bool ndarray, optional
        Whether each E lies outside the first calibration's interval
        (``Assessment.beyond``); computed here when not given.

    Returns
    -------
    rows : list of dict
        Keys :data:`HISTORY_COLUMNS`: ``date`` ISO, ``day`` since the first
        calibration, ``folder`` as given, E (MPa), nu, c (N/mm), beta with
        the low and high ends of their intervals (95 % unless the fits said
        otherwise), certified and rejected presses, the clock offset (s,
        None when unknown), ``beyond_day0_ci`` and ``date_source``. Floats
        that are NaN become None.
    """
    if not records:
        return []
    first = records[0]
    if beyond is None:
        lo, hi = first.E_ci95_mpa
        beyond = np.array([i > 0 and not lo <= r.E_mpa <= hi for i, r in enumerate(records)])

    def num(v: float) -> float | None:
        return float(v) if math.isfinite(v) else None

    rows = []
    for r, b in zip(records, beyond, strict=True):
        rows.append({
            "date": r.date.isoformat(), "day": (r.date - first.date).days,
            "folder": str(r.folder),
            "E_mpa": r.E_mpa, "E_lo_mpa": r.E_ci95_mpa[0], "E_hi_mpa": r.E_ci95_mpa[1],
            "nu": r.nu, "nu_lo": r.nu_ci95[0], "nu_hi": r.nu_ci95[1],
            "c_n_per_mm": r.c_n_per_mm, "c_lo_n_per_mm": num(r.c_ci95_n_per_mm[0]),
            "c_hi_n_per_mm": num(r.c_ci95_n_per_mm[1]),
            "beta": r.beta, "beta_lo": r.beta_ci95[0], "beta_hi": r.beta_ci95[1],
            "n_presses": r.n_presses, "n_rejected": r.n_rejected,
            "clock_offset_s": num(r.clock_offset_s), "beyond_day0_ci": bool(b),
            "date_source": r.date_source,
        })
    return rows


def sensor_file_name(sensor: str) -> str:
    """``history_<sensor>.csv`` with every character outside ``[A-Za-z0-9_.-]`` made ``_``.

    Parameters
    ----------
    sensor : str

    Returns
    -------
    name : str
    """
    return "history_" + (re.sub(r"[^A-Za-z0-9_.-]", "_", sensor) or "unnamed") + ".csv"


def write_history_csv(path: str | Path, rows: Sequence[dict]) -> Path:
    """Write the rows of :func:`history_rows` as CSV (columns :data:`HISTORY_COLUMNS`).

    Parameters
    ----------
    path : str or Path
    rows : sequence of dict

    Returns
    -------
    path : Path
        Floats with 6 significant digits; None as an empty cell; booleans
        as ``true``/``false``.

    Raises
    ------
    OSError
        When the file cannot be written.
    """
    path = Path(path)

    def cell(v) -> str:
        if v is None:
            return ""
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, float):
            return f"{v:.6g}"
        return str(v)

    with path.open("w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(HISTORY_COLUMNS)
        for row in rows:
            w.writerow([cell(row[k]) for k in HISTORY_COLUMNS])
    return path
