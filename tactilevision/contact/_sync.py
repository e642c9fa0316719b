"""Camera and F/T clocks: contact onsets on both, and the offset between them.

The F/T log runs on its own clock. When ``session.toml`` gives no
``clock_offset_s``, the offset is estimated from the presses themselves: each
press starts a contact in the frames (the first frame whose colour change
shows contact) and a rise of Fz in the F/T log. Matching the two lists of
onsets gives offset = t_force - t_frame (formats.md section 1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._checks import InputError, check_array

__all__ = ["MIN_CLOCK_PRESSES", "ClockSync", "contact_onsets", "estimate_clock_offset",
           "force_onsets", "press_clock_offset", "refine_clock_offset"]


@dataclass(frozen=True)
class ClockSync:
    """Estimated clock offset between the F/T log and the frames.

    Attributes
    ----------
    offset_s : float
        t_force - t_frame, s (add it to frame times to get F/T times).
    n_matched : int
        Onsets matched between the two clocks.
    n_frame_onsets, n_force_onsets : int
        Onsets found on each clock.
    spread_s : float
        Median absolute deviation of the matched differences about the
        offset, s (the jitter of one onset; the offset itself is better by
        about 1 / sqrt(n_matched)).
    tolerance_s : float
        Window within which two onsets count as the same press.
    """

    offset_s: float
    n_matched: int
    n_frame_onsets: int
    n_force_onsets: int
    spread_s: float
    tolerance_s: float


def contact_onsets(times_s: np.ndarray, in_contact: np.ndarray, *,
                   min_gap_s: float = 0.0) -> np.ndarray:
    """Times at which a boolean contact signal switches on.

    Parameters
    ----------
    times_s : (N,) array_like of float
        Strictly increasing sample times, s.
    in_contact : (N,) array_like of bool
        Contact seen at each sample.
    min_gap_s : float, default 0.0
        An onset less than this after the previous contact ended is a flicker
        of the same press and is dropped.

    Returns
    -------
    onsets : (K,) float64 ndarray
        For each onset, the midpoint between the last sample without contact
        and the first with it (the unbiased estimate for a contact that starts
        anywhere between two samples); the first sample's time if the signal
        starts in contact.

    Raises
    ------
    ShapeError
        For arrays of different length or not 1-D.
    InputError
        For times that do not increase strictly.
    """
    t = check_array(times_s, "times_s", [("N",)], dtype=np.number, finite=True).astype(float)
    c = check_array(in_contact, "in_contact", [t.shape]).astype(bool)
    if np.any(np.diff(t) <= 0):
        raise InputError("times_s must increase strictly")
    on = np.flatnonzero(c[1:] & ~c[:-1]) + 1
    off = np.flatnonzero(~c[1:] & c[:-1]) + 1       # first sample without contact
    onsets = [t[0]] if c.size and c[0] else []
    onsets += [0.5 * (t[i - 1] + t[i]) for i in on]
    if min_gap_s > 0 and len(onsets) > 1:
        ends = 0.5 * (t[off - 1] + t[off])            # contact ends, midpoints too
        keep = [onsets[0]]
        for s in onsets[1:]:
            prev_end = ends[ends < s]
            if prev_end.size and s - prev_end[-1] < min_gap_s:
                continue
            keep.append(s)
        onsets = keep
    return np.asarray(onsets, dtype=np.float64)


def force_onsets(times_s: np.ndarray, fz_n: np.ndarray, *, threshold_n: float | None = None,
                 min_gap_s: float = 0.05) -> np.ndarray:
    """Times at which Fz rises above a threshold (press starts on the F/T clock).

    Parameters
    ----------
    times_s : (M,) array_like of float
        F/T sample times, strictly increasing, s.
    fz_n : (M,) array_like of float
        Normal force, N, positive pushing into the gel.
    threshold_n : float, optional
        Contact threshold on Fz. Default: the unloaded level plus the larger
        of 0.02 N and 6 sample-noise standard deviations (robust: the median
        absolute first difference, scaled to a Gaussian sd, over sqrt(2)). The
        unloaded level is the force Fz holds most often (:func:`_rest_level`):
        the rests between presses, however long the presses last (the median
        of all of Fz was a held force on a Taxim session whose presses filled
        61 % of its F/T log, and put every onset 0.4 s late).
    min_gap_s : float, default 0.05
        Crossings closer than this to the end of the previous contact are
        noise on the same press.

    Returns
    -------
    onsets : (K,) float64 ndarray, s

    Raises
    ------
    ShapeError, InputError
        As :func:`contact_onsets`; InputError for a non-positive threshold.
    """
    t = check_array(times_s, "times_s", [("M",)], dtype=np.number, finite=True).astype(float)
    f = check_array(fz_n, "fz_n", [t.shape], dtype=np.number, finite=True).astype(float)
    if threshold_n is None:
        d = np.diff(f)
        noise = 1.4826 * float(np.median(np.abs(d - np.median(d)))) / np.sqrt(2)
        threshold_n = _rest_level(f, noise) + max(6.0 * noise, 0.02)
    elif not threshold_n > 0:
        raise InputError(f"threshold_n must be positive, got {threshold_n!r}")
    return contact_onsets(t, f > threshold_n, min_gap_s=min_gap_s)


def _rest_level(fz: np.ndarray, noise: float) -> float:
    """The force an F/T log holds most often, N: the median of the samples in the fullest
    bin of a histogram of bins two noise sds wide (at least a thousandth of its range)
    and the bins either side. The rests between presses are one level, where each hold
    is its own and a relaxing gel's holds and recoveries spread out."""
    lo, hi = (float(v) for v in np.percentile(fz, [0.1, 99.9]))
    if hi <= lo:
        return float(np.median(fz))
    width = max(2.0 * noise, (hi - lo) / 1000.0)
    counts, edges = np.histogram(fz, np.arange(lo, hi + width, width))
    k = int(np.argmax(counts))
    near = fz[(fz >= edges[k] - width) & (fz <= edges[k + 1] + width)]
    return float(np.median(near))


def estimate_clock_offset(frame_onsets_s: np.ndarray, force_onsets_s: np.ndarray, *,
                          tolerance_s: float = 0.05,
                          max_offset_s: float | None = None) -> ClockSync:
    """Offset t_force - t_frame that best matches two lists of press onsets.

    Parameters
    ----------
    frame_onsets_s : (K,) array_like of float
        Contact onsets on the camera clock (:func:`contact_onsets`).
    force_onsets_s : (L,) array_like of float
        Fz onsets on the F/T clock (:func:`force_onsets`).
    tolerance_s : float, default 0.05
        Two onsets within this of each other (after the offset) are the same
        press: a few frame periods, far less than the time between presses.
    max_offset_s : float, optional
        Search only |offset| <= this.

    Returns
    -------
    ClockSync

    Raises
    ------
    InputError
        With fewer than two onsets on either clock, or when no offset matches
        at least two presses (the message says how many onsets each clock had).

    Notes
    -----
    Every pairwise difference force - frame is a candidate offset; the one
    with the most onsets matched within `tolerance_s` wins (ties: the
    smaller spread), and the offset is then the median of its matched
    differences. Extra or missing onsets on either side (a press the camera
    missed, a bump of the F/T sensor) only lower the count.

    Both onsets are threshold crossings on a rising load: the offset is
    biased by the difference of the times the two signals take to cross
    their thresholds (a few ms for a 0.2 s approach; tests/test_contact_sync.py
    measures 1.6 to 5.8 ms over five simulated sessions at 90 frames/s).
    """
    a = np.sort(check_array(frame_onsets_s, "frame_onsets_s", [("K",)], dtype=np.number,
                            finite=True).astype(float))
    b = np.sort(check_array(force_onsets_s, "force_onsets_s", [("L",)], dtype=np.number,
                            finite=True).astype(float))
    if a.size < 2 or b.size < 2:
        raise InputError(f"clock sync needs two press onsets or more on each clock; found "
                         f"{a.size} in the frames and {b.size} in the F/T log (give "
                         "[force_sensor] clock_offset_s in session.toml)")
    cands = (b[None, :] - a[:, None]).ravel()
    if max_offset_s is not None:
        cands = cands[np.abs(cands) <= max_offset_s]
    best: tuple[int, float, float, np.ndarray] | None = None
    for d in np.unique(np.round(cands, 9)):
        diff = b[None, :] - a[:, None] - d                 # (K, L)
        j = np.argmin(np.abs(diff), axis=1)
        near = np.abs(diff[np.arange(a.size), j]) <= tolerance_s
        # one force onset per frame onset
        _, first = np.unique(j[near], return_index=True)
        matched = (b[j[near]] - a[near])[first]
        n = matched.size
        if n < 2:
            continue
        off = float(np.median(matched))
        spread = float(np.median(np.abs(matched - off)))
        if best is None or n > best[0] or (n == best[0] and spread < best[2]):
            best = (n, off, spread, matched)
    if best is None:
        raise InputError(f"no clock offset matches two presses: {a.size} contact onsets in the "
                         f"frames, {b.size} Fz onsets in the F/T log (give [force_sensor] "
                         "clock_offset_s in session.toml)")
    n, _, _, matched = best
    off = float(np.median(matched))
    return ClockSync(offset_s=off, n_matched=int(n), n_frame_onsets=int(a.size),
                     n_force_onsets=int(b.size),
                     spread_s=float(np.median(np.abs(matched - off))), tolerance_s=tolerance_s)


def refine_clock_offset(frame_times_s: np.ndarray, contact_signal: np.ndarray,
                        force_times_s: np.ndarray, fz_n: np.ndarray, offset_s: float, *,
                        span_s: float = 0.2, step_s: float = 0.001) -> tuple[float, float]:
    """Sharpen an onset-based clock offset by correlating whole press profiles.

    Onsets are threshold crossings, biased by the time each signal needs to
    cross its threshold (up to a frame period for the camera). Every frame of
    every press carries timing information, though: the contact area rises,
    holds and falls with the depth, as Fz does. The offset that maximises the
    Pearson correlation between the frames' contact signal and Fz read at the
    frame times plus the offset uses all of them.

    Parameters
    ----------
    frame_times_s : (F,) array_like of float
        Frame times, camera clock, strictly increasing.
    contact_signal : (F,) array_like of float
        Contact area (px) of each frame.
    force_times_s, fz_n : (M,) array_like of float
        The F/T log's times (its own clock) and Fz.
    offset_s : float
        Starting estimate of t_force - t_frame (:func:`estimate_clock_offset`).
    span_s : float, default 0.2
        Search ``offset_s +- span_s``.
    step_s : float, default 0.001
        Grid step (the F/T sample period is a natural choice); the grid is the whole
        multiples of it within ``offset_s +- span_s``.

    Returns
    -------
    offset_s : float
        The best offset on the grid.
    correlation : float
        The correlation there.

    Raises
    ------
    ShapeError
        For arrays of mismatched shape or with NaNs.
    InputError
        When the contact signal is constant (no press in the frames).

    Notes
    -----
    On the simulated sample session (10 frames/s, true offset 0.137 s) the
    onset estimate is 0.0375 s (a frame period early) and the refined one
    0.137 s (tests/test_calibrate.py).
    """
    tf = check_array(frame_times_s, "frame_times_s", [("F",)], dtype=np.number,
                     finite=True).astype(float)
    a = check_array(contact_signal, "contact_signal", [tf.shape], dtype=np.number,
                    finite=True).astype(float)
    ft = check_array(force_times_s, "force_times_s", [("M",)], dtype=np.number,
                     finite=True).astype(float)
    fz = check_array(fz_n, "fz_n", [ft.shape], dtype=np.number, finite=True).astype(float)
    if np.ptp(a) == 0:
        raise InputError("the contact signal is constant: no press to synchronise on")
    # the grid: whole multiples of the step, so that where the search starts moves only
    # its ends
    lo, hi = _search_ends(offset_s, span_s, step_s)
    grid = step_s * np.arange(round(lo / step_s), round(hi / step_s) + 1)
    a0 = (a - a.mean()) / a.std()
    best = (-np.inf, float(offset_s))
    for o in grid:
        f = np.interp(tf + o, ft, fz)
        sd = f.std()
        if sd == 0:
            continue
        c = float(np.mean(a0 * (f - f.mean())) / sd)
        if c > best[0]:
            best = (c, float(o))
    return best[1], best[0]


#: Fewest presses whose own profile correlations set the clock (:func:`press_clock_offset`).
MIN_CLOCK_PRESSES = 5


def _search_ends(offset_s: float, span_s: float, step_s: float) -> tuple[float, float]:
    """The first and last offsets :func:`refine_clock_offset` tries: the whole multiples
    of `step_s` nearest inside ``offset_s +- span_s``, s."""
    return (step_s * math.ceil((offset_s - span_s) / step_s - 1e-9),
            step_s * math.floor((offset_s + span_s) / step_s + 1e-9))


def _on_search_edge(found_s: float, offset_s: float, span_s: float, step_s: float) -> bool:
    """Whether :func:`refine_clock_offset`'s best offset lies on its grid's first or last
    point: the correlation still rose there, so it bounds the offset rather than reads it.
    """
    lo, hi = _search_ends(offset_s, span_s, step_s)
    return found_s <= lo + 0.5 * step_s or found_s >= hi - 0.5 * step_s


def press_clock_offset(frame_times_s: np.ndarray, contact_signal: np.ndarray,
                       runs: list[np.ndarray], force_times_s: np.ndarray, fz_n: np.ndarray,
                       offset_s: float, *, span_s: float = 0.2, step_s: float = 0.001
                       ) -> tuple[float, float, int]:
    """The clock offset as the median of each press's own profile correlation, and its
    standard error.

    :func:`refine_clock_offset` over all presses at once weighs the deep presses most,
    whose contact area follows the force least linearly. Each press correlated on its
    own frames (the run and three frames either side) gives one offset (none where its
    best lies on the search grid's edge, :func:`_on_search_edge`); their median is the
    estimate, ``1.2533 x 1.4826 x MAD / sqrt(n)`` its standard error (a median's, of a
    normal spread). On 12 gauge-block sessions rendered by Taxim (10 frames/s, true
    offset 0.137 s) the all-press correlation was off by 4.9 ms RMS (up to 9.5), the
    median of the presses' by 2.9 ms, and its error over its standard error by about 1
    RMS (issue 53).

    Parameters
    ----------
    frame_times_s, contact_signal, force_times_s, fz_n, offset_s, span_s, step_s
        As :func:`refine_clock_offset` (`offset_s`: the start of each search).
    runs : list of (K,) int ndarray
        Each press's frames (indices into the frames).

    Returns
    -------
    offset_s : float
        The median (NaN with fewer than :data:`MIN_CLOCK_PRESSES` presses correlated).
    se_s : float
        Its standard error, s (NaN likewise).
    n : int
        Presses correlated.
    """
    tf = np.asarray(frame_times_s, np.float64)
    a = np.asarray(contact_signal, np.float64)
    per = []
    for r in runs:
        sel = np.arange(max(0, int(r[0]) - 3), min(a.size, int(r[-1]) + 4))
        if np.ptp(a[sel]) == 0:
            continue
        o = refine_clock_offset(tf[sel], a[sel], force_times_s, fz_n, offset_s,
                                span_s=span_s, step_s=step_s)[0]
        if not _on_search_edge(o, offset_s, span_s, step_s):
            per.append(o)
    if len(per) < MIN_CLOCK_PRESSES:
        return float("nan"), float("nan"), len(per)
    per_a = np.asarray(per)
    med = float(np.median(per_a))
    mad = float(np.median(np.abs(per_a - med)))
    return med, 1.2533 * 1.4826 * mad / np.sqrt(per_a.size), per_a.size
