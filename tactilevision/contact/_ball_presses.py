"""The presses of a ball session: each hold's force window and the frame at its middle.

A ball has no gauge block: nothing marks the depth of a press, which the ball's
contact circle gives instead (:func:`tactilevision.pipeline.calibrate_ball_session`).
What certification does here is find the presses in the frames (runs of frames in
contact), synchronise the F/T clock on their onsets (as for a gauge block:
:func:`.certify_session`), find each hold's start in the force
(:func:`.hold_start`), average ``window_samples`` F/T samples from it (or ending
where the release begins, ``window_at = "end"``) and pick the frame nearest the
window's middle: the ball at rest at the depth the force was read at.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from .._checks import InputError
from ._certify import _contact_areas, _runs, _sync_clock
from ._force import force_window
from ._holds import hold_end, hold_start
from ._mask import noise_level
from ._results import MAX_TANGENTIAL_RATIO, Rejection

__all__ = ["BallPress", "BallPresses", "find_ball_presses"]


@dataclass(frozen=True)
class BallPress:
    """One hold of a ball: its force window and the frame at the window's middle.

    Attributes
    ----------
    press : int
        Index among the runs of frames in contact.
    frame : int
        The frame nearest the force window's middle (camera clock).
    t_frame_s : float
        Its time, camera clock, s.
    force_n, force_std_n, force_sem_n : float
        Mean fz over the window, its samples' sd and the mean's standard error, N.
    fx_n, fy_n, tangential_ratio : float
        Mean shear components, N, and |(fx, fy)| / fz.
    hold_s : float
        The window's middle after the hold's start, s.
    """

    press: int
    frame: int
    t_frame_s: float
    force_n: float
    force_std_n: float
    force_sem_n: float
    fx_n: float
    fy_n: float
    tangential_ratio: float
    hold_s: float


@dataclass(frozen=True)
class BallPresses:
    """The presses :func:`find_ball_presses` found.

    Attributes
    ----------
    presses : list of BallPress
    rejected : list of Rejection
    clock_offset_s : float
        F/T clock minus camera clock, s.
    clock_source : {'session.toml', 'estimated'}
    noise_sigma : float
        The frames' noise against the reference (:func:`.noise_level`).
    contact_area_px : (F,) int64 ndarray
        Pixels in contact in each frame.
    press_spans_s : (P, 2) float64 ndarray
        First and last frame in contact of every run of frames (presses and rejected
        ones), camera clock, s.
    warnings : list of str
    """

    presses: list[BallPress]
    rejected: list[Rejection]
    clock_offset_s: float
    clock_source: str
    noise_sigma: float
    contact_area_px: np.ndarray = field(repr=False)
    press_spans_s: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)), repr=False)
    warnings: list[str] = field(default_factory=list)


def find_ball_presses(session, *, min_contact_px: int = 200,
                      progress: Callable | None = None) -> BallPresses:
    """Find every press of a ball session, its force window and its frame at rest.

    Parameters
    ----------
    session : tactilevision.io.Session
        A session whose ``[indenter] shape`` is ``"sphere"`` (any session is read the
        same way; nothing of a gauge block is used).
    min_contact_px : int, default 200
        A frame is in contact when its contact mask (:func:`.contact_mask`) holds this
        many pixels.
    progress : callable, optional
        Wraps the frame iterator (e.g. ``tqdm``).

    Returns
    -------
    BallPresses

    Raises
    ------
    InputError
        When no frame is in contact, or the clock cannot be synchronised (no
        ``clock_offset_s`` and too few press onsets shared by frames and F/T log).

    Notes
    -----
    A press is rejected, with its reason, when the F/T log shows no hold start
    within its frames (``'hold start not found'``), its force window runs past its
    last frame in contact or before its release (``'hold too short'``), lies outside
    the log (``'force window outside the log'``), or the ball pushed sideways
    (``'misaligned'``, |Fxy| / Fz above 0.1).
    """
    times = session.frame_times_s
    sigma = noise_level(session.frame(0), session.reference)
    area = _contact_areas(session, sigma, min_contact_px, progress, None)
    period = float(np.median(np.diff(times))) if times.size > 1 else 1.0
    runs = _runs(times, area >= min_contact_px, max_gap_s=2.5 * period)
    if not runs:
        raise InputError(f"no press found in the {times.size} frames of {session.path} (no "
                         f"frame has {min_contact_px} px of colour change above the noise)")
    offset, source, _, warnings, _ = _sync_clock(session, times, area, runs, period, None)
    presses: list[BallPress] = []
    rejected: list[Rejection] = []
    for k, run in enumerate(runs):
        # the force rises before the frames see 200 px of contact: the hold is looked for
        # from halfway back to the previous press (at most a second back)
        t_first = float(times[run[0]])
        t_prev = float(times[runs[k - 1][-1]]) if k else t_first - 2.0
        got = _ball_press(session, k, run, offset, period,
                          max(0.5 * (t_prev + t_first), t_first - 1.0))
        (rejected if isinstance(got, Rejection) else presses).append(got)
    return BallPresses(presses=presses, rejected=rejected, clock_offset_s=offset,
                       clock_source=source, noise_sigma=sigma, contact_area_px=area,
                       press_spans_s=np.array([(times[r[0]], times[r[-1]]) for r in runs],
                                              np.float64).reshape(-1, 2),
                       warnings=list(warnings))


def _ball_press(session, k: int, run: np.ndarray, offset: float, period: float,
                t_from: float) -> BallPress | Rejection:
    """One run of frames in contact: its press, or why it is rejected (the hold's start
    looked for from `t_from`, camera clock)."""
    cfg = session.config
    times = session.frame_times_s
    ft, fz = session.force_times_s, session.forces_n[:, 2]
    t_first, t_last = float(times[run[0]]), float(times[run[-1]])

    def reject(reason: str, detail: str) -> Rejection:
        return Rejection(press=k, reason=reason, detail=detail, t_frame_s=t_first,
                         frame=int(run[len(run) // 2]))

    t_hold = hold_start(ft, fz, t_from + offset, t_last + offset)
    if t_hold is None:
        return reject("hold start not found", "the F/T log shows no approach ending in a "
                      f"hold between {t_from:.3f} and {t_last:.3f} s (camera clock)")
    half = 0.5 * cfg.window_samples / cfg.rate_hz
    if cfg.window_at == "end":
        t_release = hold_end(ft, fz, t_hold)
        if t_release is None or t_release - 2 * half < t_hold:
            return reject("hold too short", f"the {cfg.window_samples}-sample force window "
                          "does not fit between the hold's start and its release")
        centre = t_release - half
    else:
        centre = t_hold + half
        if centre + half > t_last + offset + period:
            return reject("hold too short", f"the {cfg.window_samples}-sample force window "
                          f"from the hold's start ({t_hold - offset:.3f} s, camera clock) runs "
                          f"past the press's last frame in contact ({t_last:.3f} s)")
    try:
        fw = force_window(ft, session.forces_n, centre, cfg.window_samples)
    except InputError as exc:
        return reject("force window outside the log", str(exc))
    if fw.tangential_ratio > MAX_TANGENTIAL_RATIO:
        return reject("misaligned", f"|Fxy| / Fz = {fw.tangential_ratio:.3f} > "
                      f"{MAX_TANGENTIAL_RATIO:g}")
    frame = int(run[np.argmin(np.abs(times[run] + offset - centre))])
    return BallPress(press=k, frame=frame, t_frame_s=float(times[frame]), force_n=fw.fz_n,
                     force_std_n=fw.fz_std_n, force_sem_n=fw.fz_sem_n, fx_n=fw.fx_n,
                     fy_n=fw.fy_n, tangential_ratio=fw.tangential_ratio,
                     hold_s=float(centre - t_hold))
