"""What certification finds: the certified presses, the rejections, the thresholds.

The dataclasses :class:`CertifiedPress`, :class:`Rejection` and
:class:`Certification` returned by :func:`~tactilevision.contact.certify_session`,
the thresholds its checks use, and what the per-press steps share
(:class:`_PressContext`, :class:`_Reject`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ._footprint import Footprint
from ._sync import ClockSync
from ._vernier import BevelGeometry, BevelReading

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
#: ... and a frame before the onset, rising towards it, shows a trace of the mark when its
#: projection lies this many sds above the approach's level (the crossing's period then
#: ends at it: :func:`~tactilevision.contact._onset._mark_template_onset`). On five Taxim
#: mark sessions of drawn designs the first traces past w0 lay 6.0 to 49 sds off; one at
#: 4.4 sds (against the template, 22 um before w0: the punch's shading deepening over a
#: three-frame approach at 25 frames/s, 1.24 mm/s) put its press's bracket a period early,
#: its indenter's brackets disjoint, and a stiffness step on the session's null; under 5
#: sds such a frame is a faint trace (:data:`MARK_Z_FAINT`): its period joins the bracket
#: rather than ending it.
MARK_Z_SEEN = 5.0
#: A frame whose profile across the mark departs from the approach's, less its projection
#: on the hold's template, by at least this share of the template's norm (and by
#: :data:`MARK_Z_SEEN` sds of the approach frames' own, from the frames before it) shows
#: the mark too, whatever its projection: on Taxim's frames a ridge a few um past w0 shows
#: a change shaped otherwise than the hold's, which projects anywhere from -0.7 to +0.2 of
#: the way. On a Taxim mark session of a drawn design (seed 9781, d24) four presses whose
#: frame before the step projected -0.03 to +0.17 of the way (under :data:`MARK_TRACE`, or
#: within the approach's scatter) departed from it by 1.19 to 1.41 of the template's norm,
#: where the approach frames lay at 0.02 to 0.15: their brackets read a period late (18 to
#: 34 mN above P(w0)), and their indenters' P(w0) up to 61 mN high.
MARK_TRACE_SHAPE = 0.3
#: ... and at least this share of the way to the hold's level (an approach whose shading
#: moves lifts the frames before the crossing by a few sds of a steady one: 0.01 of the way
#: at 5 sd on a Taxim session with shadows).
MARK_TRACE = 0.1
#: ... and where the frame before the first trace so found does not show the mark, the one
#: before it still does when its projection lies this many sds off the approach's level and
#: as far off the frames before it (either way: :func:`~tactilevision.contact._onset._departs`),
#: and as far from the frame after it (an approach lifted by shading lifts both alike): a
#: trace's change turns into the hold's shape on its way up, and its projection can pass
#: back through the approach's level for a frame. On two Taxim mark sessions without shadows
#: of designs drawn at random (seeds 10039 d09 and 10141 d03, 16 and 33 um of travel per
#: frame), four presses' frames 3.3 to 10 um past w0 projected -0.5 to -2.0 of the way (19
#: to 31 sds), their next frames 0.03 to 0.43, and the first trace was read one or two periods
#: late (the brackets began 3.3 to 43 um past w0). Over the 1,875 template-read presses of 100
#: such sessions, no frame two before a first trace and before w0 lay past 5.6 sds.
MARK_Z_BRIDGE = 10.0
#: ... and the frame just before that first trace may show the mark too faintly to count
#: (a renderer's toe: on a Taxim session without shadows, 14 of the 23 presses its template
#: read showed their first frame past w0 at only 0.05 to 0.23 of the way, 1.9 to 3.7 sds)
#: where its projection lies this many sds above the approach's level and as far above
#: the frames before it (:func:`~tactilevision.contact._onset._level_before`): the
#: crossing's bracket spans its period as well. A needless period is no harmless width:
#: it widens the bracket downwards only, so an indenter's intersection reads P(w0) low and
#: its depths deep. At 0 (any frame above the approach's level, which the indenter's
#: shading lifts on most presses) the depths of Taxim mark sessions of designs drawn at
#: random read +10 to +44 um deep (issue 83; benchmarks/bench_mark_sweep.py). A trace
#: missed costs more than a needless period (a late bracket moves its indenter's
#: intersection; one needless period rarely does): 2 sds, not 3 (a frame 8 um past w0
#: projected 2.7 sds on a Taxim session without shadows, its bracket late)...
MARK_Z_FAINT = 2.0
#: ... and at least this share of the way (with Taxim's shadows the approach frames'
#: sd is 0.003 of the way, under the 0.01 an approach's shading lifts a frame: a frame
#: 100 um before w0 passed 2 sds and doubled the bracket of an indenter's only press,
#: certified 128 um deep; a toe 8 um past w0 without shadows projected 0.25)...
MARK_FAINT_FLOOR = 0.05
#: ... and at most this many such frames (on four Taxim sessions without shadows the
#: crossing never lay more than one period before the first trace).
MARK_FAINT_MAX = 1

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
        ``'onset'``: fz when the land reached w0 (the middle of the smoothed
        fz over the frame period before the first frame showing the mark,
        or two where the frame before may show it faintly; the approach's ramp
        extrapolated past the hold's start) and its uncertainty (that fz's
        spread over the periods and its noise), N: the force rises from there
        to the window's as the stage goes on past w0 (NaN for ``'vernier'``).
    onset_span_s : (float, float)
        ``'onset'``: the instants, F/T clock, s, between which the land crossed w0
        (``force_onset_n`` is the force's bracket over them,
        :func:`~tactilevision.contact.crossing_bracket`); NaN for ``'vernier'``.
    hold_start_s : float
        ``'onset'``: where the approach's ramp ended, the hold's start in the F/T
        log (F/T clock, s; :func:`~tactilevision.contact.hold_start`): past it the
        bracket's force is the ramp's, extrapolated; NaN where the log shows none
        and for ``'vernier'``.
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
    onset_span_s: tuple[float, float] = (float("nan"), float("nan"))
    hold_start_s: float = float("nan")


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
    clock_offset_se_s : float
        The estimated offset's standard error from the spread of the presses' own
        correlations (:func:`press_clock_offset`), s; NaN where the offset is stated or
        too few presses give one.
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
    clock_offset_se_s: float = float("nan")


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
    runs: tuple = ()

    @property
    def vernier(self) -> bool:
        """Whether the bevel is machined (a vernier), not a flat mark."""
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
