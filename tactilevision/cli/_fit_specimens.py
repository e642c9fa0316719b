"""``tactilevision fit a.csv b.csv ...`` (or a table with a ``specimen`` column): each
specimen or repeat fitted on its own, then the batch's E with the spread between them
(:func:`~tactilevision.mechanics.pool_specimens`)."""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

from .. import InputError
from ..io import Measurements, read_measurements
from ..mechanics import SpecimenPool, pool_specimens
from ._fit_indenter import fit_laws, run_ramp

__all__ = ["SPECIMEN_COLUMN", "fit_specimens", "specimen_groups", "specimen_lines",
           "table_specimens"]

#: The measurements table's column that names each row's specimen (formats.md §2).
SPECIMEN_COLUMN = "specimen"


def specimen_groups(table: Measurements) -> list[tuple[str, np.ndarray]]:
    """The rows of each specimen of `table` (its ``specimen`` column, text or numbers), in
    order of first appearance; one group of every row without the column.

    Raises
    ------
    InputError
        Naming the file and line: a row with an empty ``specimen`` cell.
    """
    if SPECIMEN_COLUMN in table.labels:
        values = [str(v) for v in table.labels[SPECIMEN_COLUMN]]
    elif SPECIMEN_COLUMN in table.columns:
        col = table.columns[SPECIMEN_COLUMN]
        values = ["" if not np.isfinite(v) else f"{v:g}" for v in col]
    else:
        return [("", np.arange(table.depth_mm.size))]
    empty = [i for i, v in enumerate(values) if not v]
    if empty:
        raise InputError(f"{table.path} line {int(table.line_numbers[empty[0]])}, column "
                         f"{SPECIMEN_COLUMN}: empty (every row names its specimen, or none "
                         "does)")
    order = list(dict.fromkeys(values))
    return [(v, np.array([i for i, x in enumerate(values) if x == v])) for v in order]


def _cut(table: Measurements, rows: np.ndarray) -> Measurements:
    cols = {k: np.asarray(v)[rows] for k, v in table.columns.items()}
    labels = {k: tuple(v[i] for i in rows) for k, v in table.labels.items()}
    return replace(table, columns=cols, labels=labels, line_numbers=table.line_numbers[rows])


def _fit_one(table: Measurements, args: argparse.Namespace, fit_flat) -> dict:
    """One specimen's fit as its JSON object (flat punch through `fit_flat`, a ball through
    its laws)."""
    shape = args.shape or table.indenter.get("shape", "flat_punch")
    if shape == "flat_punch":
        return fit_flat(table).to_json_dict()
    std = table.columns.get("depth_std_mm")
    std = None if args.ignore_depth_std or std is None or np.any(np.isnan(std)) else std
    fit, _, _ = fit_laws(table, args, std)
    return fit.to_json_dict()


def fit_specimens(paths: list[Path], args: argparse.Namespace, fit_flat
                  ) -> tuple[list[tuple[str, dict]], list[tuple[str, str]], SpecimenPool | None]:
    """Each specimen's fit, those left out of the pool and why, and the pool.

    Parameters
    ----------
    paths : list of Path
        The tables (or, with ``--ramp``, the ramps): one specimen each, or several in
        a table's ``specimen`` column.
    args : argparse.Namespace
        ``fit``'s options.
    fit_flat : callable
        ``fit_flat(table) -> IndentationFit``: the flat punch's fit of one table as
        ``fit`` makes it.

    Returns
    -------
    fits : list of (str, dict)
        Each specimen's label and fit JSON object.
    left_out : list of (str, str)
        Specimens whose E is not a measurement (out of the table, not identified, no
        interval), and why.
    pool : SpecimenPool or None
        None with fewer than two specimens left.
    """
    fits: list[tuple[str, dict]] = []
    stems = [p.stem for p in paths]
    for path in paths:
        name = path.stem if stems.count(path.stem) == 1 else str(path)
        if args.ramp:
            obj, _ = run_ramp(args, path)
            fits.append((name, obj))
            continue
        table = read_measurements(path, thickness_mm=args.thickness_mm,
                                  radius_mm=args.radius_mm)
        for note in table.notes:        # the sidecar's unread keys among them
            print(f"tactilevision fit: warning: {note}", file=sys.stderr)
        for label, rows in specimen_groups(table):
            sub = table if not label else _cut(table, rows)
            tag = label if len(paths) == 1 else (f"{name}:{label}" if label else name)
            try:
                fits.append((tag, _fit_one(sub, args, fit_flat)))
            except InputError as exc:
                raise InputError(f"specimen {tag}: {exc}") from None
    left_out, keep = [], []
    for tag, obj in fits:
        E, ci = obj.get("E_mpa"), obj.get("E_ci95_mpa") or [None, None]
        ok = (E is not None and all(v is not None for v in ci) and 0 < ci[0] <= E <= ci[1]
              and obj.get("E_identified", True) and obj.get("identified", True))
        if ok:
            keep.append((tag, E, ci))
        else:
            left_out.append((tag, "its E is not a measurement (out of the table, not "
                                  "identified, or no interval)"))
    pool = None
    if len(keep) >= 2:
        pool = pool_specimens([k[0] for k in keep], [k[1] for k in keep],
                              [k[2] for k in keep])
    return fits, left_out, pool


def specimen_lines(fits: list[tuple[str, dict]], left_out: list[tuple[str, str]],
                   pool: SpecimenPool | None) -> list[str]:
    """The printed summary of a fit of several specimens."""
    lines = [f"{len(fits)} specimens, each fitted on its own:"]
    for tag, obj in fits:
        E, ci = obj.get("E_mpa"), obj.get("E_ci95_mpa") or [None, None]
        e_txt = ("E not computed" if E is None or not math.isfinite(E) else
                 f"E = {E:.4f} MPa [{ci[0]:.4f}, {ci[1]:.4f}]" if None not in ci else
                 f"E = {E:.4f} MPa")
        n = obj.get("n_presses") or obj.get("n_points")
        warn = " (WARNING: misfit)" if (obj.get("misfit") or {}).get("warning") else ""
        lines.append(f"  {tag}: {e_txt}" + (f", {n} presses" if n else "") + warn)
    for tag, why in left_out:
        lines.append(f"  left out of the batch: {tag}: {why}")
    if pool is None:
        lines.append("  fewer than two specimens give an E: no batch E")
    else:
        lines.append(f"  {pool.message}")
    return lines


def table_specimens(table: Measurements, args: argparse.Namespace, fit_flat
                    ) -> tuple[dict | None, list[str]]:
    """A table's specimens (its ``specimen`` column) fitted on their own and pooled, for
    ``diagnose``: the JSON object and the summary lines; (None, []) with one specimen."""
    if len(specimen_groups(table)) < 2:
        return None, []
    fits, left_out, pool = [], [], None
    for label, rows in specimen_groups(table):
        try:
            fits.append((label, _fit_one(_cut(table, rows), args, fit_flat)))
        except InputError as exc:
            left_out.append((label, str(exc)))
    keep = [(t, o["E_mpa"], o["E_ci95_mpa"]) for t, o in fits
            if o.get("E_mpa") is not None and None not in (o.get("E_ci95_mpa") or [None])
            and 0 < o["E_ci95_mpa"][0] <= o["E_mpa"] <= o["E_ci95_mpa"][1]]
    left_out += [(t, "its E is not a measurement") for t, o in fits
                 if t not in {k[0] for k in keep}]
    if len(keep) >= 2:
        pool = pool_specimens([k[0] for k in keep], [k[1] for k in keep],
                              [k[2] for k in keep])
    obj = {"fits": dict(fits), "left_out": [{"specimen": t, "why": w} for t, w in left_out],
           "pool": None if pool is None else pool.to_json_dict()}
    return obj, specimen_lines(fits, left_out, pool)
