"""The keys of ``session.toml`` this version reads, and one rule for those it does not.

Every reader of a ``session.toml`` (a session folder, a dead-weights folder, the sidecar
of a measurements table or of a ramp, a design, a calibration folder's copy) names the
tables and keys it does not read, each with the nearest known one
(:func:`difflib.get_close_matches`), so that a typo in an optional key never falls back to
its default without a word (formats.md section 1). Readers that return notes (a session,
a measurements table) carry these sentences in their notes, which the command line prints
as warnings; the others warn them (:class:`~tactilevision.InputWarning`).
"""

from __future__ import annotations

import difflib
import math
import warnings
from collections.abc import Collection, Mapping
from pathlib import Path
from typing import Any

from .._checks import InputError, InputWarning

__all__ = ["KNOWN_KEYS", "SIDECAR_KEYS", "equal_area_radius", "unknown_key_notes",
           "warn_unknown_keys"]

#: The keys of session.toml this version reads, per table (formats.md section 1).
KNOWN_KEYS: dict[str, tuple[str, ...]] = {
    "sensor": ("name", "mm_per_px", "gel_thickness_mm", "gel_radius_mm", "gel_dome_radius_mm",
               "gel_width_mm", "gel_length_mm"),
    "indenter": ("radius_mm", "shape", "contact"),
    "gauge_block": ("depths_mm", "bevel_offset_mm", "bevel_direction_deg", "bevel_angle_deg",
                    "bevel_length_mm", "bulge_correction", "bevel_force_correction",
                    "max_overshoot_mm", "depth_tolerance_mm"),
    "force_sensor": ("rate_hz", "clock_offset_s", "window_samples", "window_at"),
    "optics": ("calibration",),
    "session": ("date",),
}

#: The keys of the sidecar ``session.toml`` of a measurements table or a ramp (formats.md
#: section 2): a session's keys and ``[certification] depth_rule``, which ``calibrate``
#: writes. A key of a session that the table's reader does not use is no mistake.
SIDECAR_KEYS: dict[str, tuple[str, ...]] = {**KNOWN_KEYS, "certification": ("depth_rule",)}

#: How close a name must be to a known one to be offered as meant (difflib's ratio).
CUTOFF = 0.75


def unknown_key_notes(doc: Mapping[str, Any], toml: str | Path,
                      known: Mapping[str, Collection[str]], *,
                      unset: str = "it stays unset",
                      skip: Collection[str] = ()) -> list[str]:
    """One sentence per table and key of `doc` that `known` does not list.

    Parameters
    ----------
    doc : mapping
        The parsed TOML document.
    toml : str or Path
        The file it was read from, named in each sentence.
    known : mapping of str to collection of str
        The tables a reader reads, each with its keys.
    unset : str, default 'it stays unset'
        What becomes of the key meant, said after the nearest known key.
    skip : collection of str, default ()
        Tables the caller checks itself (not reported here).

    Returns
    -------
    notes : list of str
        ``'<toml>: [table] key is not a key tactilevision reads (did you mean near?
        <unset>)'`` per unknown key, ``'<toml>: table [name] is not read by tactilevision
        (did you mean [near]?)'`` per unknown table, and for a key outside every table
        ``'<toml>: key name (outside any table) is not read by tactilevision (did you mean
        [table] near?)'``; the hint only where a known name is close
        (:data:`CUTOFF`).

    Examples
    --------
    >>> notes = unknown_key_notes({"sensor": {"mm_per_pix": 0.03}}, "s.toml", KNOWN_KEYS)
    >>> print(notes[0])
    s.toml: [sensor] mm_per_pix is not a key tactilevision reads (did you mean mm_per_px? it
    stays unset)
    """
    notes = []
    for table, section in doc.items():
        if table in skip:
            continue
        if not isinstance(section, dict):
            if table in known:
                continue                # the reader refuses a key that should be a table
            flat = {key: t for t, keys in known.items() for key in keys}
            near = difflib.get_close_matches(table, list(flat), n=1, cutoff=CUTOFF)
            hint = f" (did you mean [{flat[near[0]]}] {near[0]}?)" if near else ""
            notes.append(f"{toml}: key {table} (outside any table) is not read by "
                         f"tactilevision{hint}")
            continue
        if table not in known:
            near = difflib.get_close_matches(table, list(known), n=1, cutoff=CUTOFF)
            hint = f" (did you mean [{near[0]}]?)" if near else ""
            notes.append(f"{toml}: table [{table}] is not read by tactilevision{hint}")
            continue
        for key in section:
            if key not in known[table]:
                near = difflib.get_close_matches(key, list(known[table]), n=1, cutoff=CUTOFF)
                hint = f" (did you mean {near[0]}? {unset})" if near else ""
                notes.append(f"{toml}: [{table}] {key} is not a key tactilevision reads{hint}")
    return notes


def warn_unknown_keys(doc: Mapping[str, Any], toml: str | Path,
                      known: Mapping[str, Collection[str]], *,
                      unset: str = "it stays unset", skip: Collection[str] = (),
                      stacklevel: int = 2) -> list[str]:
    """Warn each sentence of :func:`unknown_key_notes` (:class:`~tactilevision.InputWarning`).

    Parameters
    ----------
    doc, toml, known, unset, skip
        As :func:`unknown_key_notes`.
    stacklevel : int, default 2
        As :func:`warnings.warn`, counted from the caller of this function.

    Returns
    -------
    notes : list of str
        The sentences warned.
    """
    notes = unknown_key_notes(doc, toml, known, unset=unset, skip=skip)
    for note in notes:
        warnings.warn(note, InputWarning, stacklevel=stacklevel + 1)
    return notes


def equal_area_radius(doc: Mapping[str, Any], toml: str | Path
                      ) -> tuple[float | None, list[str]]:
    """A rectangular pad's ``[sensor] gel_width_mm`` and ``gel_length_mm`` as the radius
    of the disc of the same area, sqrt(width length / pi).

    Parameters
    ----------
    doc : mapping
        The parsed ``session.toml``.
    toml : str or Path
        The file it was read from, named in the notes and errors.

    Returns
    -------
    radius_mm : float or None
        The equal-area radius, mm, where both keys are given and ``[sensor] gel_radius_mm``
        is not; else None.
    notes : list of str
        What was made of the two keys: read as the equal-area radius, or not read (one
        without the other, or beside ``gel_radius_mm``, which wins); empty without them.

    Raises
    ------
    InputError
        For a width or length that is not a positive number (naming the file and key).
    """
    sensor = doc.get("sensor")
    if not isinstance(sensor, dict):
        return None, []
    given = {key: sensor[key] for key in ("gel_width_mm", "gel_length_mm") if key in sensor}
    if not given:
        return None, []
    for key, v in given.items():
        if isinstance(v, bool) or not isinstance(v, int | float) or not (
                math.isfinite(v) and v > 0):
            raise InputError(f"{toml}: [sensor] {key} must be a positive number, got {v!r}")
    names = " and ".join(f"[sensor] {key}" for key in given)
    if "gel_radius_mm" in sensor:
        return None, [f"{toml}: {names} {'are' if len(given) == 2 else 'is'} not read: "
                      "[sensor] gel_radius_mm gives the pad's radius"]
    if len(given) == 1:
        other = "gel_length_mm" if "gel_width_mm" in given else "gel_width_mm"
        return None, [f"{toml}: {names} is not read without [sensor] {other} (a rectangular "
                      "pad is read as the disc of the same area, which needs both)"]
    width, length = float(given["gel_width_mm"]), float(given["gel_length_mm"])
    radius = math.sqrt(width * length / math.pi)
    return radius, [f"{toml}: the rectangular pad [sensor] gel_width_mm x gel_length_mm = "
                    f"{width:g} x {length:g} mm is read as the disc of the same area, "
                    f"gel_radius_mm = sqrt(width x length / pi) = {radius:.4g} mm, the pad's "
                    "radius wherever a model takes the pad's size"]
