"""The depth of a press certified by a bevel mark: w0 plus the force's rise past the
crossing (tactilevision.contact.mark_depths), worked by hand."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.contact import (
    _onset,
    crossing_bracket,
    crossing_forces,
    mark_depths,
    mark_shared_mm,
)
from tactilevision.contact._mark import CLOCK_SD_S, STIFFNESS_REL
from tactilevision.contact._onset import _crossing_force, _mark_template_onset, _press_forces
from tactilevision.contact._results import MARK_FAINT_MAX


def test_depth_is_w0_plus_the_force_rise_over_the_slope():
    """P rises from 1.00 N at the crossing to 1.15 N in the window at dP/dw = 5 N/mm: the
    stage went 30 um past w0; the uncertainty is the two forces' over dP/dw."""
    d, sd, after = mark_depths([0.3, 0.5], [1.15, 2.0], [1.0, 2.0], [5.0, 6.0],
                               force_sem_n=[0.001, 0.001], force_crossing_sd_n=[0.02, 0.0],
                               travel_mm=[0.06, 0.1])
    np.testing.assert_allclose(after, [0.03, 0.0])
    np.testing.assert_allclose(d, [0.33, 0.5])
    np.testing.assert_allclose(sd, [np.hypot(0.02, 0.001) / 5.0, 0.001 / 6.0])


def test_unread_crossing_keeps_half_a_frame():
    """Without the crossing's force, w0 + half the stage's travel in a frame, +- travel /
    sqrt(12) (the onset comes within one frame of w0)."""
    d, sd, after = mark_depths([0.3], [1.2], [np.nan], [5.0], force_sem_n=[0.001],
                               force_crossing_sd_n=[np.nan], travel_mm=[0.06])
    assert d[0] == pytest.approx(0.33) and after[0] == pytest.approx(0.03)
    assert sd[0] == pytest.approx(0.06 / np.sqrt(12))


def test_shared_part_is_clock_and_slope():
    """speed x CLOCK_SD_S + STIFFNESS_REL x |depth past w0|: at 1 mm/s (0.1 mm a 0.1 s
    frame) and 40 um past w0."""
    half = mark_shared_mm([0.1], [0.04], 0.1)
    assert half[0] == pytest.approx(1.0 * CLOCK_SD_S + STIFFNESS_REL * 0.04)


def test_bad_input():
    with pytest.raises(InputError, match="stiffness"):
        mark_depths([0.3], [1.0], [0.9], [0.0], force_sem_n=[0], force_crossing_sd_n=[0],
                    travel_mm=[0.1])
    with pytest.raises(InputError, match="travel"):
        mark_depths([0.3], [1.0], [0.9], [5.0], force_sem_n=[0], force_crossing_sd_n=[0],
                    travel_mm=[-0.1])
    with pytest.raises(ValueError, match="force_n"):
        mark_depths([0.3, 0.4], [1.0], [0.9, 1.0], [5.0, 5.0], force_sem_n=[0, 0],
                    force_crossing_sd_n=[0, 0], travel_mm=[0.1, 0.1])


def test_crossing_force_is_the_intersection_of_an_indenters_brackets():
    """Three presses of one indenter bracket P(w0) by [1.00, 1.20], [1.10, 1.30] and [0.95,
    1.15] N: P(w0) lies in [1.10, 1.15], its middle 1.125 N, its sd 0.05 / sqrt(12) shared by
    the three (so stated times sqrt(3)); another indenter's single press keeps its own; an
    indenter whose brackets do not meet gets their mean and is counted."""
    half = np.array([0.1, 0.1, 0.1, 0.05, 0.01, 0.01]) / np.sqrt(3)   # sd of a bracket
    mid = np.array([1.10, 1.20, 1.05, 2.0, 3.0, 3.5])
    ind = np.array([0, 0, 0, 1, 2, 2])
    f, sd, disjoint = crossing_forces(ind, mid, half)
    np.testing.assert_allclose(f[:3], 1.125)
    np.testing.assert_allclose(sd[:3], 0.05 / np.sqrt(12) * np.sqrt(3))
    assert f[3] == pytest.approx(2.0) and sd[3] == pytest.approx(0.1 / np.sqrt(12))
    assert disjoint == 1 and f[4] == f[5] == pytest.approx(3.25)
    f2, _, _ = crossing_forces([0, 0], [1.0, np.nan], [0.01, np.nan])
    assert f2[0] == pytest.approx(1.0) and np.isnan(f2[1])


def test_a_press_force_shares_are_of_its_own_force_whatever_the_ft_zero():
    """_press_forces: the F/T at a press's frames less its rest before the press, so the
    shares MARK_BASELINE_FORCE and MARK_HOLD_FORCE pick the same frames with 0.3 N on every
    sample (an F/T zeroed before a fixture was mounted: on a Taxim mark session the raw
    forces' shares put one onset two frames early, its crossing force 35 % low); and where
    the rest still holds the last press's release, from the press's least force."""
    tf = np.arange(0.0, 4.0, 1e-3)
    true = np.interp(tf, [0.0, 1.0, 1.5, 2.5, 3.0, 4.0], [0.0, 0.0, 2.0, 2.0, 0.0, 0.0])
    frames = np.arange(0.0, 4.0, 0.1)
    run = np.flatnonzero((frames > 1.05) & (frames < 2.95))
    for zero in (0.0, 0.3):
        session = SimpleNamespace(force_times_s=tf, frame_times_s=frames,
                                  forces_n=np.column_stack([0 * tf, 0 * tf, true + zero]))
        ctx = SimpleNamespace(session=session, offset=0.0, period=0.1)
        f = _press_forces(ctx, run)
        assert np.allclose(f, np.interp(frames[run], tf, true), atol=1e-9)
    # a last press still releasing over the rest: the rest is the press's least instead
    tail = true + 0.3 + np.where(tf < 1.0, 1.0, 0.0)
    session = SimpleNamespace(force_times_s=tf, frame_times_s=frames,
                              forces_n=np.column_stack([0 * tf, 0 * tf, tail]))
    f = _press_forces(SimpleNamespace(session=session, offset=0.0, period=0.1), run)
    on = np.interp(frames[run], tf, true)
    assert np.allclose(f, on - on.min(), atol=1e-9)


def _ramp_session():
    """fz rising at 2 N/s from t = 1 s to a 2 N hold at 2 s (1 kHz, noise-free), frames
    every 0.1 s; the press's frames in contact."""
    tf = np.arange(0.0, 4.0, 1e-3)
    fz = np.interp(tf, [0.0, 1.0, 2.0, 3.0, 3.5, 4.0], [0.0, 0.0, 2.0, 2.0, 0.0, 0.0])
    frames = np.arange(0.0, 4.0, 0.1)
    session = SimpleNamespace(force_times_s=tf, frame_times_s=frames,
                              forces_n=np.column_stack([0 * tf, 0 * tf, fz]))
    return session, np.flatnonzero((frames > 1.05) & (frames < 3.45))


def test_crossing_bracket_spans_its_periods_and_ends_at_the_hold_when_told():
    """The crossing lies in the `periods` frame periods before the mark's first trace: a
    trace at 1.55 s brackets fz over [1.45, 1.55] s = [0.9, 1.1] N with one period, [0.7,
    1.1] N with two; a trace at 2.05 s, the hold begun at 2.0 s, over [1.95, 2.05] s with
    the approach's ramp extrapolated past the hold's start: [1.9, 2.1] N (clipped at the
    hold, [1.8, 2.0] N, the crossing sat near the top of such brackets whenever the stage
    stopped within a period of w0, and the intersections read P(w0) low: issue 83); with
    `to_hold` (an onset that may be early) the bracket ends at the hold's start (2.0 s,
    2 N); a trace whose frame before was already in the hold puts it in the periods before
    the hold's start.
    Returned as the middle and the sd of a uniform over the bracket."""
    session, run = _ramp_session()

    def bracket(t_on, periods=1, to_hold=False):
        mid, sd, span, hold = _crossing_force(session, run, t_on, 0.0, 0.1, periods, to_hold)
        assert hold == pytest.approx(2.0, abs=2e-3)
        # the instants it is read at, kept with the press: the same bracket read again
        assert crossing_bracket(session.force_times_s, session.forces_n[:, 2],
                                *span, ramp_end_s=hold) == (mid, sd)
        half = np.sqrt(3.0) * sd
        return mid - half, mid + half

    np.testing.assert_allclose(bracket(1.55), [0.9, 1.1], atol=2e-3)
    np.testing.assert_allclose(bracket(1.55, 2), [0.7, 1.1], atol=2e-3)
    np.testing.assert_allclose(bracket(2.05), [1.9, 2.1], atol=1e-2)
    np.testing.assert_allclose(bracket(1.55, 2, to_hold=True), [0.7, 2.0], atol=1e-2)
    np.testing.assert_allclose(bracket(2.35, 2), [1.6, 2.0], atol=1e-2)
    # an onset read in the hold (a noise frame, the template failing): still two periods
    np.testing.assert_allclose(bracket(2.15, 2, to_hold=True), [1.6, 2.0], atol=1e-2)
    _, _, span, _ = _crossing_force(session, run, 1.55, 0.0, 0.1, 2, False)
    np.testing.assert_allclose(span, [1.35, 1.55], atol=1e-9)
    # read on another force at those instants (the elastic force behind a relaxing log)
    twice = session.forces_n[:, 2] * 2.0
    mid, sd = crossing_bracket(session.force_times_s, twice, *span)
    np.testing.assert_allclose([mid - np.sqrt(3) * sd, mid + np.sqrt(3) * sd], [1.4, 2.2],
                               atol=4e-3)
    assert np.isnan(crossing_bracket(session.force_times_s, twice, 5.0, 5.2)[0])


def _faint_press(monkeypatch, before: list[float]):
    """A press whose template projections are known: approach frames at +-0.01 of the
    way (fz under MARK_BASELINE_FORCE of the largest), then the frames `before` (fz 0.75 of
    it), then six hold frames at the hold's level; each frame's profile across the mark is
    its projection times a trough. `_mark_template_onset`'s ``(onset, first, faint)``."""
    trough = -np.exp(-0.5 * (np.linspace(-3.0, 3.0, 41) / 0.6) ** 2)
    a = [0.01, -0.01] * 4 + list(before) + [1.0] * 6
    forces = np.array([0.05 * (k + 1) for k in range(8)] + [0.75] * len(before) + [1.0] * 6)
    monkeypatch.setattr(_onset, "_press_forces", lambda ctx, run: forces[:len(run)])
    monkeypatch.setattr(_onset, "_mark_residual", lambda ctx, centre, i: (
        np.arange(41.0), np.column_stack([a[i] * trough] * 3)))
    run = np.arange(len(a))
    got, why = _mark_template_onset(SimpleNamespace(), (0.0, 0.0), run)
    assert got is not None, why
    return got


def test_frames_before_the_first_trace_that_may_show_it_faintly_widen_its_bracket(
        monkeypatch):
    """A mark's trace grows from nothing at w0: the frame before the first that counts as a
    trace (4 sds and 0.1 of the way) is counted as possibly showing the mark when it lies
    MARK_Z_FAINT sds above the approach's level and as far above the frames before it (on
    Taxim's frames without shadows the first frame past w0 showed 0.01 to 0.23 of the
    way), at most MARK_FAINT_MAX of them; one at or under the approach's level is not, nor
    one within MARK_Z_FAINT sds of it (issue 83: at 0 sds, any frame above the approach's
    level, the needless periods widened the brackets downwards only and the depths read
    deep)."""
    onset, first, faint = _faint_press(monkeypatch, [-0.02, 0.06])
    assert (onset, first, faint) == (10, 10, 1)
    assert _faint_press(monkeypatch, [0.06, -0.02])[2] == 0
    assert _faint_press(monkeypatch, [0.03, 0.05, 0.07])[2] == MARK_FAINT_MAX == 1
    # 0.015 of the way: under MARK_Z_FAINT sds of the approach's frames (sd 0.011)
    assert _faint_press(monkeypatch, [-0.02, 0.015])[2] == 0
    # a frame over 4 sds and 0.1 of the way, rising towards the hold, is the first trace
    onset, first, faint = _faint_press(monkeypatch, [-0.02, 0.3])
    assert (onset, first, faint) == (10, 9, 0)


def test_a_trace_that_passes_back_through_the_approachs_level_still_starts_the_bracket(
        monkeypatch):
    """A trace's change turns into the hold's shape on its way up: a frame just past w0 may
    project far below the approach's level (Taxim without shadows: -0.5 to -2.0 of the way,
    19 to 31 sds) and the next one back at it. The trace two frames before the first rising
    one starts the bracket when it lies MARK_Z_BRIDGE sds off, and as far from the frame
    between; a frame under that (here 0.105
    of the way, 9.8 sds of the approach's frames' 0.0107) bridges nothing (issue 83: on two
    drawn designs, four brackets began 3 to 43 um past w0)."""
    assert _faint_press(monkeypatch, [0.0, -0.5, 0.01]) == (11, 9, 0)
    assert _faint_press(monkeypatch, [0.0, -0.5, 0.3]) == (11, 9, 0)
    assert _faint_press(monkeypatch, [0.0, 0.105, 0.01]) == (11, 11, 0)
    # without the frame between, the walk is the rise's own
    assert _faint_press(monkeypatch, [0.0, 0.0, 0.01]) == (11, 11, 0)


def test_a_trace_rises_above_the_frames_before_it_not_an_approach_lifted_by_shading(
        monkeypatch):
    """An approach whose shading lifts the mark's profile lifts every frame before the
    crossing (Taxim, seed 171, no shadows: 0.07 to 0.20 of the way on the first press's
    last four): a frame 4 sds and 0.1 of the way up counts as the first trace only when it
    also lies 4 sds above the median of the three frames before the one before it (that
    one may show the mark's toe). Here 0.17 after 0.20, 0.14 and 0.07 does not: the onset
    is the first trace; 2.8 sds of the approach's frames over them, it may be a faint one
    (MARK_Z_FAINT), so its period joins the bracket. After frames at the approach's level
    the same 0.17 is the trace."""
    lifted = [0.20, 0.14, 0.07, 0.17]
    onset, first, faint = _faint_press(monkeypatch, lifted)
    assert (onset, first, faint) == (12, 12, 1)
    # lifted as much as the frames before it, it is no trace at all: its period stays out
    assert _faint_press(monkeypatch, [0.20, 0.14, 0.16, 0.15])[1:] == (12, 0)
    onset, first, faint = _faint_press(monkeypatch, [0.01, -0.01, 0.0, 0.17])
    assert (onset, first, faint) == (12, 11, 0)
