"""``tactilevision fit`` for an indenter other than the flat punch (a ball): E at a stated
or fitted nu, each material law's fit and the apparent E of every press."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from .. import InputError
from ..io import Measurements, read_ramp, sidecar_geometry
from ..mechanics import IndenterFit, fit_indenter, fit_ramp, indenter_from_config

__all__ = ["depth_shared", "fit_laws", "force_sd", "indenter_of", "note_lines", "nu_words",
           "run_indenter", "run_ramp", "summary_lines"]


def indenter_of(table: Measurements, args: argparse.Namespace):
    """The indenter and stated contact of a table: its sidecar's keys, overridden by
    ``--shape``, ``--contact``, ``--pad-radius-mm``."""
    keys = dict(table.indenter)
    cfg = {"shape": args.shape or keys.get("shape", "flat_punch"),
           "radius_mm": table.radius_mm}
    ind = indenter_from_config(cfg, where=f"{table.path}: indenter")
    pad = args.pad_radius_mm if args.pad_radius_mm is not None else keys.get("pad_radius_mm")
    dome = getattr(args, "dome_radius_mm", None)
    dome = dome if dome is not None else keys.get("dome_radius_mm")
    if dome is not None and ind.shape != "sphere":
        raise InputError(f"{table.path}: a domed gel's top is modelled under a ball "
                         "(--shape sphere) only")
    if pad is not None and ind.shape == "sphere":
        for name, v in (("pad radius ([sensor] gel_radius_mm, --pad-radius-mm)", pad),
                        ("dome radius ([sensor] gel_dome_radius_mm, --dome-radius-mm)",
                         dome)):
            if v is not None and (isinstance(v, bool) or not isinstance(v, int | float)
                                  or not (math.isfinite(v) and v > 0)):
                raise InputError(f"{table.path}: the {name} must be a positive number of mm, "
                                 f"got {v!r}")
        try:
            ind = type(ind)(ind.radius_mm, pad_radius_mm=float(pad),
                            dome_radius_mm=None if dome is None else float(dome))
        except InputError as exc:
            raise InputError(f"{table.path}: {exc}") from None
    elif dome is not None:
        raise InputError(f"{table.path}: a domed gel (dome radius {dome!r} mm) needs the pad's "
                         "radius ([sensor] gel_radius_mm or --pad-radius-mm)")
    contact = args.contact or keys.get("contact")
    mu = getattr(args, "friction", None)
    if (contact == "coulomb") != (mu is not None):
        raise InputError("--contact coulomb and --friction MU go together (Coulomb's "
                         "friction between ball and gel)")
    if mu is not None:
        if ind.shape != "sphere":
            raise InputError("--friction is for a ball (--shape sphere)")
        try:
            ind = type(ind)(ind.radius_mm, pad_radius_mm=ind.pad_radius_mm, friction=mu,
                            dome_radius_mm=ind.dome_radius_mm)
        except InputError as exc:
            raise InputError(f"--friction: {exc}") from None
        return ind, contact
    if contact is not None and contact not in ind.contacts:
        raise InputError(f"{table.path}: contact {contact!r} must be one of {ind.contacts} "
                         f"for a {ind.shape}")
    return ind, contact


def fit_laws(table: Measurements, args: argparse.Namespace,
             depth_std: np.ndarray | None) -> tuple[IndenterFit, dict[str, IndenterFit], str]:
    """Fit each law asked for; the one reported, all fits by law, and why it was chosen."""
    ind, contact = indenter_of(table, args)
    laws = ("linear", "neo_hookean") if args.law == "auto" else (args.law,)
    if contact == "coulomb":                          # built for the small-strain law only
        if args.law == "neo_hookean":
            raise InputError("--contact coulomb is computed for --law linear only")
        laws = ("linear",)
    fits = {}
    for law in laws:
        try:
            fits[law] = fit_indenter(table.depth_mm, table.force_n, ind,
                                     thickness_mm=table.thickness_mm, law=law, contact=contact,
                                     nu=args.nu, depth_std_mm=depth_std,
                                     depth_shared_mm=depth_shared(table, depth_std),
                                     force_std_n=force_sd(table))
        except InputError as exc:
            raise InputError(f"{table.path}: {exc}") from None
    if len(fits) == 1:
        return fits[laws[0]], fits, f"--law {laws[0]}"
    best = min(fits, key=lambda k: fits[k].chi2)
    other = next(k for k in fits if k != best)
    why = (f"selected: {best} (rmse {fits[best].rmse_n * 1e3:.4g} mN against "
           f"{fits[other].rmse_n * 1e3:.4g} mN for {other}; the same parameters, so the "
           "smaller residuals)")
    return fits[best], fits, why


def depth_shared(table: Measurements, depth_std: np.ndarray | None) -> np.ndarray | float:
    """The depths' shared error (``depth_shared_mm``: a ball's contact circles all off by
    the detector's bias) where every row has one and the depths' errors are used."""
    shared = table.columns.get("depth_shared_mm")
    if depth_std is None or shared is None or not np.all(np.isfinite(shared) & (shared >= 0)):
        return 0.0
    return shared


def force_sd(table: Measurements) -> np.ndarray | None:
    """The forces' stated standard uncertainty (``force_sem_n``: an F/T window's standard
    error, a dead weight's mass uncertainty times g) where every row has one."""
    sem = table.columns.get("force_sem_n")
    return sem if sem is not None and np.all(np.isfinite(sem)) else None


def _drift(fit: IndenterFit, depth: np.ndarray) -> str:
    """The apparent E's change from the shallowest to the deepest presses, in words."""
    order = np.argsort(depth)
    e = fit.apparent_E_mpa[order]
    k = max(1, e.size // 4)
    lo, hi = float(np.mean(e[:k])), float(np.mean(e[-k:]))
    return (f"apparent E {lo:.4f} MPa at the shallowest presses, {hi:.4f} MPa at the deepest "
            f"({100 * (hi / lo - 1):+.1f} %)")


def summary_lines(fit: IndenterFit, fits: dict[str, IndenterFit], why: str,
                  table: Measurements) -> list[str]:
    """The printed summary of an indenter fit."""
    pct = f"{fit.confidence:.0%}"
    pad = table.indenter.get("pad_radius_mm")
    lines = [f"{table.path}: {fit.n_presses} presses of a {fit.shape} of radius "
             f"{fit.radius_mm:g} mm on h = {fit.thickness_mm:g} mm"
             + (f" (pad radius {pad:g} mm)" if pad is not None else "")
             + f", {fit.contact} contact",
             f"  law: {fit.law} ({why})",
             f"  E  = {fit.E_mpa:.4f} MPa  {pct} CI [{fit.E_ci95_mpa[0]:.4f}, "
             f"{fit.E_ci95_mpa[1]:.4f}] MPa at nu = {fit.nu:.4g}" + nu_words(fit),
             f"  rmse = {fit.rmse_n * 1e3:.4g} mN; {_drift(fit, table.depth_mm)}"]
    if fit.nu_identified:
        lines.insert(3, f"  nu = {fit.nu:.4f}      {pct} CI [{fit.nu_ci95[0]:.4f}, "
                        f"{fit.nu_ci95[1]:.4f}]")
    for law, other in fits.items():
        if other is not fit:
            lines.append(f"  {law} law: E = {other.E_mpa:.4f} MPa [{other.E_ci95_mpa[0]:.4f}, "
                         f"{other.E_ci95_mpa[1]:.4f}], rmse = {other.rmse_n * 1e3:.4g} mN; "
                         f"{_drift(other, table.depth_mm)}")
    order = np.argsort(table.depth_mm)
    lines.append("  apparent E per press (depth mm: MPa): " + ", ".join(
        f"{table.depth_mm[i]:.4g}: {fit.apparent_E_mpa[i]:.4f}" for i in order[:12])
        + (" ..." if order.size > 12 else ""))
    lines += note_lines(fit.notes)
    return lines


def note_lines(notes: tuple[str, ...] | list[str]) -> list[str]:
    """A fit's notes as summary lines: a note starting ``warning:`` (the model does not
    explain the data to within their noise) as ``WARNING:``, first."""
    warn = [f"  WARNING: {n.removeprefix('warning: ')}" for n in notes
            if n.startswith("warning: ")]
    return warn + [f"  note: {n}" for n in notes if not n.startswith("warning: ")]


def nu_words(fit) -> str:
    """What the summary says after E's nu: nothing where nu is identified, else that it is
    stated, with the bound the presses put on it."""
    if fit.nu_identified:
        return ""
    if fit.nu_bound:
        return f" (stated: nu not identified; the presses say {fit.nu_bound}, a bound)"
    return " (stated: nu not identified)"


def run_indenter(args: argparse.Namespace, table: Measurements, path: Path,
                 depth_std: np.ndarray | None) -> tuple[dict, list[str]]:
    """Fit, and the JSON object and summary lines (the caller writes and prints them)."""
    fit, fits, why = fit_laws(table, args, depth_std)
    obj = fit.to_json_dict()
    obj["law_selection"] = why
    obj["laws"] = {law: f.to_json_dict() for law, f in fits.items()}
    return obj, summary_lines(fit, fits, why, table)


def run_ramp(args: argparse.Namespace, path: Path) -> tuple[dict, list[str]]:
    """``fit --ramp``: the contact point, baseline and E of a force-depth ramp.

    Raises
    ------
    InputError
        For a bad ramp file, missing geometry (one sentence naming the value, the option
        and the sidecar key), or a fit that cannot be made (no loading part, ...).
    """
    ramp = read_ramp(path)
    h, a, _, keys = sidecar_geometry(path, thickness_mm=args.thickness_mm,
                                     radius_mm=args.radius_mm)
    table = Measurements(path=path, columns={"depth_mm": np.ones(1), "force_n": np.ones(1)},
                         labels={}, line_numbers=np.ones(1, np.int64), thickness_mm=h,
                         radius_mm=a, thickness_source="", radius_source="", indenter=keys)
    ind, contact = indenter_of(table, args)
    law = "neo_hookean" if args.law == "auto" else args.law
    fit = fit_ramp(ramp.displacement_mm, ramp.force_n, ind, thickness_mm=h, law=law,
                   contact=contact, nu=args.nu, source=path)
    pct = f"{fit.confidence:.0%}"
    lo, hi = fit.contact_point_ci_mm
    lines = [f"{path}: a ramp of {len(ramp)} rows, {fit.n_points} presses read from its "
             f"loading part; a {ind.shape} of radius {ind.radius_mm:g} mm on h = {h:g} mm, "
             f"{fit.law} law, {fit.contact} contact",
             f"  contact point z0 = {fit.contact_point_mm:.5f} mm  {pct} CI [{lo:.5f}, "
             f"{hi:.5f}] mm; baseline {fit.baseline_n * 1e3:.4g} mN",
             f"  E  = {fit.E_mpa:.4f} MPa  {pct} CI [{fit.E_ci95_mpa[0]:.4f}, "
             f"{fit.E_ci95_mpa[1]:.4f}] MPa at nu = {fit.nu:.4g}" + nu_words(fit),
             f"  rmse = {fit.rmse_n * 1e3:.4g} mN"]
    lines += note_lines(fit.notes)
    return fit.to_json_dict(), lines
