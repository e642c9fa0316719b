"""Clock sync from press onsets: a simulated session with a known offset."""

from __future__ import annotations

import numpy as np
import pytest

from tactilevision import InputError, ShapeError
from tactilevision.contact import contact_onsets, estimate_clock_offset, force_onsets

FPS, RATE, OFFSET = 90.0, 1000.0, 0.3712  # camera, F/T rate, t_force - t_frame


def timeline(seed: int = 0, n_presses: int = 12):
    """True press intervals (a common time base), frames and forces on their clocks."""
    rng = np.random.default_rng(seed)
    starts = np.cumsum(rng.uniform(2.0, 3.0, n_presses))      # s, waits between presses
    ends = starts + rng.uniform(0.8, 1.2, n_presses)
    t_frame = np.arange(0.0, ends[-1] + 1.0, 1 / FPS) + rng.uniform(0, 2e-3, 1)  # camera clock
    t_frame = t_frame + rng.normal(0, 1e-4, t_frame.size)                      # jitter
    t_frame.sort()
    t_force = np.arange(-0.5, ends[-1] + OFFSET + 1.0, 1 / RATE)              # F/T clock

    def depth_fraction(t):  # 0..1 ramp over 0.2 s, hold, ramp down
        out = np.zeros_like(t)
        for s, e in zip(starts, ends, strict=True):
            out = np.maximum(out, np.clip(np.minimum(t - s, e - t) / 0.2, 0, 1))
        return out

    in_contact = depth_fraction(t_frame) > 0.02                  # colour change above noise
    fz = 2.0 * depth_fraction(t_force - OFFSET) + 0.05 + rng.normal(0, 1 / 80, t_force.size)
    return starts, t_frame, in_contact, t_force, fz


def test_offset_recovered_within_a_frame_period():
    starts, t_frame, contact, t_force, fz = timeline()
    a = contact_onsets(t_frame, contact)
    b = force_onsets(t_force, fz)
    assert a.size == b.size == starts.size
    sync = estimate_clock_offset(a, b)
    assert sync.n_matched == starts.size
    # both onset estimates lag the true start a little (ramp to threshold);
    # the lags differ by < 5 ms, well inside a frame period of 11 ms
    assert sync.offset_s == pytest.approx(OFFSET, abs=0.5 / FPS)
    assert sync.spread_s < 1 / FPS


def test_extra_and_missing_onsets_do_not_move_it():
    _, t_frame, contact, t_force, fz = timeline(seed=3)
    a = contact_onsets(t_frame, contact)[2:]                  # camera missed two presses
    b = np.sort(np.append(force_onsets(t_force, fz), [0.7, 15.03]))  # two F/T bumps
    sync = estimate_clock_offset(a, b)
    assert sync.n_matched == a.size and sync.n_force_onsets == b.size
    assert sync.offset_s == pytest.approx(OFFSET, abs=0.5 / FPS)


def test_negative_offset_and_search_window():
    a = np.array([1.0, 4.0, 6.5, 10.0])
    sync = estimate_clock_offset(a, a - 2.25, max_offset_s=3.0)
    assert sync.offset_s == pytest.approx(-2.25) and sync.n_matched == 4
    with pytest.raises(InputError, match="no clock offset matches two presses"):
        estimate_clock_offset(a, a - 2.25, max_offset_s=1.0)


def test_contact_onsets_midpoints_and_flicker():
    t = np.arange(10.0)
    c = np.array([1, 1, 0, 0, 1, 0, 1, 1, 0, 0], bool)
    np.testing.assert_allclose(contact_onsets(t, c), [0.0, 3.5, 5.5])
    # the contact starting at 5.5 comes 1.0 s after the one ending at 4.5: a flicker
    np.testing.assert_allclose(contact_onsets(t, c, min_gap_s=1.5), [0.0, 3.5])


def test_force_onsets_threshold():
    t = np.arange(0, 3, 1e-3)
    fz = np.where((t > 1.0) & (t < 2.0), 1.0, 0.0)
    np.testing.assert_allclose(force_onsets(t, fz), [1.0005], atol=1e-9)
    np.testing.assert_allclose(force_onsets(t, fz, threshold_n=0.5), [1.0005], atol=1e-9)
    assert force_onsets(t, fz, threshold_n=2.0).size == 0


def test_bad_input():
    with pytest.raises(InputError, match="two press onsets or more on each clock; found 1"):
        estimate_clock_offset([1.0], [1.0, 2.0])
    with pytest.raises(ShapeError, match="in_contact"):
        contact_onsets([0.0, 1.0], [True])
    with pytest.raises(InputError, match="increase strictly"):
        contact_onsets([0.0, 0.0], [True, False])
    with pytest.raises(ShapeError, match="fz_n must be finite"):
        force_onsets([0.0, 1.0], [0.0, np.nan])
    with pytest.raises(InputError, match="threshold_n must be positive"):
        force_onsets([0.0, 1.0], [0.0, 1.0], threshold_n=0.0)


def _presses(offset: float, depths: list[float], fps: float = 10.0, seed: int = 0):
    """Frames at `fps` and a 1 kHz F/T log of presses of the given depths (0.5 s ramps,
    0.5 s holds, 0.25 s releases, 2 s apart), the contact area a saturating function of
    the force (sqrt: the deeper presses' area follows it least linearly), the camera's
    phase random; t_force = t_frame + offset."""
    rng = np.random.default_rng(seed)
    t_end = 2.0 * len(depths) + 2.0
    tf = np.arange(0.0, t_end, 0.001)
    w = np.zeros_like(tf)
    for k, d in enumerate(depths):
        t0 = 1.0 + 2.0 * k
        w = np.maximum(w, np.interp(tf, [t0, t0 + 0.5, t0 + 1.0, t0 + 1.25, t0 + 2.0],
                                    [0.0, d, d, 0.0, 0.0]))
    fz = 3.5 * w * (1 + w) + rng.normal(0, 0.005, tf.size)
    frames = np.arange(rng.uniform(0, 1 / fps), t_end - 0.5, 1 / fps)
    area = 4000.0 * np.sqrt(np.interp(frames + offset, tf, 3.5 * w * (1 + w)))
    return frames, area, tf, fz


def test_press_clock_offset_is_the_median_of_the_presses():
    """Twenty presses of 0.1 to 0.6 mm: each press's own correlation, their median within
    2 ms of the true 0.137 s and within 3 of its standard errors; fewer than
    MIN_CLOCK_PRESSES presses: NaN."""
    from tactilevision.contact import press_clock_offset, refine_clock_offset
    from tactilevision.contact._sync import MIN_CLOCK_PRESSES

    depths = list(np.resize([0.1, 0.6, 0.3, 0.5, 0.2, 0.4], 20))
    frames, area, tf, fz = _presses(0.137, depths)
    on = np.flatnonzero(area > 0)
    runs = np.split(on, np.flatnonzero(np.diff(on) > 1) + 1)
    assert len(runs) == 20
    start, _ = refine_clock_offset(frames, area, tf, fz, 0.14)
    med, se, n = press_clock_offset(frames, area, runs, tf, fz, start)
    assert n == 20 and np.isfinite(se) and se > 0
    assert abs(med - 0.137) < 0.002 and abs(med - 0.137) <= 3 * se + 0.001
    med, se, n = press_clock_offset(frames, area, runs[:MIN_CLOCK_PRESSES - 1], tf, fz, start)
    assert np.isnan(med) and np.isnan(se) and n == MIN_CLOCK_PRESSES - 1


def test_force_onsets_when_presses_fill_most_of_the_session():
    """Presses that hold the force for most of a session (long holds, short rests): the
    unloaded level is still the rests', and each onset lies within 0.1 s of its touch
    (the threshold's own lag: 6 noise sds at 1.5 N/s, 50 ms; the median of Fz, a held
    force here, put them 0.3 s and more late)."""
    rng = np.random.default_rng(5)
    tf = np.arange(0.0, 60.0, 0.001)
    touches = 1.0 + np.arange(12) * 4.8 + rng.uniform(0.0, 0.3, 12)
    hold = 2.5
    w = np.zeros_like(tf)
    for t0, d in zip(touches, rng.uniform(0.15, 0.6, 12), strict=True):
        # 0.4 mm/s approach, a 2.5 s hold, 0.25 s release: 3.7 of every 4.8 s loaded
        w = np.maximum(w, np.interp(tf, [t0, t0 + d / 0.4, t0 + d / 0.4 + hold,
                                         t0 + d / 0.4 + hold + 0.25], [0.0, d, d, 0.0],
                                    left=0.0, right=0.0))
    fz = 3.65 * w * (1 + 1.5 * w / 3.0) + rng.normal(0, 1 / 80, tf.size)
    assert np.mean(fz > 0.05) > 0.5                  # the median is a held force
    on = force_onsets(tf, fz)
    assert on.size == 12
    assert np.all((on > touches) & (on - touches < 0.1))


def test_press_clock_offset_leaves_out_a_search_that_ends_on_its_edge():
    """Searched from 0.45 s off with a 0.2 s span, most presses' best lies on the grid's
    edge: those are not read, too few are left, and the median is NaN (each such edge
    once counted as a value)."""
    from tactilevision.contact import press_clock_offset
    from tactilevision.contact._sync import MIN_CLOCK_PRESSES

    depths = list(np.resize([0.1, 0.6, 0.3, 0.5, 0.2, 0.4], 20))
    frames, area, tf, fz = _presses(0.137, depths)
    on = np.flatnonzero(area > 0)
    runs = np.split(on, np.flatnonzero(np.diff(on) > 1) + 1)
    med, se, n = press_clock_offset(frames, area, runs, tf, fz, 0.137 + 0.45, span_s=0.2)
    assert np.isnan(med) and np.isnan(se) and n < MIN_CLOCK_PRESSES


def test_a_clock_search_that_keeps_ending_on_its_edge_is_said(monkeypatch):
    """Where the profile correlation's best lies on the search's edge every time, the
    search moves on CLOCK_SEARCHES times and then says that the presses do not pin the
    clock (and how far it searched), instead of taking the edge silently."""
    from types import SimpleNamespace

    from tactilevision.contact import _certify

    depths = list(np.resize([0.1, 0.6, 0.3, 0.5, 0.2, 0.4], 20))
    frames, area, tf, fz = _presses(0.137, depths)
    on = np.flatnonzero(area > 0)
    runs = np.split(on, np.flatnonzero(np.diff(on) > 1) + 1)
    starts = []

    def to_the_edge(times, signal, ft, f, offset_s, *, span_s, step_s):
        starts.append(offset_s)
        return offset_s + span_s, 0.5

    monkeypatch.setattr(_certify, "refine_clock_offset", to_the_edge)
    monkeypatch.setattr(_certify, "press_clock_offset",
                        lambda *a, **k: (float("nan"), float("nan"), 0))
    forces = np.column_stack([np.zeros_like(fz), np.zeros_like(fz), fz])
    session = SimpleNamespace(config=SimpleNamespace(rate_hz=1000.0, clock_offset_s=None),
                              force_times_s=tf, forces_n=forces, path="session")
    offset, source, _, notes, _ = _certify._sync_clock(session, frames, area, runs, 0.1, None)
    assert len(starts) == _certify.CLOCK_SEARCHES and source == "estimated"
    assert np.isclose(offset, starts[-1] + 0.3)         # the span: 3 periods of 0.1 s
    assert any("do not pin the clock" in n and "clock_offset_s" in n for n in notes)
