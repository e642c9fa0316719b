"""The depth of a press certified by a bevel mark (no vernier): w0, plus what the force says.

A drawn mark (``bevel_angle_deg = 0``) shows when the block's land reaches the gel,
at depth w0. The first frame that shows it comes up to one frame period after that
instant, and the stage goes on to its stop: every press is held past w0, by the same
sign (issue 39: a median of 22 um random uncertainty stated, E's interval excluding
the truth on 3 of 4 sessions). The force says how far. The land reached w0 within
the frame period before the onset frame (or two, where the frame before may show the
mark faintly; and before the stage stopped), where the
F/T log reads fz; from there to the force window fz rises by dP/dw times the depth
the stage went on by:

    w = w0 + (P_window - P_crossing) / (dP/dw),

with P_crossing the mean of fz over that period (the crossing uniform in time over
it; its spread is the random uncertainty: ``CertifiedPress.force_onset_n``) and
dP/dw from the fitted eq. (5) between the two. What stays shared by every press,
and so cannot average out: the clock offset (a clock off by dt puts the crossing's
force ``speed x dt`` along the ramp) and dP/dw (eq. 5's slope scales every overshoot
alike): :func:`mark_shared_mm`.
"""

from __future__ import annotations

import math

import numpy as np

from .._checks import InputError, check_array

__all__ = ["CLOCK_SD_S", "CROSSING_CHECK_P", "STIFFNESS_REL", "crossing_consistency",
           "crossing_forces", "mark_depths", "mark_shared_mm"]

#: The mark rule says so where the crossing forces scatter within indenters more than
#: their brackets allow at this significance (:func:`crossing_consistency`; the read
#: bands' crests are checked at the same level).
CROSSING_CHECK_P = 0.05
#: Draws behind :func:`crossing_consistency`'s p-value, and their seed.
_CONSISTENCY_DRAWS, _CONSISTENCY_SEED = 4000, 20261127

#: The clock offset's error taken as shared by every press, s (the profile correlation
#: that synchronises the F/T log gave 0.1335 to 0.1370 s against the true 0.137 s on the
#: simulated sessions: docs/relaxation.md).
CLOCK_SD_S = 0.003
#: Relative error of dP/dw taken as shared (eq. 5's slope between the onset and the
#: window, against the FEM's).
STIFFNESS_REL = 0.05


def mark_depths(w0_mm: np.ndarray, force_n: np.ndarray, force_crossing_n: np.ndarray,
                stiffness_n_per_mm: np.ndarray, *, force_sem_n: np.ndarray,
                force_crossing_sd_n: np.ndarray, travel_mm: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Certified depths of presses whose mark's onset was seen (module docstring).

    Parameters
    ----------
    w0_mm : (N,) float ndarray
        Each press's indenter protrusion over the land, mm.
    force_n : (N,) float ndarray
        The force window's mean, N.
    force_crossing_n : (N,) float ndarray
        fz when the land reached w0, N (NaN where not read: the press then
        keeps w0 + travel / 2, with travel / sqrt(12) as its uncertainty).
    stiffness_n_per_mm : (N,) float ndarray
        dP/dw between the crossing and the window, N/mm (> 0).
    force_sem_n, force_crossing_sd_n : (N,) float ndarray
        Standard error of the window's mean, and the crossing force's
        uncertainty, N (NaN counts as 0).
    travel_mm : (N,) float ndarray
        The stage's depth per frame period at the onset, mm (>= 0).

    Returns
    -------
    depth_mm : (N,) float64 ndarray
        w0 + the depth the force says the stage went on by past it.
    depth_std_mm : (N,) float64 ndarray
        The random part of its uncertainty, mm: ``sqrt(sd_crossing^2 +
        sem^2) / (dP/dw)``.
    after_mm : (N,) float64 ndarray
        ``(P_window - P_crossing) / (dP/dw)``, mm (travel / 2 where not read).

    Raises
    ------
    ShapeError
        For arrays of different lengths.
    InputError
        For a negative travel or a stiffness that is not positive.
    """
    w0 = check_array(w0_mm, "w0_mm", [("N",)], dtype=np.number).astype(np.float64)
    n = (w0.shape[0],)

    def arr(x, name):
        return check_array(x, name, [n], dtype=np.number).astype(np.float64)

    f, fc, k = arr(force_n, "force_n"), arr(force_crossing_n, "force_crossing_n"), arr(
        stiffness_n_per_mm, "stiffness_n_per_mm")
    se = np.nan_to_num(arr(force_sem_n, "force_sem_n"))
    sd_c = np.nan_to_num(arr(force_crossing_sd_n, "force_crossing_sd_n"))
    u = arr(travel_mm, "travel_mm")
    if np.any(u < 0) or not np.all(np.isfinite(u)):
        raise InputError("travel_mm must be finite and >= 0")
    if not np.all(np.isfinite(k) & (k > 0)):
        raise InputError("stiffness_n_per_mm must be positive")
    read = np.isfinite(fc)
    after = np.where(read, (f - np.where(read, fc, 0.0)) / k, u / 2)
    std = np.where(read, np.sqrt(sd_c ** 2 + se ** 2) / k, u / np.sqrt(12.0))
    return w0 + after, std, after


def crossing_forces(indenter: np.ndarray, force_crossing_n: np.ndarray,
                    force_crossing_sd_n: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """P(w0) of each indenter, from all of its presses at once.

    Every press of one indenter crossed the same w0, so its crossing force is the same
    P(w0) (an elastic, uniform gel), and each press brackets it: the crossing lies in the
    frame period before its mark first showed, where fz ran from ``mean - sqrt(3) sd`` to
    ``mean + sqrt(3) sd`` (a uniform crossing: ``CertifiedPress.force_onset_n`` and
    ``force_onset_sem_n``). The brackets' intersection holds P(w0) for each of them; a
    press alone says little at a low frame rate (a period of 100 um of travel at 10
    frames/s), n of them at random phases narrow it to about 2 / (n + 1) of one, without
    assuming how far the stage overshoots (on one 10 frames/s session, E 0.20 MPa, each
    press's own bracket read E 0.29 MPa, the intersections 0.21).

    Parameters
    ----------
    indenter : (N,) ndarray
        Each press's indenter (the group).
    force_crossing_n, force_crossing_sd_n : (N,) float ndarray
        Each press's crossing force and uncertainty, N (NaN: not read; left out).

    Returns
    -------
    force_n : (N,) float64 ndarray
        The group's P(w0) on each of its presses: the middle of the intersection (the
        midpoints' mean when the brackets do not all meet; NaN where none was read).
    sd_n : (N,) float64 ndarray
        Its uncertainty (the intersection's width / sqrt(12), or the midpoints' scatter
        over sqrt(n)) times sqrt(n) of its n presses: the error is shared by the group's
        presses, which a fit taking each as independent would otherwise average n-fold.
    n_disjoint : int
        Groups whose brackets do not all meet (a gel not uniform, a drifting force).
    """
    ind = np.asarray(indenter)
    fc = np.asarray(force_crossing_n, np.float64)
    sd = np.nan_to_num(np.asarray(force_crossing_sd_n, np.float64))
    out, out_sd = np.full(fc.shape, np.nan), np.full(fc.shape, np.nan)
    disjoint = 0
    for g in np.unique(ind):
        sel = (ind == g) & np.isfinite(fc)
        n = int(sel.sum())
        if n == 0:
            continue
        lo, hi = fc[sel] - np.sqrt(3) * sd[sel], fc[sel] + np.sqrt(3) * sd[sel]
        a, b = float(lo.max()), float(hi.min())
        if a <= b:
            mid, u = 0.5 * (a + b), (b - a) / np.sqrt(12)
        else:
            disjoint += 1
            mid = float(fc[sel].mean())
            u = float(np.std(fc[sel], ddof=1) / np.sqrt(n)) if n > 1 else float(sd[sel][0])
        out[sel] = mid
        out_sd[sel] = u * np.sqrt(n)
    return out, out_sd, disjoint


def crossing_consistency(indenter: np.ndarray, force_crossing_n: np.ndarray,
                         force_crossing_sd_n: np.ndarray) -> tuple[float, float]:
    """Whether the crossing forces of each indenter agree as well as their brackets state.

    Parameters
    ----------
    indenter : (N,) ndarray
    force_crossing_n, force_crossing_sd_n : (N,) float ndarray
        Each press's crossing force and its sd, N (NaN: not read; left out, as are
        indenters with one press read).

    Returns
    -------
    birge : float
        sqrt(chi2 / dof) of the crossing forces about their indenters' weighted means
        (Birge's ratio; Birge, Phys. Rev. 40, 207, 1932): about 1 where they scatter as
        stated.
    p_value : float
        The share of :data:`_CONSISTENCY_DRAWS` seeded draws of the forces, each crossing
        uniform over its bracket (the statement's own noise, the one ``diagnose`` draws
        its brackets from), that scatter as much: (hits + 1) / (draws + 1). Both NaN
        without two presses read in an indenter. (chi2's own tail would err large: a
        uniform crossing has no tails, and on honest brackets it fell under 0.05 in 0.5 %
        of tables.)

    Notes
    -----
    Within one indenter every press crossed the same w0, so on an elastic, uniform gel
    their forces differ only by what the brackets state. A scatter beyond it is a
    certification that reads some onsets late or early, or a gel that changes between
    the presses (which ``diagnose`` tests); either way each indenter's P(w0), the
    intersection of its brackets, is less sure than it claims.
    """
    ind = np.asarray(indenter)
    f = np.asarray(force_crossing_n, np.float64)
    sd = np.asarray(force_crossing_sd_n, np.float64)
    ok = np.isfinite(f) & np.isfinite(sd) & (sd > 0)
    counts = {g: int(np.sum(ok & (ind == g))) for g in np.unique(ind[ok])}
    ok &= np.array([counts.get(g, 0) >= 2 for g in ind])
    dof = int(ok.sum()) - len({g for g, n in counts.items() if n >= 2})
    if dof <= 0:
        return math.nan, math.nan
    _, gid = np.unique(ind[ok], return_inverse=True)
    wt = 1.0 / sd[ok] ** 2
    one = np.eye(int(gid.max()) + 1)[gid]           # (M, K): each press's indenter

    def chi2(x: np.ndarray) -> np.ndarray:          # (D, M) forces -> (D,) scatter
        mean = ((x * wt) @ one / (wt @ one)) @ one.T
        return np.sum(wt * (x - mean) ** 2, axis=1)

    observed = float(chi2(f[ok][None])[0])
    # each crossing uniform over its bracket (width sqrt(12) sd): what the statement says
    rng = np.random.default_rng(_CONSISTENCY_SEED)
    drawn = chi2((rng.random((_CONSISTENCY_DRAWS, int(ok.sum()))) - 0.5) * np.sqrt(12) * sd[ok])
    p = float((np.sum(drawn >= observed) + 1) / (_CONSISTENCY_DRAWS + 1))
    return math.sqrt(observed / dof), p


def mark_shared_mm(travel_mm: np.ndarray, after_onset_mm: np.ndarray, period_s: float,
                   clock_sd_s: float = CLOCK_SD_S) -> np.ndarray:
    """Half-width of the depth error every press shares under :func:`mark_depths`, mm.

    Parameters
    ----------
    travel_mm : (N,) float ndarray
        The stage's depth per frame period at each onset, mm.
    after_onset_mm : (N,) float ndarray
        The depth read from the force after the onset, mm.
    period_s : float
        The frame period, s.
    clock_sd_s : float, default CLOCK_SD_S
        The clock offset's error, s (the larger of :data:`CLOCK_SD_S` and the
        estimate's own standard error, :func:`press_clock_offset`, where it was
        estimated).

    Returns
    -------
    shared_mm : (N,) float64 ndarray
        ``speed x clock_sd_s + STIFFNESS_REL x |after_onset|`` per press: the
        clock's share (the onset's force read ``clock_sd_s`` early or late on
        the ramp) and dP/dw's; every press moves the same way, so the
        intervals of E and nu carry it whole, not averaged.
    """
    u = np.asarray(travel_mm, np.float64)
    speed = u / float(period_s) if period_s > 0 else np.zeros_like(u)
    return speed * clock_sd_s + STIFFNESS_REL * np.abs(np.asarray(after_onset_mm, np.float64))
