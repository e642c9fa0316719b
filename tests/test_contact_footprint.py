"""Footprint of a flat punch in a height map: circle, depth, edge cut, indenter."""

from __future__ import annotations

import numpy as np
import pytest

from tactilevision import InputError, ShapeError
from tactilevision.contact import fit_footprint, nearest_indenter

A_MM, S = 2.5, 0.05  # indenter radius, mm per px (a = 50 px)


def punch_map(w=0.3, center=(100.0, 80.0), shape=(160, 200), noise=0.003, seed=0):
    """Height map of a flat punch on an elastic half-space: w inside r < a,
    (2 w / pi) arcsin(a / r) outside (Johnson, Contact Mechanics, eq. 3.38)."""
    rows, cols = np.indices(shape)
    r = np.hypot(cols - center[0], rows - center[1]) * S
    z = np.where(r <= A_MM, w, 2 * w / np.pi * np.arcsin(np.minimum(A_MM / np.maximum(r, 1e-9),
                                                                     1.0)))
    return z + np.random.default_rng(seed).normal(0, noise, shape)


def test_circle_depth_and_radius():
    fp = fit_footprint(punch_map(), S, indenter_radius_mm=A_MM)
    np.testing.assert_allclose(fp.center_px, [100.0, 80.0], atol=0.3)
    # the 0.9 threshold sits where (2/pi) arcsin(a/r) = 0.9: r = 1.0125 a
    assert fp.radius_mm == pytest.approx(1.0125 * A_MM, abs=S)
    assert fp.depth_mm == pytest.approx(0.3, abs=0.002)
    assert fp.radius_ok and not fp.cut_by_edge and fp.fit_rms_px < 1.0
    assert fp.n_edge_points > 200


def test_off_centre_subpixel_and_cut_by_edge():
    fp = fit_footprint(punch_map(w=0.15, center=(61.3, 70.6)), S, indenter_radius_mm=A_MM)
    np.testing.assert_allclose(fp.center_px, [61.3, 70.6], atol=0.3)
    assert not fp.cut_by_edge
    cut = fit_footprint(punch_map(center=(30.0, 80.0)), S, indenter_radius_mm=A_MM)
    assert cut.cut_by_edge


def test_wrong_indenter_radius_is_flagged():
    fp = fit_footprint(punch_map(), S, indenter_radius_mm=2.0)
    assert not fp.radius_ok


def test_nearest_indenter():
    depths = (0.15, 0.30, 0.40, 0.50, 0.60)
    assert [nearest_indenter(d, depths) for d in (0.12, 0.33, 0.44, 0.46, 0.9)] == [0, 1, 2, 3, 4]
    with pytest.raises(InputError):
        nearest_indenter(0.3, ())


def test_bad_input():
    with pytest.raises(InputError, match="no indentation"):
        fit_footprint(np.zeros((50, 50)), S, indenter_radius_mm=A_MM)
    with pytest.raises(ShapeError, match="height_mm"):
        fit_footprint(np.zeros((2, 50, 50)), S, indenter_radius_mm=A_MM)
    with pytest.raises(InputError, match="mm_per_px"):
        fit_footprint(punch_map(), 0.0, indenter_radius_mm=A_MM)
    z = np.zeros((12, 12))
    z[5:7, 4:7] = 1.0
    with pytest.raises(InputError, match="too small to fit a circle"):
        fit_footprint(z, S, indenter_radius_mm=A_MM)
