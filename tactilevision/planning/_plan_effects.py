"""Before the first press: the smallest size of each catalogue effect ``diagnose`` will find.

:func:`effect_sensitivity` answers, for a design (:class:`Design`), how large each
effect of the catalogue (formats.md §5) must be for
:func:`~tactilevision.diagnosis.diagnose` to name it in 95 % of sessions at its default
thresholds: the design's presses, columns and noise as a
:class:`~tactilevision.diagnosis.ReplaySetup`, and ``diagnose``'s decisions replayed on
many drawn sessions of it (:func:`~tactilevision.diagnosis.replay_sizes`; the method in
that module's docstring). The noise per press is the F/T window's sd and the certified
depth's (:func:`plan_session`'s) through the FEM's dP/dw, white; tangential forces at
2 % of the normal force, random.
"""

from __future__ import annotations

import math

import numpy as np

from ..diagnosis import (
    DEPTH_ONLY,
    EffectSensitivity,
    ReplaySetup,
    crossing_sensitivity,
    replay_power,
    replay_sizes,
    table_sensitivity,
)
from ..mechanics import EFFECT_SIZE_PARAMS, fem_force
from ._design import (
    Design,
    depth_uncertainty,
    design_table,
    indenter_speeds,
    planned_columns,
    press_indenters,
    press_times,
    untestable_effects,
)

__all__ = ["LOST_SESSIONS", "SESSION_SEED", "crossing_effect_sizes", "crossing_offset_sizes",
           "crossing_sessions", "crossing_table", "design_setup",
           "effect_power", "effect_sensitivity", "measured_bracket_periods",
           "press_bracket_periods"]


def press_bracket_periods(mean: float, n: int) -> np.ndarray:
    """The frame periods each of `n` presses' crossing brackets spans, in press order,
    averaging `mean` (:attr:`Design.bracket_periods`): ``floor(mean)``, plus one on a
    share ``mean - floor(mean)`` of the presses spread evenly over them (1, 2 in turn
    for 1.5; every press 2 for 2).

    Returns
    -------
    periods : (n,) float64 ndarray
    """
    base = math.floor(mean)
    frac = mean - base
    i = np.arange(n, dtype=np.float64)
    return base + np.floor((i + 1) * frac + 1e-9) - np.floor(i * frac + 1e-9)


def _press_order(design: Design) -> np.ndarray:
    """Each press's indenter, in the order pressed: the schedule's, or round the
    indenters ``repeats`` times."""
    if design.schedule is not None:
        return press_indenters(design)
    return np.tile(np.arange(len(design.depths_mm)), int(design.repeats))


def _one_period(design: Design) -> tuple[np.ndarray, float]:
    """Each indenter's crossing bracket over one frame period, N (the stage's travel in
    one frame at the indenter's speed times the FEM's dP/dw at its w0), and the noise of
    the 10 ms F/T average ``calibrate`` reads the bracket's ends with, N."""
    w0 = np.asarray(design.depths_mm, np.float64)
    args = (design.E_mpa, design.nu, design.radius_mm, design.thickness_mm)
    eps = 1e-3 * float(np.min(w0))
    slope = (fem_force(*args, w0 + eps) - fem_force(*args, w0 - eps)) / (2 * eps)
    avg = design.force_noise_n / math.sqrt(max(1.0, 0.01 * design.rate_hz))
    return slope * indenter_speeds(design) / design.frame_rate_hz, avg


def design_setup(design: Design) -> ReplaySetup:
    """The design's presses, columns and noise as the replay draws them."""
    w, _ = design_table(design)
    sd_um, _, _ = depth_uncertainty(design)
    return ReplaySetup(
        E_mpa=design.E_mpa, nu=design.nu, radius_mm=design.radius_mm,
        thickness_mm=design.thickness_mm, depths_mm=tuple(design.depths_mm), w=w,
        cols=planned_columns(design), sigma=None, untestable=untestable_effects(design),
        relaxation_tau_s=design.relaxation_tau_s,
        force_sd_n=design.force_noise_n / math.sqrt(design.window_samples),
        depth_sd_mm=sd_um * 1e-3, own_tangential=False)


def effect_power(design: Design, effect: str, size: float, *, draws: int = 2000,
                 seed: int = 0) -> float:
    """Share of sessions of the design in which ``diagnose`` (replayed, linearized)
    names `effect` at `size`: :func:`~tactilevision.diagnosis.replay_power` on the
    design's sessions (:func:`design_setup`); its parameters, return value and errors.
    """
    return replay_power(design_setup(design), effect, size, draws=draws, seed=seed)


def effect_sensitivity(design: Design, *, power: float = 0.95, draws: int = 1000,
                       seed: int = 0) -> dict[str, EffectSensitivity]:
    """The smallest size of each catalogue effect ``diagnose`` names in `power` of the
    sessions of a design: :func:`~tactilevision.diagnosis.replay_sizes` on the design's
    sessions (:func:`design_setup`: the F/T window's sd and the certified depth's,
    :func:`plan_session`'s, through the FEM's dP/dw, white; tangential forces at 2 % of
    the normal force, random); its parameters, return value and errors.
    """
    return replay_sizes(design_setup(design), power=power, draws=draws, seed=seed)


def crossing_table(design: Design) -> dict[str, np.ndarray]:
    """The crossing forces a session of a drawn-mark design will write (formats.md §2
    ``force_w0_n``, ``force_w0_sem_n``), noise-free, with their stated uncertainties.

    The presses go round the indenters (each round presses every depth once, ``repeats``
    rounds), at the times and positions of :func:`planned_columns`; with a ``schedule``,
    its indenters and positions in its order. A press crosses w0
    within the frame period before the mark first shows, or within the periods of the
    frames before that which may show it faintly: ``calibrate`` brackets the force over
    those periods, whose width is the stage's travel in one frame (at the indenter's
    speed, :func:`indenter_speeds`) times dP/dw at w0 (the FEM's) times the periods,
    widened by four times the noise of its 10 ms average of the F/T; the stated sd is
    the bracket's width over sqrt(12) (a uniform crossing). The presses' periods average
    the design's ``bracket_periods`` (:func:`press_bracket_periods`: 1, 2 in turn by
    default).

    Returns
    -------
    columns : dict of str to (N,) float64 ndarray
        ``indenter``, ``press``, ``time_s``, ``x_mm``, ``y_mm``, ``force_w0_n`` (N),
        ``force_w0_sem_n`` (N).
    """
    cols = planned_columns(design)
    ind = _press_order(design)
    n = ind.size
    w0 = np.asarray(design.depths_mm, np.float64)
    p0 = fem_force(design.E_mpa, design.nu, design.radius_mm, design.thickness_mm, w0)
    unit, avg = _one_period(design)
    periods = press_bracket_periods(float(design.bracket_periods), n)
    width = unit[ind] * periods + 4.0 * avg
    return {"indenter": ind.astype(np.float64), "press": np.arange(n, dtype=np.float64),
            "time_s": press_times(design, ind), "x_mm": cols["x_mm"][:n],
            "y_mm": cols["y_mm"][:n],
            "force_w0_n": p0[ind], "force_w0_sem_n": width / math.sqrt(12.0)}


def measured_bracket_periods(design: Design, w0_mm: np.ndarray, sem_n: np.ndarray
                             ) -> float | None:
    """The frame periods a session's crossing brackets spanned on average, as
    :func:`crossing_table` counts them: the brackets' summed widths (``sqrt(12)
    force_w0_sem_n``) less their F/T noise widening over the summed widths of one frame's
    travel times dP/dw at each press's w0 (the design's speeds and FEM slope), within
    [1, 4]. Planned with it, :func:`crossing_table` states brackets as wide on average as
    the session's.

    Parameters
    ----------
    design : Design
        The session's design (a drawn mark: ``bevel_angle_deg`` 0).
    w0_mm : (N,) float64 ndarray
        Each press's gauge-block depth w0, mm (one of ``design.depths_mm``; others and
        NaN skipped).
    sem_n : (N,) float64 ndarray
        Each press's ``force_w0_sem_n``, N (NaN skipped).

    Returns
    -------
    periods : float or None
        None for a vernier design or fewer than 3 presses with both.
    """
    w0 = np.asarray(w0_mm, np.float64)
    sem = np.asarray(sem_n, np.float64)
    depths = np.asarray(design.depths_mm, np.float64)
    idx = np.clip(np.searchsorted(depths, w0), 0, depths.size - 1)
    ok = np.isfinite(w0) & np.isfinite(sem) & (sem > 0) & np.isclose(depths[idx], w0,
                                                                         atol=1e-4)
    if design.bevel_angle_deg != 0.0 or np.count_nonzero(ok) < 3:
        return None
    unit, avg = _one_period(design)
    width = math.sqrt(12.0) * sem[ok] - 4.0 * avg
    return float(np.clip(np.sum(width) / np.sum(unit[idx[ok]]), 1.0, 4.0))


#: Sessions :func:`crossing_sessions` draws presses lost in (each with its own draws of
#: the brackets' periods), and the seed of its draws (a design plans the same each time).
LOST_SESSIONS, SESSION_SEED = 5, 20261128


def crossing_sessions(design: Design, *, draws: int = 1000
                      ) -> list[tuple[np.ndarray, np.ndarray]]:
    """Sessions of a drawn-mark design as they fall out, for
    :func:`~tactilevision.diagnosis.crossing_sizes`'s ``sessions``: each press's bracket
    spans ``floor(bracket_periods)`` frame periods, or one more with probability
    ``bracket_periods - floor(bracket_periods)``, drawn press by press and draw by draw
    (which presses span two falls by chance, where :func:`crossing_table` spreads them
    evenly); with an ``unseen_share``, :data:`LOST_SESSIONS` sessions each lose every
    press with that probability (seeded: :data:`SESSION_SEED`).

    Returns
    -------
    sessions : list of (keep, sem)
        ``keep`` (N,) bool, the presses certified; ``sem`` (M, N) float64, the stated sds
        of their crossing forces (N) in each of M draws, ``draws`` in all.
    """
    ind = _press_order(design).astype(np.int64)
    unit, avg = _one_period(design)
    base = math.floor(design.bracket_periods)
    share = design.bracket_periods - base
    rng = np.random.default_rng(SESSION_SEED)
    n_sessions = LOST_SESSIONS if design.unseen_share > 0 else 1
    out = []
    for _ in range(n_sessions):
        keep = rng.random(ind.size) >= design.unseen_share
        periods = base + (rng.random((draws // n_sessions, ind.size)) < share)
        out.append((keep, (unit[ind] * periods + 4.0 * avg) / math.sqrt(12.0)))
    return out


def crossing_effect_sizes(design: Design, *, power: float = 0.95
                          ) -> dict[str, EffectSensitivity]:
    """The within-indenter changes a drawn-mark design's crossing forces let ``diagnose``
    name in `power` of sessions: a stiffness step half-way through the presses, a steady
    change with time, a gradient across the pad
    (:func:`~tactilevision.diagnosis.crossing_sizes` on :func:`crossing_table`, over the
    sessions :func:`crossing_sessions` draws of it, at the table's thresholds). Empty for
    a bevel read as a vernier (its depths do not absorb them: the replay sizes them).

    On the design of a Taxim mark session without the renderer's shadows (211's, brackets
    of 1.93 periods; ``benchmarks/bench_bracket_spread.py``, 20 sessions drawn), the
    sizes named on drawn sessions were 1.00, 1.10 and 1.06 times the evenly spread
    table's (medians; gradient, steady change, step) and 1.08, 1.15 and 1.16 with each
    press lost with probability 0.1.
    """
    if design.bevel_angle_deg != 0.0:
        return {}
    lost = (f"; {100 * design.unseen_share:.3g} % of presses unseen"
            if design.unseen_share > 0 else "")
    return crossing_sensitivity(
        crossing_table(design), power=power, sessions=crossing_sessions(design),
        why="from the crossing forces within indenters (each bracketed by "
            f"{design.bracket_periods:.3g} frame periods of travel on average, press by "
            f"press at random{lost}; the "
            + ("presses in the schedule's order and places)" if design.schedule is not None
               else "presses going round the indenters)"))


def crossing_offset_sizes(design: Design, *, power: float = 0.95, draws: int = 400
                          ) -> dict[str, EffectSensitivity]:
    """The offsets along depth alone (``depth_offset``, ``force_offset``) that a
    drawn-mark design's crossing forces let ``diagnose`` name in `power` of sessions.

    Under the mark rule ``diagnose`` names such an offset only where the ladder on the
    crossing forces' own table (each press at its w0, certified apart from the force;
    :func:`~tactilevision.diagnosis.crossing_measurements`) names it too: within an
    indenter the mark's depths are read through the force. So an offset must be as large
    as both the mark's table and this one need. Here the crossing forces of
    :func:`crossing_table` at the design's w0, each with its stated sd, are replayed as a
    table of their own (:func:`~tactilevision.diagnosis.table_sensitivity`, `draws`
    sessions; the other effects, which the mark's table or the crossing tests size,
    are not tried there). Empty for a bevel read as a vernier.
    """
    if design.bevel_angle_deg != 0.0:
        return {}
    c = crossing_table(design)
    w0 = np.asarray(design.depths_mm, np.float64)[c["indenter"].astype(int)]
    cols = {**{k: v for k, v in c.items() if k not in ("force_w0_n", "force_w0_sem_n")},
            "depth_mm": w0, "force_n": c["force_w0_n"]}
    sizes = table_sensitivity(cols, thickness_mm=design.thickness_mm,
                              radius_mm=design.radius_mm, E_mpa=design.E_mpa, nu=design.nu,
                              sigma_n=c["force_w0_sem_n"], power=power, draws=draws,
                              untestable={k: "sized on the mark's table" for k in
                                          EFFECT_SIZE_PARAMS if k not in DEPTH_ONLY})
    return {k: sizes[k] for k in DEPTH_ONLY if k in sizes}


def larger_of(mark: EffectSensitivity, crossing: EffectSensitivity) -> EffectSensitivity:
    """An offset along depth under the mark rule: the larger of what the mark's table and
    the crossing forces' need (both must name it), said so; NaN (untestable) where either
    is."""
    if math.isnan(mark.size_param):
        return mark
    if math.isnan(crossing.size_param):
        return crossing
    big = crossing if crossing.size_param > mark.size_param else mark
    needs = "the crossing forces" if big is crossing else "the mark's depths"
    return EffectSensitivity(
        big.effect, big.parameter, big.unit, big.size, big.size_param, big.power, big.snr,
        f"under the mark rule both the mark's depths and the crossing forces must name it: "
        f"{mark.size:.3g} and {crossing.size:.3g}{' ' + big.unit if big.unit else ''} "
        f"({needs} need more)", big.dip)
