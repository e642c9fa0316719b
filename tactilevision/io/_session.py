"""The indentation session folder of ``formats.md`` section 1: read and check it.

A session is what ``tactilevision calibrate`` works on: ``session.toml``,
``reference.png``, ``frames/`` with ``frames.csv`` (frame times), ``forces.csv``
(the F/T log on its own clock) and an optional ``presses.csv``. Reading checks
every part and raises :class:`~tactilevision.InputError` naming the file, line
and column at fault; frames are listed and their sizes checked from the image
headers, but their pixels are read only on demand (:meth:`Session.frame`).
"""

from __future__ import annotations

import datetime
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from PIL import Image

from .._checks import InputError
from ._frames import read_image
from ._keys import KNOWN_KEYS, equal_area_radius, unknown_key_notes
from ._measurements import _read_table

__all__ = ["DEPTH_TOLERANCE_MM", "Session", "SessionConfig", "read_presses", "read_session"]

#: ``[gauge_block] depth_tolerance_mm``'s default: a depth counts as certified when its
#: 95 % interval lies within +- this, mm (issue 83's target: a depth within 5 um, its sd at
#: most 10 um).
DEPTH_TOLERANCE_MM = 0.02

_FORCE_COLUMNS = ("t_s", "fx_n", "fy_n", "fz_n")
_TORQUE_COLUMNS = ("tx_nmm", "ty_nmm", "tz_nmm")
_PRESS_COLUMNS = ("press", "indenter", "x_mm", "y_mm")


@dataclass(frozen=True)
class SessionConfig:
    """The keys of ``session.toml`` (units in the names).

    Attributes
    ----------
    sensor_name : str
    mm_per_px, gel_thickness_mm, gel_radius_mm, indenter_radius_mm : float
        Image scale on the gel, h, the pad's lateral half-size (``[sensor]
        gel_radius_mm``; else a rectangular pad's equal-area radius, sqrt(``gel_width_mm``
        ``gel_length_mm`` / pi); else 20 h), a.
    depths_mm : tuple of float
        Gauge-block depth w0 of each indenter, in indenter order (indenter ids
        are 0, 1, ...).
    rate_hz : float
        F/T sampling rate.
    clock_offset_s : float or None
        Forces' t_s minus frames' t_s when known; None to estimate it.
    window_samples : int
        F/T samples averaged per certified press.
    date : datetime.date or None
        The day of the session (optional key ``[session] date``, a TOML date
        such as ``2026-11-02``); None when not given. ``calibrate`` copies it
        into ``fit.json`` (``session_date``) and ``history`` orders a gel's
        calibrations by it.
    window_at : {'start', 'end'}
        Where in each hold the force window lies (optional key of
        ``[force_sensor]``, default 'start'): from the hold's start, or
        ending where the release begins (the settled force; with holds of
        different lengths the windows then fall at different times of their
        holds, and a relaxing gel shows in the table's ``hold_s``).
    calibration : Path or None
        Photometric calibration (resolved against the session folder), or None
        for the sensor's default.
    bevel_offset_mm : float
        Distance from the indenter axis to the bevel's crest line (optional
        key of ``[gauge_block]``, default 4.5 mm).
    bevel_direction_deg : float
        Direction from the indenter axis to the bevel in the image (default
        0 = +x along the columns; 90 = +y down the rows).
    bevel_angle_deg : float
        Flank angle theta of the bevel ridge, degrees in [0, 45) (default 0:
        a mark with no vernier, certified by its onset).
    bevel_length_mm : float
        Length of the bevel's crest line (default 2.4 mm).
    bulge_correction : bool
        Whether certified depths are corrected for the gel's bulge at the
        bevel (default true; only with a vernier).
    bevel_force_correction : bool
        Whether the force of the bevel's own band of contact is taken off the
        F/T force (default true; only with a vernier).
    max_overshoot_mm : float
        ``[gauge_block] max_overshoot_mm``: the most the stage goes past an
        indenter's w0, mm (default 0.1): a press certified deeper than its w0
        plus this is refused, never fitted.
    depth_tolerance_mm : float
        ``[gauge_block] depth_tolerance_mm``: a press's depth counts as certified
        when its 95 % interval lies within +- this, mm (default 0.02); a press
        read more loosely (a mark's crossing bracketed by a frame period of fast
        stage travel, a vernier band too short to read) is still fitted with its
        weight, but named as bounded, not certified.
    indenter_shape : {'flat_punch', 'sphere'}
        ``[indenter] shape`` (default 'flat_punch'). A ball (``'sphere'``)
        needs no ``[gauge_block]``: its depths come from its contact circles
        (``depths_mm`` is then empty unless given).
    indenter_contact : {'frictionless', 'tied'} or None
        ``[indenter] contact`` of a ball (None: the indenter's default).
    gel_dome_radius_mm : float or None
        ``[sensor] gel_dome_radius_mm``: a domed gel's top, its radius of curvature
        (read under a ball, with ``gel_radius_mm``); None for a flat top.
    """

    sensor_name: str
    mm_per_px: float
    gel_thickness_mm: float
    gel_radius_mm: float
    indenter_radius_mm: float
    depths_mm: tuple[float, ...]
    rate_hz: float
    clock_offset_s: float | None
    window_samples: int
    calibration: Path | None
    bevel_offset_mm: float = 4.5
    bevel_angle_deg: float = 0.0
    bevel_length_mm: float = 2.4
    bevel_direction_deg: float = 0.0
    bulge_correction: bool = True
    bevel_force_correction: bool = True
    max_overshoot_mm: float = 0.1
    depth_tolerance_mm: float = DEPTH_TOLERANCE_MM
    window_at: str = "start"
    date: datetime.date | None = None
    indenter_shape: str = "flat_punch"
    indenter_contact: str | None = None
    gel_dome_radius_mm: float | None = None


#: The places of the force window in a hold (``[force_sensor] window_at``).
WINDOW_AT = ("start", "end")


@dataclass(frozen=True)
class Session:
    """A checked session folder; frames are read on demand.

    Attributes
    ----------
    path : Path
    config : SessionConfig
    reference : (H, W, 3) uint8 ndarray
        The no-contact frame, BGR.
    frame_paths : tuple of Path
        Frames in the order of ``frames.csv``.
    frame_times_s : (F,) float64 ndarray
        Strictly increasing, camera clock.
    force_times_s : (M,) float64 ndarray
        Strictly increasing, F/T clock.
    forces_n : (M, 3) float64 ndarray
        (fx, fy, fz); fz positive pushing into the gel.
    torques_nmm : (M, 3) float64 ndarray or None
    presses : dict of str to ndarray, or None
        ``presses.csv`` columns ``press``, ``indenter`` (int64), ``x_mm``,
        ``y_mm`` (float64), each (P,).
    notes : tuple of str
        Things worth knowing that are not errors (frames on disk that
        ``frames.csv`` does not list, an irregular F/T rate).
    """

    path: Path
    config: SessionConfig
    reference: np.ndarray
    frame_paths: tuple[Path, ...]
    frame_times_s: np.ndarray
    force_times_s: np.ndarray
    forces_n: np.ndarray
    torques_nmm: np.ndarray | None
    presses: dict[str, np.ndarray] | None
    notes: tuple[str, ...] = field(default=())

    @property
    def n_frames(self) -> int:
        """Number of frames listed."""
        return len(self.frame_paths)

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W) of the reference and of every frame."""
        return self.reference.shape[0], self.reference.shape[1]

    def frame(self, i: int) -> np.ndarray:
        """Frame `i` as (H, W, 3) uint8 BGR.

        Raises
        ------
        InputError
            If the file became unreadable or its size differs from the
            reference.
        """
        img = read_image(self.frame_paths[i], colour_only=True)
        if img.shape != self.reference.shape:
            raise InputError(f"frame {self.frame_paths[i]} is {img.shape[1]} x {img.shape[0]} px, "
                             f"the reference {self.shape[1]} x {self.shape[0]} px")
        return img


# ------------------------------------------------------------------ config


def _toml_number(doc: dict, toml: Path, table: str, key: str, *, positive: bool = True,
                 default: float | None = None, required: bool = True) -> float | None:
    section = doc.get(table, {})
    if not isinstance(section, dict):
        raise InputError(f"{toml}: [{table}] must be a table")
    if key not in section:
        if required and default is None:
            raise InputError(f"{toml}: missing key [{table}] {key}")
        return default
    v = section[key]
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v) or (
            positive and v <= 0):
        need = "a positive number" if positive else "a finite number"
        raise InputError(f"{toml}: [{table}] {key} must be {need}, got {v!r}")
    return float(v)


def _unknown_keys(folder: Path) -> list[str]:
    """Notes on tables and keys of session.toml this version does not read (a typo in an
    optional key would otherwise fall back to its default without a word), and on a
    rectangular pad's width and length (:func:`~tactilevision.io.equal_area_radius`)."""

    toml = folder / "session.toml"
    with toml.open("rb") as fh:
        doc = tomllib.load(fh)
    return unknown_key_notes(doc, toml, KNOWN_KEYS) + equal_area_radius(doc, toml)[1]


def _indenter_shape(doc: dict, toml: Path) -> tuple[str, str | None]:
    """``[indenter] shape`` and ``contact``, checked (formats.md section 1)."""
    section = doc.get("indenter") if isinstance(doc.get("indenter"), dict) else {}
    shape = section.get("shape", "flat_punch")
    if shape not in ("flat_punch", "sphere"):
        raise InputError(f"{toml}: [indenter] shape must be \"flat_punch\" or \"sphere\", got "
                         f"{shape!r}")
    contact = section.get("contact")
    if contact is not None and contact not in ("frictionless", "tied"):
        raise InputError(f"{toml}: [indenter] contact must be \"frictionless\" or \"tied\", "
                         f"got {contact!r}")
    return shape, contact


def _read_config(folder: Path) -> SessionConfig:
    toml = folder / "session.toml"
    if not toml.is_file():
        raise InputError(f"session folder {folder} has no session.toml")
    try:
        with toml.open("rb") as fh:
            doc = tomllib.load(fh)
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise InputError(f"{toml} is not valid TOML: {exc}") from None
    shape, contact = _indenter_shape(doc, toml)
    depths = doc.get("gauge_block", {}).get("depths_mm") if isinstance(
        doc.get("gauge_block"), dict) else None
    if depths is None and shape == "sphere":
        depths = []                      # a ball's depths are read from its contact circles
    elif depths is None:
        raise InputError(f"{toml}: missing key [gauge_block] depths_mm")
    if not isinstance(depths, list) or (not depths and shape != "sphere") or not all(
            isinstance(d, int | float) and not isinstance(d, bool) and math.isfinite(d) and d > 0
            for d in depths):
        raise InputError(f"{toml}: [gauge_block] depths_mm must be a list of positive numbers, "
                         f"got {depths!r}")
    window = _toml_number(doc, toml, "force_sensor", "window_samples", default=200)
    if window != int(window) or window < 2:
        raise InputError(f"{toml}: [force_sensor] window_samples must be a whole number of at "
                         f"least 2, got {window!r}")
    window_at = doc.get("force_sensor", {}).get("window_at", "start") if isinstance(
        doc.get("force_sensor"), dict) else "start"
    if window_at not in WINDOW_AT:
        raise InputError(f"{toml}: [force_sensor] window_at must be one of "
                         f"{', '.join(repr(w) for w in WINDOW_AT)}, got {window_at!r}")
    calibration = doc.get("optics", {}).get("calibration") if isinstance(
        doc.get("optics"), dict) else None
    cal_path = None
    if calibration is not None:
        if not isinstance(calibration, str) or not calibration:
            raise InputError(f"{toml}: [optics] calibration must be a file path")
        cal_path = Path(calibration)
        cal_path = cal_path if cal_path.is_absolute() else folder / cal_path
        if not cal_path.is_file():
            raise InputError(f"{toml}: [optics] calibration {cal_path} does not exist")
    name = doc.get("sensor", {}).get("name", "") if isinstance(doc.get("sensor"), dict) else ""
    h = _toml_number(doc, toml, "sensor", "gel_thickness_mm")
    rectangle, _ = equal_area_radius(doc, toml)     # a rectangular pad: its equal-area disc
    return SessionConfig(
        sensor_name=str(name),
        mm_per_px=_toml_number(doc, toml, "sensor", "mm_per_px"),
        gel_thickness_mm=h,
        gel_radius_mm=_toml_number(doc, toml, "sensor", "gel_radius_mm",
                                   default=20.0 * h if rectangle is None else rectangle),
        indenter_radius_mm=_toml_number(doc, toml, "indenter", "radius_mm"),
        depths_mm=tuple(float(d) for d in depths),
        indenter_shape=shape,
        indenter_contact=contact,
        gel_dome_radius_mm=_toml_number(doc, toml, "sensor", "gel_dome_radius_mm",
                                        required=False),
        rate_hz=_rate(doc, toml),
        clock_offset_s=_toml_number(doc, toml, "force_sensor", "clock_offset_s", positive=False,
                                    required=False),
        window_samples=int(window),
        window_at=str(window_at),
        calibration=cal_path,
        bevel_offset_mm=_toml_number(doc, toml, "gauge_block", "bevel_offset_mm", default=4.5),
        bevel_angle_deg=_bevel_angle(doc, toml),
        bevel_length_mm=_toml_number(doc, toml, "gauge_block", "bevel_length_mm", default=2.4),
        bevel_direction_deg=_toml_number(doc, toml, "gauge_block", "bevel_direction_deg",
                                         positive=False, default=0.0),
        bulge_correction=_toml_bool(doc, toml, "gauge_block", "bulge_correction", default=True),
        bevel_force_correction=_toml_bool(doc, toml, "gauge_block", "bevel_force_correction",
                                          default=True),
        max_overshoot_mm=_toml_number(doc, toml, "gauge_block", "max_overshoot_mm",
                                      default=0.1),
        depth_tolerance_mm=_toml_number(doc, toml, "gauge_block", "depth_tolerance_mm",
                                        default=DEPTH_TOLERANCE_MM),
        date=_session_date(doc, toml),
    )


def _session_date(doc: dict, toml: Path) -> datetime.date | None:
    """``[session] date``: a TOML date (``2026-11-02``), or an ISO date string; None if absent.

    A TOML date-time keeps its day. Anything else is refused naming the key.
    """
    section = doc.get("session", {})
    if not isinstance(section, dict):
        raise InputError(f"{toml}: [session] must be a table")
    if "date" not in section:
        return None
    v = section["date"]
    if isinstance(v, datetime.datetime):
        return v.date()
    if isinstance(v, datetime.date):
        return v
    if isinstance(v, str):
        try:
            return datetime.date.fromisoformat(v.strip())
        except ValueError:
            pass
    raise InputError(f"{toml}: [session] date must be a date such as 2026-11-02, got {v!r}")


#: The fastest F/T log read (commercial six-axis sensors stream at up to about 7 kHz); the
#: clock refinement's grid steps by one sample, so a mistyped rate would exhaust memory.
MAX_RATE_HZ = 100_000.0


def _rate(doc: dict, toml: Path) -> float:
    rate = _toml_number(doc, toml, "force_sensor", "rate_hz", default=1000.0)
    if rate > MAX_RATE_HZ:
        raise InputError(f"{toml}: [force_sensor] rate_hz = {rate:g} is beyond any F/T sensor "
                         f"(at most {MAX_RATE_HZ:g} Hz read)")
    return rate


def _bevel_angle(doc: dict, toml: Path) -> float:
    theta = _toml_number(doc, toml, "gauge_block", "bevel_angle_deg", positive=False, default=0.0)
    if not 0.0 <= theta < 45.0:
        raise InputError(f"{toml}: [gauge_block] bevel_angle_deg is the flank angle of the bevel "
                         f"ridge, in [0, 45) degrees (0: no vernier), got {theta:g}; the bevel's "
                         "direction in the image is bevel_direction_deg")
    return theta


def _toml_bool(doc: dict, toml: Path, table: str, key: str, *, default: bool) -> bool:
    section = doc.get(table, {})
    if not isinstance(section, dict) or key not in section:
        return default
    v = section[key]
    if not isinstance(v, bool):
        raise InputError(f"{toml}: [{table}] {key} must be true or false, got {v!r}")
    return v


# ------------------------------------------------------------------ tables


def _read_csv(path: Path, required: tuple[str, ...]) -> tuple[list[str], list[list[str]],
                                                              list[int]]:
    """Header and rows of a session CSV, every required column present, at least one row."""
    if not path.is_file():
        raise InputError(f"session file {path} is missing")
    header, rows, lines = _read_table(path, "session file")
    missing = [c for c in required if c not in header]
    if missing:
        raise InputError(f"{path} line 1: missing column(s) {', '.join(missing)} "
                         f"(needs {','.join(required)})")
    if not rows:
        raise InputError(f"{path} has no rows")
    return header, rows, lines


#: The largest force a sample of an F/T log may hold, N (torques: 1e3 times it, N mm): an
#: indenter pressed into a gel sees newtons; 1e5 N is far beyond any F/T sensor a tactile
#: lab uses, and beyond it a value is a logging fault (sums of squares overflow near
#: 1e154).
MAX_FT_ABS = 1e5


def _numbers(path: Path, header: list[str], rows: list[list[str]], lines: list[int],
             column: str, *, finite: bool = True, limit: float | None = None) -> np.ndarray:
    j = header.index(column)
    out = np.empty(len(rows))
    for i, row in enumerate(rows):
        text = row[j].strip()
        if not text:
            raise InputError(f"{path} line {lines[i]}, column {column}: empty cell (every value "
                             "must be a finite number)")
        try:
            v = float(text)
        except ValueError:
            raise InputError(f"{path} line {lines[i]}, column {column}: '{text}' is not a "
                             "number") from None
        if finite and not math.isfinite(v):
            raise InputError(f"{path} line {lines[i]}, column {column}: {text} (every value "
                             "must be a finite number)")
        if limit is not None and abs(v) > limit:
            raise InputError(f"{path} line {lines[i]}, column {column}: {text} is beyond "
                             f"+-{limit:g}, not a force or torque an F/T sensor logs")
        out[i] = v
    return out


def _increasing(path: Path, t: np.ndarray, lines: list[int], column: str = "t_s") -> None:
    bad = np.flatnonzero(np.diff(t) <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        raise InputError(f"{path} line {lines[i]}, column {column}: {t[i]:g} does not increase "
                         f"(previous {t[i - 1]:g}); times must be strictly increasing")


def _read_frames(folder: Path, reference_shape: tuple[int, ...]
                 ) -> tuple[tuple[Path, ...], np.ndarray, list[str]]:

    table = folder / "frames.csv"
    header, rows, lines = _read_csv(table, ("frame", "t_s"))
    frames_dir = folder / "frames"
    if not frames_dir.is_dir():
        raise InputError(f"session folder {folder} has no frames/ folder")
    times = _numbers(table, header, rows, lines, "t_s")
    _increasing(table, times, lines)
    j = header.index("frame")
    names = [r[j].strip() for r in rows]
    paths = []
    for name, line in zip(names, lines, strict=True):
        p = frames_dir / name
        if not name or Path(name).name != name:
            raise InputError(f"{table} line {line}, column frame: '{name}' must be a file name "
                             "inside frames/")
        if not p.is_file():
            raise InputError(f"{table} line {line}: frame {name} is listed but {p} does not "
                             "exist")
        try:
            with Image.open(p) as im:
                w, h = im.size
        except OSError:
            raise InputError(f"frame {p} is not a readable image") from None
        if (h, w) != tuple(reference_shape[:2]):
            raise InputError(f"frame {p} is {w} x {h} px, the reference "
                             f"{reference_shape[1]} x {reference_shape[0]} px")
        paths.append(p)
    dup = {n for n in names if names.count(n) > 1}
    if dup:
        raise InputError(f"{table}: frame {sorted(dup)[0]} is listed twice")
    notes = []
    listed = set(names)
    extra = sorted(p.name for p in frames_dir.iterdir()
                   if p.suffix.lower() in (".png", ".jpg", ".jpeg") and p.name not in listed)
    if extra:
        notes.append(f"{len(extra)} image(s) in {frames_dir} not listed in frames.csv are "
                     f"ignored (first: {extra[0]})")
    return tuple(paths), times, notes


def _read_forces(folder: Path, rate_hz: float
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, list[str]]:
    path = folder / "forces.csv"
    header, rows, lines = _read_csv(path, _FORCE_COLUMNS)
    t = _numbers(path, header, rows, lines, "t_s")
    _increasing(path, t, lines)
    f = np.stack([_numbers(path, header, rows, lines, c, limit=MAX_FT_ABS)
                  for c in _FORCE_COLUMNS[1:]], axis=1)
    torques = None
    if all(c in header for c in _TORQUE_COLUMNS):
        torques = np.stack([_numbers(path, header, rows, lines, c, limit=1e3 * MAX_FT_ABS)
                            for c in _TORQUE_COLUMNS], axis=1)         # N mm
    notes = []
    if t.size > 2:
        dt = float(np.median(np.diff(t)))
        ratio = dt * rate_hz               # 1 when the log's times match rate_hz
        if ratio > 30 or ratio < 1 / 30:
            unit = (" (times in milliseconds? t_s must be seconds)" if 300 < ratio < 3000 else
                    "")
            raise InputError(f"{path}: the samples are {dt:.4g} s apart, {1 / dt:.4g} Hz, but "
                             f"[force_sensor] rate_hz = {rate_hz:g}{unit}; the clock cannot be "
                             "synchronised with the frames")
        if abs(1.0 / dt - rate_hz) > 0.05 * rate_hz:
            notes.append(f"{path}: median sample interval {dt * 1e3:.3g} ms, "
                         f"{1 / dt:.4g} Hz against [force_sensor] rate_hz = {rate_hz:g}")
    return t, f, torques, notes


def _read_presses(folder: Path, n_indenters: int) -> dict[str, np.ndarray] | None:
    path = folder / "presses.csv"
    return read_presses(path, n_indenters) if path.exists() else None


def read_presses(path: str | Path, n_indenters: int) -> dict[str, np.ndarray]:
    """Read a ``presses.csv`` (formats.md section 1): what the robot commanded, press by press.

    Parameters
    ----------
    path : str or Path
        The file: columns ``press``, ``indenter``, ``x_mm``, ``y_mm``, one row a press.
    n_indenters : int
        The gauge block's indenters (``[gauge_block] depths_mm``): an indenter is an index
        0 to ``n_indenters - 1``.

    Returns
    -------
    presses : dict of str to (N,) ndarray
        ``press``, ``indenter`` (int64), ``x_mm``, ``y_mm`` (float64, mm), in the file's
        order.

    Raises
    ------
    InputError
        A missing or unreadable file, a missing column, a value that is not a number,
        a press or indenter that is not a whole number, or an indenter outside the block,
        each naming the file, line and column.
    """
    path = Path(path)
    header, rows, lines = _read_csv(path, _PRESS_COLUMNS)
    out = {c: _numbers(path, header, rows, lines, c) for c in _PRESS_COLUMNS}
    for c in ("press", "indenter"):
        v = out[c]
        bad = np.flatnonzero(v != np.round(v))
        if bad.size:
            raise InputError(f"{path} line {lines[bad[0]]}, column {c}: {v[bad[0]]:g} is not a "
                             "whole number")
        out[c] = v.astype(np.int64)
    bad = np.flatnonzero((out["indenter"] < 0) | (out["indenter"] >= n_indenters))
    if bad.size:
        raise InputError(f"{path} line {lines[bad[0]]}, column indenter: "
                         f"{out['indenter'][bad[0]]} is not an indenter of [gauge_block] "
                         f"depths_mm (0 to {n_indenters - 1})")
    return out


def read_session(path: str | Path) -> Session:
    """Read and check an indentation session folder (formats.md section 1).

    Parameters
    ----------
    path : str or Path
        The session folder.

    Returns
    -------
    session : Session
        Config, reference frame, frame list and times, F/T log, presses.

    Raises
    ------
    InputError
        Naming the file (and line, column or key) at fault: a missing part
        (``session.toml``, ``reference.png``, ``frames/``, ``frames.csv``,
        ``forces.csv``), a missing or malformed key, a frame listed but
        absent, a frame whose size differs from the reference, times that do
        not increase strictly, a non-number or NaN in the F/T log, an unknown
        indenter in ``presses.csv``.

    Examples
    --------
    >>> from tactilevision.io import read_session
    >>> s = read_session("my_session")                    # doctest: +SKIP
    >>> s.n_frames, s.shape, s.config.depths_mm           # doctest: +SKIP
    (1800, (320, 427), (0.15, 0.3, 0.4, 0.5, 0.6))
    """
    folder = Path(path)
    if not folder.is_dir():
        raise InputError(f"session folder {folder} does not exist")
    config = _read_config(folder)
    ref_path = folder / "reference.png"
    if not ref_path.is_file():
        raise InputError(f"session folder {folder} has no reference.png")
    reference = read_image(ref_path, colour_only=True)
    frame_paths, frame_times, notes = _read_frames(folder, reference.shape)
    t, f, torques, force_notes = _read_forces(folder, config.rate_hz)
    if frame_times.size > 1 and t.size > 1:
        fps = 1.0 / float(np.median(np.diff(frame_times)))
        ft_hz = 1.0 / float(np.median(np.diff(t)))
        if ft_hz < 2.0 * fps:
            force_notes = [*force_notes, f"{folder / 'forces.csv'} samples at {ft_hz:.3g} Hz, "
                           f"less than twice the {fps:.3g} frames/s of "
                           f"{folder / 'frames.csv'}: the force cannot follow a press as "
                           "closely as the frames do (an F/T sensor logs at hundreds of Hz "
                           "or more)"]
    if config.window_samples > t.size:
        force_notes = [*force_notes, f"{folder / 'session.toml'}: [force_sensor] "
                       f"window_samples = {config.window_samples} is more than the {t.size} "
                       f"samples of {folder / 'forces.csv'}: no press can be certified"]
    presses = _read_presses(folder, len(config.depths_mm))
    if config.indenter_shape == "sphere" and config.depths_mm:
        force_notes = [*force_notes, f"{folder / 'session.toml'}: [gauge_block] is not used "
                       "for a ball ([indenter] shape = \"sphere\"): each depth is read from "
                       "the ball's contact circle"]
    return Session(path=folder, config=config, reference=reference, frame_paths=frame_paths,
                   frame_times_s=frame_times, force_times_s=t, forces_n=f, torques_nmm=torques,
                   presses=presses, notes=tuple(_unknown_keys(folder) + notes + force_notes))
