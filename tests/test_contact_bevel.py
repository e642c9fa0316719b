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


def test_footprint_ignores_a_blob_reaching_into_it():
    """A blob of colour change reaching into the footprint from its rim (Taxim draws one
    beside the flat punch, 20 px by 8 px) must not pull the circle in: the plain
    algebraic fit gives a radius 5% short, the trimmed one the true radius."""
    from tactilevision.contact._footprint import _fit_circle

    mask = _ring((240, 320), (150.3, 120.6), 50.0, 70.0)
    rows, cols = np.indices(mask.shape)
    mask |= (np.abs(rows - 118) <= 4) & (cols >= 178) & (cols <= 202)
    fp = footprint_from_frame(mask, 0.05, indenter_radius_mm=2.5)
    np.testing.assert_allclose(fp.center_px, (150.3, 120.6), atol=0.4)
    assert fp.radius_px == pytest.approx(50.0, abs=0.7)
    from scipy import ndimage

    hole = ndimage.binary_fill_holes(mask) & ~mask
    ys, xs = np.nonzero(hole & ~ndimage.binary_erosion(hole))
    plain = _fit_circle(np.column_stack([xs, ys]).astype(float))[2] + 0.5
    assert plain < 0.97 * 50.0


def test_footprint_ignores_specks_inside_it():
    """Specks of colour change inside the flat footprint (a Taxim frame shows a line of
    them across the flat face: the fitted radius came out 2.10 mm for a 2.4 mm footprint,
    and the press was rejected) are islands in the hole: the ring's inner edge is fitted,
    not the specks' outlines."""
    mask = _ring((240, 320), (150.3, 120.6), 50.0, 70.0)
    for x in range(112, 190, 9):                 # a line of 3 x 3 px specks across it
        mask[119:122, x:x + 3] = True
    fp = footprint_from_frame(mask, 0.05, indenter_radius_mm=2.5)
    np.testing.assert_allclose(fp.center_px, (150.3, 120.6), atol=0.3)
    assert fp.radius_px == pytest.approx(50.0, abs=0.7)
    assert fp.radius_ok


def test_footprint_radius_check_and_open_ring():
    mask = _ring((240, 320), (150, 120), 30.0, 45.0)
    fp = footprint_from_frame(mask, 0.05, indenter_radius_mm=2.5)
    assert fp is not None and not fp.radius_ok
    # cut open by the image edge: no enclosed hole
    assert footprint_from_frame(_ring((240, 320), (20, 120), 50.0, 70.0), 0.05,
                                indenter_radius_mm=2.5) is None
    assert footprint_from_frame(np.zeros((50, 50), bool), 0.05, indenter_radius_mm=2.5) is None


def test_bevel_score_on_rendered_presses():
    """A bevel mark (no vernier: the legacy drawn line) before and after the land touches,
    rendered through Taxim's shading and JPEG-compressed as in the sample sessions: the
    line is seen only after; a mark out of the image scores 0, never NaN."""
    pytest.importorskip("taxim")
    import cv2

    from tactilevision.sim import GaugeBlock, press_profile, press_surface, taxim_shading

    table, ref = taxim_shading()
    prof = press_profile(2.5 / 3, 0.48, steps=8, cell=0.5, edge_refinements=5)
    rng = np.random.default_rng(0)
    block = GaugeBlock(bevel_angle_deg=0.0, bevel_offset_mm=4.5, bevel_length_mm=2.4)
    scores = {}
    for depth in (0.29, 0.3003):
        z, touching = press_surface(prof, block, indenter=1, depth_mm=depth,
                                    centre_px=(300.4, 250.2), shape=table.shape,
                                    mm_per_px=table.mm_per_px, thickness_mm=3.0)
        img = table.render(z, ref, noise_dn=2.0, rng=rng)
        img = cv2.imdecode(cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, 75])[1], 1)
        scores[touching] = bevel_score(img, ref, (300.4, 250.2), table.mm_per_px, offset_mm=4.5)
    assert scores[False] < 9.0 < 12.0 < scores[True]
    assert bevel_score(img, ref, (800.0, 250.0), table.mm_per_px, offset_mm=4.5) == 0.0


def test_machined_bevel_meets_the_bulging_gel():
    """The simulator's ridge on the FEM surface: the band's reach on each side is where the
    flank meets the surface (checked on the drawn height map against the truth helper)."""
    pytest.importorskip("taxim")
    from tactilevision.sim import GaugeBlock, press_profile, press_surface

    prof = press_profile(2.5 / 3, 0.48, steps=8, cell=0.5, edge_refinements=5)
    block = GaugeBlock()                        # 5 deg flanks, crest 9 mm out
    s, shape, c = 0.0295, (480, 640), (100.3, 240.0)
    _, touching_free = press_surface(prof, GaugeBlock(bevel_angle_deg=0.0, land="ideal"),
                                          indenter=4, depth_mm=0.55, centre_px=c, shape=shape,
                                          mm_per_px=s, thickness_mm=3.0)
    assert not touching_free                   # 0.55 < w0 = 0.6: no mark
    z, touching = press_surface(prof, block, indenter=4, depth_mm=0.63, centre_px=c,
                                shape=shape, mm_per_px=s, thickness_mm=3.0)
    assert touching
    row = z[240].astype(np.float64)
    crest = c[0] + 9.0 / s
    tan = np.tan(np.deg2rad(5.0))
    overshoot = 0.03
    bulge = -prof.depth_at(0.63 / 3, np.array([3.0]))[0] * 3.0
    assert 0.01 < bulge / 0.63 < 0.03
    # on the crest the gel is pushed to the crest's depth, the overshoot
    assert row[round(crest)] == pytest.approx(overshoot - abs(round(crest) - crest) * s * tan,
                                                   abs=2e-5)
    # the band: where the gel follows the flank; its half-width ~ (overshoot + bulge) / tan
    cols = np.arange(shape[1])
    flank = overshoot - np.abs(cols - crest) * s * tan
    on = np.isclose(row, flank, atol=1e-6) & (np.abs(cols - crest) < 40)
    half = 0.5 * (cols[on].max() - cols[on].min()) * s
    assert half == pytest.approx((overshoot + bulge) / tan, abs=2 * s)


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
