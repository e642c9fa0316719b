"""Certify the presses of a session: which indenter, when the bevel shows, the force then.

The steps of the paper's procedure (method.md, "Measurement procedure"), one
press at a time, on a :class:`~tactilevision.io.Session`:

1. contact in every frame (colour change above the camera noise), presses as
   runs of frames in contact;
2. the clock offset between frames and F/T log: the one stated in
   ``session.toml``, checked against the presses, else estimated from them
   (:func:`estimate_clock_offset` on the onsets, sharpened by
   :func:`refine_clock_offset` on the whole press profiles); a stated offset
   that the presses contradict (by more than half a frame period or 20 ms)
   is replaced by the estimate, with a warning;
3. per press: the footprint (a circle on the flat region enclosed by the
   contact ring; its radius must match a, the pad edge must not cut it), the
   indenter (from ``presses.csv``: row by row when it lists as many presses as
   the frames show, else the nearest commanded position; without it the
   press is rejected, as photometric depth cannot tell the indenters), the first
   frame where the bevel line shows (among the frames within 10% of the
   press's largest contact, seen in two consecutive frames or at twice the
   threshold), the F/T window of ``window_samples``
   samples from that instant (mean, std), or ending where the hold ends
   (``[force_sensor] window_at = "end"``: :func:`hold_end`), and the check
   |Fxy| << Fz;
4. every press that fails a check is listed with its reason, none is dropped
   silently.

The certified *depth* is left to the caller (:func:`certified_depths`): the
gauge block's w0, or the depth at which the bulging gel meets the land, which
needs nu.

The results and thresholds live in :mod:`._results`, the holds in the F/T log in
:mod:`._holds`, a bevel mark's onset in :mod:`._onset` and a machined bevel's
band in :mod:`._vernier_presses`; this module runs the steps.
"""


from __future__ import annotations

import os
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace

import numpy as np

from .._checks import InputError
from ._bevel import footprint_from_frame
from ._footprint import Footprint
from ._force import force_window
from ._holds import approach_start, hold_end, hold_start
from ._land import land_contact_depths_mm
from ._mask import contact_mask, noise_level
from ._onset import _crossing_force, _mark_null, _mark_onset, _onset_travel
from ._results import (
    BACKGROUND_DEGREE,
    FRAME_SNR,
    MARK_BASELINE_FORCE,
    MARK_BLOCK,
    MARK_HOLD_FORCE,
    MARK_NULL_FRAMES,
    MARK_Z_BLOCK,
    MARK_Z_FRAME,
    MARK_Z_STEP,
    MAX_CLOSURE_MM,
    MAX_SATURATED_FRACTION,
    MAX_TANGENTIAL_RATIO,
    MIN_BAND_CONTRAST,
    MIN_BEVEL_COVERAGE,
    VERNIER_SNR,
    Certification,
    CertifiedPress,
    Rejection,
    _PressContext,
    _Reject,
)
from ._sync import (
    ClockSync,
    _on_search_edge,
    estimate_clock_offset,
    force_onsets,
    press_clock_offset,
    refine_clock_offset,
)
from ._vernier import BevelGeometry
from ._vernier_presses import (
    AGREE_PX,
    BLUR_SHRINK,
    CREST_NOMINAL_PX,
    CREST_TOLERANCE_PX,
    EDGE_SHARED_FRACTION,
    INDENTER_CLEARANCE_MM,
    LINES_RSS_RATIO,
    SHADOW_RATIO,
    _read_vernier_presses,
    _vernier_onset,
    unresolved_closure,
    vernier_shared_mm,
)

# the thresholds, results and hold finders live in their own modules; they stay importable
# from here
__all__ = [
    "AGREE_PX",
    "BACKGROUND_DEGREE",
    "BLUR_SHRINK",
    "CREST_NOMINAL_PX",
    "CREST_TOLERANCE_PX",
    "EDGE_SHARED_FRACTION",
    "FRAME_SNR",
    "INDENTER_CLEARANCE_MM",
    "LINES_RSS_RATIO",
    "MARK_BASELINE_FORCE",
    "MARK_BLOCK",
    "MARK_HOLD_FORCE",
    "MARK_NULL_FRAMES",
    "MARK_Z_BLOCK",
    "MARK_Z_FRAME",
    "MARK_Z_STEP",
    "MAX_CLOSURE_MM",
    "MAX_SATURATED_FRACTION",
    "MAX_TANGENTIAL_RATIO",
    "MIN_BAND_CONTRAST",
    "MIN_BEVEL_COVERAGE",
    "SHADOW_RATIO",
    "VERNIER_SNR",
    "Certification",
    "CertifiedPress",
    "Rejection",
    "approach_start",
    "certified_depths",
    "certify_session",
    "hold_end",
    "hold_start",
    "unresolved_closure",
    "vernier_shared_mm",
]


class _Sized:
    """An iterator with a length, so that a progress bar knows its total."""

    def __init__(self, it, n: int) -> None:
        self._it, self._n = it, n

    def __iter__(self):
        return iter(self._it)

    def __len__(self) -> int:
        return self._n


def _runs(times: np.ndarray, on: np.ndarray, max_gap_s: float) -> list[np.ndarray]:
    """The presses: runs of frames `on` no more than `max_gap_s` apart, two frames or more."""
    idx = np.flatnonzero(on)
    if idx.size == 0:
        return []
    split = np.flatnonzero(np.diff(times[idx]) > max_gap_s) + 1
    return [r for r in np.split(idx, split) if r.size >= 2]


def _saturated(frame: np.ndarray, reference: np.ndarray, mask: np.ndarray) -> float:
    """Fraction of the contact's bounding box saturated in the frame but not in the reference.

    Saturated: a channel at 255 (over-exposed) or every channel at 0 (black).
    A single dark channel at 0 is not counted: dim references (GelSlim 3.0)
    have channels that flicker to 0 with the noise alone.
    """
    rows, cols = np.nonzero(mask)
    if rows.size == 0:
        return 0.0
    win = (slice(rows.min(), rows.max() + 1), slice(cols.min(), cols.max() + 1))

    def clipped(img: np.ndarray) -> np.ndarray:
        return np.any(img == 255, axis=-1) | np.all(img == 0, axis=-1)

    new = clipped(frame[win]) & ~clipped(reference[win])
    return float(new.mean()) if new.size else 0.0


def certify_session(session, *, min_contact_px: int = 200,
                    bevel_threshold: float | str = "auto",
                    progress: Callable | None = None, sync_fz_n: np.ndarray | None = None,
                    contact_area_px: np.ndarray | None = None) -> Certification:
    """Find and certify every press of a session.

    Parameters
    ----------
    session : tactilevision.io.Session
    min_contact_px : int, default 200
        A frame is in contact when its contact mask holds this many pixels.
    bevel_threshold : float or 'auto', default 'auto'
        For a bevel mark with no vernier (``bevel_angle_deg = 0``): when the
        mark is seen. ``'auto'``: from the session's own frames. The score
        (:func:`bevel_score`) of no-contact frames at each press's mark
        (:data:`MARK_NULL_FRAMES` per press, the nearest in time) gives the
        score's frame-to-frame sd s (each press's scores about their own
        median, pooled; 1.4826 MAD); each press's approach, its frames with
        fz under :data:`MARK_BASELINE_FORCE` of its largest, gives its
        baseline b. A frame shows the mark when its score exceeds b +
        :data:`MARK_Z_FRAME` s, the mean of it and the next frames
        (:data:`MARK_BLOCK` in all, while the press lasts) exceeds b +
        :data:`MARK_Z_BLOCK` s / sqrt(n), and it lies nearer the next frames'
        median than b: the mark stays through the hold, noise does not
        (Taxim's thin mark line with shadows scored 7 to 9.6 where its
        approach scored 5 to 8 and the no-contact frames 4.6 +- 1.0, under
        the old fixed 12: 14 of 20 presses certified, 0 before). A number:
        the fixed rule, two consecutive frames above it or one above twice it
        (at most 9.0 on approach frames before the mark, at least 16.6 with
        it, over the 48 good presses of the legacy sample session;
        ``benchmarks/bench_certification.py``). A machined bevel is seen
        above :data:`VERNIER_SNR` either way.
    progress : callable, optional
        Wraps the frame iterator (e.g. ``tqdm``).
    sync_fz_n : (M,) float64 ndarray, optional
        The normal force the clock is synchronised on, in place of the F/T
        log's fz (its times): for a viscoelastic gel, the elastic force
        (:func:`~tactilevision.mechanics.elastic_force`), which follows the
        depth, and so the frames' contact area, where the measured force
        relaxes during each hold and would pull the profile correlation off
        (42 ms on a gel with g 0.25, tau 0.7 s). Force windows, holds and
        forces still come from the log.
    contact_area_px : (F,) int64 ndarray, optional
        The frames' contact areas of an earlier certification of this
        session (:attr:`Certification.contact_area_px`), to skip reading the
        frames again.

    Returns
    -------
    Certification

    Raises
    ------
    InputError
        When no press is found in the frames, or the F/T log and the frames
        share no press onsets (the clock cannot be synchronised); for a
        `sync_fz_n` or `contact_area_px` of the wrong length.
    """
    cfg = session.config
    ref = session.reference
    times = session.frame_times_s
    nf = session.n_frames
    sigma = noise_level(session.frame(0), ref)
    area = _contact_areas(session, sigma, min_contact_px, progress, contact_area_px)
    period = float(np.median(np.diff(times))) if nf > 1 else 1.0
    runs = _runs(times, area >= min_contact_px, max_gap_s=2.5 * period)
    if not runs:
        raise InputError(f"no press found in the {nf} frames of {session.path} (no frame has "
                         f"{min_contact_px} px of colour change above the noise)")
    warnings: list[str] = []
    offset, source, clock, clock_notes, clock_se = _sync_clock(session, times, area, runs,
                                                               period, sync_fz_n)
    warnings.extend(clock_notes)
    commanded = session.presses
    if commanded is not None and len(commanded["press"]) != len(runs):
        warnings.append(f"presses.csv lists {len(commanded['press'])} presses, the frames show "
                        f"{len(runs)}: presses are matched to the nearest commanded position")
    geom = BevelGeometry(offset_mm=cfg.bevel_offset_mm, direction_deg=cfg.bevel_direction_deg,
                         angle_deg=cfg.bevel_angle_deg, length_mm=cfg.bevel_length_mm)
    mark_rule = None
    if geom.tan_theta <= 0:
        if bevel_threshold == "auto":
            mark_rule = _mark_null(session, runs, area, min_contact_px, sigma)
            if mark_rule is None:
                warnings.append("too few frames without contact to read the mark's noise from: "
                                "the fixed threshold 12 is used")
            else:
                warnings.append(
                    f"bevel mark seen from the session's own frames: {mark_rule['n_frames']} "
                    f"no-contact frames score {mark_rule['median']:.2f} at the presses' marks, "
                    f"+- {mark_rule['sd']:.2f} from frame to frame; a frame shows it "
                    f"{MARK_Z_FRAME:g} sd above its press's approach, when it and the next "
                    f"{MARK_BLOCK - 1} average {MARK_Z_BLOCK:g} sd / sqrt({MARK_BLOCK}) above "
                    "it and it lies nearer the mark's level than the approach's; first, each "
                    "press's own template (its hold's profile across the mark less its "
                    "approach's) is looked for as a step from the approach to the hold")
        if mark_rule is None:
            thr = 12.0 if bevel_threshold == "auto" else float(bevel_threshold)
            mark_rule = {"rule": "fixed", "threshold": thr}
    ctx = _PressContext(session=session, sigma=sigma, area=area, period=period, offset=offset,
                        geom=geom, n_runs=len(runs), mark_rule=mark_rule, runs=tuple(runs))

    certified: list[CertifiedPress] = []
    rejected: list[Rejection] = []
    pending: list[dict] = []          # vernier presses waiting for the session's flank colours
    prev_end = float("nan")
    for k, run in enumerate(runs):
        got = _certify_press(ctx, k, run, wait_s=float(times[run[0]]) - prev_end)
        prev_end = float(times[run[-1]])
        if isinstance(got, Rejection):
            rejected.append(got)
        elif isinstance(got, dict):
            pending.append(got)
        else:
            certified.append(got)
    optics = None
    if pending:
        read, faint, optics = _read_vernier_presses(pending, geom, cfg.mm_per_px)
        certified.extend(read)
        rejected.extend(faint)
        rejected.sort(key=lambda r: r.press)
        certified.sort(key=lambda p: p.press)
    return Certification(presses=certified, rejected=rejected, clock=clock,
                         clock_offset_s=offset, clock_source=source, noise_sigma=sigma,
                         clock_offset_se_s=clock_se,
                         contact_area_px=area, warnings=warnings, bevel_optics=optics,
                         mark_rule=mark_rule,
                         press_spans_s=np.array([(times[r[0]], times[r[-1]]) for r in runs],
                                                np.float64).reshape(-1, 2))


def _contact_areas(session, sigma: float, min_contact_px: int, progress: Callable | None,
                   contact_area_px: np.ndarray | None) -> np.ndarray:
    """Step 1: the contact area of every frame, px, (F,) int64 (or the given one, checked)."""
    nf = session.n_frames
    area = np.zeros(nf, np.int64)
    if contact_area_px is not None:
        if np.shape(contact_area_px) != (nf,):
            raise InputError(f"contact_area_px has {np.size(contact_area_px)} values for {nf} "
                             "frames")
        area[:] = contact_area_px
        return area
    ref = session.reference

    def contact_px(i: int) -> int:
        return int(np.count_nonzero(contact_mask(session.frame(i), ref, sigma=sigma)))

    # OpenCV decodes and filters outside the GIL: threads use every core
    with ThreadPoolExecutor(max_workers=max(1, min(4, os.cpu_count() or 1))) as pool:
        it = pool.map(contact_px, range(nf))
        for i, n_px in enumerate(it if progress is None else progress(_Sized(it, nf))):
            area[i] = n_px
    return area


def _centre(fp: Footprint | None) -> tuple[float, float] | None:
    """The footprint's centre ``(x, y)``, px, or None without one."""
    return None if fp is None else (float(fp.center_px[0]), float(fp.center_px[1]))


def _certify_press(ctx: _PressContext, k: int, run: np.ndarray, wait_s: float
                   ) -> CertifiedPress | dict | Rejection:
    """Step 3 for one press (the run of frames `run`): a certified press, a vernier press
    waiting for the session's flank colours (a dict), or its rejection."""
    session = ctx.session
    times = session.frame_times_s
    t0 = float(times[run[0]])
    peak = int(run[np.argmax(ctx.area[run])])
    fp = None
    try:
        fp = _press_footprint(ctx, peak)
        return _press_reading(ctx, k, run, peak, fp, wait_s)
    except _Reject as r:
        return Rejection(press=k, reason=r.reason, detail=r.detail, t_frame_s=t0,
                         frame=peak if r.at is None else r.at, bevel_score=r.score,
                         centre_px=_centre(fp) if r.centre is None else r.centre)


def _press_footprint(ctx: _PressContext, peak: int) -> Footprint:
    """The footprint at the press's deepest frame; raises :class:`_Reject` for saturation,
    a cut or missing footprint, a wrong radius."""
    session = ctx.session
    cfg = session.config
    frame = session.frame(peak)
    mask = contact_mask(frame, session.reference, sigma=ctx.sigma)
    sat = _saturated(frame, session.reference, mask)
    fp = footprint_from_frame(mask, cfg.mm_per_px, indenter_radius_mm=cfg.indenter_radius_mm)

    def fail(reason: str, detail: str) -> _Reject:
        return _Reject(reason, detail, centre=_centre(fp))

    if sat > MAX_SATURATED_FRACTION:
        raise fail("saturated frames", f"{100 * sat:.1f}% of the pixels of the contact are "
                   "saturated (a channel at 255 or all at 0) and are not in the reference")
    edge_touch = bool(mask[0].any() or mask[-1].any() or mask[:, 0].any() or mask[:, -1].any())
    if fp is None or fp.cut_by_edge:
        if edge_touch or (fp is not None and fp.cut_by_edge):
            raise fail("footprint cut by the pad edge",
                       "the contact reaches the edge of the sensed area")
        raise fail("no footprint", "the contact encloses no flat region")
    if not fp.radius_ok:
        raise fail("footprint radius", f"fitted radius {fp.radius_mm:.3f} mm, indenter "
                   f"{cfg.indenter_radius_mm:g} mm")
    return fp


def _press_indenter(ctx: _PressContext, k: int, x_mm: float, y_mm: float) -> int:
    """Which indenter made press `k`, from ``presses.csv``: row by row when it lists as many
    presses as the frames show, else the nearest commanded position."""
    commanded = ctx.session.presses
    if commanded is None:
        raise _Reject("unknown indenter", "no presses.csv tells which indenter was pressed")
    if len(commanded["press"]) == ctx.n_runs:
        j = k
    else:
        j = int(np.argmin(np.hypot(commanded["x_mm"] - x_mm, commanded["y_mm"] - y_mm)))
    indenter = int(commanded["indenter"][j])
    if indenter < 0:
        raise _Reject("unknown indenter", "no presses.csv tells which indenter was pressed")
    return indenter


def _press_reading(ctx: _PressContext, k: int, run: np.ndarray, peak: int, fp: Footprint,
                   wait_s: float) -> CertifiedPress | dict:
    """The indenter, the bevel's onset and the force window of a press with a good
    footprint; raises :class:`_Reject` at the first check that fails."""
    session = ctx.session
    cfg = session.config
    s = cfg.mm_per_px
    times = session.frame_times_s
    hw, hh = (session.shape[1] - 1) / 2, (session.shape[0] - 1) / 2
    centre = _centre(fp)
    x_mm, y_mm = (fp.center_px[0] - hw) * s, (fp.center_px[1] - hh) * s
    indenter = _press_indenter(ctx, k, x_mm, y_mm)
    # the bevel is looked for in the frames near full contact (the land meets the gel at
    # the deepest part of the press)
    area = ctx.area
    full = run[area[run] >= 0.9 * area[peak]]
    start = int(np.searchsorted(run, full[0]))
    cand = run[max(0, start - 1):int(np.searchsorted(run, full[-1])) + 1]
    t_hold_end = float(times[full[-1]])
    if ctx.vernier:
        got = _vernier_onset(session, ctx.geom, centre, s, cand, ctx.reach, ctx.period,
                             ctx.half, ctx.offset, float(times[run[0]]))
        if isinstance(got, Rejection):
            raise _Reject(got.reason, got.detail, at=got.frame, score=got.bevel_score)
        t_cert, onset, window, profiles, score, quick = got
    else:
        onset, score, first, periods, to_hold = _mark_onset(ctx, centre, cand, run)
        t_cert = float(times[onset])
    hold_mid = _window_middle(session, t_cert, ctx.offset, ctx.half, t_hold_end, ctx.period)
    if isinstance(hold_mid, tuple):
        raise _Reject(*hold_mid, at=onset, score=score)
    try:
        fw = force_window(session.force_times_s, session.forces_n,
                          t_cert + ctx.offset + hold_mid, cfg.window_samples)
    except InputError as exc:
        raise _Reject("force window outside the log", str(exc), at=onset, score=score) from None
    if fw.tangential_ratio > MAX_TANGENTIAL_RATIO:
        raise _Reject("misaligned", f"|Fxy| / Fz = {fw.tangential_ratio:.3f} > "
                      f"{MAX_TANGENTIAL_RATIO:g}", at=onset, score=score)
    w0 = float(cfg.depths_mm[indenter])
    press = CertifiedPress(
        press=k, indenter=indenter, w0_mm=w0, frame=onset,
        t_frame_s=t_cert, footprint=fp, x_mm=float(x_mm), y_mm=float(y_mm),
        force_n=fw.fz_n, force_std_n=fw.fz_std_n, force_sem_n=fw.fz_sem_n,
        fx_n=fw.fx_n, fy_n=fw.fy_n,
        tangential_ratio=fw.tangential_ratio, time_s=t_cert - float(times[0]),
        hold_s=hold_mid, wait_s=wait_s, bevel_score=score)
    if ctx.vernier:
        return {"press": press, "profiles": profiles, "window": window, "quick": quick,
                "t0": float(times[run[0]]), "centre": centre}
    travel = _onset_travel(session, run, first, ctx.offset, ctx.period, w0)
    f_on, f_on_se, span, t_hold = _crossing_force(session, run, float(times[first]) + ctx.offset,
                                                  ctx.offset, ctx.period, periods, to_hold)
    return replace(press, rule="onset", closure_mm=0.0, closure_std_mm=travel / np.sqrt(12.0),
                   force_onset_n=f_on, force_onset_sem_n=f_on_se, travel_mm=float(travel),
                   onset_span_s=span, hold_start_s=t_hold)


def _window_middle(session, t_cert: float, offset: float, half: float, t_hold_end: float,
                   period: float) -> float | tuple[str, str]:
    """Where a press's force window lies: its middle after the hold's start, s, or the
    rejection ``(reason, detail)`` when it cannot lie there.

    ``window_at = "start"``: half the window after the hold's start, which the window
    must not run past (the last full-contact frame). ``"end"``: ending where the release
    begins (:func:`hold_end` on the F/T log), which must leave room for the window.
    """
    cfg = session.config
    if cfg.window_at == "end":
        t_release = hold_end(session.force_times_s, session.forces_n[:, 2], t_cert + offset)
        if t_release is None:
            return ("hold end not found", "window_at = 'end', but the F/T log shows no "
                    f"release after the hold that starts at {t_cert:.3f} s (frames' clock)")
        middle = t_release - half - (t_cert + offset)
        if middle < half - 1e-9:
            return ("hold too short", f"the hold lasts {t_release - t_cert - offset:.3f} s, "
                    f"less than the {cfg.window_samples}-sample force window")
        return middle
    if t_cert + 2 * half > t_hold_end + period:
        return ("bevel seen too late", f"the bevel shows at {t_cert:.3f} s, the "
                f"{cfg.window_samples}-sample force window would run past the hold "
                f"(last full-contact frame {t_hold_end:.3f} s)")
    return half


#: Searches of +-span each that the profile correlation may move through before the
#: clock is called unread (:func:`_sync_clock`).
CLOCK_SEARCHES = 4


def _sync_clock(session, times: np.ndarray, area: np.ndarray, runs: list[np.ndarray],
                period: float, sync_fz_n: np.ndarray | None
                ) -> tuple[float, str, ClockSync | None, list[str], float]:
    """The clock offset between frames and F/T log (step 2 of the module docstring).

    Returns ``(offset_s, source, clock, warnings, se_s)``: the offset used (the median of
    the presses' own profile correlations where five or more give one:
    :func:`press_clock_offset`; the all-press correlation else), 'session.toml' or
    'estimated', the onset match (None when too few onsets), and the warning when a stated
    offset is contradicted by the presses.
    """
    cfg = session.config
    warnings: list[str] = []
    frame_on = np.array([times[r[0]] for r in runs])
    fz = session.forces_n[:, 2]
    _check_fz_sign(session, fz)
    force_on = force_onsets(session.force_times_s, fz)
    tol = max(0.05, 2.5 * period)
    clock = None
    refined = None
    se = float("nan")
    if len(runs) >= 2 and force_on.size >= 2:
        clock = estimate_clock_offset(frame_on, force_on, tolerance_s=tol)
        if sync_fz_n is not None and np.shape(sync_fz_n) != fz.shape:
            raise InputError(f"sync_fz_n has {np.size(sync_fz_n)} values for {fz.size} F/T "
                             "samples")
        fz_sync = fz if sync_fz_n is None else sync_fz_n
        span, step = max(0.2, 3 * period), 1.0 / cfg.rate_hz
        # a best offset on the search's edge is a bound: the search moves there and goes
        # on (the onsets may be off by more than the span)
        start = clock.offset_s
        for _ in range(CLOCK_SEARCHES):
            refined, _ = refine_clock_offset(times, area, session.force_times_s, fz_sync,
                                             start, span_s=span, step_s=step)
            if not _on_search_edge(refined, start, span, step):
                break
            start = refined
        else:
            warnings.append(
                f"the frames' contact area and the F/T force correlate best ever further "
                f"from the press onsets' clock offset ({clock.offset_s:.3f} s; searched "
                f"{CLOCK_SEARCHES} x +-{span:g} s to {refined:.3f} s, which is used): the "
                "presses do not pin the clock; give [force_sensor] clock_offset_s in "
                "session.toml")
        median, se, _ = press_clock_offset(times, area, runs, session.force_times_s, fz_sync,
                                           refined, span_s=span, step_s=step)
        # within one grid step of the all-press value, that value is kept (the same step:
        # only the float's last digits would move)
        if np.isfinite(median) and abs(median - refined) >= 0.5 * step:
            refined = median
    if cfg.clock_offset_s is not None:
        offset, source = float(cfg.clock_offset_s), "session.toml"
        if refined is not None and abs(refined - offset) > max(0.5 * period, 0.02):
            warnings.append(
                f"session.toml gives clock_offset_s = {offset:g} s but the presses say "
                f"{refined:.3f} s ({clock.n_matched} onsets matched, refined on the press "
                "profiles): the estimate is used")
            offset, source = refined, "estimated"
    elif refined is not None:
        offset, source = refined, "estimated"
    else:
        raise InputError(f"{session.path}: session.toml has no [force_sensor] clock_offset_s and "
                         "the frames and the F/T log share too few press onsets to estimate it")
    return offset, source, clock, warnings, (se if source == "estimated" else float("nan"))


def _check_fz_sign(session, fz: np.ndarray) -> None:
    """Refuse an F/T log whose presses read negative (formats.md: fz_n > 0 pushing in):
    a flipped z axis would otherwise show as a clock that cannot be synchronised."""
    if fz.size < 10:
        return
    lo, hi = (float(v) for v in np.percentile(fz, [0.5, 99.5]))
    base = float(np.median(fz))
    if base - lo > 3.0 * max(hi - base, 1e-9) and base - lo > 0.05:
        raise InputError(f"{session.path / 'forces.csv'}: fz_n departs from its rest level "
                         f"downwards (to {lo:.3g} N, rest {base:.3g} N, up to {hi:.3g} N) while "
                         "the frames show presses: the F/T sensor's z axis points the other way? "
                         "fz_n must be positive when the indenter pushes into the gel")


def certified_depths(w0_mm: np.ndarray, *, rule: str, thickness_mm: float, radius_mm: float,
                     nu: float | None = None) -> np.ndarray:
    """Depth of each press at its certification.

    Parameters
    ----------
    w0_mm : (N,) array_like of float
        The pressed indenters' protrusions over the land, mm.
    rule : {'land', 'nominal'}
        ``'nominal'``: the paper's rule, w = w0. ``'land'``: the depth at
        which the bulging gel first meets the land (:func:`land_contact_depth`,
        from the FEM surface at `nu`); smaller than w0 by the crest height.
    thickness_mm, radius_mm : float
    nu : float, optional
        Needed for ``'land'``.

    Returns
    -------
    depth_mm : (N,) float64 ndarray

    Raises
    ------
    InputError
        For an unknown rule or ``'land'`` without nu.
    """
    w0 = np.asarray(w0_mm, np.float64)
    if rule == "nominal":
        return w0.copy()
    if rule != "land":
        raise InputError(f"depth rule must be 'land' or 'nominal', got {rule!r}")
    if nu is None:
        raise InputError("the 'land' depth rule needs nu")
    uniq = np.unique(w0)
    wc = land_contact_depths_mm(uniq, thickness_mm=thickness_mm, radius_mm=radius_mm, nu=nu)
    return wc[np.searchsorted(uniq, w0)]
