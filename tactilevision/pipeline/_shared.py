"""A depth error shared by every press, carried into the intervals of E, nu and beta."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .._checks import InputError
from ..mechanics import IndentationFit

__all__ = ["with_shared_depth"]


def with_shared_depth(fit: IndentationFit, fit_at, depth: np.ndarray, std: np.ndarray,
                       force: np.ndarray, low: np.ndarray, high: np.ndarray) -> IndentationFit:
    """E's, nu's and beta's intervals widened by a depth error that every press shares.

    The depths are moved by `low` and by `high` (mm, per press: the error's bounds) and
    fitted again; the intervals become the hull of the three fits' intervals and point
    values. A bounded systematic error does not average out over presses: its whole
    range is carried (the hull covers at least as often as each fit's interval, whatever
    the error within its bounds). beta is eq. (5)'s own parameter, so its interval is
    widened whatever the tables say; for E and nu, a bound at which beta's whole interval
    leaves the FEM table is excluded by the data (no layer fits the presses so moved) and
    adds nothing; one that cannot be fitted for another reason is said to leave the
    intervals too narrow. With E and nu out of the table at the certified depths, only
    beta's interval is widened (E and nu stay unreported)."""
    moved, failed = [], []
    for shift in (low, high):
        if not np.any(shift != 0):
            continue
        d = depth + shift
        try:
            if np.any(d <= 0):
                raise InputError("a depth at the error's bound is not positive")
            moved.append((shift, fit_at(d, std, force)))
        except InputError as exc:
            failed.append(str(exc))
    fit = _beta_hull(fit, moved, low, high)
    if not (np.isfinite(fit.E_mpa) and np.isfinite(fit.nu)):
        # beta's interval leaves the table at the certified depths: a bound of the shared
        # error may fit a layer, but E and nu from that bound alone came out confident and
        # wrong on simulated sessions (nu [0.34, 0.38] for a true 0.48): not reported
        return fit
    return _E_nu_hull(fit, moved, failed, low, high)


def _beta_hull(fit: IndentationFit, moved: list, low: np.ndarray, high: np.ndarray
               ) -> IndentationFit:
    """beta's interval widened to the hull of the fits at the shared error's bounds."""
    lo, hi = fit.beta_ci95
    betas = [(f.beta, *f.beta_ci95) for _, f in moved]
    vals = [v for b in betas for v in b if np.isfinite(v)]
    if not vals or not (np.isfinite(lo) and np.isfinite(hi)):
        return fit
    new = (float(min(lo, *vals)), float(max(hi, *vals)))
    if new == (lo, hi):
        return fit
    note = (f"beta's interval carries the shared depth error too "
            f"({1e3 * float(np.median(low)):+.1f} to {1e3 * float(np.median(high)):+.1f} um "
            f"median): the hull of the fits at its "
            f"bounds, [{new[0]:.4f}, {new[1]:.4f}] (the press scatter alone: [{lo:.4f}, "
            f"{hi:.4f}])")
    return replace(fit, beta_ci95=new, notes=(*fit.notes, note))


def _E_nu_hull(fit: IndentationFit, moved: list, failed: list[str], low: np.ndarray,
               high: np.ndarray) -> IndentationFit:
    """E's and nu's intervals widened to the hull of the fits at the shared error's
    bounds that the table allows."""
    E_lo, E_hi = fit.E_ci95_mpa
    nu_lo, nu_hi = fit.nu_ci95
    kept, excluded = [], []
    for shift, f2 in moved:
        if not (np.isfinite(f2.E_mpa) and np.isfinite(f2.nu)):
            # beta's whole interval beyond the table: no layer of any nu fits the presses
            # with the depths moved so far, so the data exclude that end of the error
            excluded.append(f"{1e3 * float(np.median(shift)):+.1f} um")
            continue
        kept.append(f2)
        E_lo, E_hi = min(E_lo, f2.E_mpa, f2.E_ci95_mpa[0]), max(E_hi, f2.E_mpa, f2.E_ci95_mpa[1])
        nu_lo = min(nu_lo, f2.nu, f2.nu_ci95[0])
        nu_hi = max(nu_hi, f2.nu, f2.nu_ci95[1])
    if failed:
        # a bound that cannot be fitted: the intervals cannot carry the error, and say so
        note = (f"the shared depth error ({1e3 * float(np.median(low)):+.1f} to "
                f"{1e3 * float(np.median(high)):+.1f} um median) could not be carried into the "
                f"intervals: at its bound {'; '.join(failed)}; E's and nu's intervals hold the "
                "press scatter only and are too narrow")
        fit = replace(fit, notes=(*fit.notes, note))
    if excluded:
        fit = replace(fit, notes=(*fit.notes, (
            f"the shared depth error at {' and '.join(excluded)} (median over presses) puts "
            "beta's whole interval outside the FEM table (no nu of a bonded elastic layer fits "
            "the presses so moved): the data exclude that end of it, and E's and nu's "
            "intervals carry the rest")))
    if not kept:
        return fit
    where = "its bounds" if len(kept) == 2 else "the bound the data allow"
    note = (f"shared depth error {1e3 * float(np.median(low)):+.1f} to "
            f"{1e3 * float(np.median(high)):+.1f} um (median over presses): E and nu refitted at "
            f"{where} ({', '.join(f'E = {m.E_mpa:.4f} MPa, nu = {m.nu:.4f}' for m in kept)}); "
            f"the intervals are the hull: E [{E_lo:.4f}, {E_hi:.4f}] MPa, nu [{nu_lo:.4f}, "
            f"{nu_hi:.4f}] (the press scatter alone: E [{fit.E_ci95_mpa[0]:.4f}, "
            f"{fit.E_ci95_mpa[1]:.4f}], nu [{fit.nu_ci95[0]:.4f}, {fit.nu_ci95[1]:.4f}])")
    return replace(fit, E_ci95_mpa=(float(E_lo), float(E_hi)), nu_ci95=(float(nu_lo),
                                                                          float(nu_hi)),
                   notes=(*fit.notes, note))
