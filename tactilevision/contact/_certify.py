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
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace

import numpy as np

from .._checks import InputError
from ._bevel import _background_basis, bevel_score, footprint_from_frame
from ._footprint import Footprint
from ._force import force_window
from ._mask import contact_mask, noise_level
from ._sync import ClockSync, estimate_clock_offset, force_onsets, refine_clock_offset
from ._vernier import RESOLVED_PX, BevelGeometry, BevelReading, bevel_profile, read_bevel

__all__ = [
    "Certification",
    "CertifiedPress",
    "Rejection",
    "approach_start",
    "certified_depths",
    "certify_session",
    "hold_start",
]

#: Presses whose |(Fx, Fy)| / Fz exceeds this are misaligned (the paper: "much smaller").
MAX_TANGENTIAL_RATIO = 0.1
#: Fraction of saturated pixels around the contact (not in the reference) that rejects it.
MAX_SATURATED_FRACTION = 0.005
#: Vernier: the band of contact on the bevel is seen when the frames of the hold, read
#: together, reach this signal-to-noise ratio (:func:`read_bevel`) and agree on its width
#: (benchmarks/bench_vernier.py prints the ratio on frames with no contact).
VERNIER_SNR = 10.0
#: Vernier, when the F/T log shows no hold: frames taken as seeing the band.
FRAME_SNR = 12.0
#: Vernier: degree of the smooth background under the band (the press's own shading).
BACKGROUND_DEGREE = 4
#: Vernier: largest crest penetration looked for, mm.
MAX_CLOSURE_MM = 0.1
#: Vernier: least fraction of the bevel's band inside the image.
MIN_BEVEL_COVERAGE = 0.6
#: Mark, ``bevel_threshold='auto'``: a frame shows the mark when its score lies this many
#: sds (the no-contact frames' frame-to-frame sd) above its press's approach...
MARK_Z_FRAME = 2.5
#: ... and the mean of it and the next MARK_BLOCK - 1 frames (the mark stays through the
#: hold) this many sds of such a mean (sd / sqrt(MARK_BLOCK)).
MARK_Z_BLOCK = 4.0
MARK_BLOCK = 4
#: No-contact frames scored per press for the null.
MARK_NULL_FRAMES = 6
#: A press's approach frames under this share of its largest fz are before the land can
#: reach the gel (depth under about 0.6 of the deepest: w0 + an overshoot of less than 60 %
#: of w0): the press's own baseline of the mark's score.
MARK_BASELINE_FORCE = 0.6
#: A press's frames with fz at least this share of its largest are its hold: the land is
#: past w0 there, so they show the mark if any frame does (the press's template).
MARK_HOLD_FORCE = 0.9
#: The press's template: the onset's step, in sds of the difference of two approach
#: frames' projections on it.
MARK_Z_STEP = 5.0

#: Vernier: least colour contrast of a band (:attr:`BevelReading.contrast`), as a fraction
#: of the median over the session's long, clear bands. The flanks tilt the gel by theta
#: whatever the band's length, so real bands keep most of it: 0.41 or more of the median
#: (median 0.98 to 1.27) on eight simulated and Taxim-rendered sessions (241 bands, 1.2 to
#: 25 px half-width), where a press stopped 0.9 um past w0 on Taxim's renderer showed
#: smooth shading at 0.05 of it, read as a 22 px band (benchmarks/bench_vernier.py). A
#: band narrower than the blur keeps less (a 1 px half-width band blurred by 1 px: 0.2),
#: hence the margin.
MIN_BAND_CONTRAST = 0.15


@dataclass(frozen=True)
class CertifiedPress:
    """One press that passed every check.

    Attributes
    ----------
    press : int
        Chronological index among the presses found in the frames.
    indenter : int
        Gauge-block indenter.
    w0_mm : float
        That indenter's protrusion over the land.
    frame : int
        Index of the first frame showing the bevel (the certification frame).
    t_frame_s : float
        Its time, camera clock.
    footprint : Footprint
        Fitted on the certification frame.
    x_mm, y_mm : float
        Footprint centre from the image centre (x along columns, y down rows).
    force_n, force_std_n, fx_n, fy_n, tangential_ratio : float
        The F/T window.
    time_s, hold_s, wait_s : float
        Certification time since the first frame; window middle after the
        hold's start (half the window, or the hold's length less half the
        window with ``window_at = "end"``); rest since the previous press
        ended (NaN for the first).
    bevel_score : float
        Signal-to-noise ratio of the bevel at certification (:func:`read_bevel`
        or :func:`bevel_score`).
    rule : {'vernier', 'onset'}
        How the press was certified: the band of contact on a machined bevel
        read over the force window's frames, or the first frame showing a
        bevel mark (``bevel_angle_deg = 0``).
    closure_mm, closure_std_mm : float
        ``'vernier'``: how far the bevel's crest is pressed into the gel's
        surface (overshoot past w0 plus the bulge there) and its standard
        uncertainty, mm. ``'onset'``: 0 and the uncertainty of the onset (the
        depth the stage covers in one frame period, / sqrt(12)).
    reading : BevelReading or None
        The vernier reading of the window's frames (None for ``'onset'``).
    window_frames : tuple of int
        Frames read for the vernier (inside the force window).
    force_sem_n : float
        Standard error of the F/T window's mean fz, its autocorrelation
        included (``force_std_n`` is the window's sd), N.
    force_onset_n, force_onset_sem_n : float
        ``'onset'``: fz when the land reached w0 (the mean of the smoothed
        fz over the frame period before the first frame showing the mark,
        up to the hold's start) and its uncertainty (that fz's spread over
        the period and its noise), N: the force rises from there to the
        window's as the stage goes on past w0 (NaN for ``'vernier'``).
    travel_mm : float
        ``'onset'``: the depth the stage covers in one frame period at the
        onset, mm (the speed read from the approach's force: the mark shows
        w0 into it): the mark shows within that of w0 (NaN for
        ``'vernier'``).
    band_resolved : bool
        ``'vernier'``: whether the band's half-width was read (long enough to
        show its shape, or read with the session's flank colours as a prior);
        False: only bounded, ``closure_std_mm`` that of a uniform over its
        possible range (:func:`unresolved_closure`) and ``closure_mm`` within
        it. True for ``'onset'``.
    """

    press: int
    indenter: int
    w0_mm: float
    frame: int
    t_frame_s: float
    footprint: Footprint
    x_mm: float
    y_mm: float
    force_n: float
    force_std_n: float
    fx_n: float
    fy_n: float
    tangential_ratio: float
    time_s: float
    hold_s: float
    wait_s: float
    bevel_score: float
    rule: str = "onset"
    closure_mm: float = 0.0
    closure_std_mm: float = 0.0
    reading: BevelReading | None = None
    window_frames: tuple[int, ...] = ()
    force_sem_n: float = float("nan")
    force_onset_n: float = float("nan")
    force_onset_sem_n: float = float("nan")
    travel_mm: float = float("nan")
    band_resolved: bool = True


@dataclass(frozen=True)
class Rejection:
    """A press that failed a check.

    Attributes
    ----------
    press : int
    reason : str
        ``'misaligned'``, ``'footprint cut by the pad edge'``, ``'bevel never
        seen'``, ``'bevel seen too late'``, ``'bevel out of view'``,
        ``'saturated frames'``, ``'no footprint'``, ``'footprint radius'``,
        ``'unknown indenter'``, ``'force window outside the log'``.
    detail : str
        The numbers behind it, one sentence.
    t_frame_s : float
        First frame of the press, camera clock.
    frame : int
        A frame that shows it (for the report).
    bevel_score : float
        Best bevel signal-to-noise ratio seen in the press (NaN when the
        bevel was not looked at).
    centre_px : (x, y) or None
        Footprint centre, when one was found (for the report's bevel panel).
    """

    press: int
    reason: str
    detail: str
    t_frame_s: float
    frame: int
    bevel_score: float = float("nan")
    centre_px: tuple[float, float] | None = None


@dataclass(frozen=True)
class Certification:
    """Everything certification found in a session.

    Attributes
    ----------
    presses : list of CertifiedPress
    rejected : list of Rejection
    clock : ClockSync or None
        The onset-based estimate (None when fewer than two presses); the
        offset used is its refinement.
    clock_offset_s : float
        The offset used (t_force - t_frame).
    clock_source : str
        ``'session.toml'`` or ``'estimated'``.
    noise_sigma : float
        Camera noise (:func:`noise_level` of the first frame).
    contact_area_px : (F,) int64 ndarray
        Contact pixels in each frame.
    warnings : list of str
    bevel_optics : dict or None
        For a vernier session: the edge blur (``blur_px``) chosen on the
        session's long bands, how many bands chose it (``n_bands``), the band
        model's lines (``lines``) and whether the short bands leaned on the
        session's flank colours (``prior``).
    press_spans_s : (P, 2) float64 ndarray
        First and last frame in contact of every press found, certified or
        not, camera clock, s (where the F/T's zero is read between them:
        :func:`force_zero`).
    mark_rule : dict or None
        For a bevel mark: when it counts as seen. ``{'rule': 'auto', 'median',
        'sd', 'n_frames', 'z_frame', 'z_block', 'block_frames'}`` (the null of
        the session's no-contact frames, and how many of its sds above each
        press's approach a frame, and a block of frames, must lie) or
        ``{'rule': 'fixed', 'threshold'}``; None for a vernier.
    """

    presses: list[CertifiedPress]
    rejected: list[Rejection]
    clock: ClockSync | None
    clock_offset_s: float
    clock_source: str
    noise_sigma: float
    contact_area_px: np.ndarray
    warnings: list[str] = field(default_factory=list)
    bevel_optics: dict | None = None
    press_spans_s: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    mark_rule: dict | None = None


class _Sized:
    """An iterator with a length, so that a progress bar knows its total."""

    def __init__(self, it, n: int) -> None:
        self._it, self._n = it, n

    def __iter__(self):
        return iter(self._it)

    def __len__(self) -> int:
        return self._n


def _runs(times: np.ndarray, on: np.ndarray, max_gap_s: float) -> list[np.ndarray]:
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
    offset, source, clock, clock_notes = _sync_clock(session, times, area, runs, period,
                                                     sync_fz_n)
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
                        geom=geom, n_runs=len(runs), mark_rule=mark_rule)

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


@dataclass(frozen=True)
class _PressContext:
    """What every press of a session shares (step 3 of the module docstring)."""

    session: object
    sigma: float
    area: np.ndarray
    period: float
    offset: float
    geom: BevelGeometry
    n_runs: int
    mark_rule: dict | None

    @property
    def vernier(self) -> bool:
        return self.geom.tan_theta > 0

    @property
    def reach(self) -> float:
        """Vernier: how far from the footprint's edge the bevel's band is looked for, px."""
        if not self.vernier:
            return 0.0
        s = self.session.config.mm_per_px
        return min(MAX_CLOSURE_MM / self.geom.tan_theta / s, 120.0) + 8.0

    @property
    def half(self) -> float:
        """Half the force window, s."""
        cfg = self.session.config
        return cfg.window_samples / (2.0 * cfg.rate_hz)


class _Reject(Exception):
    """A check of one press failed: ``(reason, detail)``, the frame and score it was seen at."""

    def __init__(self, reason: str, detail: str, at: int | None = None,
                 score: float = float("nan"), centre: tuple[float, float] | None = None
                 ) -> None:
        super().__init__(reason)
        self.reason, self.detail, self.at, self.score = reason, detail, at, score
        self.centre = centre


def _centre(fp: Footprint | None) -> tuple[float, float] | None:
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


def _mark_baseline(ctx: _PressContext, centre: tuple[float, float], run: np.ndarray,
                   fallback: float) -> tuple[float, int]:
    """The mark's score on this press's own approach, before the land can reach the gel:
    the median over its frames whose fz (the F/T log at their time) is under
    :data:`MARK_BASELINE_FORCE` of the press's largest (the indenter's contact moves the
    score at the mark on some renderers: Taxim's by up to 3.4 sd); `fallback` without such
    frames. Returns the baseline and the frames it used."""
    session = ctx.session
    tf, fz = session.force_times_s, session.forces_n[:, 2]
    t = session.frame_times_s[run] + ctx.offset
    f = np.interp(t, tf, fz)
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


def _mark_template_onset(ctx: _PressContext, centre: tuple[float, float], run: np.ndarray
                         ) -> tuple[int | None, str]:
    """A mark's onset from the press's own template: ``(frame, why)``, frame None where
    the press has too few frames to build one or the template shows no step (``why``
    says which).

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
    depth (the indenter's shading, no mark) rises over the approach instead."""
    session = ctx.session
    tf, fz = session.force_times_s, session.forces_n[:, 2]
    f = np.interp(session.frame_times_s[run] + ctx.offset, tf, fz)
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
        return int(run[j]), ""
    return None, f"the press's own template shows no step: {why}"


def _mark_onset(ctx: _PressContext, centre: tuple[float, float], cand: np.ndarray,
                run: np.ndarray) -> tuple[int, float]:
    """A bevel mark with no vernier: the first frame of `cand` where it shows firmly
    (:func:`certify_session`'s `bevel_threshold`), then back through the press's earlier
    frames while they show it too (`cand` starts near full contact, which the sink-in
    ring's growth can put frames after the mark's first showing), ``(frame, score)``.
    With the session's own rule, the press's own template decides first where it can
    (:func:`_mark_template_onset`); the score is then the onset frame's
    :func:`bevel_score`."""
    cfg = ctx.session.config
    rule = ctx.mark_rule
    if rule["rule"] == "auto":
        onset, template_why = _mark_template_onset(ctx, centre, run)
        if onset is not None:
            return onset, _mark_score(ctx, centre, onset)
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
    return onset, score


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
        onset, score = _mark_onset(ctx, centre, cand, run)
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
    travel = _onset_travel(session, run, onset, ctx.offset, ctx.period, w0)
    f_on, f_on_se = _crossing_force(session, run, t_cert + ctx.offset, ctx.offset, ctx.period)
    return replace(press, rule="onset", closure_mm=0.0, closure_std_mm=travel / np.sqrt(12.0),
                   force_onset_n=f_on, force_onset_sem_n=f_on_se, travel_mm=float(travel))


def _crossing_force(session, run: np.ndarray, t_on: float, offset: float, period: float
                    ) -> tuple[float, float]:
    """fz when the land reached w0, from the F/T log, and its uncertainty, N.

    The mark first shows at `t_on` (F/T clock), so the land reached w0 within the frame
    period before, and not after the stage stopped (the hold's start, :func:`hold_start`):
    fz at the ends of ``[t_on - period, min(t_on, t_hold)]`` (a 10 ms moving average,
    read at the instants) brackets P(w0), widened by twice that average's noise. Returned
    as the bracket's middle and the sd of a uniform over it. A hold that started before
    that period (the mark seen late) puts the crossing in the period before the hold's
    start. ``(nan, nan)`` when the log does not cover it.
    """
    tf, fz = session.force_times_s, session.forces_n[:, 2]
    times = session.frame_times_s
    t_hold = hold_start(tf, fz, float(times[run[0]]) + offset - period,
                        float(times[run[-1]]) + offset + period)
    t_a, t_b = t_on - period, t_on
    if t_hold is not None:
        t_b = min(t_b, t_hold)
        if t_b <= t_a:
            t_a, t_b = t_hold - period, t_hold
    dt = float(np.median(np.diff(tf))) if tf.size > 1 else 1.0
    k = max(1, round(0.01 / dt))
    sel = np.flatnonzero((tf >= t_a - k * dt) & (tf <= t_b + k * dt))
    if sel.size < k + 2:
        return float("nan"), float("nan")
    smooth = np.convolve(fz[sel], np.ones(k) / k, mode="same")
    ok = np.arange(sel.size)
    ok = ok[(ok >= k // 2) & (ok < sel.size - k // 2)]          # the average's own edges
    if ok.size < 2:
        return float("nan"), float("nan")
    f_a, f_b = np.interp([t_a, t_b], tf[sel][ok], smooth[ok])
    noise = float(np.std(np.diff(fz[sel]))) / np.sqrt(2.0 * k)      # one smoothed sample's
    # the bracket [fz(t_a), fz(t_b)] holds P(w0), widened by twice the smoothed noise; given
    # as its middle and the sd of a uniform over it (crossing_forces reads it back)
    lo, hi = min(f_a, f_b) - 2 * noise, max(f_a, f_b) + 2 * noise
    return float(0.5 * (lo + hi)), float((hi - lo) / np.sqrt(12.0))


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


def hold_start(force_times_s: np.ndarray, fz_n: np.ndarray, t0_s: float, t1_s: float, *,
               smooth_s: float = 0.05, span_s: float = 0.15) -> float | None:
    """When a press stops going deeper, from its force: the start of its hold, F/T clock, s.

    Parameters
    ----------
    force_times_s : (M,) float64 ndarray
    fz_n : (M,) float64 ndarray
        The F/T log's normal force.
    t0_s, t1_s : float
        The press, F/T clock (its first frame in contact to its last).
    smooth_s : float, default 0.05
        Length of the moving average and half-span of the central difference
        that locate the end of the rise roughly.
    span_s : float, default 0.15
        Half-width of the window of the exact fit around it.

    Returns
    -------
    t_hold : float or None
        None when the log holds too few samples or no rising approach.

    Notes
    -----
    A press approaches at about constant speed (Fz rising by P / approach
    time: several N/s), then holds: the rise stops at once, where a gel's
    relaxation bends Fz only slowly. The steepest rise of the smoothed force
    and the first point after it rising at under a fifth of that place the
    stop roughly; then two straight lines meeting at t_hold (rise, hold) are
    fitted by least squares to the samples within `span_s`, t_hold on a
    grid of the sampling interval. Single 1 kHz samples of an ATI-class
    sensor (1/80 N) are too noisy to differentiate: the smoothing is needed.
    """
    sel = (force_times_s >= t0_s) & (force_times_s <= t1_s)
    t, f = force_times_s[sel], fz_n[sel]
    if t.size < 20:
        return None
    dt = float(np.median(np.diff(t)))
    k = max(1, round(smooth_s / dt))
    if t.size < 4 * k:
        return None
    fs = np.convolve(f, np.ones(k) / k, mode="same")
    d = np.full(t.size, 0.0)
    d[k:-k] = (fs[2 * k:] - fs[:-2 * k]) / (t[2 * k:] - t[:-2 * k])
    d[: 2 * k] = 0.0
    d[-2 * k:] = 0.0
    peak = int(np.argmax(d))
    if d[peak] <= 0:
        return None
    after = np.flatnonzero(d[peak:] < 0.2 * d[peak])
    if not after.size:
        return None
    # an approach is a rise that stands out of the samples' noise (robust sd of the first
    # differences, which a trend does not move): ten times it, from the lowest force before
    # the steepest rise to the stop; a falling force or noise alone has none
    df = np.diff(f)
    noise = 1.4826 * float(np.median(np.abs(df - np.median(df)))) / np.sqrt(2.0)
    if fs[peak + after[0]] - float(np.min(fs[k:peak + 1])) <= 10 * noise:
        return None
    guess = float(t[peak + after[0]])
    win = (t >= guess - span_s) & (t <= guess + span_s)
    tw, fw = t[win], f[win]
    if tw.size < 5:
        return guess
    rss, _ = _knee_fits(tw, fw, tw[2:-2], slope_before=True)
    return float(tw[2:-2][int(np.argmin(rss))])


def _knee_fits(t: np.ndarray, f: np.ndarray, knees: np.ndarray, *, slope_before: bool
               ) -> tuple[np.ndarray, np.ndarray]:
    """Two straight lines meeting at each candidate knee, fitted by least squares at once.

    The design at knee k is ``[1, min(t - k, 0), max(t - k, 0)]`` (a line on each side,
    `slope_before`) or ``[1, max(t - k, 0)]`` (flat, then a line). Returns the residual
    sum of squares (K,) and the coefficients (K, p) of every knee, from the normal
    equations of all knees solved together (each knee strictly inside `t`, so every
    design has full rank).
    """
    d = t[None, :] - knees[:, None]                                      # (K, n)
    cols = [np.ones_like(d)]
    if slope_before:
        cols.append(np.minimum(d, 0.0))
    cols.append(np.maximum(d, 0.0))
    X = np.stack(cols, axis=-1)                                          # (K, n, p)
    coef = np.linalg.solve(np.einsum("kni,knj->kij", X, X),
                           np.einsum("kni,n->ki", X, f)[..., None])[..., 0]      # (K, p)
    rss = np.sum((f[None, :] - np.einsum("kni,ki->kn", X, coef)) ** 2, axis=1)
    return rss, coef


def hold_end(force_times_s: np.ndarray, fz_n: np.ndarray, t_hold_s: float, *,
             max_hold_s: float = 600.0) -> float | None:
    """When a press's hold ends (the release begins), from its force, F/T clock, s.

    Parameters
    ----------
    force_times_s : (M,) float64 ndarray
    fz_n : (M,) float64 ndarray
        The F/T log's normal force.
    t_hold_s : float
        The hold's start (:func:`hold_start`), F/T clock.
    max_hold_s : float, default 600
        Longest hold searched.

    Returns
    -------
    t_release : float or None
        None when the force never falls below half its value at the hold's
        start within `max_hold_s`, or the log is too short.

    Notes
    -----
    The release is the mirror image of the approach: the force falls at
    about constant speed from the held level. The first sample after the
    hold's start below half the force held over its first 50 ms brackets
    it; :func:`hold_start` on the time-reversed log, between that sample
    (plus 50 ms) and the hold's start, finds where the fall begins. A
    relaxing gel loses force slowly during the hold (a fifth of it, say):
    that is not a release.
    """
    t = np.asarray(force_times_s, np.float64)
    f = np.asarray(fz_n, np.float64)
    start = (t >= t_hold_s) & (t <= t_hold_s + 0.05)
    if start.sum() < 3:
        return None
    held = float(np.mean(f[start]))
    if held <= 0:
        return None
    later = np.flatnonzero((t > t_hold_s + 0.05) & (t <= t_hold_s + max_hold_s)
                           & (f < 0.5 * held))
    if not later.size:
        return None
    t_half = float(t[later[0]])
    sel = (t >= t_hold_s) & (t <= t_half + 0.05)
    tr, fr = -t[sel][::-1], f[sel][::-1]
    back = hold_start(tr, fr, -(t_half + 0.05), -t_hold_s)
    return None if back is None else min(-back, t_half)


def approach_start(force_times_s: np.ndarray, fz_n: np.ndarray, t_hold_s: float, *,
                   max_ramp_s: float = 10.0, smooth_s: float = 0.01) -> float | None:
    """When a press's force began to rise: the start of its approach, F/T clock, s.

    Parameters
    ----------
    force_times_s : (M,) float64 ndarray
    fz_n : (M,) float64 ndarray
        The F/T log's normal force.
    t_hold_s : float
        The hold's start (:func:`hold_start`), F/T clock.
    max_ramp_s : float, default 10
        Longest approach searched.
    smooth_s : float, default 0.01
        The log is averaged in blocks of this length first.

    Returns
    -------
    t_start : float or None
        The knee of a flat-then-rising line fitted by least squares to the
        force before `t_hold_s`, over three times the time the force took to
        rise from half its held value; None when the log holds too few
        samples there or the force never rose.

    Notes
    -----
    ``t_hold_s - t_start`` is the loading time of the press, which a
    viscoelastic gel's hold curve depends on
    (:func:`~tactilevision.mechanics.fit_relaxation`). A threshold on the
    force would be thrown by the rest level's own wanderings (a relaxing
    gel's force undershoots after each release and recovers over tau); the
    two lines fit the level just before the rise, whatever it is.
    """
    t = np.asarray(force_times_s, np.float64)
    f = np.asarray(fz_n, np.float64)
    sel = np.flatnonzero((t >= t_hold_s - max_ramp_s) & (t <= t_hold_s))
    if sel.size < 20:
        return None
    tt, ff = t[sel], f[sel]
    dt = float(np.median(np.diff(tt)))
    k = max(1, round(smooth_s / dt))
    m = tt.size // k
    if m < 10:
        return None
    cut = tt.size - m * k                      # keep the samples next to the hold
    ts = tt[cut:].reshape(m, k).mean(1)
    fs = ff[cut:].reshape(m, k).mean(1)
    top = float(fs[-1])
    below = np.flatnonzero(fs < top - 0.5 * (top - float(fs.min())))
    if not below.size or top - float(fs.min()) <= 0:
        return None
    span = 3.0 * (t_hold_s - float(ts[below[-1]]))
    w = ts >= t_hold_s - span
    tw, fw = ts[w], fs[w]
    if tw.size < 6:
        return None
    knees = tw[1:-2]
    rss, coef = _knee_fits(tw, fw, knees, slope_before=False)
    rss = np.where(coef[:, 1] > 0, rss, np.inf)          # the force must rise after it
    return float(knees[int(np.argmin(rss))]) if np.isfinite(rss).any() else None


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


def _sync_clock(session, times: np.ndarray, area: np.ndarray, runs: list[np.ndarray],
                period: float, sync_fz_n: np.ndarray | None
                ) -> tuple[float, str, ClockSync | None, list[str]]:
    """The clock offset between frames and F/T log (step 2 of the module docstring).

    Returns ``(offset_s, source, clock, warnings)``: the offset used, 'session.toml' or
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
    if len(runs) >= 2 and force_on.size >= 2:
        clock = estimate_clock_offset(frame_on, force_on, tolerance_s=tol)
        if sync_fz_n is not None and np.shape(sync_fz_n) != fz.shape:
            raise InputError(f"sync_fz_n has {np.size(sync_fz_n)} values for {fz.size} F/T "
                             "samples")
        refined, _ = refine_clock_offset(times, area, session.force_times_s,
                                         fz if sync_fz_n is None else sync_fz_n, clock.offset_s,
                                         span_s=max(0.2, 3 * period),
                                         step_s=1.0 / cfg.rate_hz)
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
    return offset, source, clock, warnings


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


def _vernier_onset(session, geom: BevelGeometry, centre: tuple[float, float], s: float,
                   cand: np.ndarray, reach: float, period: float, half: float, offset: float,
                   t_first: float):
    """Hold of a press and the vernier's frames: the force's hold, the band read over it.

    The hold starts where the F/T log stops rising (:func:`hold_start`), else
    at the first of the longest run of frames that show the band at one
    width. The window's frames (the force window's span from there) must
    show the band together (signal-to-noise ratio :data:`VERNIER_SNR`, not
    filling the whole profile) and three in four of them at the same width
    (to 2.5 sd or 2.5 px, the quick looks being on a 1 px grid): a structure
    that is not a band wanders from frame to frame.

    Returns ``(t_cert, onset, window_frames, window_profiles, snr, reading)``
    or a :class:`Rejection` (its press, time and centre filled in by the caller).
    """
    ref = session.reference
    times = session.frame_times_s
    inner = (geom.offset_mm - session.config.indenter_radius_mm - INDENTER_CLEARANCE_MM) / s
    profiles = {int(i): bevel_profile(session.frame(int(i)), ref, centre, s, geom, reach_px=reach,
                                      inner_px=min(reach, inner))
                for i in cand}
    cover = min(p.coverage for p in profiles.values())
    if cover < MIN_BEVEL_COVERAGE:
        return Rejection(press=-1, reason="bevel out of view",
                         detail=f"only {100 * cover:.0f}% of the bevel's band "
                                f"({geom.offset_mm:g} mm from the indenter at "
                                f"{geom.direction_deg:g} deg) lies inside the image",
                         t_frame_s=float("nan"), frame=int(cand[-1]))
    kw = dict(max_closure_mm=MAX_CLOSURE_MM, coarse=True, background_degree=BACKGROUND_DEGREE)
    fz = session.forces_n[:, 2]
    # from the press's first contact: the whole rise must be in view
    t_hold = hold_start(session.force_times_s, fz, t_first + offset - period,
                        float(times[cand[-1]]) + offset + period)
    if t_hold is not None:
        t_cert = t_hold - offset
        in_window = (times[cand] >= t_cert - 1e-9) & (times[cand] <= t_cert + 2 * half + 1e-9)
        if not in_window.any():         # a window shorter than a frame period
            later = np.flatnonzero(times[cand] >= t_cert - 1e-9)
            if later.size:
                in_window[later[0]] = True
        window = [int(i) for i in cand[in_window]]
    else:
        window = []
    if not window:
        # no hold in the force: the longest run of frames seeing the band at one width
        reads = {i: read_bevel(p, geom, s, **kw) for i, p in profiles.items()}
        snr = np.array([reads[int(i)].snr for i in cand])
        half_w = np.array([reads[int(i)].half_width_px for i in cand])
        runs: list[list[int]] = []
        for j in np.flatnonzero(snr >= FRAME_SNR):
            if runs and runs[-1][-1] == j - 1 and abs(
                    half_w[j] - float(np.median(half_w[runs[-1]]))) <= 1.5:
                runs[-1].append(int(j))
                continue
            runs.append([int(j)])
        if not runs:
            return _never_seen(geom, float(snr.max()), int(cand[int(np.argmax(snr))]))
        run = max(runs, key=lambda r: (len(r), float(snr[r].sum())))
        t_cert = float(times[cand[run[0]]])
        window = [int(cand[j]) for j in run if times[cand[j]] <= t_cert + 2 * half + 1e-9]
    onset = window[0]
    # seen: with lines along the edges too (renderers' and optics' shadows), which no band of
    # another kind needs
    plain = read_bevel([profiles[i] for i in window], geom, s, **kw)
    joint = read_bevel([profiles[i] for i in window], geom, s, **kw, lines="all", line_px=2.0)
    if plain.snr >= joint.snr:
        joint = plain
    # the frames must agree on the width (without lines: a line at an edge trades off
    # against its position, frame by frame)
    per = [read_bevel(profiles[i], geom, s, **kw) for i in window] if len(window) > 1 else [plain]
    # (quick looks on a 1 px grid: each may land a grid step either side)
    agree = [abs(r.half_width_px - plain.half_width_px) <= max(2.5 * r.half_width_std_px, 2.5)
             for r in per]
    consistent = float(np.mean(agree)) >= 0.75       # one noisy frame of 18 (90 fps) may stray
    if joint.snr < VERNIER_SNR:
        why = "" if consistent else "; the frames of the hold also disagree on its width"
        return _never_seen(geom, joint.snr, onset, why)
    if not consistent:
        # seen, but not steady: the deciding reason first, the ratio that passed after it
        return Rejection(
            press=-1, reason="bevel band unsteady",
            detail=f"the frames of the hold disagree on the width of the band on the bevel "
                   f"{geom.offset_mm:g} mm from the indenter at {geom.direction_deg:g} deg: "
                   f"{int(np.sum(agree))} of {len(agree)} frames agree with their joint reading "
                   f"({plain.half_width_px:.1f} px half-width), three in four are needed; the "
                   f"band's signal-to-noise ratio, {joint.snr:.1f}, passes the threshold "
                   f"{VERNIER_SNR:g}",
            t_frame_s=float("nan"), frame=onset, bevel_score=joint.snr)
    return t_cert, onset, tuple(window), [profiles[i] for i in window], joint.snr, joint


def _never_seen(geom: BevelGeometry, best: float, frame: int, why: str = "") -> Rejection:
    return Rejection(press=-1, reason="bevel never seen",
                     detail=f"the frames of the hold show no band of contact on the bevel "
                            f"{geom.offset_mm:g} mm from the indenter at {geom.direction_deg:g} "
                            f"deg (signal-to-noise ratio {best:.1f}, threshold "
                            f"{VERNIER_SNR:g}{why})",
                     t_frame_s=float("nan"), frame=frame, bevel_score=best)


#: With lines, a long band is read only when its edges alone (``read_bevel(lines='only')``)
#: give its half-width within this (px): in cell E of ``benchmarks/bench_vernier.py
#: --sweep``, Taxim's shadow block beside four narrow bands (2 to 4 px) read 19 to 21 px
#: with flanks and 4 to 5 px without, its long bands agreeing within 0.5 px; in cells B
#: and D some long bands disagree by 2 to 5 px and are not read.
AGREE_PX = 1.5
#: A band whose crest lies farther than this (px), or 4 robust sd of the long bands'
#: crests, from their median is not read (the crest's place is fixed by the block: the
#: long bands of sweep cells A and B lie within 1 px of their median; the misread narrow
#: bands that passed for long ones, 3 to 5.5 px off).
CREST_TOLERANCE_PX = 2.0


#: The shared error of a read band's half-width, as a fraction of the session's edge width
#: (:func:`vernier_shared_mm`).
EDGE_SHARED_FRACTION = 0.4


def _edge_width(optics: dict) -> float:
    """The session's edge width, px: the least-squares edge blur of its long bands (before
    :data:`BLUR_SHRINK`), or their edge lines' sd when they carry lines, if wider."""
    blur = float(optics["blur_px"]) / (BLUR_SHRINK if optics.get("n_bands", 0) >= 2 else 1.0)
    if optics.get("lines", "none") != "none":
        blur = max(blur, float(optics.get("line_px", 0.0)))
    return round(blur, 4)


def vernier_shared_mm(band_resolved: np.ndarray, bevel: BevelGeometry, mm_per_px: float,
                      edge_px: float) -> np.ndarray:
    """The bound of the vernier's error that every read band shares: where its edges sit.

    Parameters
    ----------
    band_resolved : (N,) array_like of bool
        Which presses' bands were read (:attr:`CertifiedPress.band_resolved`);
        unresolved ones carry their whole range already.
    bevel : BevelGeometry
    mm_per_px : float
    edge_px : float
        The session's edge width, px (``Certification.bevel_optics['edge_px']``).

    Returns
    -------
    (N,) float64 ndarray
        ``EDGE_SHARED_FRACTION * edge_px * tan(theta) * mm_per_px`` for read
        bands, 0 for the others, mm: the error lies within plus or minus it.

    Notes
    -----
    The band model places each edge at the middle of a blurred step (or on a
    line). Where a renderer's or a sensor's colour edge sits against the true
    edge of contact is not known from the frames: the gel leaves the flank
    tangentially, and shadows fall outward. The read bands' mean error was
    -0.85 to +0.14 px on the Taxim cells of ``benchmarks/bench_vernier.py
    --sweep`` (edge width 3 px: at most 0.28 of it), and -0.22 and -0.05 px
    on our two simulated 50-press sessions (``bench_vernier.py``; edge widths
    2.5 and 1.75 px), one value for every press of a session: a systematic
    error, carried into E's and nu's intervals by refits at its bounds, not
    averaged over the presses.
    """
    r = np.asarray(band_resolved, bool)
    half = EDGE_SHARED_FRACTION * float(edge_px) * bevel.tan_theta * float(mm_per_px)
    return np.where(r, half, 0.0)


def unresolved_closure(bevel: BevelGeometry, mm_per_px: float,
                       top_px: float = RESOLVED_PX) -> tuple[float, float]:
    """The closure of a band too short to read, as a uniform over its possible range.

    Parameters
    ----------
    bevel : BevelGeometry
        Needs ``angle_deg > 0``.
    mm_per_px : float
    top_px : float, default ``RESOLVED_PX``
        The largest half-width the band may have, px.

    Returns
    -------
    closure_mm, closure_std_mm : float
        The middle of ``[0, top_px] tan(theta) mm_per_px`` and the sd of a
        uniform over it (``/ sqrt(12)``), mm: the band was seen, so the crest
        reached the gel, but its half-width is somewhere under `top_px`.
    """
    top = max(float(top_px), 0.0) * bevel.tan_theta * float(mm_per_px)
    return 0.5 * top, top / math.sqrt(12.0)


def _read_vernier_presses(pending: list[dict], geom: BevelGeometry, s: float
                          ) -> tuple[list[CertifiedPress], list[Rejection], dict]:
    """Read every press's band over its window, with the session's own optics.

    1. The session's edge blur is chosen on its longest, clearest bands
       (:func:`_session_optics`).
    2. Every press is read with it, its flank colours free.
    3. The flank colours of the long bands (half-width >= ``RESOLVED_PX``)
       are fitted as a plane over the bevel's position in the image (the
       sensor's lighting varies across it: 6% of the colours left against 19%
       for one colour, on the simulated sample session); short bands, whose
       shape the blur hides, are read again with that plane's colours at
       their position as a prior, weighted by its residual spread.
    4. Without that prior (bands carrying lines or shadows along their
       edges, or too few long bands), a band is read only when it is long
       (half-width >= ``RESOLVED_PX``), its crest lies where the session's
       long bands put it (within :data:`CREST_TOLERANCE_PX`, or 4 robust sd
       of theirs, of their median crest; three or more long bands needed),
       and, in a session with lines, its edges alone (``lines='only'``) give
       its width within :data:`AGREE_PX`. With or without the prior, its
       inner edge must also lie two edge widths clear of the profile's end
       on the indenter's side (:data:`INDENTER_CLEARANCE_MM`). Any other band
       is *unresolved*: its width is only bounded, to ``[0, max(RESOLVED_PX,
       L)]`` pixels' worth (L plus two edge widths for a band cut off at the
       profile's end), its uncertainty that of a uniform over that range
       (:func:`unresolved_closure`), and the fit weighs it accordingly; the
       point within it is the band read with thin edge lines and shadows cast
       outward (``lines='shadows'``), clipped to the range. On
       Taxim's renders, whose shadows paint a block 10 to 25 px wide beside
       narrow bands, every band model read such bands 2 to 21 px long
       whatever their true length (1 to 7 px), at
       stated uncertainties of a fraction of that: 49 um off at 4 um stated
       on a 15 deg bevel (``benchmarks/bench_vernier.py --sweep``).
    5. A band whose colour contrast is under :data:`MIN_BAND_CONTRAST` of the
       long bands' (median, when two or more are long) is shading, not a
       band: the press is rejected as ``'bevel never seen'``.

    Returns the certified presses, those rejected in step 4 and the optics.
    """
    optics = _session_optics(pending, geom, s)
    kw = dict(max_closure_mm=MAX_CLOSURE_MM, lines=optics["lines"], blur_px=optics["blur_px"],
              line_px=optics.get("line_px", 2.0))
    first = [read_bevel(d["profiles"], geom, s, **kw) for d in pending]
    # with lines: the band seen by its edges alone must be the band seen with its flanks (a
    # block of colour beside a narrow band, such as Taxim's shadow, reads as a long band
    # only with flanks)
    agrees = np.ones(len(first), bool)
    if optics["lines"] != "none":
        for k, (d, r) in enumerate(zip(pending, first, strict=True)):
            if r.resolved:
                edges = read_bevel(d["profiles"], geom, s, **{**kw, "lines": "only"})
                agrees[k] = abs(edges.half_width_px - r.half_width_px) <= AGREE_PX
    long = np.array([r.resolved and r.snr >= 2 * VERNIER_SNR for r in first]) & agrees
    X = np.array([[1.0, d["press"].x_mm, d["press"].y_mm] for d in pending])
    C = np.array([r.flank_colours.ravel() for r in first])            # (N, 6)
    plane = None
    if long.sum() >= 6:
        coef, *_ = np.linalg.lstsq(X[long], C[long], rcond=None)
        res = C[long] - X[long] @ coef
        spread = float(np.sqrt(np.mean(res ** 2) / max(np.mean(C[long] ** 2), 1e-12)))
        plane = (coef, max(spread, 0.03))
    elif long.sum() >= 2:
        mean = C[long].mean(axis=0)
        spread = float(np.sqrt(np.mean((C[long] - mean) ** 2) / max(np.mean(mean ** 2), 1e-12)))
        plane = (np.vstack([mean, np.zeros((2, 6))]), max(spread, 0.1))
    if plane is not None and plane[1] > 0.5:
        plane = None       # the long bands' colours scatter too much to inform the short ones
    if optics["lines"] != "none":
        plane = None       # lines or shadows at the edges: the model reads short bands itself
    out: list[CertifiedPress] = []
    faint: list[Rejection] = []
    n_unresolved = 0
    edge = _edge_width(optics)
    crest0, crest_tol = float("nan"), float("inf")
    seen_long = [r.crest_px for r, ok in zip(first, agrees, strict=True) if r.resolved and ok]
    if len(seen_long) >= 3:
        cr = np.array(seen_long)
        crest0 = float(np.median(cr))
        crest_tol = max(CREST_TOLERANCE_PX, 4.0 * 1.4826 * float(np.median(np.abs(cr - crest0))))
    contrast_long = (float(np.median([r.contrast for r, ok in zip(first, long, strict=True)
                                      if ok])) if long.sum() >= 2 else float("nan"))
    for k, (d, r) in enumerate(zip(pending, first, strict=True)):
        if r.contrast < MIN_BAND_CONTRAST * contrast_long:      # False when NaN
            p = d["press"]
            faint.append(Rejection(
                press=p.press, reason="bevel never seen",
                detail=f"the best band on the bevel ({r.half_width_px:.1f} px half-width) has "
                       f"a colour contrast of {r.contrast:.1f} grey levels, "
                       f"{100 * r.contrast / contrast_long:.0f}% of the session's long bands' "
                       f"{contrast_long:.1f} (threshold {100 * MIN_BAND_CONTRAST:.0f}%): "
                       "shading, not a band of contact",
                t_frame_s=d["t0"], frame=p.frame, bevel_score=r.snr, centre_px=d["centre"]))
            continue
        closure, closure_std = r.closure_mm, r.closure_std_mm
        if plane is not None and not r.resolved:
            # a short band: lines at its edges would trade off against L; its colours
            # come from the long bands at its position
            prior = (X[k] @ plane[0]).reshape(2, 3)
            r = read_bevel(d["profiles"], geom, s, flank_colours=prior, colour_sd=plane[1],
                           **{**kw, "lines": "none"})
            closure, closure_std = r.closure_mm, r.closure_std_mm
        # the inner edge must lie inside the profile, clear of its end by two edge widths
        to_end = r.crest_px - d["profiles"][0].u_px[0]          # crest to the profile's end
        clear = to_end - r.half_width_px >= 2.0 * edge
        read = clear and (plane is not None or (r.resolved and abs(r.crest_px - crest0)
                                                <= crest_tol and agrees[k]))
        if not read:
            # no prior, and not long where the long bands are: only bounded (step 4)
            # (a band cut off at the profile's end may be longer than read; a short band
            # misread long may reach the end too, so no lower bound is drawn from it)
            top = max(RESOLVED_PX, r.half_width_px + (0.0 if clear else 2.0 * edge))
            closure, closure_std = unresolved_closure(geom, s, top)
            # the point within the bounds: the band read with thin edge lines and shadows
            # cast outward (read_bevel(lines='shadows'))
            sh = read_bevel(d["profiles"], geom, s, **{**kw, "lines": "shadows"})
            closure = float(np.clip(sh.half_width_px, 0.0, top)) * geom.tan_theta * s
            n_unresolved += 1
        out.append(replace(d["press"], rule="vernier", closure_mm=closure,
                           closure_std_mm=closure_std, reading=r, bevel_score=r.snr,
                           window_frames=d["window"], band_resolved=read))
    optics["unresolved"] = n_unresolved
    optics["shadows"] = n_unresolved          # their point: the shadows reading
    optics["edge_px"] = edge
    optics["crest_px"] = None if np.isnan(crest0) else round(crest0, 3)
    optics["prior"] = plane is not None and any(not r.resolved for r in first)
    optics["colour_spread"] = None if plane is None else round(plane[1], 4)
    optics["contrast_long"] = None if np.isnan(contrast_long) else round(contrast_long, 2)
    return out, faint, optics


#: The blur that fits the long bands best, times this, reads the short bands without bias.
#: JPEG and the renderer's finite differences make the band's edges a sharp core with
#: tails, which a Gaussian fitted by least squares widens; a short band read with that
#: wider blur comes out short. Measured on three simulated 50-press sessions (JPEG quality
#: 75 and 90): least-squares blurs 1.75 to 2.5 px, unbiased short bands at 1.5 to 2.0 px
#: (benchmarks/bench_vernier.py prints the bias by band length).
BLUR_SHRINK = 0.8
#: Widths (sd, px) of the lines along the band's edges tried on the session's long bands.
_LINE_SDS = (1.2, 2.0, 3.0)
#: The bevel's profile stops this far (mm) from the indenter's footprint on its side: the
#: indenter's own contact shades the gel beside it (Taxim's renders: a trough whose deepest
#: part lies within 0.2 mm of the edge; a 3.5 deg bevel 4 mm from the axis of a 2.5 mm
#: indenter read it into its bands, 3 px too long, and saw 8 of 20 bands under the
#: threshold; ``benchmarks/bench_vernier.py --sweep``, cell L).
INDENTER_CLEARANCE_MM = 0.25
#: A session's bands carry lines when lines at their edges leave less than this share of
#: the residual variance (median over its long bands): 0.03 to 0.39 on 13 Taxim sessions
#: (bevels of 3 to 13 deg; ``benchmarks/bench_vernier.py --sweep`` and its Taxim rows),
#: 0.65 and 0.70 on our two simulated 50-press sessions, whose bands have none.
LINES_RSS_RATIO = 0.5
#: Edge blurs (sd, px) tried on the session's long bands.
_BLURS = (0.6, 0.8, 1.0, 1.25, 1.5, 1.75, 2.0, 2.5, 3.0)


def _session_optics(pending: list[dict], geom: BevelGeometry, s: float, *, n_max: int = 8
                    ) -> dict:
    """The edge blur and band model that explain the session's long bands best.

    On up to `n_max` bands at least ``RESOLVED_PX`` long (the clearest):
    the blur of :data:`_BLURS` with the least summed residual, times
    :data:`BLUR_SHRINK`; then whether
    the bands carry lines along their edges (renderers' and real optics'
    shadows): if reading them with lines moves L by more than 1 px, or
    leaves under :data:`LINES_RSS_RATIO` of the residual variance (medians
    over the bands), the session is read with lines, else without (a line
    at an edge trades off against the edge's position, so it costs
    precision where it is not needed). Defaults (1.0 px, no lines) when
    fewer than two bands are long enough.
    """
    long = sorted((d for d in pending if d["quick"].half_width_px >= RESOLVED_PX),
                  key=lambda d: -d["quick"].snr)[:n_max]
    if len(long) < 2:
        return {"blur_px": 1.0, "lines": "none", "line_px": 2.0, "n_bands": len(long)}
    totals = []
    for blur in _BLURS:
        rs = [read_bevel(d["profiles"], geom, s, max_closure_mm=MAX_CLOSURE_MM, lines="none",
                         blur_px=blur) for d in long]
        totals.append((sum(r.noise ** 2 * r.model.size for r in rs), blur, rs))
    _, blur, plain = min(totals, key=lambda t: t[0])
    lined = {sd: [read_bevel(d["profiles"], geom, s, max_closure_mm=MAX_CLOSURE_MM, lines="all",
                             blur_px=blur, line_px=sd) for d in long] for sd in _LINE_SDS}
    line_sd = min(_LINE_SDS, key=lambda sd: sum(r.noise ** 2 for r in lined[sd]))
    # do the bands carry lines? judged with the narrowest lines, which move the edges least
    # where there are none
    shift = float(np.median([abs(a.half_width_px - b.half_width_px)
                             for a, b in zip(plain, lined[_LINE_SDS[0]], strict=True)]))
    ratio = float(np.median([(b.noise / max(a.noise, 1e-12)) ** 2
                             for a, b in zip(plain, lined[line_sd], strict=True)]))
    lines = "all" if shift > 1.0 or ratio < LINES_RSS_RATIO else "none"
    return {"blur_px": round(BLUR_SHRINK * blur, 4), "lines": lines,
            "line_px": line_sd, "n_bands": len(long), "line_shift_px": round(shift, 3),
            "line_rss_ratio": round(ratio, 3)}


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
    from ._land import land_contact_depths_mm

    uniq = np.unique(w0)
    wc = land_contact_depths_mm(uniq, thickness_mm=thickness_mm, radius_mm=radius_mm, nu=nu)
    return wc[np.searchsorted(uniq, w0)]
