"""Absolute-depth metrics and the ball-cap fit: known answers on constructed arrays.

The cap ``z = L + d - (R - sqrt(R^2 - r^2))`` inside the contact and the
metrics' sums are written out here from their definitions; no rendering.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tactilevision import InputError, ShapeError
from tactilevision.optics import (
    AbsoluteDepthMetrics,
    BallCapFit,
    absolute_depth_metrics,
    fit_ball_cap,
)

MM = 0.03


def _cap(shape, centre, depth, radius, level=0.0, mm=MM):
    """A ball of `radius` pressed `depth` mm below a gel at `level` (mm), no sink-in."""
    yy, xx = np.indices(shape, dtype=np.float64)
    r2 = ((xx - centre[0]) ** 2 + (yy - centre[1]) ** 2) * mm * mm
    cap = depth - (radius - np.sqrt(np.maximum(radius * radius - r2, 0.0)))
    a_px = math.sqrt(2 * radius * depth - depth * depth) / mm
    return level + np.maximum(cap, 0.0), a_px


# ------------------------------------------------------------------ fit_ball_cap


def test_cap_recovered_with_offset_level_and_noise():
    rng = np.random.default_rng(3)
    z, a_px = _cap((240, 320), (161.3, 118.6), 0.35, 2.5, level=-0.04)
    z = (z + rng.normal(0.0, 0.002, z.shape)).astype(np.float32)
    fit = fit_ball_cap(z, MM, (158.0, 121.0), a_px)          # centre 4 px off
    assert isinstance(fit, BallCapFit)
    assert fit.gel_level_mm == pytest.approx(-0.04, abs=5e-4)
    assert fit.depth_mm == pytest.approx(0.35, abs=2e-3)
    assert fit.radius_mm == pytest.approx(2.5, rel=0.02)
    assert fit.centre_px == pytest.approx((161.3, 118.6), abs=0.3)
    assert fit.rim_height_mm == pytest.approx(0.0, abs=5e-3)
    assert fit.rms_mm == pytest.approx(0.002, rel=0.1)        # the noise, nothing else
    assert not fit.radius_fixed and fit.n_far_field > 1000
    assert fit.n_pixels == pytest.approx(math.pi * (0.9 * a_px) ** 2, rel=0.02)


def test_cap_radius_fixed_and_exact():
    z, a_px = _cap((200, 200), (100.0, 100.0), 0.2, 2.0, level=0.1)
    fit = fit_ball_cap(z, MM, (100.0, 100.0), a_px, ball_radius_mm=2.0)
    assert fit.radius_fixed and fit.radius_mm == 2.0
    assert fit.depth_mm == pytest.approx(0.2, abs=1e-6)
    assert fit.rms_mm < 1e-6


def test_cap_depth_is_measured_from_the_far_field_not_the_rim():
    # the same cap sunk 0.05 mm into a gel that sinks in around it: d grows by 0.05,
    # the rim lies 0.05 below the gel level
    z, a_px = _cap((200, 200), (100.0, 100.0), 0.2, 2.0)
    yy, xx = np.indices(z.shape)
    inside = (xx - 100.0) ** 2 + (yy - 100.0) ** 2 < a_px**2
    z = np.where(inside, z + 0.05, 0.0)
    fit = fit_ball_cap(z, MM, (100.0, 100.0), a_px)
    assert fit.depth_mm == pytest.approx(0.25, abs=1e-5)
    assert fit.rim_height_mm == pytest.approx(0.05, abs=1e-4)


def test_cap_gel_level_options():
    z, a_px = _cap((200, 200), (100.0, 100.0), 0.2, 2.0, level=0.1)
    assert fit_ball_cap(z, MM, (100, 100), a_px).depth_mm == pytest.approx(0.2, abs=1e-6)
    # the map's own zero: the 0.1 mm offset comes back in d
    zero = fit_ball_cap(z, MM, (100, 100), a_px, gel_level="zero")
    assert zero.gel_level_mm == 0.0 and zero.depth_mm == pytest.approx(0.3, abs=1e-6)
    given = fit_ball_cap(z, MM, (100, 100), a_px, gel_level=0.05)
    assert given.depth_mm == pytest.approx(0.25, abs=1e-6)


def test_far_field_annulus_clipped_to_the_image():
    # contact near a corner: the annulus is mostly outside but what is inside counts
    z, a_px = _cap((120, 160), (20.0, 20.0), 0.1, 2.0, level=0.02)
    fit = fit_ball_cap(z, MM, (20.0, 20.0), a_px)
    assert 0 < fit.n_far_field < math.pi * ((3 * a_px) ** 2 - (1.5 * a_px) ** 2) / 2
    assert fit.gel_level_mm == pytest.approx(0.02, abs=1e-9)


@pytest.mark.parametrize("radius", [0.0, -3.0, float("nan")])
def test_cap_contact_radius_must_be_positive(radius):
    with pytest.raises(InputError, match="contact_radius_px must be positive"):
        fit_ball_cap(np.zeros((50, 50)), MM, (25, 25), radius)


def test_cap_bad_inputs():
    z = np.zeros((50, 50))
    with pytest.raises(ShapeError, match=r"height_mm must have shape \(H, W\)"):
        fit_ball_cap(np.zeros((50, 50, 3)), MM, (25, 25), 10)
    with pytest.raises(ShapeError, match="height_mm must have dtype float"):
        fit_ball_cap(np.zeros((50, 50), np.uint8), MM, (25, 25), 10)
    with pytest.raises(ShapeError, match="height_mm must be finite"):
        fit_ball_cap(np.full((50, 50), np.nan), MM, (25, 25), 10)
    with pytest.raises(ShapeError, match=r"center_px must have shape \(2\)"):
        fit_ball_cap(z, MM, (25, 25, 1), 10)
    with pytest.raises(InputError, match="mm_per_px must be positive"):
        fit_ball_cap(z, 0.0, (25, 25), 10)
    with pytest.raises(InputError, match="ball_radius_mm must be positive"):
        fit_ball_cap(z, MM, (25, 25), 10, ball_radius_mm=-1.0)
    with pytest.raises(InputError, match="gel_level must be 'far_field', 'zero' or a number"):
        fit_ball_cap(z, MM, (25, 25), 10, gel_level="median")
    with pytest.raises(InputError, match="far_field must satisfy 0 < inner < outer"):
        fit_ball_cap(z, MM, (25, 25), 10, far_field=(3.0, 1.5))
    with pytest.raises(InputError, match="fewer than 10"):
        fit_ball_cap(z, MM, (500, 500), 10)                   # disc off the image
    with pytest.raises(InputError, match=r"far-field annulus .* has no pixel"):
        fit_ball_cap(z, MM, (25, 25), 40)                     # annulus beyond the image


# ------------------------------------------------------------------ absolute_depth_metrics


def _punch(shape=(100, 120), centre=(60.0, 50.0), radius=10.0, depth=0.3):
    yy, xx = np.indices(shape, dtype=np.float64)
    r = np.hypot(xx - centre[0], yy - centre[1])
    return np.where(r < radius, depth, 0.0), r


def test_metrics_constant_offset_is_not_removed():
    truth, r = _punch()
    m = absolute_depth_metrics(truth + 0.01, truth, r < 9.0)
    assert isinstance(m, AbsoluteDepthMetrics)
    assert m.true_deepest_mm == pytest.approx(0.3)
    assert m.deepest_error_mm == pytest.approx(0.01)
    assert m.deepest_error_rel == pytest.approx(0.01 / 0.3)
    assert m.profile_mean_mm == pytest.approx(0.01)
    assert m.profile_rms_mm == pytest.approx(0.01)
    assert m.background_mean_mm == pytest.approx(0.01)
    assert m.background_rms_mm == pytest.approx(0.01)
    assert m.background_max_mm == pytest.approx(0.01)


def test_metrics_default_background_is_beyond_one_and_a_half_radii():
    truth, r = _punch()
    contact = r < 10.0
    # the default: farther than 0.5 a_eq from the contact, a_eq = sqrt(area / pi): for a
    # disc, beyond 1.5 a_eq from its centre (to a pixel)
    a_eq = math.sqrt(contact.sum() / math.pi)
    near = ~contact & (r < 1.5 * a_eq - 1.5)
    height = np.where(contact, truth, np.where(near, 0.5, 0.02))
    m = absolute_depth_metrics(height, truth, contact)
    assert m.background_rms_mm == pytest.approx(0.02)           # nothing of the near ring
    assert m.background_max_mm == pytest.approx(0.02)
    assert int((r > 1.5 * a_eq + 1.5).sum()) <= m.n_background <= int((~contact & ~near).sum())


def test_metrics_known_numbers():
    truth, r = _punch(depth=0.2)
    contact = r < 9.0
    height = truth.copy()
    height[contact] = np.where(np.arange(contact.sum()) % 2 == 0, 0.23, 0.17)  # +-0.03
    height[50, 60] = 0.26                                       # the deepest point
    bg = np.zeros_like(truth, bool)
    bg[:5, :] = True
    height[:5, :] = np.linspace(-0.04, 0.02, 120)               # a tilt along the top rows
    m = absolute_depth_metrics(height, truth, contact, background_mask=bg)
    err = height[contact] - 0.2
    assert m.deepest_mm == pytest.approx(0.26)
    assert m.deepest_error_mm == pytest.approx(0.06)
    assert m.deepest_error_rel == pytest.approx(0.3)
    assert m.profile_rms_mm == pytest.approx(math.sqrt(np.mean(err**2)))
    assert m.profile_mean_mm == pytest.approx(err.mean())
    assert m.background_mean_mm == pytest.approx(-0.01)
    assert m.background_max_mm == pytest.approx(0.04)
    assert m.n_background == 600 and m.n_contact == int(contact.sum())


def test_metrics_too_shallow_is_negative():
    truth, r = _punch(depth=0.4)
    m = absolute_depth_metrics(0.5 * truth, truth, r < 9.0)
    assert m.deepest_error_mm == pytest.approx(-0.2)
    assert m.deepest_error_rel == pytest.approx(-0.5)
    assert m.profile_mean_mm == pytest.approx(-0.2) and m.background_rms_mm == 0.0


def test_metrics_zero_truth_has_no_relative_error():
    truth = np.zeros((40, 40))
    contact = np.zeros((40, 40), bool)
    contact[18:22, 18:22] = True
    m = absolute_depth_metrics(truth + 0.1, truth, contact)
    assert m.deepest_error_mm == pytest.approx(0.1) and math.isnan(m.deepest_error_rel)


def test_metrics_bad_inputs():
    truth, r = _punch()
    contact = r < 9.0
    with pytest.raises(ShapeError,
                       match=r"truth_mm must have shape \(100, 120\), got \(100, 119\)"):
        absolute_depth_metrics(truth, truth[:, :-1], contact)
    with pytest.raises(ShapeError, match="contact_mask must have shape"):
        absolute_depth_metrics(truth, truth, contact[:-1])
    with pytest.raises(ShapeError, match="contact_mask must have dtype bool"):
        absolute_depth_metrics(truth, truth, contact.astype(np.uint8))
    with pytest.raises(InputError, match="contact_mask selects no pixel"):
        absolute_depth_metrics(truth, truth, np.zeros_like(contact))
    with pytest.raises(InputError, match="background_mask selects no pixel"):
        absolute_depth_metrics(truth, truth, contact, background_mask=np.zeros_like(contact))
    with pytest.raises(ShapeError, match="height_mm must be finite"):
        absolute_depth_metrics(np.where(contact, np.nan, 0.0), truth, contact)
    with pytest.raises(InputError, match="no background pixel"):
        everywhere = np.ones_like(contact)
        absolute_depth_metrics(truth, truth, everywhere)
