"""Where the bulging gel meets the gauge-block land, and the certified-depth rules."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.contact import bulge_height, certified_depths, land_contact_depth
from tactilevision.sim import press_profile


@dataclass
class FlatProfile:
    """A gel that does not bulge: depth w inside r < a, 0 outside."""

    a_over_h: float = 0.8
    w_over_h: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.25]))

    def depth_at(self, w, r):
        return np.where(np.asarray(r) < self.a_over_h, w, 0.0)


@dataclass
class LinearBulge:
    """A bulge of crest k w at r = 2a (known answer: w_c = w0 / (1 + k))."""

    k: float = 0.1
    a_over_h: float = 0.8
    w_over_h: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.25]))

    def depth_at(self, w, r):
        r = np.asarray(r)
        return np.where(r < self.a_over_h, w, -self.k * w * np.exp(-((r - 1.6) / 0.3) ** 2))


def test_no_bulge_certifies_w0():
    assert land_contact_depth(0.1, FlatProfile()) == 0.1


def test_known_bulge():
    assert land_contact_depth(0.2, LinearBulge(0.1)) == pytest.approx(0.2 / 1.1, rel=1e-5)
    h, r = bulge_height(LinearBulge(0.1), 0.2)
    assert h == pytest.approx(0.02, rel=1e-4) and r == pytest.approx(1.6, abs=0.01)


@pytest.fixture(scope="module")
def fem_profiles():
    return {nu: press_profile(2.5 / 3, nu, steps=8, cell=0.5, edge_refinements=5)
            for nu in (0.45, 0.49)}


def test_fem_bulge(fem_profiles):
    """On the FEM surface w_c + crest(w_c) = w0, and the crest is 7-13% of w,
    growing with nu (the more incompressible gel bulges more)."""
    wc = {}
    for nu, prof in fem_profiles.items():
        wc[nu] = land_contact_depth(0.2, prof)
        crest, r = bulge_height(prof, wc[nu])
        assert wc[nu] + crest == pytest.approx(0.2, abs=1e-7)
        assert 1.3 < r < 1.8
    assert 0.2 / 1.14 < wc[0.49] < wc[0.45] < 0.2 / 1.06


def test_certified_depth_rules():
    w0 = np.array([0.15, 0.3, 0.15])
    np.testing.assert_array_equal(certified_depths(w0, rule="nominal", thickness_mm=3,
                                                   radius_mm=2.5), w0)
    land = certified_depths(w0, rule="land", thickness_mm=3, radius_mm=2.5, nu=0.48)
    assert land[0] == land[2]
    assert np.all(land < w0) and np.all(land > 0.85 * w0)
    with pytest.raises(InputError, match="needs nu"):
        certified_depths(w0, rule="land", thickness_mm=3, radius_mm=2.5)
    with pytest.raises(InputError, match="rule"):
        certified_depths(w0, rule="paper", thickness_mm=3, radius_mm=2.5)
    with pytest.raises(InputError, match="w0/h"):
        land_contact_depth(0.5, FlatProfile())
