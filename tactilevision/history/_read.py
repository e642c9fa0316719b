"""Read the output folders of ``tactilevision calibrate`` into calibration records (I/O edge).

``calibrate`` writes ``fit.json`` (formats.md section 3: the ``fit --json``
keys, then the session's, including ``sensor_name`` and ``session_date``),
``measurements.csv`` and ``rejected.csv``. :func:`read_calibration` reads the
numbers ``history`` tabulates; :func:`gather` reads many folders and sorts
them into one date-ordered list per sensor.
"""

from __future__ import annotations

import csv
import datetime
import math
import tomllib
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path

from scipy import stats

from .._checks import InputError
from ..io import SIDECAR_KEYS, warn_unknown_keys
from ..pipeline import CalibrationResult

__all__ = ["CalibrationRecord", "gather", "read_calibration"]

#: The sensor name used when neither fit.json nor the folder's session.toml names one.
UNNAMED = "unnamed"


@dataclass(frozen=True)
class CalibrationRecord:
    """One calibration of one gel, as ``history`` reads it. Units are in the names.

    Attributes
    ----------
    folder : Path
        The ``calibrate`` output folder.
    sensor : str
        ``sensor_name`` of fit.json (``[sensor] name`` of the session), else
        the folder's session.toml ``[sensor] name``, else ``'unnamed'``; with
        ``(specimen S)`` after it where the folder's measurements.csv has a
        ``specimen`` column naming one specimen S (each specimen a series).
    date : datetime.date
        The day of the calibration session.
    date_source : str
        Where `date` came from: ``'--date'``, ``'fit.json'`` or ``'session.toml'``.
    E_mpa : float
        Young's modulus, MPa.
    E_ci95_mpa : (float, float)
        Its interval at `confidence`, MPa.
    E_se_mpa : float
        Its standard error, MPa (``E_se_mpa`` of fit.json; when absent or
        null, the interval's half-width over the normal quantile).
    nu : float
    nu_ci95 : (float, float)
    c_n_per_mm : float
        Intercept c of eq. (5), N/mm.
    c_ci95_n_per_mm : (float, float)
        c +- t c_se, with the Student quantile t the fit used for beta
        (recovered as the half-width of ``beta_ci95`` over ``beta_se``).
    beta : float
    beta_ci95 : (float, float)
    confidence : float
        Confidence level of the intervals (0.95 unless the fit was asked otherwise).
    n_presses : int
        Certified presses fitted.
    n_rejected : int
        Presses rejected (``n_rejected`` of fit.json, else the rows of rejected.csv).
    clock_offset_s : float
        F/T clock minus camera clock, s (NaN when fit.json has none).
    """

    folder: Path
    sensor: str
    date: datetime.date
    date_source: str
    E_mpa: float
    E_ci95_mpa: tuple[float, float]
    E_se_mpa: float
    nu: float
    nu_ci95: tuple[float, float]
    c_n_per_mm: float
    c_ci95_n_per_mm: tuple[float, float]
    beta: float
    beta_ci95: tuple[float, float]
    confidence: float
    n_presses: int
    n_rejected: int
    clock_offset_s: float


def _number(obj: Mapping, key: str, where: Path, *, required: bool = True) -> float:
    v = obj.get(key)
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
        if not required:
            return math.nan
        why = "missing" if key not in obj else f"{v!r}, not a finite number"
        raise InputError(f"{where}: key {key} is {why}; history needs the E, nu, c and beta "
                         f"of a completed calibration (run tactilevision calibrate again)")
    return float(v)


def _interval(obj: Mapping, key: str, where: Path) -> tuple[float, float]:
    v = obj.get(key)
    if (not isinstance(v, list) or len(v) != 2 or not all(
            isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x)
            for x in v) or v[0] > v[1]):
        why = "missing" if key not in obj else f"{v!r}, not an interval [low, high]"
        raise InputError(f"{where}: key {key} is {why}; history needs the E, nu, c and beta "
                         f"of a completed calibration with their intervals")
    return float(v[0]), float(v[1])


def _toml(folder: Path) -> dict:
    """The folder's session.toml (a copy of the session's, or calibrate's sidecar), or {}."""
    path = folder / "session.toml"
    if not path.is_file():
        return {}
    try:
        with path.open("rb") as fh:
            doc = tomllib.load(fh)
    except (tomllib.TOMLDecodeError, UnicodeDecodeError, OSError):
        return {}
    warn_unknown_keys(doc, path, SIDECAR_KEYS, stacklevel=3)
    return doc


def _date(fit: Mapping, toml: Mapping, folder: Path,
          override: datetime.date | None) -> tuple[datetime.date, str]:
    if override is not None:
        return override, "--date"
    text = fit.get("session_date")
    if text is not None:
        try:
            return datetime.date.fromisoformat(str(text)), "fit.json"
        except ValueError:
            raise InputError(f"{folder / 'fit.json'}: session_date {text!r} is not a date "
                             "YYYY-MM-DD") from None
    section = toml.get("session")
    v = section.get("date") if isinstance(section, dict) else None
    if isinstance(v, datetime.datetime):
        return v.date(), "session.toml"
    if isinstance(v, datetime.date):
        return v, "session.toml"
    raise InputError(f"calibration folder {folder} has no date (fit.json has no session_date, "
                     "and no session.toml there has [session] date): add [session] date = "
                     "YYYY-MM-DD to the session's session.toml and calibrate again, or pass "
                     f"--date {folder}=YYYY-MM-DD")


def _n_rejected(result: CalibrationResult, folder: Path) -> int:
    """Presses rejected: fit.json's n_rejected, else the rows of rejected.csv."""
    v = result.fit.get("n_rejected")
    if isinstance(v, int) and not isinstance(v, bool) and v >= 0:
        return v
    if not (folder / "rejected.csv").is_file():
        raise InputError(f"calibration folder {folder}: fit.json has no n_rejected and there "
                         "is no rejected.csv (is it the output of tactilevision calibrate?)")
    return len(result.rejected)


def _specimen(folder: Path) -> str:
    """The ``specimen`` column of the folder's measurements.csv: its one value, or '' when
    the table has no such column (or no table).

    Raises
    ------
    InputError
        Naming the folder, when the column names more than one specimen: a calibration
        folder is one gel's; several specimens are pooled by ``fit``.
    """
    path = folder / "measurements.csv"
    if not path.is_file():
        return ""
    with path.open(newline="") as f:
        rows = list(csv.reader(line for line in f if line.strip()
                               and not line.lstrip().startswith("#")))
    if not rows or "specimen" not in [c.strip() for c in rows[0]]:
        return ""
    i = [c.strip() for c in rows[0]].index("specimen")
    values = sorted({r[i].strip() for r in rows[1:] if len(r) > i and r[i].strip()})
    if len(values) > 1:
        raise InputError(f"calibration folder {folder}: its measurements.csv names "
                         f"{len(values)} specimens ({', '.join(values[:4])}"
                         f"{', ...' if len(values) > 4 else ''}): a history follows one gel "
                         "per calibration; pool specimens with `tactilevision fit` (its "
                         "specimen column)")
    return values[0] if values else ""


def read_calibration(folder: str | Path, *, date: datetime.date | None = None
                     ) -> CalibrationRecord:
    """Read one ``calibrate`` output folder.

    Parameters
    ----------
    folder : str or Path
        Holds ``fit.json`` (formats.md section 3) and, optionally,
        ``rejected.csv`` and a ``session.toml``.
    date : datetime.date, optional
        The calibration's day, overriding ``session_date`` of fit.json (for
        folders calibrated before the key existed: ``--date``).

    Returns
    -------
    record : CalibrationRecord

    Raises
    ------
    InputError
        Naming the folder or file: the folder does not exist, has no
        fit.json, fit.json is not a JSON object, lacks E, nu, c or beta or
        their intervals (or they are null: a fit out of the beta table), or no
        date is known (the message gives both fixes: ``[session] date`` in
        session.toml, or ``--date FOLDER=YYYY-MM-DD``).
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError(f"calibration folder {folder} does not exist or is not a folder")
    result = CalibrationResult.load(folder, tables=False)
    fit = result.fit
    path = folder / "fit.json"
    toml = _toml(folder)
    sensor = fit.get("sensor_name")
    if not isinstance(sensor, str) or not sensor.strip():
        section = toml.get("sensor")
        sensor = section.get("name") if isinstance(section, dict) else None
    sensor = sensor.strip() if isinstance(sensor, str) and sensor.strip() else UNNAMED
    specimen = _specimen(folder)
    if specimen:            # each specimen of a sensor's gels is a series of its own
        sensor = f"{sensor} (specimen {specimen})"
    when, source = _date(fit, toml, folder, date)
    E = _number(fit, "E_mpa", path)
    E_ci = _interval(fit, "E_ci95_mpa", path)
    conf = _number(fit, "confidence", path, required=False)
    conf = 0.95 if math.isnan(conf) else conf
    E_se = _number(fit, "E_se_mpa", path, required=False)
    if math.isnan(E_se):
        E_se = (E_ci[1] - E_ci[0]) / (2.0 * float(stats.norm.ppf(0.5 + conf / 2)))
    beta = _number(fit, "beta", path)
    beta_ci = _interval(fit, "beta_ci95", path)
    c = _number(fit, "c_n_per_mm", path)
    c_se = _number(fit, "c_se_n_per_mm", path, required=False)
    beta_se = _number(fit, "beta_se", path, required=False)
    if math.isfinite(c_se) and math.isfinite(beta_se) and beta_se > 0:
        tq = (beta_ci[1] - beta_ci[0]) / (2.0 * beta_se)
        c_ci = (c - tq * c_se, c + tq * c_se)
    else:
        c_ci = (math.nan, math.nan)
    n = fit.get("n_presses")
    if isinstance(n, bool) or not isinstance(n, int) or n < 0:
        raise InputError(f"{path}: key n_presses is {n!r}, not a number of presses")
    return CalibrationRecord(
        folder=folder, sensor=sensor, date=when, date_source=source, E_mpa=E, E_ci95_mpa=E_ci,
        E_se_mpa=E_se, nu=_number(fit, "nu", path), nu_ci95=_interval(fit, "nu_ci95", path),
        c_n_per_mm=c, c_ci95_n_per_mm=c_ci, beta=beta, beta_ci95=beta_ci, confidence=conf,
        n_presses=n, n_rejected=_n_rejected(result, folder),
        clock_offset_s=_number(fit, "clock_offset_s", path, required=False))


def gather(folders: Iterable[str | Path], *,
           dates: Mapping[str | Path, datetime.date] | None = None
           ) -> dict[str, list[CalibrationRecord]]:
    """Read calibration folders into one date-ordered list per sensor.

    Parameters
    ----------
    folders : iterable of str or Path
        ``calibrate`` output folders, any order, any mix of sensors.
    dates : mapping of folder to datetime.date, optional
        Dates for folders without one (``--date``); keys are matched to
        `folders` by their resolved paths.

    Returns
    -------
    by_sensor : dict of str to list of CalibrationRecord
        Sensors in order of first appearance; each list sorted by date (then
        folder name).

    Raises
    ------
    InputError
        For no folders, a folder given twice, a date for a folder not among
        `folders`, or any folder :func:`read_calibration` refuses.
    """
    folders = [Path(f) for f in folders]
    if not folders:
        raise InputError("no calibration folders given")
    resolved = [f.resolve() for f in folders]
    seen: dict[Path, Path] = {}
    for f, r in zip(folders, resolved, strict=True):
        if r in seen:
            raise InputError(f"calibration folder {f} is given twice")
        seen[r] = f
    override = {}
    for k, v in (dates or {}).items():
        r = Path(k).resolve()
        if r not in seen:
            raise InputError(f"--date names {k}, which is not among the calibration folders")
        override[r] = v
    by_sensor: dict[str, list[CalibrationRecord]] = {}
    for f, r in zip(folders, resolved, strict=True):
        rec = read_calibration(f, date=override.get(r))
        by_sensor.setdefault(rec.sensor, []).append(rec)
    for recs in by_sensor.values():
        recs.sort(key=lambda x: (x.date, str(x.folder)))
    return by_sensor
