"""A bevel mark with no vernier (``bevel_angle_deg = 0``): when a press first shows it.

The mark's score on the session's no-contact frames (the null of
``bevel_threshold='auto'``), each press's own baseline and template, the first
frame showing the mark, and the force and stage travel at that onset
(step 3 of :mod:`tactilevision.contact._certify`).
"""

from __future__ import annotations

import numpy as np

from ._bevel import _background_basis, bevel_score
from ._holds import hold_start
from ._mask import contact_mask
from ._results import (
    MARK_BASELINE_FORCE,
    MARK_BLOCK,
    MARK_FAINT_FLOOR,
    MARK_FAINT_MAX,
    MARK_HOLD_FORCE,
    MARK_NULL_FRAMES,
    MARK_TRACE,
    MARK_TRACE_SHAPE,
    MARK_Z_BLOCK,
    MARK_Z_BRIDGE,
    MARK_Z_FAINT,
    MARK_Z_FRAME,
    MARK_Z_SEEN,
    MARK_Z_STEP,
    _PressContext,
    _Reject,
)
from ._vernier import BevelGeometry, bevel_profile

#: The F/T's rest before a press, s (:func:`_press_forces`).
_REST_S = 0.3


def _mark_score(ctx: _PressContext, centre: tuple[float, float], i: int) -> float:
    """:func:`bevel_score` of frame `i` at the mark of the press centred at `centre`."""
    session = ctx.session
    cfg = session.config
    return float(bevel_score(session.frame(int(i)), session.reference, centre, cfg.mm_per_px,
                             offset_mm=cfg.bevel_offset_mm,
                             direction_deg=cfg.bevel_direction_deg,
                             length_mm=cfg.bevel_length_mm))


def _mark_null(session, runs: list[np.ndarray], area: np.ndarray, min_contact_px: int,
               sigma: float) -> dict | None:
    """The mark's score on frames without contact, at each press's mark: the null that
    ``bevel_threshold='auto'`` reads its thresholds from: the median, and the frame-to-frame
    sd at one place (each press's scores about their own median, pooled; the places' own
    levels differ more than the frames at one place do). None with fewer than 10."""
    cfg = session.config
    ref = session.reference
    free = np.flatnonzero(area < min_contact_px)
    if free.size == 0:
        return None
    scores, resid = [], []
    for r in runs:
        peak = int(r[np.argmax(area[r])])
        ys, xs = np.nonzero(contact_mask(session.frame(peak), ref, sigma=sigma))
        if xs.size == 0:
            continue
        centre = (float(xs.mean()), float(ys.mean()))
        near = free[np.argsort(np.abs(free - r[0]), kind="stable")[:MARK_NULL_FRAMES]]
        v = np.array([bevel_score(session.frame(int(i)), ref, centre, cfg.mm_per_px,
                                  offset_mm=cfg.bevel_offset_mm,
                                  direction_deg=cfg.bevel_direction_deg,
                                  length_mm=cfg.bevel_length_mm) for i in near])
        v = v[np.isfinite(v)]
        scores += list(v)
        if v.size >= 2:
            # the frame-to-frame noise at one place: each press's scores about their median
            resid += list((v - np.median(v)) * np.sqrt(v.size / (v.size - 1)))
    v = np.asarray(scores, np.float64)
    if v.size < 10 or len(resid) < 10:
        return None
    med = float(np.median(v))
    res = np.asarray(resid)
    sd = max(1.4826 * float(np.median(np.abs(res - np.median(res)))), 1e-3)
    return {"rule": "auto", "median": med, "sd": sd, "n_frames": int(v.size),
            "z_frame": MARK_Z_FRAME, "z_block": MARK_Z_BLOCK, "block_frames": MARK_BLOCK}


def _press_forces(ctx: _PressContext, run: np.ndarray) -> np.ndarray:
    """fz at the press's frames (the F/T log at their times) less the F/T's rest before it:
    the median over :data:`_REST_S` ending a frame period before its first frame (the
    indenter touches the gel after that), or the least of the frames' where that is
    higher (or the log has no sample there). The shares of the largest that
    :data:`MARK_BASELINE_FORCE` and :data:`MARK_HOLD_FORCE` set are then shares of the
    press's own force, whatever the F/T's zero (an F/T zeroed before a fixture was
    mounted reads it on every sample: on a Taxim mark session with 0.3 N so added, one
    press's template took two frames of its approach as the mark's, its crossing force
    35 % low)."""
    session = ctx.session
    tf, fz = session.force_times_s, session.forces_n[:, 2]
    f = np.interp(session.frame_times_s[run] + ctx.offset, tf, fz)
    if f.size == 0:
        return f
    t0 = float(session.frame_times_s[run[0]]) + ctx.offset - ctx.period
    rest = fz[(tf >= t0 - _REST_S) & (tf < t0)]
    # a rest still in the last press's release (presses close together) reads above this
    # press's first frames: the lower of the two
    return f - min(float(np.median(rest)) if rest.size else np.inf, float(np.min(f)))


def _mark_baseline(ctx: _PressContext, centre: tuple[float, float], run: np.ndarray,
                   fallback: float) -> tuple[float, int]:
    """The mark's score on this press's own approach, before the land can reach the gel:
    the median over its frames whose fz (the F/T log at their time) is under
    :data:`MARK_BASELINE_FORCE` of the press's largest (the indenter's contact moves the
    score at the mark on some renderers: Taxim's by up to 3.4 sd); `fallback` without such
    frames. Returns the baseline and the frames it used."""
    f = _press_forces(ctx, run)
    early = run[f < MARK_BASELINE_FORCE * float(np.max(f))] if f.size else run[:0]
    if early.size == 0:
        return fallback, 0
    return float(np.median([_mark_score(ctx, centre, int(i)) for i in early])), int(early.size)


def _mark_residual(ctx: _PressContext, centre: tuple[float, float], i: int
                   ) -> tuple[np.ndarray, np.ndarray] | None:
    """Frame `i`'s profile across the mark, less a quadratic background (the press's own
    shading), as :func:`bevel_score` fits it: ``(u_px, residual (n, 3))``; None where
    under 0.3 of the line lies in the image."""
    session = ctx.session
    cfg = session.config
    s = cfg.mm_per_px
    geom = BevelGeometry(offset_mm=cfg.bevel_offset_mm, direction_deg=cfg.bevel_direction_deg,
                         length_mm=cfg.bevel_length_mm)
    prof = bevel_profile(session.frame(int(i)), session.reference, centre, s, geom,
                         reach_px=max(0.8 / s, 12.0))
    if prof.coverage < 0.3:
        return None
    u, R = prof.u_px, np.asarray(prof.colour, np.float64)
    B = _background_basis(u)
    coef, *_ = np.linalg.lstsq(B, R, rcond=None)
    return u, R - B @ coef


def _mark_template_onset(ctx: _PressContext, centre: tuple[float, float], run: np.ndarray,
                         lead: np.ndarray | None = None
                         ) -> tuple[tuple[int, int, int] | None, str]:
    """A mark's onset from the press's own template: ``((onset, first, faint), why)``,
    None where the press has too few frames to build one or the template shows no step
    (``why`` says which); ``first`` is the first frame that shows a trace of the mark,
    ``faint`` the number of frames just before it that may show it too faintly to count.

    The per-frame score (:func:`bevel_score`) is a generic line filter; a thin mark
    under a renderer's shadows (Taxim's: a trough some 30 px wide) scores barely above
    an approach whose shading moves. Here the mark's change is what the press's hold
    (frames with fz at least :data:`MARK_HOLD_FORCE` of its largest) shows that its
    approach and release (under :data:`MARK_BASELINE_FORCE` of it, before the land can
    reach the gel) do not: the difference of their mean profiles across the mark,
    each less its quadratic background. Each frame is projected on that template (0:
    the approach's level, 1: the hold's); a hold frame on the template of the other
    hold frames, so that no frame is scored on its own noise. The onset is the first
    frame projected at least half-way whose next :data:`MARK_BLOCK` - 1 frames are
    half-way on average, and the mark counts as seen only when it steps there: the
    last frame under a quarter of the way lies at most two frames before the onset,
    and the step from it is :data:`MARK_Z_STEP` sds of a difference of two frames (the
    approach frames' projections' sd) high. A change that grows with the press's
    depth (the indenter's shading, no mark) rises over the approach instead.

    The mark's change grows with the land's depth past w0 (on Taxim's frames the projection
    ran about linear in it: 0.41 of the hold's depth past w0 projected 0.50), so a frame
    that crossed w0 shortly before it was taken can show the mark at less than half-way: the
    onset then lies a frame after the crossing's period. ``first`` walks back from the onset
    through the frames rising towards it while they lie :data:`MARK_Z_SEEN` sds (and
    :data:`MARK_TRACE` of the way) off the approach's level, and as far off the three
    frames before the one before it (their median), the same way (:func:`_departs`; a
    trace may project either way): the crossing lies in the period before ``first`` (on a
    Taxim session at 10 frames/s, one such press put its indenter's P(w0) 6 % high and its
    depths 8 um shallow).
    A trace rises from the frames before it; an approach whose shading lifts the mark's
    profile lifts them all (on a Taxim session without shadows, seed 171, the first press's
    four frames before its crossing projected 0.07 to 0.20 of the way, 1.7 to 4.9 sds: the
    last, 0.6 sd above that level, was taken for the first trace, its bracket 77 mN under
    P(w0), and the crossing forces named a stiffness step along time on the session's null;
    on seed 191 a frame 4.0 sds up, 3.7 above that level, put a bracket 120 mN under P(w0)).
    A trace's change turns into the hold's shape on its way up, so its projection may pass
    back through the approach's level for a frame: where the frame before ``first`` shows
    nothing, the one before that still starts the trace when it lies :data:`MARK_Z_BRIDGE`
    sds off (either way) and as far from that frame, and the walk goes on from there (an
    approach lifted by shading lifts both alike; on Taxim sessions without
    shadows, frames 3 to 10 um past w0 projected -0.5 to -2.0 of the way, their next frames
    about 0, and four brackets began 3 to 43 um past w0 without it).

    A mark's trace grows from nothing at w0, so a frame taken just past it may show the
    mark below any threshold that noise does not cross: ``faint`` counts the frames before
    ``first`` (at most :data:`MARK_FAINT_MAX`) projected over :data:`MARK_Z_FAINT` sds
    (and :data:`MARK_FAINT_FLOOR` of the way) off the approach's level and as far off the
    frames before them, whose periods the
    crossing's bracket then spans too (on a Taxim session at 30 frames/s without shadows,
    16 of 28 brackets missed P(w0), all above it; an indenter's P(w0) is the intersection
    of its presses' brackets, which one late bracket moves). A needless period widens the
    press's bracket downwards only, and so moves its indenter's intersection: the test
    is a rise, not any frame above the approach's level (issue 83).

    `lead`: frames just before the press's first frame in contact (no contact yet, so no
    mark), taken into the approach's frames: a fast approach at a low frame rate shows
    under three frames in contact before the land reaches the gel (on a Taxim session at
    12 frames/s and 1.3 mm/s, 9 of 17 presses, whose marks stepped 0 to 1.0 of the way
    at 0.003 sd, were refused as never seen without them)."""
    if lead is not None and len(lead):
        run = np.concatenate([np.asarray(lead, run.dtype), run])
    f = _press_forces(ctx, run)
    few = "the press has too few frames for its own template"
    if f.size == 0:
        return None, few
    top = float(np.max(f))
    hold_idx = np.flatnonzero(f >= MARK_HOLD_FORCE * top)
    last = int(hold_idx[-1])
    base_idx = np.flatnonzero(f[:last + 1] < MARK_BASELINE_FORCE * top)
    if base_idx.size < 3 or hold_idx.size < 2:
        return None, few
    res = [_mark_residual(ctx, centre, int(i)) for i in run[:last + 1]]
    if any(r is None for r in res):
        return None, "the mark's line lies mostly outside the image"
    R = np.stack([r[1] for r in res])
    base_mean = R[base_idx].mean(axis=0)
    D = R - base_mean
    hold_sum = D[hold_idx].sum(axis=0)
    T = hold_sum / hold_idx.size

    def along(d: np.ndarray, t: np.ndarray) -> float:
        tt = float(np.sum(t * t))
        return float(np.sum(d * t)) / tt if tt > 0 else 0.0

    a = np.array([along(D[j], T) for j in range(last + 1)])
    for j in hold_idx:                     # leave the frame out of its own template
        a[j] = along(D[j], (hold_sum - D[j]) / (hold_idx.size - 1))
    sd_a = max(float(np.std(a[base_idx], ddof=1)), 1e-3)
    # what each frame shows besides the template's shape, in the template's norm, and its
    # frame-to-frame noise over the approach (differences: a level that steps as the
    # indenter touches is no noise)
    shape = np.array([float(np.linalg.norm(D[j] - a[j] * T)) for j in range(last + 1)])
    shape /= max(float(np.linalg.norm(T)), 1e-12)
    step_sd = np.abs(np.diff(shape[base_idx]))
    sd_shape = max(float(np.median(step_sd)) / 0.6745 / np.sqrt(2.0) if step_sd.size else 0.0,
                   1e-3)

    def shows_shape(k: int) -> bool:
        """Frame `k` departs from the frames before it by a change the template's shape
        does not hold (:data:`MARK_TRACE_SHAPE`)."""
        d = shape[k] - _level_before(shape, k)
        return bool(d >= MARK_TRACE_SHAPE and d >= MARK_Z_SEEN * sd_shape)
    why = "no frame of the press steps half-way"
    for j in range(1, last + 1):
        if a[j] < 0.5 or a[j:j + MARK_BLOCK].mean() < 0.5:
            continue
        low = np.flatnonzero(a[:j] < 0.25)
        if low.size == 0 or j - int(low[-1]) > 2:
            why = "the press's frames rise towards it over the approach, with no step"
            break
        step = (a[j] - a[int(low[-1])]) / (np.sqrt(2.0) * sd_a)
        if step < MARK_Z_STEP:
            why = (f"its step is {step:.1f} sd of a frame difference, under "
                   f"{MARK_Z_STEP:g}")
            break
        first = j
        while True:
            while first > 0 and ((a[first - 1] < a[first]
                                  and _departs(a, first - 1, MARK_Z_SEEN * sd_a, MARK_TRACE))
                                 or shows_shape(first - 1)):
                first -= 1
            # a trace's change turns into the hold's shape on its way up: its projection
            # may pass back through the approach's level for a frame between an
            # unmistakable trace and the rest of the rise (MARK_Z_BRIDGE)
            if (first >= 2 and _departs(a, first - 2, MARK_Z_BRIDGE * sd_a, MARK_TRACE)
                    and abs(a[first - 2] - a[first - 1]) >= MARK_Z_BRIDGE * sd_a):
                first -= 2
                continue
            break
        faint = 0
        while (faint < MARK_FAINT_MAX and first - faint > 0
               and _departs(a, first - faint - 1, MARK_Z_FAINT * sd_a, MARK_FAINT_FLOOR)):
            faint += 1
        return (int(run[j]), int(run[first]), faint), ""
    return None, f"the press's own template shows no step: {why}"


#: Frames before a press's first frame in contact taken into its template's approach, at
#: most (:func:`_lead_frames`).
_LEAD_FRAMES = 3


def _lead_frames(ctx: _PressContext, run: np.ndarray) -> np.ndarray:
    """Up to :data:`_LEAD_FRAMES` frames just before `run`, after the last press's frames
    and within one frame period of each other (the camera running through the press's
    approach): the frames before its contact (:func:`_mark_template_onset`)."""
    runs = getattr(ctx, "runs", ())
    times = ctx.session.frame_times_s
    prev_end = max((int(r[-1]) for r in runs if int(r[-1]) < int(run[0])), default=-1)
    lead = []
    k = int(run[0]) - 1
    while (k > prev_end and len(lead) < _LEAD_FRAMES
           and times[k + 1] - times[k] < 1.5 * ctx.period):
        lead.append(k)
        k -= 1
    return np.array(lead[::-1], np.int64)


def _departs(a: np.ndarray, k: int, z_sd: float, floor: float) -> bool:
    """Whether frame `k`'s projection departs from the approach's level (0) by more than
    `z_sd` and `floor`, and by more than `z_sd` from the frames before it
    (:func:`_level_before`), the same way: a trace of the mark, which may project either
    way (on Taxim's frames a ridge pressed 3 um past w0 projected -0.52 of the way, 170
    sds, its next frame 1.05), where an approach whose shading moves drifts slowly."""
    d = a[k] - _level_before(a, k)
    return bool(abs(a[k]) > max(z_sd, floor) and abs(d) > z_sd and d * a[k] > 0)


def _level_before(a: np.ndarray, k: int) -> float:
    """The median projection of the (up to) three frames before frame `k`'s neighbour
    (``k - 4`` to ``k - 2``; 0 where none): the level a trace at `k` must rise above
    (:func:`_mark_template_onset`). The frame just before `k` is left out: it may show
    the mark's toe (:data:`MARK_Z_FAINT`)."""
    before = a[max(k - 4, 0):max(k - 1, 0)]
    return float(np.median(before)) if before.size else 0.0


def _mark_onset(ctx: _PressContext, centre: tuple[float, float], cand: np.ndarray,
                run: np.ndarray) -> tuple[int, float, int, int, bool]:
    """A bevel mark with no vernier: the first frame of `cand` where it shows firmly
    (:func:`certify_session`'s `bevel_threshold`), then back through the press's earlier
    frames while they show it too (`cand` starts near full contact, which the sink-in
    ring's growth can put frames after the mark's first showing), ``(frame, score)``.
    With the session's own rule, the press's own template decides first where it can
    (:func:`_mark_template_onset`); the score is then the onset frame's
    :func:`bevel_score`. ``(onset, score, first, periods, to_hold)``: ``first`` the first
    frame that shows a trace of the mark (the template's; the onset otherwise), where the
    crossing's bracket ends, ``periods`` the frame periods it spans back from there: 1
    plus the template's faint frames, 1 with a fixed threshold; and ``to_hold`` whether
    the bracket ends at the hold's start instead. Where the session's rule reads the
    press without its template (a hold too faint to build one: an overshoot of a few um)
    a noise frame can pass for the onset, early or late: the bracket then spans 2 periods
    and ends at the hold's start (on a Taxim session without shadows, a press with 4 um
    of overshoot read this way put its crossing force 7.0 sds under P(w0), and still 4.5
    with its bracket spanning two periods up to that onset)."""
    cfg = ctx.session.config
    rule = ctx.mark_rule
    if rule["rule"] == "auto":
        got, template_why = _mark_template_onset(ctx, centre, run, _lead_frames(ctx, run))
        if got is not None:
            return got[0], _mark_score(ctx, centre, got[0]), got[1], 1 + got[2], False
    scores = np.array([_mark_score(ctx, centre, int(i)) for i in cand])
    if rule["rule"] == "auto":
        base, n_base = _mark_baseline(ctx, centre, run, rule["median"])
        thr = base + MARK_Z_FRAME * rule["sd"]
        seen = scores > thr
        firm = np.zeros(seen.shape, bool)
        for j in np.flatnonzero(seen):
            block = scores[j:j + MARK_BLOCK]
            after = scores[j + 1:j + 1 + MARK_BLOCK]
            # the block is the mark, and frame j looks like it rather than the approach (a
            # frame just before the step, lifted by noise or the approach, is not the onset)
            firm[j] = (block.mean() > base + MARK_Z_BLOCK * rule["sd"] / np.sqrt(block.size)
                       and (after.size == 0
                            or scores[j] > 0.5 * (base + float(np.median(after)))))
        text = (f"the rule from the session's own frames: this press's approach scores "
                f"{base:.2f} ({n_base} frames), the no-contact frames' sd {rule['sd']:.2f}; a "
                f"frame above {thr:.2f} whose next {MARK_BLOCK - 1} average above "
                f"{base + MARK_Z_BLOCK * rule['sd'] / np.sqrt(MARK_BLOCK):.2f} with it; "
                f"{template_why}")
    else:
        thr = rule["threshold"]
        seen = scores > thr
        firm = seen & (np.append(seen[1:], False) | (scores > 2 * thr))
        text = f"the rule: two consecutive frames above {thr:g}, or one above {2 * thr:g}"
    if not firm.any():
        raise _Reject("bevel never seen", f"no frame of the press shows a mark "
                      f"{cfg.bevel_offset_mm:g} mm from the indenter at "
                      f"{cfg.bevel_direction_deg:g} deg (best signal-to-noise ratio "
                      f"{scores.max():.1f}; {text})", score=float(scores.max()))
    first = int(np.argmax(firm))
    onset, score = int(cand[first]), float(scores[first])
    # back through earlier frames while they show it too; with the session's rule, a frame
    # must also lie nearer the mark's level (its first block's median) than the baseline:
    # a faint mark's noise before the step is not the mark
    back = thr
    if rule["rule"] == "auto":
        back = max(thr, 0.5 * (base + float(np.median(scores[first:first + MARK_BLOCK]))))
    j = int(np.searchsorted(run, onset))
    while j > 0:
        before = _mark_score(ctx, centre, int(run[j - 1]))
        if not before > back:
            break
        j -= 1
        onset, score = int(run[j]), before
    auto = rule["rule"] == "auto"
    return onset, score, onset, 2 if auto else 1, auto


def _crossing_force(session, run: np.ndarray, t_on: float, offset: float, period: float,
                    periods: int = 1, to_hold: bool = False
                    ) -> tuple[float, float, tuple[float, float], float]:
    """fz when the land reached w0, from the F/T log, its uncertainty, N, the instants
    that bracket it, F/T clock, s, and the hold's start (F/T clock, s; NaN where the log
    shows none).

    The mark first shows at `t_on` (F/T clock), so the land reached w0 within the
    `periods` frame periods before (1, or 2 where the frame before may show it faintly:
    :func:`_mark_onset`): fz at the ends of ``[t_on - periods * period, t_on]`` brackets
    P(w0) (:func:`crossing_bracket`). A bracket is the frames' periods whatever the stage
    did: where the stage stopped (the hold's start, :func:`hold_start`) inside them, the
    force at the instants past the stop is the approach's ramp extrapolated (the force
    the press would have had, had it gone on), not the hold's. The frames' phase is
    independent of the press, so the crossing is uniform over the periods; clipped at the
    hold's start, the bracket held it near its top wherever the stage stopped within a
    period of w0 (an overshoot under one period's travel), and the brackets' middles read
    P(w0) low: on Taxim mark sessions at 10 and 12 frames/s the clipped brackets put the
    depths 20 to 60 um deep (benchmarks/bench_mark_sweep.py). Where the frame before the
    first trace was already in the hold (the mark seen late), the crossing lies in the
    `periods` before the hold's start. `to_hold`: the bracket ends at the hold's start
    whatever `t_on` (an onset that may be early or late), from the periods before the
    earlier of the two (on a Taxim session without shadows, a press with 14 um of
    overshoot read 2 frames into its hold: a bracket from 2 periods before that to the
    hold's start was half a period wide, its middle 5.8 sds above P(w0)). ``(nan, nan,
    span, t_hold)`` when the log does not cover it.
    """
    tf, fz = session.force_times_s, session.forces_n[:, 2]
    times = session.frame_times_s
    t_hold = hold_start(tf, fz, float(times[run[0]]) + offset - period,
                        float(times[run[-1]]) + offset + period)
    t_b, t_a = t_on, t_on - periods * period
    if t_hold is not None and (to_hold or t_a >= t_hold):
        t_b = t_hold
        t_a = min(t_on, t_b) - periods * period
    hold = float("nan") if t_hold is None else float(t_hold)
    return (*crossing_bracket(tf, fz, t_a, t_b, ramp_end_s=hold), (float(t_a), float(t_b)),
            hold)


def crossing_bracket(force_times_s: np.ndarray, fz_n: np.ndarray, t_a: float, t_b: float,
                     ramp_end_s: float = float("nan")) -> tuple[float, float]:
    """The force a press had when it crossed a depth between two instants, N.

    Parameters
    ----------
    force_times_s : (M,) float64 ndarray
        F/T clock, s.
    fz_n : (M,) float64 ndarray
        Normal force, N: the F/T log's, or the elastic force behind it for a relaxing
        gel (:func:`~tactilevision.mechanics.elastic_force`).
    t_a, t_b : float
        The instants the crossing lies between, F/T clock, s
        (:attr:`CertifiedPress.onset_span_s`).
    ramp_end_s : float, default NaN
        Where the approach's ramp ended (the hold's start, F/T clock, s;
        :attr:`CertifiedPress.hold_start_s`): at an instant past it the force is
        the ramp's, a straight line fitted to the :data:`_RAMP_S` of fz before it
        (or the bracket's length, if longer) and extrapolated, not the hold's.
        NaN: fz at both instants.

    Returns
    -------
    force, sd : float
        The middle of the bracket ``[fz(t_a), fz(t_b)]`` (a 10 ms moving average read at
        the instants), widened by twice that average's noise, and the sd of a uniform
        over it; ``(nan, nan)`` when the log does not cover the instants.
    """
    tf, fz = np.asarray(force_times_s, np.float64), np.asarray(fz_n, np.float64)
    if not (np.isfinite(t_a) and np.isfinite(t_b)) or tf.size < 2:
        return float("nan"), float("nan")
    # the log's times increase strictly (read_session): the samples about the bracket by
    # bisection, their own spacing, not a pass over the whole log per press
    i_a, i_b = np.searchsorted(tf, [t_a, t_b])
    dt = float(np.median(np.diff(tf[max(i_a - 20, 0):min(i_b + 20, tf.size)])))
    k = max(1, round(0.01 / dt))
    sel = np.arange(np.searchsorted(tf, t_a - k * dt, side="left"),
                    np.searchsorted(tf, t_b + k * dt, side="right"))
    if sel.size < k + 2:
        return float("nan"), float("nan")
    smooth = np.convolve(fz[sel], np.ones(k) / k, mode="same")
    ok = np.arange(sel.size)
    ok = ok[(ok >= k // 2) & (ok < sel.size - k // 2)]          # the average's own edges
    if ok.size < 2:
        return float("nan"), float("nan")
    f_a, f_b = np.interp([t_a, t_b], tf[sel][ok], smooth[ok])
    if np.isfinite(ramp_end_s) and t_b > ramp_end_s:
        ramp = _ramp_line(tf, fz, float(ramp_end_s), max(_RAMP_S, t_b - t_a))
        if ramp is not None:
            f_a = float(np.polyval(ramp, t_a)) if t_a > ramp_end_s else f_a
            f_b = float(np.polyval(ramp, t_b))
    noise = float(np.std(np.diff(fz[sel]))) / np.sqrt(2.0 * k)      # one smoothed sample's
    # the bracket [fz(t_a), fz(t_b)] holds P(w0), widened by twice the smoothed noise; given
    # as its middle and the sd of a uniform over it (crossing_forces reads it back)
    lo, hi = min(f_a, f_b) - 2 * noise, max(f_a, f_b) + 2 * noise
    return float(0.5 * (lo + hi)), float((hi - lo) / np.sqrt(12.0))


#: Least span of the approach's force before the hold's start that its ramp is fitted to, s
#: (:func:`crossing_bracket`).
_RAMP_S = 0.05


def _ramp_line(tf: np.ndarray, fz: np.ndarray, t_end: float, span: float
               ) -> np.ndarray | None:
    """The approach's ramp, a straight line (``np.polyval`` coefficients) fitted by least
    squares to fz over ``[t_end - span, t_end]``; None with fewer than 5 samples there."""
    i0, i1 = np.searchsorted(tf, [t_end - span, t_end], side="right")
    if i1 - i0 < 5:
        return None
    slope, level = np.polyfit(tf[i0:i1] - t_end, fz[i0:i1], 1)     # centred: well posed
    return np.array([slope, level - slope * t_end])


def _onset_travel(session, run: np.ndarray, onset: int, offset: float, period: float,
                  w0: float) -> float:
    """The stage's travel in one frame period at a mark's onset, mm (the onset frame shows
    the mark within that of w0: its uncertainty, uniform, is that / sqrt(12)).

    The stage speed is read from the approach: the indenter first touches the
    gel when the F/T force first rises (2% of its value at the onset, on a
    20 ms moving average), and the mark shows w0 deeper at `onset`.
    """
    times = session.frame_times_s
    t_on = float(times[onset]) + offset
    t_first = float(times[run[0]]) + offset - 1.0
    sel = (session.force_times_s >= t_first) & (session.force_times_s <= t_on)
    t, f = session.force_times_s[sel], session.forces_n[sel, 2]
    travel = float(times[onset] - times[run[0]]) + period        # fallback: the frames'
    if t.size > 40:
        k = max(1, round(0.02 / float(np.median(np.diff(t)))))
        fs = np.convolve(f, np.ones(k) / k, mode="same")
        above = np.flatnonzero(fs > 0.02 * fs[-k - 1])
        if above.size and fs[-k - 1] > 0:
            travel = t_on - float(t[above[0]])
    speed = w0 / max(travel, period)
    return speed * period
