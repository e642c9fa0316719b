"""Footprint from the contact ring, the bevel line, and the clock refined on whole presses."""

from __future__ import annotations

import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.contact import bevel_score, footprint_from_frame, refine_clock_offset


def _ring(shape, centre, r_in, r_out):
    rows, cols = np.indices(shape)
    r = np.hypot(cols - centre[0], rows - centre[1])
    return (r >= r_in) & (r < r_out)


def test_footprint_from_ring():
    mask = _ring((240, 320), (150.3, 120.6), 50.0, 70.0)
    fp = footprint_from_frame(mask, 0.05, indenter_radius_mm=2.5)
    assert fp is not None
    np.testing.assert_allclose(fp.center_px, (150.3, 120.6), atol=0.3)
    assert fp.radius_px == pytest.approx(50.0, abs=0.7)
    assert fp.radius_ok and not fp.cut_by_edge


def test_footprint_radius_check_and_open_ring():
    mask = _ring((240, 320), (150, 120), 30.0, 45.0)
    fp = footprint_from_frame(mask, 0.05, indenter_radius_mm=2.5)
    assert fp is not None and not fp.radius_ok
    # cut open by the image edge: no enclosed hole
    assert footprint_from_frame(_ring((240, 320), (20, 120), 50.0, 70.0), 0.05,
                                indenter_radius_mm=2.5) is None
    assert footprint_from_frame(np.zeros((50, 50), bool), 0.05, indenter_radius_mm=2.5) is None


def test_bevel_score_on_rendered_presses():
    """Taxim-rendered press before and after the land touches: the line is seen
    only after (JPEG-compressed as in the sample session)."""
    pytest.importorskip("taxim")
    import cv2

    from tactilevision.sim import GaugeBlock, press_profile, press_surface, taxim_shading

    table, ref = taxim_shading()
    prof = press_profile(2.5 / 3, 0.48, steps=8, cell=0.5, edge_refinements=5)
    rng = np.random.default_rng(0)
    scores = {}
    for depth in (0.29, 0.3003):
        z, touching = press_surface(prof, GaugeBlock(), indenter=1, depth_mm=depth,
                                    centre_px=(300.4, 250.2), shape=table.shape,
                                    mm_per_px=table.mm_per_px, thickness_mm=3.0)
        img = table.render(z, ref, noise_dn=2.0, rng=rng)
        img = cv2.imdecode(cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, 75])[1], 1)
        scores[touching] = bevel_score(img, ref, (300.4, 250.2), table.mm_per_px, offset_mm=4.5)
    assert scores[False] < 4.0 < 8.0 < scores[True]
    assert np.isnan(bevel_score(img, ref, (620.0, 250.0), table.mm_per_px, offset_mm=4.5))


def test_refine_clock_offset():
    """Presses as trapezoids: contact area from frames at 10 fps, Fz at 1 kHz on a
    clock 0.137 s ahead; an onset estimate a frame early is pulled back."""
    rng = np.random.default_rng(1)
    starts = np.cumsum(rng.uniform(2.0, 3.0, 12))

    def depth(t):
        d = np.zeros_like(t)
        for s in starts:
            u = t - s
            d = np.maximum(d, np.clip(np.minimum(u / 0.5, (1.25 - u) / 0.25), 0, 1))
        return d

    tf = np.arange(0, starts[-1] + 2, 0.1)
    area = 2e4 * depth(tf) ** 0.7
    ft = np.arange(0, starts[-1] + 2, 0.001) + 0.137
    fz = 2.0 * depth(ft - 0.137) ** 1.2 + rng.normal(0, 1 / 80, ft.size)
    off, corr = refine_clock_offset(tf, area, ft, fz, 0.037)
    assert off == pytest.approx(0.137, abs=0.003)
    assert corr > 0.95
    with pytest.raises(InputError, match="constant"):
        refine_clock_offset(tf, np.zeros_like(tf), ft, fz, 0.0)
