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
   samples from that instant (mean, std), and the check |Fxy| << Fz;
4. every press that fails a check is listed with its reason, none is dropped
   silently.

The certified *depth* is left to the caller (:func:`certified_depths`): the
gauge block's w0, or the depth at which the bulging gel meets the land, which
needs nu.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from .._checks import InputError
from ._bevel import bevel_score, footprint_from_frame
from ._footprint import Footprint
from ._force import force_window
from ._mask import contact_mask, noise_level
from ._sync import ClockSync, estimate_clock_offset, force_onsets, refine_clock_offset

__all__ = ["Certification", "CertifiedPress", "Rejection", "certified_depths", "certify_session"]

#: Presses whose |(Fx, Fy)| / Fz exceeds this are misaligned (the paper: "much smaller").
MAX_TANGENTIAL_RATIO = 0.1
#: Fraction of saturated pixels around the contact (not in the reference) that rejects it.
MAX_SATURATED_FRACTION = 0.005


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
        certification; rest since the previous press ended (NaN for the
        first).
    bevel_score : float
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


@dataclass(frozen=True)
class Rejection:
    """A press that failed a check.

    Attributes
    ----------
    press : int
    reason : str
        ``'misaligned'``, ``'footprint cut by the pad edge'``, ``'bevel never
        seen'``, ``'bevel seen too late'``, ``'saturated frames'``, ``'no footprint'``,
        ``'footprint radius'``,
        ``'unknown indenter'``, ``'force window outside the log'``.
    detail : str
        The numbers behind it, one sentence.
    t_frame_s : float
        First frame of the press, camera clock.
    frame : int
        A frame that shows it (for the report).
    """

    press: int
    reason: str
    detail: str
    t_frame_s: float
    frame: int


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
    """

    presses: list[CertifiedPress]
    rejected: list[Rejection]
    clock: ClockSync | None
    clock_offset_s: float
    clock_source: str
    noise_sigma: float
    contact_area_px: np.ndarray
    warnings: list[str] = field(default_factory=list)


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


def certify_session(session, *, min_contact_px: int = 200, bevel_threshold: float = 5.5,
                    progress: Callable | None = None) -> Certification:
    """Find and certify every press of a session.

    Parameters
    ----------
    session : tactilevision.io.Session
    min_contact_px : int, default 200
        A frame is in contact when its contact mask holds this many pixels.
    bevel_threshold : float, default 5.5
        :func:`bevel_score` above which the bevel line is seen (at most 3.2
        without the line, at least 7.5 with it, over 36 rendered presses).
    progress : callable, optional
        Wraps the frame iterator (e.g. ``tqdm``).

    Returns
    -------
    Certification

    Raises
    ------
    InputError
        When no press is found in the frames, or the F/T log and the frames
        share no press onsets (the clock cannot be synchronised).
    """
    cfg = session.config
    ref = session.reference
    s = cfg.mm_per_px
    times = session.frame_times_s
    nf = session.n_frames
    first = session.frame(0)
    sigma = noise_level(first, ref)
    area = np.zeros(nf, np.int64)
    it = range(nf) if progress is None else progress(range(nf))
    for i in it:
        area[i] = int(contact_mask(session.frame(i), ref, sigma=sigma).sum())
    period = float(np.median(np.diff(times))) if nf > 1 else 1.0
    runs = _runs(times, area >= min_contact_px, max_gap_s=2.5 * period)
    if not runs:
        raise InputError(f"no press found in the {nf} frames of {session.path} (no frame has "
                         f"{min_contact_px} px of colour change above the noise)")
    warnings: list[str] = []

    # clock
    frame_on = np.array([times[r[0]] for r in runs])
    fz = session.forces_n[:, 2]
    force_on = force_onsets(session.force_times_s, fz)
    tol = max(0.05, 2.5 * period)
    clock = None
    refined = None
    if len(runs) >= 2 and force_on.size >= 2:
        clock = estimate_clock_offset(frame_on, force_on, tolerance_s=tol)
        refined, _ = refine_clock_offset(times, area, session.force_times_s, fz, clock.offset_s,
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

    commanded = session.presses
    if commanded is not None and len(commanded["press"]) != len(runs):
        warnings.append(f"presses.csv lists {len(commanded['press'])} presses, the frames show "
                        f"{len(runs)}: presses are matched to the nearest commanded position")
    hw, hh = (session.shape[1] - 1) / 2, (session.shape[0] - 1) / 2

    certified: list[CertifiedPress] = []
    rejected: list[Rejection] = []
    prev_end = float("nan")
    for k, run in enumerate(runs):
        t0 = float(times[run[0]])
        wait = t0 - prev_end
        prev_end = float(times[run[-1]])
        peak = int(run[np.argmax(area[run])])
        frame = session.frame(peak)
        mask = contact_mask(frame, ref, sigma=sigma)
        sat = _saturated(frame, ref, mask)
        fp = footprint_from_frame(mask, s, indenter_radius_mm=cfg.indenter_radius_mm)

        def reject(reason: str, detail: str, at: int = peak, k: int = k, t0: float = t0) -> None:
            rejected.append(Rejection(press=k, reason=reason, detail=detail, t_frame_s=t0,
                                      frame=at))

        if sat > MAX_SATURATED_FRACTION:
            reject("saturated frames", f"{100 * sat:.1f}% of the pixels of the contact are "
                   "saturated (a channel at 255 or all at 0) and are not in the reference")
            continue
        edge_touch = bool(mask[0].any() or mask[-1].any() or mask[:, 0].any()
                          or mask[:, -1].any())
        if fp is None or fp.cut_by_edge:
            if edge_touch or (fp is not None and fp.cut_by_edge):
                reject("footprint cut by the pad edge",
                       "the contact reaches the edge of the sensed area")
            else:
                reject("no footprint", "the contact encloses no flat region")
            continue
        if not fp.radius_ok:
            reject("footprint radius", f"fitted radius {fp.radius_mm:.3f} mm, indenter "
                   f"{cfg.indenter_radius_mm:g} mm")
            continue
        x_mm, y_mm = (fp.center_px[0] - hw) * s, (fp.center_px[1] - hh) * s
        # indenter
        if commanded is not None:
            if len(commanded["press"]) == len(runs):
                j = k
            else:
                j = int(np.argmin(np.hypot(commanded["x_mm"] - x_mm, commanded["y_mm"] - y_mm)))
            indenter = int(commanded["indenter"][j])
        else:
            indenter = -1
        if indenter < 0:
            reject("unknown indenter", "no presses.csv tells which indenter was pressed")
            continue
        # bevel onset: the land meets the gel at the deepest point of the press, so
        # the bevel is looked for in the frames near full contact; it must stay
        # visible in the next frame too (or be twice the threshold)
        full = run[area[run] >= 0.9 * area[peak]]
        start = int(np.searchsorted(run, full[0]))
        cand = run[max(0, start - 1):int(np.searchsorted(run, full[-1])) + 1]
        scores = np.array([bevel_score(session.frame(int(i)), ref, tuple(fp.center_px), s,
                                       offset_mm=cfg.bevel_offset_mm,
                                       angle_deg=cfg.bevel_angle_deg,
                                       length_mm=cfg.bevel_length_mm) for i in cand])
        seen = np.isfinite(scores) & (scores > bevel_threshold)
        strong = np.isfinite(scores) & (scores > 2 * bevel_threshold)
        firm = seen & (np.append(seen[1:], False) | strong)
        onset = int(cand[np.argmax(firm)]) if firm.any() else None
        score = float(scores[np.argmax(firm)]) if firm.any() else float("nan")
        if onset is None:
            reject("bevel never seen", f"no frame of the press shows a line "
                   f"{cfg.bevel_offset_mm:g} mm from the indenter at {cfg.bevel_angle_deg:g} deg "
                   f"(best score {np.nanmax(scores) if np.isfinite(scores).any() else 0:.1f}, "
                   f"threshold {bevel_threshold:g})")
            continue
        t_cert = float(times[onset])
        half = cfg.window_samples / (2.0 * cfg.rate_hz)
        t_hold_end = float(times[full[-1]])
        if t_cert + 2 * half > t_hold_end + period:
            reject("bevel seen too late", f"the bevel shows at {t_cert:.3f} s, the "
                   f"{cfg.window_samples}-sample force window would run past the hold "
                   f"(last full-contact frame {t_hold_end:.3f} s)", at=onset)
            continue
        try:
            fw = force_window(session.force_times_s, session.forces_n, t_cert + offset + half,
                              cfg.window_samples)
        except InputError as exc:
            reject("force window outside the log", str(exc), at=onset)
            continue
        if fw.tangential_ratio > MAX_TANGENTIAL_RATIO:
            reject("misaligned", f"|Fxy| / Fz = {fw.tangential_ratio:.3f} > "
                   f"{MAX_TANGENTIAL_RATIO:g}", at=onset)
            continue
        certified.append(CertifiedPress(
            press=k, indenter=indenter, w0_mm=float(cfg.depths_mm[indenter]), frame=onset,
            t_frame_s=t_cert, footprint=fp, x_mm=float(x_mm), y_mm=float(y_mm),
            force_n=fw.fz_n, force_std_n=fw.fz_std_n, fx_n=fw.fx_n, fy_n=fw.fy_n,
            tangential_ratio=fw.tangential_ratio, time_s=t_cert - float(times[0]), hold_s=half,
            wait_s=wait, bevel_score=score))
    return Certification(presses=certified, rejected=rejected, clock=clock,
                         clock_offset_s=offset, clock_source=source, noise_sigma=sigma,
                         contact_area_px=area, warnings=warnings)


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
