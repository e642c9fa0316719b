"""The height map's cap as a cross-check of a ball's depth: the gel's sink-in around the
ball against Hertz's closed form (K. L. Johnson, Contact Mechanics, 1985, eq. 3.42b), and
caps read from height maps whose truth is that closed form."""

from __future__ import annotations

import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.mechanics import Sphere, hertz_surface_depth, sphere_surface_depth
from tactilevision.pipeline import CAP_PRESS_SD, CAP_SCALE_SD, BallDepths, ball_press_caps

R, H, S = 2.0, 100.0, 0.0295          # ball, a thick gel (mm), mm per px
BALL = Sphere(R)


def test_hertz_surface_is_continuous_and_half_the_depth_at_the_edge():
    w = 0.3
    a = np.sqrt(R * w)
    d = hertz_surface_depth(w, np.array([0.0, a * (1 - 1e-9), a, a * (1 + 1e-9), 50 * a]), R)
    assert d[0] == pytest.approx(w)
    assert d[2] == pytest.approx(w / 2, rel=1e-9)
    assert d[1] == pytest.approx(d[3], rel=1e-6)
    assert d[4] == pytest.approx(4 * a**3 / (3 * np.pi * R * 50 * a), rel=0.01)   # 1/r tail


def test_the_fem_sink_in_is_hertzs_on_a_thick_gel():
    """sqrt(R w)/h <= 0.01: the FEM's surface from 1.5 to 3 contact radii, where a cap's
    gel level is read, within 2 % of w of Hertz's; w on the axis."""
    w = np.array([0.2, 0.5])
    a = np.sqrt(R * w)
    rho = np.linspace(1.5, 3.0, 7)
    for k, wk in enumerate(w):
        fem = sphere_surface_depth(BALL, [wk], rho * a[k], nu=0.5, thickness_mm=H)[0]
        hz = hertz_surface_depth(wk, rho * a[k], R)
        assert np.max(np.abs(fem - hz)) < 0.02 * wk, (fem / wk, hz / wk)
    assert sphere_surface_depth(BALL, w, [0.0], nu=0.5, thickness_mm=H)[:, 0] == \
        pytest.approx(w, rel=1e-6)
    with pytest.raises(InputError, match="reach"):
        sphere_surface_depth(BALL, [-0.1], [1.0], nu=0.5, thickness_mm=H)


def _hertz_press(w: float, shape=(240, 320), centre=(160.0, 120.0)):
    """A height map of a press (Hertz's surface on a half-space) and its true circle."""
    yy, xx = np.mgrid[0:shape[0], 0:shape[1]]
    r = np.hypot(xx - centre[0], yy - centre[1]) * S
    height = hertz_surface_depth(w, r.ravel(), R).reshape(shape)
    a = np.sqrt(R * w)
    depths = BallDepths(depth_mm=np.array([w]), depth_std_mm=np.array([0.005]),
                        depth_shared_mm=np.array([0.01]), contact_radius_mm=np.array([a]),
                        centres_px=np.array([centre]), radii_px=np.array([a / S]),
                        dw_da=np.array([2 * w / a]))
    return height, depths


def test_a_caps_depth_carries_the_shared_scale_and_one_presss_own_error():
    """depth_std_mm = hypot(CAP_SCALE_SD, press_sd) x cap / (dcap/dw): with press_sd 0 it
    is the shared scale's alone, and the default (CAP_PRESS_SD, where the calibration
    states none) multiplies it by hypot(1, CAP_PRESS_SD / CAP_SCALE_SD); a press_sd that
    is no number >= 0 is refused."""
    height, depths = _hertz_press(0.3)
    kw = dict(mm_per_px=S, thickness_mm=H)
    scale = ball_press_caps(height[None], depths, BALL, press_sd=0.0, **kw)
    default = ball_press_caps(height[None], depths, BALL, **kw)
    stated = ball_press_caps(height[None], depths, BALL, press_sd=0.031, **kw)
    assert default.press_sd == CAP_PRESS_SD
    assert default.depth_std_mm[0] / scale.depth_std_mm[0] == pytest.approx(
        np.hypot(1.0, CAP_PRESS_SD / CAP_SCALE_SD), rel=1e-9)
    assert stated.depth_std_mm[0] / scale.depth_std_mm[0] == pytest.approx(
        np.hypot(1.0, 0.031 / CAP_SCALE_SD), rel=1e-9)
    np.testing.assert_array_equal(default.depth_mm, scale.depth_mm)
    assert f"one press's cap to +-{200 * np.hypot(CAP_SCALE_SD, 0.031):.0f} %" in \
        stated.summary()
    for bad in (-0.01, float("nan"), "0.05", None, True):
        with pytest.raises(InputError, match="press_sd"):
            ball_press_caps(height[None], depths, BALL, press_sd=bad, **kw)


@pytest.mark.parametrize("w", [0.2, 0.5])
def test_a_true_height_map_reads_the_circles_depth(w):
    """The true surface, any zero: its cap is what the circle's depth predicts (within
    2 %), and read back as a depth within 2 % of w; the same surface 20 % shallow (a
    calibration that does not fit) reads 20 % low, and is said."""
    height, depths = _hertz_press(w)
    caps = ball_press_caps(height[None] - 0.05, depths, BALL, mm_per_px=S, thickness_mm=H)
    assert caps.ratio[0] == pytest.approx(1.0, abs=0.02)
    assert caps.depth_mm[0] == pytest.approx(w, rel=0.02)
    # the scale's 2.5 % and one press's 7.7 % (CAP_PRESS_SD) of the cap, through dw/dcap
    assert 0.05 * w < caps.depth_std_mm[0] < 0.1 * w
    assert caps.expected_mm[0] < 0.9 * w                   # the level has sunk in around it
    low = ball_press_caps(0.8 * height[None], depths, BALL, mm_per_px=S, thickness_mm=H)
    assert low.ratio[0] == pytest.approx(0.8, abs=0.02)
    assert low.depth_mm[0] < 0.85 * w
    assert "-20" in low.summary() or "-19" in low.summary() or "-21" in low.summary()
    with pytest.raises(InputError, match="heights_mm"):
        ball_press_caps(height, depths, BALL, mm_per_px=S, thickness_mm=H)
