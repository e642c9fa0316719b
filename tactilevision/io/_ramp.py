"""Read a force-depth ramp: one continuous loading curve from an Instron or a robot.

The file is a CSV with a header: ``displacement_mm`` (the stage's travel, increasing
into the gel) and ``force_n`` (positive into the gel) in every row, ``time_s``
optional; any other column is ignored. The contact point is not marked: the fit
(:func:`tactilevision.mechanics.fit_ramp`) finds it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._checks import InputError
from ._measurements import MAX_FORCE_N, _number, _read_table

__all__ = ["MIN_RAMP_ROWS", "RAMP_COLUMNS", "Ramp", "read_ramp"]

#: Columns every ramp must have.
RAMP_COLUMNS = ("displacement_mm", "force_n")
#: Fewest data rows a ramp may have.
MIN_RAMP_ROWS = 10


@dataclass(frozen=True)
class Ramp:
    """A force-depth ramp as read, every row kept (loading and unloading alike).

    Attributes
    ----------
    path : Path
        The file read.
    displacement_mm : (N,) float64 ndarray
        Stage travel z, mm, increasing into the gel (any zero: the contact
        point is fitted, not read).
    force_n : (N,) float64 ndarray
        Normal force P, N, positive into the gel (any baseline: it is fitted).
    time_s : (N,) float64 ndarray or None
        Time of each row, s, non-decreasing; None when the file has no
        ``time_s`` column.
    line_numbers : (N,) int64 ndarray
        Line of the file each row was read from (the header is line 1).
    """

    path: Path
    displacement_mm: np.ndarray = field(repr=False, hash=False)
    force_n: np.ndarray = field(repr=False, hash=False)
    time_s: np.ndarray | None = field(repr=False, hash=False)
    line_numbers: np.ndarray = field(repr=False, hash=False)

    def __len__(self) -> int:
        return int(self.displacement_mm.shape[0])


def _finite_column(path: Path, name: str, cells: list[str], lines: list[int]) -> np.ndarray:
    """One column's cells as finite floats, or the InputError naming the first bad cell."""
    out = np.empty(len(cells))
    for i, text in enumerate(cells):
        v = _number(text)
        if v is None:
            raise InputError(f"{path} line {lines[i]}, column {name}: '{text.strip()}' is not "
                             "a number")
        if not math.isfinite(v):
            what = "empty cell" if not text.strip() else f"'{text.strip()}'"
            raise InputError(f"{path} line {lines[i]}, column {name}: {what} is not a finite "
                             "number (a ramp needs one in every row)")
        out[i] = v
    return out


def read_ramp(path: str | Path) -> Ramp:
    """Read a force-depth ramp CSV (``docs/guide/ramps.md``).

    Parameters
    ----------
    path : str or Path
        The CSV: a header line, then one row per sample. ``displacement_mm``
        (mm, increasing into the gel) and ``force_n`` (N, positive into the
        gel) are required, ``time_s`` (s) is optional; other columns are
        ignored. Blank lines are skipped.

    Returns
    -------
    Ramp
        Every row, in file order: loading and unloading (the fit keeps the
        loading part).

    Raises
    ------
    InputError
        With one sentence naming the file and, where there is one, the line
        and column: the file missing or unreadable, a missing required column,
        a row of the wrong length, a cell that is not a number (quoted), an
        empty or non-finite value in ``displacement_mm``, ``force_n`` or
        ``time_s``, a force beyond 1e4 N in size (a unit error), a ``time_s``
        that goes back, or fewer than 10 data rows.

    Examples
    --------
    >>> ramp = read_ramp("ramp.csv")                       # doctest: +SKIP
    >>> ramp.displacement_mm.shape == ramp.force_n.shape   # doctest: +SKIP
    True
    """
    path = Path(path)
    names, rows, lines = _read_table(path, "ramp")
    missing = [c for c in RAMP_COLUMNS if c not in names]
    if missing:
        raise InputError(f"{path} line 1: missing required column(s) {', '.join(missing)} "
                         f"(a ramp has displacement_mm, force_n and optionally time_s; found: "
                         f"{', '.join(names)})")
    if len(rows) < MIN_RAMP_ROWS:
        raise InputError(f"{path} has {len(rows)} data row(s) after its header (line 1): a "
                         f"ramp needs at least {MIN_RAMP_ROWS}")
    cols = {name: _finite_column(path, name, [r[names.index(name)] for r in rows], lines)
            for name in (*RAMP_COLUMNS, "time_s") if name in names}
    force = cols["force_n"]
    big = np.abs(force) > MAX_FORCE_N
    if np.any(big):
        i = int(np.argmax(big))
        raise InputError(f"{path} line {lines[i]}, column force_n: {force[i]:g} N is beyond "
                         f"any elastomer press (at most {MAX_FORCE_N:g} N); check the column's "
                         "units")
    time = cols.get("time_s")
    if time is not None and np.any(np.diff(time) < 0):
        i = int(np.argmax(np.diff(time) < 0)) + 1
        raise InputError(f"{path} line {lines[i]}, column time_s: {time[i]:g} s is earlier "
                         f"than the row before it ({time[i - 1]:g} s)")
    return Ramp(path=path, displacement_mm=cols["displacement_mm"], force_n=force,
                time_s=time, line_numbers=np.array(lines, dtype=np.int64))
