"""The force window of a certified press."""

from __future__ import annotations

import numpy as np
import pytest

from tactilevision import InputError, ShapeError
from tactilevision.contact import force_window


def log(n=2000, seed=0):
    rng = np.random.default_rng(seed)
    t = 10.0 + np.arange(n) / 1000.0
    f = np.stack([0.02 + 0.0 * t, -0.01 + 0.0 * t, 1.5 + 0.1 * (t - 10.0)], axis=1)
    return t, f + rng.normal(0, 1 / 80, f.shape)


def test_window_mean_and_scatter():
    t, f = log()
    win = force_window(t, f, 11.0, 200)
    assert (win.start, win.stop) == (900, 1100)
    # fz ramps 0.1 N/s: the centred mean is the value at 11.0 s; noise 1/80 / sqrt(200)
    assert win.fz_n == pytest.approx(1.6, abs=4 * (1 / 80) / np.sqrt(200))
    assert win.fx_n == pytest.approx(0.02, abs=0.004)
    assert win.fy_n == pytest.approx(-0.01, abs=0.004)
    # scatter: the noise and the ramp across the 0.2 s window (uniform: range / sqrt(12))
    assert win.fz_std_n == pytest.approx(np.hypot(1 / 80, 0.1 * 0.2 / np.sqrt(12)), rel=0.15)
    assert win.tangential_ratio == pytest.approx(np.hypot(win.fx_n, win.fy_n) / win.fz_n)


def test_window_against_a_direct_mean():
    t, f = log(seed=2)
    win = force_window(t, f, 10.5004, 51)
    mid = int(np.argmin(np.abs(t - 10.5004)))
    np.testing.assert_allclose(win.fz_n, f[mid - 25:mid + 26, 2].mean())


@pytest.mark.parametrize(("args", "exc", "match"), [
    ((12.5, 200), InputError, "does not fit in the F/T log"),
    ((10.05, 200), InputError, "does not fit"),
    ((11.0, 1), InputError, "window_samples must be an integer >= 2"),
    ((11.0, 20.5), InputError, "window_samples"),
    ((11.0, 5000), InputError, "more than the 2000 samples"),
])
def test_bad_windows(args, exc, match):
    t, f = log()
    with pytest.raises(exc, match=match):
        force_window(t, f, *args)


def test_bad_arrays():
    t, f = log()
    with pytest.raises(ShapeError, match="forces_n"):
        force_window(t, f[:, :2], 11.0, 10)
    f[5, 2] = np.nan
    with pytest.raises(ShapeError, match="forces_n must be finite"):
        force_window(t, f, 11.0, 10)
