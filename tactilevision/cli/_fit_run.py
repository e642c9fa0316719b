"""What ``tactilevision fit`` does once its options are parsed
(:mod:`tactilevision.cli._fit`): E and nu from a measurements table (formats.md §3).

Imported only when the command runs, so that its ``--help`` does not load this stack.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

from .. import InputError
from ..diagnosis import crossing_measurements, stated_weights
from ..io import Measurements, read_holds, read_measurements, write_output_file
from ..mechanics import (
    APPARENT_E,
    APPARENT_E_WHY,
    BETA_TABLE_REACH,
    IndentationFit,
    RelaxationFit,
    check_fit_effects,
    fit_indentation,
    fit_model,
    fit_relaxation,
    instantaneous_forces,
    model_label,
    past_beta_table_reach,
    relaxed_moduli,
)
from ._fit_indenter import note_lines, run_indenter, run_ramp
from ._fit_specimens import SPECIMEN_COLUMN, fit_specimens, specimen_lines

__all__ = ["CROSSINGS_DATA", "depth_uncertainty", "relaxation_lines", "run", "summary"]


def _fmt_ci(ci: tuple[float | None, float | None], digits: int) -> str:
    lo, hi = (float("nan") if v is None else v for v in ci)
    return f"[{lo:.{digits}f}, {hi:.{digits}f}]"


def summary(fit: IndentationFit, path: Path) -> str:
    """Human-readable summary of a fit, a few lines.

    Parameters
    ----------
    fit : IndentationFit
    path : Path
        The table the fit came from.

    Returns
    -------
    text : str
    """
    pct = f"{fit.confidence:.0%}"
    lines = [
        f"{path}: {fit.n_presses} presses, h = {fit.thickness_mm:g} mm, "
        f"a = {fit.radius_mm:g} mm, kappa read at a/h = {fit.a_over_h:.4f}",
        f"  eq. (5) P/w = c beta (w/h) + c: c = {fit.c_n_per_mm:.4f} N/mm, "
        f"beta = {fit.beta:.4f} {pct} CI {_fmt_ci(fit.beta_ci95, 4)}, "
        f"R^2 = {fit.r_squared:.5f}, rmse = {fit.rmse_n:.4g} N",
    ]
    if not fit.identified:
        lines.insert(1, f"  NOT IDENTIFIED by this table: {', '.join(fit.unidentified)}; "
                        "E and nu below are not determined by the data")
    if fit.depth_std_used:
        lines.append(f"  depth uncertainty: depth_std_mm used (median "
                     f"{fit.depth_std_median_mm * 1e3:.3g} um), errors in both variables "
                     f"(effective variance); extra force scatter sigma0 = "
                     f"{fit.sigma0_n * 1e3:.3g} mN")
    extra = {k: v for k, v in fit.effect_params.items() if k != "beta"}
    lines.append(f"  model: {model_label(fit.effects)}"
                 + ("; " + ", ".join(f"{k} = {v:.4g}" for k, v in extra.items())
                    if extra else ""))
    if fit.out_of_table:
        lines.append(f"  OUT OF TABLE: {fit.out_of_table_message}")
        if fit.beta_table == "fem":
            lines.append("  (a Neo-Hookean layer does not stiffen this much here; "
                         "--beta-table paper reads the paper's relation (7) instead)")
    else:
        lines += [
            f"  E  = {fit.E_mpa:.4f} MPa  {pct} CI {_fmt_ci(fit.E_ci95_mpa, 4)} MPa",
            f"  nu = {fit.nu:.4f}      {pct} CI {_fmt_ci(fit.nu_ci95, 4)}"
            + (f"  (at the table's edge: {fit.nu_bound}, a bound, not a value)"
               if fit.nu_bound else ""),
            f"  Neo-Hookean (Abaqus): C10 = {fit.C10_mpa:.4f} MPa, "
            f"D1 = {fit.D1_per_mpa:.4f} 1/MPa",
        ]
    if fit.beta_table == "fem":
        lines.append(f"  beta and kappa: FEM tables, {fit.contact} punch (models/beta_fem.npz, "
                     "kappa_fem.npz)")
    else:
        lines.append("  beta: the paper's relation (7); kappa: Hayes 1972 (frictionless)")
    lines += note_lines(tuple(n for n in fit.notes
                              if not n.startswith(("intervals:", "beta table",
                                                   "errors in both variables"))
                              and n != fit.out_of_table_message))
    return "\n".join(lines)


def relaxation_lines(relax: RelaxationFit, moduli: dict | None, holds: Path, *,
                     e_finite: bool = True) -> list[str]:
    """The summary's lines on the relaxation fitted to ``holds.csv``.

    Parameters
    ----------
    relax : RelaxationFit
    moduli : dict or None
        :func:`~tactilevision.mechanics.relaxed_moduli`'s result; None when
        no relaxation was resolved (the forces were left as they are) or E
        was not computed.
    holds : Path
        The holds file.
    e_finite : bool, default True
        Whether the fit gave an E (not out of the beta table).

    Returns
    -------
    lines : list of str
    """
    pct = f"{relax.confidence:.0%}"
    if relax.identified:
        lines = [f"  relaxation ({holds}, {relax.n_presses} presses, standard linear solid after "
                 f"a linear ramp): g = {relax.g:.4f} {pct} CI {_fmt_ci(relax.g_ci, 4)}, tau = "
                 f"{relax.tau_s:.4g} s {pct} CI {_fmt_ci(relax.tau_ci_s, 3)} s, rmse = "
                 f"{relax.rmse_n * 1e3:.3g} mN"]
    else:
        lines = [f"  relaxation ({holds}, {relax.n_presses} presses): {relax.verdict}, g and "
                 "tau not identified"]
    if not relax.resolved:
        lines.append(f"  {relax.why}: the forces are used as they are")
        if relax.verdict == "decay not identified":
            lines.append(f"  E above is {APPARENT_E_WHY}")
    elif moduli is None:
        lines.append("  the forces were taken back to the instant of loading"
                     + ("" if e_finite else ", but E was not computed: no E_0 or E_inf"))
    else:
        lines.append(f"  E above is E_0, the instantaneous modulus (each force taken back to "
                     f"the instant of loading); relaxed E_inf = (1 - g) E_0 = "
                     f"{moduli['E_inf_mpa']:.4f} MPa {pct} CI "
                     f"{_fmt_ci(moduli['E_inf_ci_mpa'], 4)} MPa (E_0 with g's and tau's "
                     f"uncertainty: {_fmt_ci(moduli['E0_ci_mpa'], 4)} MPa)")
    lines += [f"  note: {n}" for n in relax.notes if n != relax.why]
    return lines


def _fit_table(table: Measurements, effects: tuple[str, ...], args: argparse.Namespace,
               depth_std: np.ndarray | None, weights: np.ndarray | None):
    """The fit of `table` (eq. 5 alone with the depths' uncertainties, else the model with
    `effects` by robust least squares, `weights` per press: 1 / sd^2 of the stated noise,
    which the intervals then do not go below) and the warnings it raised."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            if effects == ("large_deformation",) and weights is None:
                fit = fit_indentation(table.depth_mm, table.force_n,
                                      thickness_mm=table.thickness_mm,
                                      radius_mm=table.radius_mm,
                                      beta_table=args.beta_table, a_over_h=args.a_over_h,
                                      depth_std_mm=depth_std,
                                      **_indenter_shared(table, depth_std))
            else:
                fit, _ = fit_model(table.columns, ",".join(effects),
                                   thickness_mm=table.thickness_mm, radius_mm=table.radius_mm,
                                   beta_table=args.beta_table, a_over_h=args.a_over_h,
                                   weights=weights, stated_noise=weights is not None)
        except InputError as exc:
            raise InputError(f"{table.path}: {exc}") from None
    return fit, caught


def _indenter_shared(table: Measurements, depth_std: np.ndarray | None) -> dict:
    """The table's ``indenter`` and ``depth_indenter_std_mm`` (the depth error each
    indenter's presses share, as calibrate's mark rule writes it) for
    :func:`~tactilevision.mechanics.fit_indentation`, where the table states a shared part;
    else nothing."""
    cols = table.columns
    if depth_std is None or "indenter" not in cols or "depth_indenter_std_mm" not in cols:
        return {}
    ui = np.asarray(cols["depth_indenter_std_mm"], np.float64)
    ind = np.asarray(cols["indenter"], np.float64)
    if not (np.all(np.isfinite(ui)) and np.all(np.isfinite(ind)) and np.any(ui > 0)):
        return {}
    return {"indenter": ind, "depth_indenter_std_mm": np.minimum(ui, depth_std)}


#: What ``fit --crossings`` fits, in words (the summary and the JSON's ``data``).
CROSSINGS_DATA = ("the crossing forces: each press's force where it crossed its indenter's "
                  "w0, a depth the frames certify apart from the force, weighted by its "
                  "stated sd (force_w0_sem_n), the intervals no narrower than that sd makes "
                  "them")


def _rows(table: Measurements, rows: np.ndarray, columns: dict | None = None
          ) -> Measurements:
    """`table` cut to `rows` (indices), its labels and line numbers with it; `columns`
    (already cut) in place of its own where given."""
    cols = columns if columns is not None else {
        k: np.asarray(v)[rows] for k, v in table.columns.items()}
    labels = {k: tuple(v[i] for i in rows) for k, v in table.labels.items()}
    return replace(table, columns=cols, labels=labels, line_numbers=table.line_numbers[rows])


def _crossing_table(table: Measurements, args: argparse.Namespace
                    ) -> tuple[Measurements, np.ndarray]:
    """``--crossings``: the table of the presses' crossing forces
    (:func:`~tactilevision.diagnosis.crossing_measurements`) and its weights."""
    if args.holds is not None:
        raise InputError("--crossings and --holds: give one (the holds' relaxation reads the "
                         "force windows)")
    try:
        cols = crossing_measurements(table.columns)
    except InputError as exc:
        raise InputError(f"{table.path}: --crossings: {exc}") from None
    rows = cols.pop("row")
    return _rows(table, rows, cols), 1.0 / np.asarray(cols["force_sem_n"], np.float64) ** 2


def _within_reach(table: Measurements, args: argparse.Namespace, weights: np.ndarray | None
                  ) -> tuple[Measurements, np.ndarray | None, list[int]]:
    """With the FEM beta table, the rows certified past its reach by more than two of their
    ``depth_std_mm`` (:func:`~tactilevision.mechanics.past_beta_table_reach`) left out, as
    ``calibrate`` leaves them out of its fit, with a warning naming their lines; the
    table, its weights and the lines left out."""
    h = table.thickness_mm
    std = None if args.ignore_depth_std else table.columns.get("depth_std_mm")
    if args.beta_table != "fem" or not h > 0:
        return table, weights, []
    past = past_beta_table_reach(table.depth_mm, h, std)
    if not past.any() or past.all():
        return table, weights, []       # all past: the fit's own error says what to do
    lines = [int(x) for x in table.line_numbers[past]]
    print(f"tactilevision fit: warning: {table.path}: line(s) "
          + ", ".join(f"{n} (w/h {w / h:.3f})" for n, w in zip(lines, table.depth_mm[past],
                                                              strict=True))
          + f" lie past the FEM beta table's reach (w/h {BETA_TABLE_REACH:g}) by more than "
          "two of their depth uncertainties: left out of the fit, as calibrate does "
          "(--beta-table paper reads them)", file=sys.stderr)
    keep = np.flatnonzero(~past)
    return _rows(table, keep), None if weights is None else weights[keep], lines


def _relax_table(table: Measurements, holds_path: Path, effects: tuple[str, ...]
                 ) -> tuple[Measurements, RelaxationFit, bool]:
    """Fit the holds; the table with its forces taken to the instant of loading."""

    if "viscoelastic_relaxation" in effects:
        raise InputError("--holds and --effects viscoelastic_relaxation both model the "
                         "relaxation: give one")
    hold = table.columns.get("hold_s")
    if hold is None or not np.all(np.isfinite(hold)):
        raise InputError(f"{table.path}: --holds needs a hold_s in every row (the time from "
                         "reaching depth to the middle of the force window)")
    holds = read_holds(holds_path)
    # the table's presses' times and indenters tell softening from relaxation
    press, t = table.columns.get("press"), table.columns.get("time_s")
    times = groups = None
    if press is not None and t is not None:
        ok = np.isfinite(press) & np.isfinite(t)
        times = {int(p): float(v) for p, v in zip(press[ok], t[ok], strict=True)}
        ind = table.columns.get("indenter")
        if ind is None and "indenter" in table.labels:
            ind = np.array(table.labels["indenter"], dtype=object)
        if ind is not None:
            groups = {int(p): g for p, g, k in zip(press, ind, ok, strict=True) if k}
    try:
        relax = fit_relaxation(holds["press"], holds["t_s"], holds["fz_n"], holds["ramp_s"],
                               press_time_s=times, press_group=groups)
    except InputError as exc:
        raise InputError(f"{holds_path}: {exc}") from None
    if not relax.resolved:
        return table, relax, False
    given = table.columns.get("force0_n")
    if given is not None and np.all(np.isfinite(given)) and np.all(given > 0):
        f0 = given                  # calibrate's: from the elastic force behind the log
    else:
        f0 = instantaneous_forces(table.force_n, hold, relax, table.columns.get("press"))
    return replace(table, columns={**table.columns, "force_n": f0}), relax, True


def depth_uncertainty(table: Measurements, *, ignore: bool, effects: tuple[str, ...]
                      ) -> tuple[np.ndarray | None, str | None]:
    """The depth uncertainties the fit uses, and what it says of them.

    Parameters
    ----------
    table : Measurements
    ignore : bool
        ``--ignore-depth-std``.
    effects : tuple of str
        The model's effects: eq. (5) alone takes the uncertainties as errors in both
        variables; a model with effects as weights (:func:`_effects_weights`).

    Returns
    -------
    depth_std_mm : (N,) float64 ndarray, mm, or None
        The table's ``depth_std_mm`` when it has a value in every row and the
        option is off; else None.
    message : str or None
        One sentence for stderr: why the column is there but not used (other than
        the option), or how a model with effects uses it.
    """
    u = table.columns.get("depth_std_mm")
    if u is None or ignore:
        return None, None
    empty = np.isnan(u)
    if np.any(empty):
        i = int(np.argmax(empty))
        return None, (f"depth_std_mm is empty in {int(empty.sum())} of {u.size} rows (first at "
                      f"line {int(table.line_numbers[i])}): fitted without the depth "
                      "uncertainties")
    if effects != ("large_deformation",):
        return u, ("the model with effects weighs each press by its stated noise "
                   "(force_sem_n and depth_std_mm x dP/dw of eq. (5)), its intervals no "
                   "narrower than that noise makes them")
    return u, None


def _effects_weights(table: Measurements, effects: tuple[str, ...],
                     depth_std: np.ndarray | None, weights: np.ndarray | None,
                     message: str | None) -> tuple[np.ndarray | None, str | None]:
    """A model with effects weighs each press by its stated noise
    (:func:`~tactilevision.diagnosis.stated_weights`) where the table states it and no
    other weights are given (``--crossings``'); returns the weights and the message."""
    if weights is not None or depth_std is None or effects == ("large_deformation",):
        return weights, message
    weights = stated_weights(table.depth_mm, table.force_n, depth_std,
                             table.columns.get("force_sem_n"))
    if weights is None:
        message = ("the stated noise (force_sem_n, depth_std_mm) is zero at some press: the "
                   "model with effects is fitted without it")
    return weights, message


def _write_json(obj: dict, dest: str) -> None:
    text = json.dumps(obj, indent=2, allow_nan=False) + "\n"
    if dest == "-":
        sys.stdout.write(text)
        return
    # checked before any work (the command line's single-file rule, tactilevision.cli.main):
    # written whole, the old file intact until the new one is complete, and listed in the
    # folder's manifest so that a rerun may replace it
    write_output_file(dest, text, overwrite=True)


def _run_indenter(args: argparse.Namespace, table: Measurements, path: Path,
                  effects: tuple[str, ...]) -> int:
    """``fit`` of a ball (any indenter but the flat punch)."""
    if effects != ("large_deformation",) or args.holds is not None or args.crossings:
        raise InputError(f"{path}: --effects, --holds and --crossings fit the flat punch's "
                         f"eq. (5) (crossing forces come from a gauge block's mark); a "
                         f"{args.shape or table.indenter.get('shape')}'s presses take --law "
                         "(finite strain: neo_hookean) and --nu")
    depth_std, std_message = depth_uncertainty(table, ignore=args.ignore_depth_std,
                                               effects=effects)
    obj, lines = run_indenter(args, table, path, depth_std)
    for note in table.notes:
        print(f"tactilevision fit: warning: {note}", file=sys.stderr)
    if std_message is not None:
        print(f"tactilevision fit: warning: {path}: {std_message}", file=sys.stderr)
    obj["measurements"] = str(path)
    obj["thickness_source"] = table.thickness_source
    obj["radius_source"] = table.radius_source
    if args.json is not None:
        _write_json(obj, args.json)
    if args.json != "-":
        print("\n".join(lines))
    return _verdict_status(obj, path)


def _run_ramp(args: argparse.Namespace, path: Path, effects: tuple[str, ...]) -> int:
    """``fit --ramp`` of one ramp."""
    if effects != ("large_deformation",) or args.holds is not None:
        raise InputError(f"{path}: --ramp fits the indenter's own law; --effects and "
                         "--holds are for a measurements table")
    obj, lines = run_ramp(args, path)
    obj["ramp"] = str(path)
    if args.json is not None:
        _write_json(obj, args.json)
    if args.json != "-":
        print("\n".join(lines))
    return _verdict_status(obj, path)


def _has_specimens(path: Path, args: argparse.Namespace) -> bool:
    """Whether the table has a ``specimen`` column (read once more by the fit)."""
    table = read_measurements(path, thickness_mm=args.thickness_mm, radius_mm=args.radius_mm)
    return SPECIMEN_COLUMN in table.columns or SPECIMEN_COLUMN in table.labels


def _run_specimens(args: argparse.Namespace, paths: list[Path],
                   effects: tuple[str, ...]) -> int:
    """``fit`` of several specimens: each on its own, then the batch's E."""
    if args.holds is not None or args.crossings:
        raise InputError("--holds and --crossings fit one session's table: give one table")

    def fit_flat(table: Measurements) -> IndentationFit:
        table, weights, _ = _within_reach(table, args, None)
        depth_std, _ = depth_uncertainty(table, ignore=args.ignore_depth_std, effects=effects)
        weights, _ = _effects_weights(table, effects, depth_std, weights, None)
        return _fit_table(table, effects, args, depth_std, weights)[0]

    fits, left_out, pool = fit_specimens(paths, args, fit_flat)
    obj: dict = {"measurements": [str(p) for p in paths], "fits": dict(fits),
                 "left_out": [{"specimen": t, "why": w} for t, w in left_out],
                 "specimens": None if pool is None else pool.to_json_dict(),
                 "E_mpa": None if pool is None else pool.E_batch_mpa,
                 "E_ci95_mpa": (None if pool is None else list(pool.E_batch_ci95_mpa)),
                 "nu": None, "nu_ci95": None, "c_n_per_mm": None, "beta": None,
                 "rmse_n": None, "n_presses": sum(int(o.get("n_presses") or 0)
                                                 for _, o in fits),
                 "effects": list(effects), "effect_params": {}}
    if args.json is not None:
        _write_json(obj, args.json)
    if args.json != "-":
        print("\n".join(specimen_lines(fits, left_out, pool)))
    if pool is None:
        print("tactilevision fit: error: fewer than two specimens give an E: no batch E "
              "(exit status 3)", file=sys.stderr)
        return 3
    if pool.disagree:
        print(f"tactilevision fit: warning: {pool.message}", file=sys.stderr)
    return 0


def _verdict_status(obj: dict, path: Path) -> int:
    """A ball's or a ramp's exit status: its misfit's warning on stderr; 3 when E is not
    identified (its interval spans more than a factor of e^2), else 0."""
    misfit = obj.get("misfit") or {}
    if misfit.get("warning"):
        print(f"tactilevision fit: warning: {path}: {misfit['warning']}", file=sys.stderr)
    if obj.get("E_identified") is False:
        lo, hi = obj["E_ci95_mpa"]
        print(f"tactilevision fit: error: {path}: E is not identified by these data (its "
              f"interval [{lo:.4g}, {hi:.4g}] MPa spans more than a factor of 7.4; exit "
              "status 3)", file=sys.stderr)
        return 3
    return 0


def run(args: argparse.Namespace) -> int:
    """Run ``fit``: read, fit, print a summary or the JSON, write ``--json FILE``.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed options of :func:`add_parser`.

    Returns
    -------
    status : int
        0 on success; 3 when the fit ran but some of the model's parameters are
        not identified by the table (``"identified": false`` in the JSON).

    Raises
    ------
    InputError
        For bad input (the command line turns it into exit status 2); nothing
        is written then.
    """
    effects = check_fit_effects([e.strip() for e in args.effects.split(",") if e.strip()])
    if args.a_over_h is not None and not math.isfinite(args.a_over_h):
        raise InputError(f"--a-over-h must be a finite number, got {args.a_over_h}")
    paths = list(args.measurements)
    if len(paths) > 1 or (not args.ramp and _has_specimens(paths[0], args)):
        return _run_specimens(args, paths, effects)
    args.measurements = path = paths[0]
    if args.ramp:
        return _run_ramp(args, path, effects)
    table = read_measurements(path, thickness_mm=args.thickness_mm, radius_mm=args.radius_mm)
    shape = args.shape or table.indenter.get("shape", "flat_punch")
    if shape != "flat_punch":
        return _run_indenter(args, table, path, effects)
    if args.dome_radius_mm is not None:
        raise InputError(f"{path}: a domed gel's top is modelled under a ball (--shape "
                         "sphere) only")
    relax, corrected = None, False
    if args.holds is not None:
        table, relax, corrected = _relax_table(table, args.holds, effects)
    weights = None
    if args.crossings:
        table, weights = _crossing_table(table, args)
    table, weights, left_out = _within_reach(table, args, weights)
    depth_std, std_message = depth_uncertainty(table, ignore=args.ignore_depth_std,
                                               effects=effects)
    weights, std_message = _effects_weights(table, effects, depth_std, weights, std_message)
    fit, caught = _fit_table(table, effects, args, depth_std, weights)
    for note in table.notes:
        print(f"tactilevision fit: warning: {note}", file=sys.stderr)
    if std_message is not None:
        print(f"tactilevision fit: warning: {path}: {std_message}", file=sys.stderr)
    for w in caught:
        print(f"tactilevision fit: warning: {path}: {w.message}", file=sys.stderr)
    if fit.misfit is not None and fit.misfit.warning and math.isfinite(fit.E_mpa):
        print(f"tactilevision fit: warning: {path}: {fit.misfit.warning}", file=sys.stderr)
    obj = fit.to_json_dict()
    moduli = None
    if relax is not None:
        obj["relaxation"] = relax.to_json_dict()
        obj["relaxation"]["holds"] = str(args.holds)
        if corrected and math.isfinite(fit.E_mpa):
            moduli = relaxed_moduli(fit.E_mpa, fit.E_ci95_mpa, relax,
                                    table.columns["hold_s"], table.columns.get("press"))
            obj["relaxation"].update({k: list(v) if isinstance(v, tuple) else v
                                      for k, v in moduli.items()})
            obj["relaxation"]["headline_E"] = "E_mpa is E0_mpa, the instantaneous modulus"
        elif relax.verdict == "decay not identified":
            obj["relaxation"]["headline_E"] = APPARENT_E
    obj["measurements"] = str(path)
    if left_out:
        obj["left_out_rows"] = left_out
    if args.crossings:
        obj["data"] = CROSSINGS_DATA
    obj["thickness_source"] = table.thickness_source
    obj["radius_source"] = table.radius_source
    if args.json is not None:
        _write_json(obj, args.json)  # first: a failed write prints nothing else
    if args.json != "-":
        print(summary(fit, path))
        if args.crossings:
            print(f"  data: {CROSSINGS_DATA} ({table.depth_mm.size} presses)")
        if relax is not None:
            print("\n".join(relaxation_lines(relax, moduli, args.holds,
                                              e_finite=math.isfinite(fit.E_mpa))))
    if not fit.identified:
        # the numbers are printed and written, but a script must not take them as a fit
        print(f"tactilevision fit: error: {path}: the model's parameters "
              f"{', '.join(fit.unidentified)} are not identified by these data; E and nu "
              "through them are not determined (exit status 3)", file=sys.stderr)
        return 3
    if fit.out_of_table:
        # E and nu not computed: the summary says why; a script must not take it as a fit
        print(f"tactilevision fit: error: {path}: E and nu not computed (out of the table; "
              "exit status 3)", file=sys.stderr)
        return 3
    return 0
