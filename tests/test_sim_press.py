"""Height maps of flat-punch presses drawn from the FEM surface."""

from __future__ import annotations

import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.contact import fit_footprint
from tactilevision.sim import press_profile

H_MM, A_MM, S = 3.0, 2.5, 0.05


@pytest.fixture(scope="module")
def profile():
    return press_profile(A_MM / H_MM, 0.48, cell=0.25, edge_refinements=5)


def test_profile_matches_the_fem_nodes(profile):
    k = 5
    w = profile.w_over_h[k]
    r = profile.r[k]
    single = np.r_[True, np.diff(r) > 0] & np.r_[np.diff(r) > 0, True]  # not on the edge's step
    assert single.sum() >= r.size - 2
    np.testing.assert_allclose(profile.depth_at(w, r[single]), profile.depth[k][single],
                               atol=1e-12)
    # footprint flat at w, far field at rest, and a bulge (negative depth) for nu = 0.48
    inside = profile.r[k] < 0.99 * A_MM / H_MM
    np.testing.assert_allclose(profile.depth[k][inside], w, atol=1e-9)
    assert abs(profile.depth_at(w, 15.0)) < 1e-3
    assert profile.depth[k].min() < -0.05 * w
    assert np.all(np.diff(profile.force) > 0)


def test_height_map_and_its_footprint(profile):
    z = profile.height_map((160, 200), S, H_MM, (101.3, 78.6), 0.45)
    assert z.dtype == np.float32 and z.shape == (160, 200)
    assert float(z.max()) == pytest.approx(0.45, abs=1e-6)
    fp = fit_footprint(z, S, indenter_radius_mm=A_MM)
    np.testing.assert_allclose(fp.center_px, [101.3, 78.6], atol=0.3)
    assert fp.radius_mm == pytest.approx(A_MM, rel=0.03) and fp.radius_ok
    assert fp.depth_mm == pytest.approx(0.45, abs=1e-4)


def test_interpolation_between_depths(profile):
    w0, w1 = profile.w_over_h[3], profile.w_over_h[4]
    mid = profile.depth_at(0.5 * (w0 + w1), np.array([0.0]))
    assert mid[0] == pytest.approx(0.5 * (w0 + w1), abs=1e-9)
    with pytest.raises(InputError, match="outside the simulated depths"):
        profile.depth_at(0.5, np.array([0.0]))
