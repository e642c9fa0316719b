"""Simulated press schedules, depth trajectories and F/T logs, checked by the contact module."""

from __future__ import annotations

import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.contact import estimate_clock_offset, force_onsets, force_window
from tactilevision.sim import depth_trajectory, ft_log, press_schedule

DEPTHS = (0.15, 0.30, 0.40, 0.50, 0.60)


def test_schedule_is_shuffled_balanced_and_deterministic():
    s = press_schedule(DEPTHS, seed=4)
    assert s.n_presses == 50 and np.bincount(s.indenter).tolist() == [10] * 5
    assert not np.array_equal(s.indenter, np.sort(s.indenter))          # shuffled
    np.testing.assert_allclose(s.depth_mm, np.array(DEPTHS)[s.indenter])
    assert np.all(np.hypot(s.x_mm, s.y_mm) <= 5.0)
    assert np.all(s.t_start_s[1:] - s.t_end_s[:-1] >= 3.0 - 1e-12)   # waits respected
    np.testing.assert_allclose(s.t_start_s[1:] - s.t_end_s[:-1], s.wait_s[1:])
    again = press_schedule(DEPTHS, seed=4)
    np.testing.assert_array_equal(again.indenter, s.indenter)
    np.testing.assert_array_equal(again.x_mm, s.x_mm)


def test_depth_trajectory_ramps_and_holds():
    s = press_schedule((0.3,), repeats=2, seed=0)
    t0 = s.t_start_s[0]
    d, p = depth_trajectory(s, np.array([t0 - 0.1, t0 + 0.25, t0 + 1.0, t0 + 2.25, t0 + 2.6]))
    np.testing.assert_allclose(d, [0.0, 0.15, 0.3, 0.15, 0.0])
    assert p.tolist() == [-1, 0, 0, 0, -1]


def test_ft_log_forces_onsets_and_windows():
    s = press_schedule(DEPTHS, seed=1)
    k = 8.0  # N/mm: a linear spring for the test
    t, f = ft_log(s, lambda i, d: k * d, duration_s=float(s.t_end_s[-1]) + 1.0,
                  clock_offset_s=0.42, seed=2)
    assert f.shape == (t.size, 3) and t[0] == pytest.approx(0.42)
    np.testing.assert_allclose(np.diff(t), 1e-3, rtol=1e-6)
    # the hold force of each press, from a 200-sample window mid-hold
    for i in (0, 17, 49):
        mid = s.t_start_s[i] + s.approach_s[i] + 0.5 * s.hold_s[i] + 0.42
        win = force_window(t, f, mid, 200)
        assert win.fz_n == pytest.approx(k * s.depth_mm[i], abs=4 / 80 / np.sqrt(200))
        assert win.tangential_ratio == pytest.approx(0.01, abs=0.01)
    # onsets on the F/T clock match the schedule's starts shifted by the offset
    onsets = force_onsets(t, f[:, 2])
    assert onsets.size == s.n_presses
    sync = estimate_clock_offset(s.t_start_s, onsets)
    assert sync.offset_s == pytest.approx(0.42, abs=0.02) and sync.n_matched == 50


def test_bad_schedules():
    with pytest.raises(InputError, match="depths_mm"):
        press_schedule(())
    with pytest.raises(InputError, match="repeats"):
        press_schedule(DEPTHS, repeats=0)
    with pytest.raises(InputError, match="hold_s"):
        press_schedule(DEPTHS, hold_s=0.0)
    with pytest.raises(InputError, match="wait_s"):
        press_schedule(DEPTHS, wait_s=(5.0, 3.0))
