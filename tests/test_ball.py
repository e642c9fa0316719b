"""Ball-press geometry: gradient labels, normals, metrics and centre fit."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tactilevision import ShapeError
from tactilevision.optics import (
    ball_gradients,
    ball_press_metrics,
    fit_ball_centre,
    gradients_from_normals,
    normals_from_gradients,
)

SHAPE = (90, 110)
CENTRE = (52.3, 44.8)
CONTACT = 24.0
BALL = 40.0


def sphere_height(shape, centre, ball_radius, offset=0.0):
    """sqrt(R^2 - r^2) + offset on the whole grid (NaN outside the ball)."""
    h, w = shape
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    r2 = (x - centre[0]) ** 2 + (y - centre[1]) ** 2
    with np.errstate(invalid="ignore"):
        return np.sqrt(ball_radius**2 - r2) + offset


def test_ball_gradients_match_finite_differences():
    gx, gy, inside = ball_gradients(SHAPE, CENTRE, CONTACT, BALL)
    assert gx.dtype == np.float32 and gy.dtype == np.float32
    assert gx.shape == SHAPE and inside.shape == SHAPE
    # central differences (step 1e-4 px) of the analytic depth sqrt(R^2 - r^2)
    yy, xx = np.nonzero(inside)
    eps = 1e-4

    def depth(x, y):
        return np.sqrt(BALL**2 - (x - CENTRE[0]) ** 2 - (y - CENTRE[1]) ** 2)

    fdx = (depth(xx + eps, yy) - depth(xx - eps, yy)) / (2 * eps)
    fdy = (depth(xx, yy + eps) - depth(xx, yy - eps)) / (2 * eps)
    # float32 gradients of magnitude <= 0.75: a few ulp
    np.testing.assert_allclose(gx[inside], fdx, atol=1e-5)
    np.testing.assert_allclose(gy[inside], fdy, atol=1e-5)
    # depth decreases away from the centre: right of it d/dx < 0
    assert np.all(gx[inside & (np.arange(SHAPE[1])[None, :] > CENTRE[0] + 1)] < 0)
    assert np.all(gx[~inside] == 0) and np.all(gy[~inside] == 0)


def test_ball_gradients_disc():
    _, _, inside = ball_gradients(SHAPE, CENTRE, CONTACT, BALL)
    yy, xx = np.mgrid[0:SHAPE[0], 0:SHAPE[1]]
    want = (xx - CENTRE[0]) ** 2 + (yy - CENTRE[1]) ** 2 < CONTACT**2
    assert np.array_equal(inside, want)
    # pixel count ~ pi a^2 (within the perimeter, 2 pi a)
    assert abs(inside.sum() - np.pi * CONTACT**2) < 2 * np.pi * CONTACT


@pytest.mark.parametrize("contact", [0.0, BALL, BALL + 1])
def test_ball_gradients_reject_contact_not_inside_ball(contact):
    with pytest.raises(ValueError, match="contact radius"):
        ball_gradients(SHAPE, CENTRE, contact, BALL)


@settings(max_examples=60, deadline=None)
@given(st.floats(-4, 4), st.floats(-4, 4))
def test_normals_gradients_round_trip(gx, gy):
    n = normals_from_gradients(np.float32(gx), np.float32(gy))
    assert n.shape == (3,)
    assert np.linalg.norm(n) == pytest.approx(1.0, abs=1e-6)
    assert n[2] > 0  # towards the camera
    rx, ry = gradients_from_normals(n[0], n[1])
    # nz >= 1/sqrt(33) here; float32 relative precision of the round trip ~1e-6 * (1 + |g|^2)
    tol = 1e-5 * (1 + gx * gx + gy * gy)
    assert float(rx) == pytest.approx(gx, abs=tol)
    assert float(ry) == pytest.approx(gy, abs=tol)


def test_normals_shape_and_convention():
    gx = np.array([[0.0, 1.0], [0.0, -2.0]], np.float32)
    gy = np.array([[0.0, 0.0], [1.0, 0.0]], np.float32)
    n = normals_from_gradients(gx, gy)
    assert n.shape == (2, 2, 3) and n.dtype == np.float32
    np.testing.assert_allclose(n[0, 0], [0, 0, 1])
    np.testing.assert_allclose(n[0, 1], np.array([-1, 0, 1]) / np.sqrt(2), rtol=1e-6)
    np.testing.assert_allclose(n[1, 0], np.array([0, -1, 1]) / np.sqrt(2), rtol=1e-6)
    np.testing.assert_allclose(n[1, 1], np.array([2, 0, 1]) / np.sqrt(5), rtol=1e-6)


def test_gradients_from_normals_cap():
    nx = np.array([1.0, 1.2, 0.8, 0.0], np.float32)
    ny = np.array([0.0, 0.0, 0.8, -1.1], np.float32)
    gx, gy = gradients_from_normals(nx, ny, max_slope=6.0)
    assert np.all(np.hypot(gx, gy) <= 6.0 * (1 + 1e-5))


def test_gradients_from_normals_saturate_finite():
    # the part that holds: an over-long (noisy) normal gives a finite, steep
    # gradient pointing against it
    gx, gy = gradients_from_normals(np.array([1.5], np.float32), np.array([0.0], np.float32))
    assert np.isfinite(gx).all() and gx[0] < -5.0 and gy[0] == 0.0


def perfect_reconstruction(offset=3.7, shift=(0.0, 0.0)):
    """Gradients and height of a ball whose centre is CENTRE + shift."""
    c = (CENTRE[0] + shift[0], CENTRE[1] + shift[1])
    gx, gy, _ = ball_gradients(SHAPE, c, CONTACT + np.hypot(*shift) + 1, BALL)
    height = np.nan_to_num(sphere_height(SHAPE, c, BALL, offset)).astype(np.float32)
    return gx, gy, height


def test_metrics_of_perfect_reconstruction():
    gx, gy, height = perfect_reconstruction()
    m = ball_press_metrics(gx, gy, height, CENTRE, CONTACT, BALL)
    # float32 inputs: arccos of a dot product within ~1e-7 of 1 is < 0.05 deg
    assert m.normal_angle_deg < 0.05
    assert m.shape_rms_px < 1e-3  # the offset 3.7 is removed
    assert m.fitted_radius_px == pytest.approx(BALL, rel=1e-3)
    assert m.shape_rms_placed_px < 1e-3
    _, _, inside = ball_gradients(SHAPE, CENTRE, CONTACT, BALL)
    assert m.n_pixels == int(inside.sum())


def test_metrics_with_shifted_truth():
    # the reconstruction is the ball at CENTRE + d; the given centre is CENTRE
    d = (2.5, -1.5)
    gx, gy, height = perfect_reconstruction(offset=-1.0, shift=d)
    m = ball_press_metrics(gx, gy, height, CENTRE, CONTACT, BALL)
    # predicted shape error: RMS of the (mean-removed) difference between the
    # shifted and the unshifted sphere over the evaluated disc
    yy, xx = np.mgrid[0:SHAPE[0], 0:SHAPE[1]].astype(np.float64)
    disc = (xx - CENTRE[0]) ** 2 + (yy - CENTRE[1]) ** 2 < CONTACT**2
    diff = (sphere_height(SHAPE, (CENTRE[0] + d[0], CENTRE[1] + d[1]), BALL)
            - sphere_height(SHAPE, CENTRE, BALL))[disc]
    predicted = np.sqrt(np.mean((diff - diff.mean()) ** 2))
    assert predicted > 1.0  # the shift is visible
    assert m.shape_rms_px == pytest.approx(predicted, rel=0.01)
    # placing the ball by least squares removes the centre error entirely
    assert m.shape_rms_placed_px < 1e-3
    assert m.fitted_radius_px == pytest.approx(BALL, rel=1e-3)
    # normals are compared at the given centre, so they differ too
    assert m.normal_angle_deg > 1.0


def test_metrics_fitted_radius_of_wrong_ball():
    # a reconstruction of a 50 px ball evaluated as a 40 px ball
    gx, gy, _ = ball_gradients(SHAPE, CENTRE, CONTACT, 50.0)
    height = np.nan_to_num(sphere_height(SHAPE, CENTRE, 50.0)).astype(np.float32)
    m = ball_press_metrics(gx, gy, height, CENTRE, CONTACT, BALL)
    assert m.fitted_radius_px == pytest.approx(50.0, rel=1e-3)
    assert m.shape_rms_placed_px > 0.1


def test_metrics_shapes_checked():
    g = np.zeros(SHAPE, np.float32)
    with pytest.raises(ShapeError, match="gy"):
        ball_press_metrics(g, np.zeros((10, 10), np.float32), g, CENTRE, CONTACT, BALL)
    with pytest.raises(ShapeError, match="height_px"):
        ball_press_metrics(g, g, g[:-1], CENTRE, CONTACT, BALL)


@pytest.mark.parametrize("noise", [0.0, 0.02])
def test_fit_ball_centre_recovers_shift(noise):
    true = (CENTRE[0] + 3.0, CENTRE[1] - 2.0)
    gx, gy, _ = ball_gradients(SHAPE, true, CONTACT, BALL)
    rng = np.random.default_rng(0)
    gx = gx + rng.normal(0, noise, SHAPE).astype(np.float32)
    gy = gy + rng.normal(0, noise, SHAPE).astype(np.float32)
    c = fit_ball_centre(gx, gy, CENTRE, CONTACT, BALL)
    assert c.shape == (2,)
    # noise 0.02 on ~1000 pixels whose gradient changes by ~1/sqrt(R^2-r^2)
    # per px of centre shift: standard error ~0.02 * 35 / sqrt(1000) ~ 0.02 px
    np.testing.assert_allclose(c, true, atol=0.01 + 5 * noise)
