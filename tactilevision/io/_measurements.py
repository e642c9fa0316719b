"""Read a measurements table (``formats.md`` §2) and its sidecar ``session.toml``."""

from __future__ import annotations

import csv
import math
import os
import tomllib
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._checks import InputError, InputWarning
from ._keys import SIDECAR_KEYS, equal_area_radius, unknown_key_notes

__all__ = ["COLUMN_ORDER", "REQUIRED_COLUMNS", "STANDARD_GRAVITY", "Measurements", "read_holds",
           "read_measurements", "sidecar_geometry", "write_measurements"]

#: Columns every measurements table must have (formats.md §2).
REQUIRED_COLUMNS = ("depth_mm", "force_n")
#: Standard gravity, m/s^2 (CGPM 1901): the force of a dead weight of mass m is m g.
STANDARD_GRAVITY = 9.80665

#: Plausibility bounds of a measurements row: a tactile gel a few mm thick pressed by
#: a stage (values beyond are unit errors or corrupt cells, and overflow the fits).
MAX_DEPTH_MM = 100.0
MAX_FORCE_N = 1.0e4

# Optional columns of formats.md §2 that must be numeric when present.
# ``indenter`` is an id and may be text; unknown columns are covariates when
# every cell is a number, else kept as labels.
_NUMERIC_COLUMNS = frozenset({
    "press", "depth_std_mm", "depth_shared_mm", "depth_indenter_std_mm", "overshoot_mm",
    "force0_n", "force_w0_n", "force_w0_sem_n", "force_std_n", "force_sem_n", "fx_n", "fy_n",
    "ft_zero_n", "ft_drift_n",
    "time_s", "hold_s", "wait_s", "x_mm", "y_mm", "day", "temperature_c",
})

# Optional columns that are uncertainties of another column, or another reading of the
# force, not covariates.
_UNCERTAINTY_COLUMNS = ("depth_std_mm", "depth_shared_mm", "depth_indenter_std_mm",
                        "force_sem_n", "force0_n", "force_w0_n", "force_w0_sem_n")
# Columns that say what was done to the force (the F/T's zero taken off), not covariates.
_FORCE_COLUMNS = ("ft_zero_n",)
# Columns the depth rule computed (a product of the certification), not covariates.
_CERTIFICATION_COLUMNS = ("overshoot_mm",)

# (table, key, argument name) of the sidecar values.
_SIDECAR = {"thickness_mm": ("sensor", "gel_thickness_mm"),
            "radius_mm": ("indenter", "radius_mm")}


@dataclass(frozen=True)
class Measurements:
    """One row per certified press, with the geometry the fit needs.

    Attributes
    ----------
    path : Path
        The table read.
    columns : dict of str to (N,) float64 ndarray
        Every numeric column, in file order, NaN for empty cells;
        ``depth_mm`` (mm) and ``force_n`` (N) are always present and finite.
    labels : dict of str to tuple of str
        Columns holding text (e.g. an ``indenter`` id), kept as read.
    line_numbers : (N,) int64 ndarray
        Line of the file each row was read from (the header is line 1).
    thickness_mm, radius_mm : float, mm
        Gel thickness h and indenter radius a.
    thickness_source, radius_source : str
        ``'argument'`` or ``'<session.toml path> [table] key'``.
    notes : tuple of str
        Warnings on the values read (non-positive forces), each naming the
        file, line and column; and on the sidecar ``session.toml``: each table and
        key it holds that no reader of a table's sidecar reads, naming the file,
        ``[table] key`` and the nearest known key, and what was made of a
        rectangular pad's ``gel_width_mm`` and ``gel_length_mm`` (formats.md §1).
    indenter : dict of str to object
        The sidecar ``session.toml``'s ``[indenter]`` keys beside ``radius_mm``
        (``shape``, ``contact``) and its ``[sensor] gel_radius_mm`` (as
        ``pad_radius_mm``; without it, a rectangular pad's ``gel_width_mm`` and
        ``gel_length_mm`` as the radius of the disc of the same area) and
        ``gel_dome_radius_mm`` (as ``dome_radius_mm``), where it has them; empty
        without a sidecar. A flat punch is ``shape = "flat_punch"`` or no ``shape``.
    certification : dict of str to object
        The sidecar's ``[certification]`` keys (``depth_rule``: how ``calibrate``
        certified the depths, e.g. ``'mark'``, whose depths past w0 are read from
        the force); empty without them.
    """

    path: Path
    columns: dict[str, np.ndarray] = field(hash=False)
    labels: dict[str, tuple[str, ...]] = field(hash=False)
    line_numbers: np.ndarray = field(hash=False)
    thickness_mm: float
    radius_mm: float
    thickness_source: str
    radius_source: str
    notes: tuple[str, ...] = ()
    indenter: dict[str, object] = field(default_factory=dict, hash=False)
    certification: dict[str, object] = field(default_factory=dict, hash=False)

    @property
    def depth_mm(self) -> np.ndarray:
        """(N,) float64 ndarray, mm: certified depth w of each press."""
        return self.columns["depth_mm"]

    @property
    def force_n(self) -> np.ndarray:
        """(N,) float64 ndarray, N: normal force P of each press."""
        return self.columns["force_n"]

    @property
    def covariates(self) -> tuple[str, ...]:
        """Names of the numeric columns but ``depth_mm``, ``force_n``, the uncertainties
        (``depth_std_mm``, ``depth_shared_mm``, ``force_sem_n``), ``force0_n``,
        ``ft_zero_n`` and the depth rule's ``overshoot_mm``."""
        return tuple(k for k in self.columns if k not in REQUIRED_COLUMNS
                     and k not in _UNCERTAINTY_COLUMNS and k not in _FORCE_COLUMNS
                     and k not in _CERTIFICATION_COLUMNS)

    def __len__(self) -> int:
        return int(self.depth_mm.shape[0])


def _number(text: str) -> float | None:
    """Parse a cell; NaN when empty, None when not a number."""
    text = text.strip()
    if not text:
        return math.nan
    try:
        return float(text)
    except ValueError:
        return None


def _read_table(path: Path, what: str = "measurements table"
                ) -> tuple[list[str], list[list[str]], list[int]]:
    """Header names, rows and their line numbers of a CSV; every row as long as the header."""
    try:
        with path.open(newline="", encoding="utf-8-sig") as fh:
            reader = csv.reader(fh)
            header = next(reader, None)
            rows, lines = [], []
            for row in reader:
                if not row:
                    continue  # blank line
                if len(row) != len(header or ()):
                    raise InputError(f"{path} line {reader.line_num} has {len(row)} cells, "
                                     f"the header has {len(header or ())}")
                rows.append(row)
                lines.append(reader.line_num)
    except FileNotFoundError:
        raise InputError(f"{what} {path} not found") from None
    except IsADirectoryError:
        raise InputError(f"{path} is a folder, not a {what}") from None
    except OSError as exc:
        raise InputError(f"cannot read {path}: {exc.strerror}") from None
    except (UnicodeDecodeError, csv.Error) as exc:
        raise InputError(f"{path} is not a readable CSV text file ({exc})") from None
    if header is None:
        raise InputError(f"{path} is empty: no header line")
    names = [h.strip() for h in header]
    for i, name in enumerate(names):
        if not name:
            raise InputError(f"{path} line 1: column {i + 1} has no name")
        if name in names[:i]:
            raise InputError(f"{path} line 1: column '{name}' appears twice")
    return names, rows, lines


def _weights_to_forces(path: Path, names: list[str], rows: list[list[str]], lines: list[int]
                       ) -> tuple[list[str], list[list[str]]]:
    """A dead-weight table's ``mass_kg`` (and ``mass_std_kg``) as ``force_n`` (and
    ``force_sem_n``, the force's standard uncertainty): P = m g, g standard gravity.

    Raises
    ------
    InputError
        Naming the file, line and column of a mass that is not a number > 0, or a mass
        uncertainty that is not a number >= 0.
    """
    out_names = list(names)
    j = names.index("mass_kg")
    k = names.index("mass_std_kg") if "mass_std_kg" in names else None
    out_rows = [list(r) for r in rows]
    for row, line, new in zip(rows, lines, out_rows, strict=True):
        m = _number(row[j])
        if m is None or not (math.isfinite(m) and m > 0):
            raise InputError(f"{path} line {line}, column mass_kg: '{row[j].strip()}' is not a "
                             "mass (a number of kg > 0: a dead weight resting on the gel)")
        new[j] = repr(m * STANDARD_GRAVITY)
        if k is not None:
            sd = _number(row[k])
            if sd is not None and (not math.isfinite(sd) or sd < 0):
                raise InputError(f"{path} line {line}, column mass_std_kg: '{row[k].strip()}' "
                                 "is not a standard uncertainty (a number >= 0, or empty)")
            new[k] = "" if sd is None else repr(sd * STANDARD_GRAVITY)
    out_names[j] = "force_n"
    if k is not None:
        out_names[k] = "force_sem_n"
    return out_names, out_rows


def _parse_columns(path: Path, names: list[str], rows: list[list[str]], lines: list[int]
                   ) -> tuple[dict[str, np.ndarray], dict[str, tuple[str, ...]]]:
    columns: dict[str, np.ndarray] = {}
    labels: dict[str, tuple[str, ...]] = {}
    for j, name in enumerate(names):
        cells = [row[j] for row in rows]
        values = [_number(t) for t in cells]
        must = name in REQUIRED_COLUMNS or name in _NUMERIC_COLUMNS
        bad = next((i for i, v in enumerate(values) if v is None), None)
        if bad is not None and not must:
            labels[name] = tuple(t.strip() for t in cells)
            continue
        if bad is not None:
            raise InputError(f"{path} line {lines[bad]}, column {name}: "
                             f"'{cells[bad].strip()}' is not a number")
        arr = np.array(values, dtype=np.float64)  # (N,)
        if name in REQUIRED_COLUMNS and not np.all(np.isfinite(arr)):
            i = int(np.argmax(~np.isfinite(arr)))
            what = "empty cell" if not cells[i].strip() else f"'{cells[i].strip()}'"
            raise InputError(f"{path} line {lines[i]}, column {name}: {what}; "
                             f"{' and '.join(REQUIRED_COLUMNS)} need a finite number in every row")
        columns[name] = arr
    return columns, labels


def _check_uncertainties(path: Path, names: list[str], rows: list[list[str]], lines: list[int],
                         columns: dict[str, np.ndarray]) -> None:
    """A standard uncertainty column holds numbers >= 0 and finite, or empty cells."""
    for name in _UNCERTAINTY_COLUMNS:
        if name not in columns:
            continue
        v = columns[name]
        bad = np.isinf(v) | (v < 0)  # NaN (empty) is a missing value
        if np.any(bad):
            i = int(np.argmax(bad))
            cell = rows[i][names.index(name)].strip()
            raise InputError(f"{path} line {lines[i]}, column {name}: '{cell}' is not a "
                             "standard uncertainty (a finite number >= 0, or empty)")


def _geometry(path: Path, given: dict[str, float | None]) -> tuple[dict[str, float],
                                                                  dict[str, str]]:
    values: dict[str, float] = {}
    sources: dict[str, str] = {}
    for arg, v in given.items():
        if v is not None:
            x = float(v)
            if not (math.isfinite(x) and x > 0):
                raise InputError(f"{arg} must be a positive number of mm, got {v!r}")
            values[arg], sources[arg] = x, "argument"
    need = [arg for arg in _SIDECAR if arg not in values]
    if not need:
        return values, sources
    toml = path.parent / "session.toml"
    flag = "--" + need[0].replace("_", "-")
    if not toml.is_file():
        table, key = _SIDECAR[need[0]]
        raise InputError(f"{path}: {need[0]} not given and no session.toml next to it "
                         f"(give {need[0]} / {flag}, or add [{table}] {key} to {toml})")
    try:
        with toml.open("rb") as fh:
            doc = tomllib.load(fh)
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise InputError(f"{toml} is not valid TOML: {exc}") from None
    for arg in need:
        table, key = _SIDECAR[arg]
        section = doc.get(table)
        if not isinstance(section, dict) or key not in section:
            raise InputError(f"{toml}: missing key [{table}] {key} "
                             f"(or give {arg} / --{arg.replace('_', '-')})")
        v = section[key]
        if isinstance(v, bool) or not isinstance(v, int | float) or not (
                math.isfinite(v) and v > 0):
            raise InputError(f"{toml}: [{table}] {key} must be a positive number of mm, "
                             f"got {v!r}")
        values[arg], sources[arg] = float(v), f"{toml} [{table}] {key}"
    return values, sources


def read_measurements(path: str | Path, *, thickness_mm: float | None = None,
                      radius_mm: float | None = None) -> Measurements:
    """Read ``measurements.csv`` (formats.md §2) and the geometry of its session.

    Parameters
    ----------
    path : str or Path
        The CSV table: a header line, then one row per certified press.
        ``depth_mm`` and ``force_n`` are required and must be finite in every
        row; other columns are optional, empty cells are missing values.
    thickness_mm : float, optional
        Gel thickness h, mm. Default: ``[sensor] gel_thickness_mm`` of the
        ``session.toml`` in the same folder.
    radius_mm : float, optional
        Flat indenter radius a, mm. Default: ``[indenter] radius_mm`` of the
        same ``session.toml``.

    Returns
    -------
    table : Measurements
        Numeric columns as (N,) float64 arrays (NaN where empty), text columns
        as labels, and h, a with where each came from. ``session.toml`` is
        read only when an argument is missing.

    Raises
    ------
    InputError
        With one sentence naming the file and the line, column or key: file
        missing or unreadable, a missing required column, a row of the wrong
        length, a non-numeric cell in a numeric column (the bad text is
        quoted), an empty required cell, a depth not positive, no data rows,
        ``session.toml`` absent, malformed or missing a key when the value was
        not given, a geometry value that is not a positive number, or a
        negative or infinite ``depth_std_mm``.

    Notes
    -----
    Dead weights: a table with ``mass_kg`` (each weight's mass, kg, > 0) and no
    ``force_n`` is read with ``force_n = mass_kg * 9.80665`` (standard gravity),
    and ``mass_std_kg`` (the masses' standard uncertainty) as ``force_sem_n``; a
    note says so.

    ``depth_std_mm`` (standard uncertainty of ``depth_mm``, mm, >= 0) and
    ``overshoot_mm`` (certified depth minus the gauge block's nominal depth,
    mm) are optional numeric columns; ``depth_std_mm`` is not a covariate.

    Presses deeper than w/h = 0.2 are not refused here;
    :func:`tactilevision.mechanics.fit_indentation` warns about them.
    """
    path = Path(path)
    names, rows, lines = _read_table(path)
    dead_weights = "force_n" not in names and "mass_kg" in names
    if dead_weights:
        names, rows = _weights_to_forces(path, names, rows, lines)
    missing = [c for c in REQUIRED_COLUMNS if c not in names]
    if missing:
        hint = ("; it has displacement_mm: a force-depth ramp (an Instron's or a robot's "
                "loading curve) is fitted with `tactilevision fit --ramp`"
                if "displacement_mm" in names and "depth_mm" in missing else "")
        raise InputError(f"{path} line 1: missing required column(s) {', '.join(missing)} "
                         f"(found: {', '.join(names)}){hint}")
    if not rows:
        raise InputError(f"{path} has a header but no data rows")
    columns, labels = _parse_columns(path, names, rows, lines)
    depth = columns["depth_mm"]
    if np.any(depth <= 0):
        i = int(np.argmax(depth <= 0))
        raise InputError(f"{path} line {lines[i]}, column depth_mm: depth {depth[i]:g} mm "
                         "must be positive")
    force = columns["force_n"]
    notes = []
    if np.any(force <= 0):
        # a warning, not a refusal: a bad tare (the catalogue's force_offset) can put the
        # shallowest presses below zero, and diagnose must see them
        i = int(np.argmax(force <= 0))
        notes.append(f"{path} line {lines[i]}, column force_n: force {force[i]:g} N is not "
                     f"positive ({int(np.sum(force <= 0))} row(s)): a press pushes into the gel; "
                     "a sign-flipped F/T axis or a bad tare gives such forces")
    for name, limit, unit in (("depth_mm", MAX_DEPTH_MM, "mm"), ("force_n", MAX_FORCE_N, "N")):
        big = np.abs(columns[name]) > limit
        if np.any(big):
            i = int(np.argmax(big))
            raise InputError(f"{path} line {lines[i]}, column {name}: {columns[name][i]:g} {unit} "
                             f"is beyond any elastomer press (at most {limit:g} {unit}); check "
                             "the column's units")
    _check_uncertainties(path, names, rows, lines, columns)
    if dead_weights:
        notes.append(f"{path}: dead weights: force_n = mass_kg x {STANDARD_GRAVITY} m/s^2 "
                     "(standard gravity)")
    geo, src = _geometry(path, {"thickness_mm": thickness_mm, "radius_mm": radius_mm})
    certification, cert_notes = _certification_keys(path)
    cert_notes += _sidecar_notes(path)
    return Measurements(
        path=path, columns=columns, labels=labels,
        line_numbers=np.array(lines, dtype=np.int64),
        thickness_mm=geo["thickness_mm"], radius_mm=geo["radius_mm"],
        thickness_source=src["thickness_mm"], radius_source=src["radius_mm"],
        notes=tuple(notes + cert_notes), indenter=_indenter_keys(path),
        certification=certification,
    )


def sidecar_geometry(path: str | Path, *, thickness_mm: float | None = None,
                     radius_mm: float | None = None) -> tuple[float, float, dict, dict]:
    """h and the indenter's radius of a table (a measurements table, a ramp) from the options
    or the ``session.toml`` beside it, with its ``[indenter]`` keys.

    Parameters
    ----------
    path : str or Path
        The table; its sidecar is ``session.toml`` in the same folder.
    thickness_mm, radius_mm : float, optional
        Given values (mm) win over the sidecar's.

    Returns
    -------
    thickness_mm, radius_mm : float
    sources : dict of str to str
        Where each came from (``'argument'`` or the sidecar's key).
    indenter : dict
        As :attr:`Measurements.indenter`.

    Raises
    ------
    InputError
        One sentence naming what is missing (the value, and the option and sidecar key
        that give it) or bad (not a positive number, invalid TOML).

    Warns
    -----
    InputWarning
        For each table and key of the sidecar that no reader of a table's sidecar reads
        (naming the file, ``[table] key`` and the nearest known key), and on a
        rectangular pad's ``gel_width_mm`` and ``gel_length_mm``: read as the
        equal-area radius, or not read.
    """
    path = Path(path)
    geo, src = _geometry(path, {"thickness_mm": thickness_mm, "radius_mm": radius_mm})
    keys = _indenter_keys(path)
    for note in _sidecar_notes(path):
        warnings.warn(note, InputWarning, stacklevel=2)
    return geo["thickness_mm"], geo["radius_mm"], src, keys


def _sidecar(path: Path) -> tuple[Path, dict]:
    """The sidecar ``session.toml`` beside `path` and its contents ({} when absent).

    Raises
    ------
    InputError
        For a sidecar that is not valid TOML (naming the file).
    """
    toml = path.parent / "session.toml"
    if not toml.is_file():
        return toml, {}
    try:
        with toml.open("rb") as fh:
            return toml, tomllib.load(fh)
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise InputError(f"{toml} is not valid TOML: {exc}") from None


def _indenter_keys(path: Path) -> dict[str, object]:
    """``[indenter] shape, contact`` and ``[sensor] gel_radius_mm, gel_dome_radius_mm`` of
    the sidecar, if any.

    Raises
    ------
    InputError
        For a sidecar that is not valid TOML, or a ``shape`` or ``contact`` that is not a
        string (naming the file and key).
    """
    toml, doc = _sidecar(path)
    out: dict[str, object] = {}
    section = doc.get("indenter", {})
    for key in ("shape", "contact"):
        if isinstance(section, dict) and key in section:
            if not isinstance(section[key], str):
                raise InputError(f"{toml}: [indenter] {key} must be a string, got "
                                 f"{section[key]!r}")
            out[key] = section[key]
    sensor = doc.get("sensor", {})
    for key, name in (("gel_radius_mm", "pad_radius_mm"), ("gel_dome_radius_mm",
                                                            "dome_radius_mm")):
        if isinstance(sensor, dict) and key in sensor:
            out[name] = sensor[key]
    rectangle, _ = equal_area_radius(doc, toml)
    if rectangle is not None:               # a rectangular pad: the disc of the same area
        out["pad_radius_mm"] = rectangle
    return out


def _sidecar_notes(path: Path) -> list[str]:
    """Notes on the sidecar of `path`: each table and key it holds that no reader of a
    table's sidecar reads (:data:`~tactilevision.io.SIDECAR_KEYS`), with the nearest
    known one, and what was made of a rectangular pad's width and length; [] without a
    sidecar.

    Raises
    ------
    InputError
        For a sidecar that is not valid TOML, or a pad's width or length that is not a
        positive number (naming the file and key).
    """
    toml, doc = _sidecar(path)
    return (unknown_key_notes(doc, toml, SIDECAR_KEYS, skip=("certification",))
            + equal_area_radius(doc, toml)[1])


#: ``calibrate``'s depth rules, the values ``[certification] depth_rule`` takes.
DEPTH_RULES = ("vernier", "mark", "nominal", "land")


def _certification_keys(path: Path) -> tuple[dict[str, object], list[str]]:
    """``[certification]`` of the sidecar, if any, and a note for each key it does not know.

    Raises
    ------
    InputError
        For a ``depth_rule`` that is not one of :data:`DEPTH_RULES` (naming the file and
        key).
    """
    toml, doc = _sidecar(path)
    section = doc.get("certification", {})
    if not isinstance(section, dict):
        return {}, [f"{toml}: [certification] is not a table; ignored"]
    rule = section.get("depth_rule")
    if rule is not None and rule not in DEPTH_RULES:
        raise InputError(f"{toml}: [certification] depth_rule must be one of "
                         f"{', '.join(DEPTH_RULES)}, got {rule!r}")
    notes = unknown_key_notes({"certification": section}, toml, SIDECAR_KEYS)
    return {k: v for k, v in section.items() if k == "depth_rule"}, notes


#: Column order of :func:`write_measurements` (formats.md section 2); other
#: columns follow in the order given.
COLUMN_ORDER = ("press", "indenter", "depth_mm", "depth_std_mm", "depth_indenter_std_mm",
                "overshoot_mm", "force_n", "force0_n", "force_w0_n", "force_w0_sem_n",
                "bevel_force_n", "ft_zero_n", "ft_drift_n",
                "force_std_n", "force_sem_n", "fx_n", "fy_n", "time_s", "hold_s", "wait_s",
                "x_mm", "y_mm", "day", "temperature_c")


def write_measurements(path: str | Path, columns: dict[str, np.ndarray], *, thickness_mm: float,
                       radius_mm: float, digits: int = 6, depth_rule: str | None = None
                       ) -> Path:
    """Write a measurements table and its sidecar ``session.toml`` (formats.md section 2).

    Parameters
    ----------
    path : str or Path
        Destination ``.csv``; ``session.toml`` is written beside it with
        ``[sensor] gel_thickness_mm`` and ``[indenter] radius_mm``, unless
        one is there already with these values (a session's own).
    columns : dict of str to (N,) array_like
        Must hold ``depth_mm`` and ``force_n`` (finite); any other column of
        formats.md or covariate. NaN is written as an empty cell; ``press`` and
        ``indenter`` as integers.
    thickness_mm, radius_mm : float
        h and a, mm.
    digits : int, default 6
        Significant digits of the numbers.
    depth_rule : str, optional
        How the depths were certified (``calibrate``'s rule), written to a new
        sidecar as ``[certification] depth_rule``.

    Returns
    -------
    path : Path

    Raises
    ------
    InputError
        For a missing required column, columns of different lengths, a
        non-finite required value, non-positive h or a, or a ``session.toml``
        beside `path` with other values. Nothing is written then; the files
        are replaced only once complete.
    """

    path = Path(path)
    for name in REQUIRED_COLUMNS:
        if name not in columns:
            raise InputError(f"write_measurements: column {name} is required")
    arrays = {k: np.asarray(v, dtype=np.float64).ravel() for k, v in columns.items()}
    n = arrays["depth_mm"].size
    for k, v in arrays.items():
        if v.size != n:
            raise InputError(f"write_measurements: column {k} has {v.size} values, depth_mm {n}")
    for name in REQUIRED_COLUMNS:
        if not np.all(np.isfinite(arrays[name])):
            raise InputError(f"write_measurements: column {name} must be finite in every row")
    for name, v in (("thickness_mm", thickness_mm), ("radius_mm", radius_mm)):
        if not (math.isfinite(v) and v > 0):
            raise InputError(f"write_measurements: {name} must be positive, got {v!r}")
    if depth_rule is not None and depth_rule not in DEPTH_RULES:
        raise InputError(f"write_measurements: depth_rule must be one of "
                         f"{', '.join(DEPTH_RULES)}, got {depth_rule!r}")
    names = [c for c in COLUMN_ORDER if c in arrays] + [c for c in arrays if c not in COLUMN_ORDER]

    def cell(name: str, x: float) -> str:
        if not math.isfinite(x):
            return ""
        if name in ("press", "indenter"):
            return str(round(x))
        return f"{x:.{digits}g}"

    lines = [",".join(names)] + [",".join(cell(c, arrays[c][i]) for c in names)
                                 for i in range(n)]
    toml = (f"[sensor]\ngel_thickness_mm = {float(thickness_mm)!r}\n\n"
            f"[indenter]\nradius_mm = {float(radius_mm)!r}\n")
    if depth_rule is not None:
        toml += f'\n[certification]\ndepth_rule = "{depth_rule}"\n'

    side = path.parent / "session.toml"
    outputs = [(path, "\n".join(lines) + "\n")]
    if side.is_file():  # keep an existing sidecar (a session's own) when it agrees
        try:
            values, _ = _geometry(path, {"thickness_mm": None, "radius_mm": None})
        except InputError:
            values = {}
        if values != {"thickness_mm": float(thickness_mm), "radius_mm": float(radius_mm)}:
            raise InputError(f"write_measurements: {side} exists and does not hold "
                             f"gel_thickness_mm = {thickness_mm:g} and radius_mm = {radius_mm:g}; "
                             "write the table to another folder")
    else:
        outputs.append((side, toml))
    path.parent.mkdir(parents=True, exist_ok=True)
    for target, text in outputs:
        tmp = target.with_name(target.name + ".tmp")
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, target)
    return path


def read_holds(path: str | Path) -> dict[str, np.ndarray]:
    """Read ``holds.csv``: each press's force over its hold (``formats.md`` §2).

    Parameters
    ----------
    path : str or Path
        The file ``calibrate`` writes: columns ``press``, ``t_s`` (since the
        hold's start, s), ``fz_n`` (N) and, optionally, ``ramp_s`` (the
        press's loading time, s; an empty cell where it was not found).

    Returns
    -------
    columns : dict of str to (K,) ndarray
        ``press`` (int64), ``t_s``, ``fz_n`` and ``ramp_s`` (float64; NaN
        where empty or absent).

    Raises
    ------
    InputError
        Naming the file, line and column: a missing file or column, a cell
        that is not a number, an empty or non-finite ``press``, ``t_s`` or
        ``fz_n``, a negative ``t_s`` or ``ramp_s``, a ``press`` that is not a
        whole number, or no rows.
    """
    p = Path(path)
    names, rows, lines = _read_table(p, "holds table")
    for need in ("press", "t_s", "fz_n"):
        if need not in names:
            raise InputError(f"{p}: no '{need}' column (holds.csv has press, t_s, fz_n and "
                             f"ramp_s; found {', '.join(names)})")
    if not rows:
        raise InputError(f"{p} has a header but no rows")
    out: dict[str, np.ndarray] = {}
    for name in ("press", "t_s", "fz_n", "ramp_s"):
        if name not in names:
            out[name] = np.full(len(rows), np.nan)
            continue
        j = names.index(name)
        vals = np.empty(len(rows))
        for i, row in enumerate(rows):
            v = _number(row[j])
            if v is None or (name != "ramp_s" and not math.isfinite(v)):
                what = "empty" if v is not None and not row[j].strip() else f"'{row[j].strip()}'"
                raise InputError(f"{p} line {lines[i]}, column {name}: {what} is not a finite "
                                 "number")
            if name in ("t_s", "ramp_s") and v < 0:
                raise InputError(f"{p} line {lines[i]}, column {name}: {v:g} is negative")
            if name == "press" and v != int(v):
                raise InputError(f"{p} line {lines[i]}, column press: {v:g} is not a whole "
                                 "number")
            vals[i] = v
        out[name] = vals
    out["press"] = out["press"].astype(np.int64)
    return out
