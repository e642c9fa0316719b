"""The default ``forces`` path's solves on the contact's bounding box against the
solvers they replace, on the sample session's frames (issue 85 item 1).

The contact-pinned height (:func:`integrate_poisson_masked`: conjugate gradients on
the mask's bounding box, warm-started from the previous frame) against the sparse
direct solve (``method='direct'``), and the 'footprint' force map (its solve on the
footprint's bounding box, warm-started) against the padded whole-image solve
(``_Spectral.box = False``), both fed the direct solve's heights: the total force
within 0.5 % and the pressure map within 1 % of its peak. End to end (the new heights
through the new solve against the old through the old), the totals within 0.5 % but for
the force of pixels whose height lies within the heights' agreement (1e-4 of their peak)
of the footprint's threshold: such a pixel falls on either side of it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tactilevision.fem import ForceEstimator
from tactilevision.io import read_session
from tactilevision.optics import (
    DepthReconstructor,
    PhotometricCalibration,
    integrate_poisson_masked,
)

SESSION = Path(__file__).resolve().parents[1] / "sample_frames" / "gelsight_session"

#: Frames: a deep press reaching the image's bottom and left edges (40: the box's
#: transforms mirrored on those sides) and the frame after it (warm-started), a
#: shallow contact of 2 mN (90) and a frame without contact (0).
FRAMES = (40, 41, 90, 0)


@pytest.fixture(scope="module")
def maps():
    s = read_session(SESSION)
    cal = PhotometricCalibration.load(SESSION / "optics.npz")
    mm = s.config.mm_per_px
    recon = DepthReconstructor(cal, reference=s.reference, boundary="contact")
    kw = dict(thickness_mm=s.config.gel_thickness_mm, E_mpa=0.2, nu=0.48,
              contact="footprint", threshold_mm=0.02, beta=0.82)
    new, old = ForceEstimator(cal.shape, mm, **kw), ForceEstimator(cal.shape, mm, **kw)
    same = ForceEstimator(cal.shape, mm, **kw)        # the new solve on the old heights
    old._op.box = False
    out = []
    for i in FRAMES:
        frame = s.frame(i)
        h_new = recon(frame)
        gx, gy = recon.gradients(frame)
        mask = recon.contact_mask(frame, threshold="frame", fill_holes=True)
        h_old = integrate_poisson_masked(gx, gy, mask, method="direct") * np.float32(
            cal.mm_per_px)
        out.append((i, h_new, h_old, same(h_old), old(h_old), new(h_new)))
    return out


@pytest.mark.slow
def test_contact_pinned_height_matches_the_direct_solve(maps):
    for i, h_new, h_old, *_ in maps:
        peak = float(np.abs(h_old).max())
        assert np.all((h_new == 0) == (h_old == 0)), i
        assert np.abs(h_new - h_old).max() <= 1e-4 * max(peak, 1e-6), i


def test_footprint_force_map_matches_the_padded_solve(maps):
    loaded = 0
    for i, _, _, f_new, f_old, _ in maps:
        fz_old = float(f_old.total_n[2])
        if fz_old < 1e-3:                       # no contact: nothing either way
            assert abs(float(f_new.total_n[2])) < 1e-6, i
            continue
        loaded += 1
        assert float(f_new.total_n[2]) == pytest.approx(fz_old, rel=5e-3), i
        peak = float(f_old.pressure_kpa.max())
        assert np.abs(f_new.pressure_kpa - f_old.pressure_kpa).max() <= 0.01 * peak, i
        assert f_new.forces_n.dtype == f_old.forces_n.dtype
        # the footprints agree but for a rim pixel or two at the tensile cut
        assert np.count_nonzero(f_new.contact != f_old.contact) <= 0.001 * f_old.contact.sum()
    assert loaded == 3


@pytest.mark.parametrize("rows, cols", [((10, 40), (15, 60)),     # inside: sine on both axes
                                        ((0, 40), (15, 80)),      # top and right edges
                                        ((20, 64), (0, 50)),      # bottom and left edges
                                        ((0, 64), (5, 70))])      # top to bottom
def test_masked_cg_matches_the_direct_solve_at_every_border(rows, cols):
    rng = np.random.default_rng(3)
    gx, gy = rng.normal(size=(2, 64, 80)).astype(np.float32)
    mask = np.zeros((64, 80), bool)
    mask[rows[0]:rows[1], cols[0]:cols[1]] = True
    mask[rows[0] + 3:rows[0] + 6, cols[0] + 2:cols[0] + 9] = False      # a pinned island
    direct = integrate_poisson_masked(gx, gy, mask, method="direct")
    cg = integrate_poisson_masked(gx, gy, mask)
    peak = float(np.abs(direct).max())
    assert np.abs(cg - direct).max() <= 1e-5 * peak
    assert not cg[~mask].any()
    # a first guess far off is not used; a batch starts each frame from the one before
    warm = integrate_poisson_masked(gx, gy, mask, z0=np.full((64, 80), 1e6, np.float32))
    assert np.abs(warm - direct).max() <= 1e-5 * peak
    batch = integrate_poisson_masked(np.stack([gx, gx]), np.stack([gy, gy]),
                                     np.stack([mask, mask]))
    assert np.abs(batch - direct).max() <= 1e-5 * peak


@pytest.mark.parametrize("shape", [(9, 1), (1, 9), (1, 1)])
def test_a_footprint_one_pixel_wide_is_solved_on_its_box(shape):
    """A footprint one pixel wide or tall (a thin ridge's edge, the first frame of a
    contact): the box's FFT grid is kept at least 2 x 2 (OpenCV's dft refuses a single
    column with nonzeroRows), and the force equals the padded solve's."""
    kw = dict(thickness_mm=3.0, E_mpa=0.2, nu=0.48, contact="footprint",
              threshold_mm=0.01, beta=0.82)
    new, old = ForceEstimator((40, 50), 0.05, **kw), ForceEstimator((40, 50), 0.05, **kw)
    old._op.box = False
    h = np.zeros((40, 50), np.float32)
    h[20:20 + shape[0], 25:25 + shape[1]] = 0.03
    f_new, f_old = new(h), old(h)
    assert float(f_old.total_n[2]) > 0
    assert float(f_new.total_n[2]) == pytest.approx(float(f_old.total_n[2]), rel=5e-3)


def test_masked_cg_solves_separate_regions_each_on_its_own_box():
    """A press and specks of colour change far from it (the sample session's stripe of
    glare): each 4-connected region is its own problem, solved on its own box, and the
    height equals the direct solve of the whole mask."""
    rng = np.random.default_rng(5)
    gx, gy = rng.normal(size=(2, 96, 160)).astype(np.float32)
    yy, xx = np.mgrid[:96, :160]
    mask = np.hypot(yy - 48, xx - 35) < 25                  # the press
    mask |= (np.abs(xx - 130) < 3) & (np.abs(yy - 30) < 12)  # a stripe far to the right
    mask[80:84, 120:124] = True                             # a speck
    direct = integrate_poisson_masked(gx, gy, mask, method="direct")
    cg = integrate_poisson_masked(gx, gy, mask)
    peak = float(np.abs(direct).max())
    assert np.abs(cg - direct).max() <= 1e-5 * peak
    assert not cg[~mask].any()
    assert np.all(cg[80:84, 120:124] != 0)                  # the speck is solved too


def test_the_solve_log_counts_the_tensile_pixels_each_sweep_drops():
    """A flat punch's face inside a footprint that also takes in a shallow ring around
    it (just above the threshold, where the face's pressure would push the gel deeper):
    held there the ring pulls, so sweeps drop it; the pixels the log says were dropped, less
    those taken back, are the footprint less the contact the map keeps, each sweep that
    drops pixels ran iterations, and the last sweep changes nothing."""
    est = ForceEstimator((60, 60), 0.05, thickness_mm=3.0, E_mpa=0.2, nu=0.48,
                         contact="footprint", threshold_mm=0.01)
    yy, xx = np.mgrid[:60, :60]
    r = np.hypot(yy - 30, xx - 30) * 0.05
    h = np.where(r < 0.5, 0.05, 0.012 * (r < 1.0)).astype(np.float32)
    est._op.solve_log = log = []
    fm = est(h)
    assert len(log) == 1 and len(log[0]) >= 2
    dropped = sum(d for _, d, _ in log[0])
    taken = sum(b for _, _, b in log[0])
    assert log[0][-1][1:] == (0, 0) and dropped > 0
    assert dropped - taken == int((h > 0.01).sum()) - int(fm.contact.sum())
    # a sweep that drops pixels solved since the set last changed (a loose sweep may end
    # at once: the residual already under its tolerance)
    assert all(it >= 1 for it, d, _ in log[0] if d > 0)


def test_the_answer_does_not_depend_on_the_frame_before():
    """The footprint problem has one answer (the Signorini conditions): a deep press solved
    after a shallow one (its smaller contact the first guess, so the solve must take
    pixels back) equals the same press solved cold, and both keep the contact where the
    pressure pushes and the model's surface off the rest."""
    kw = dict(thickness_mm=3.0, E_mpa=0.2, nu=0.48, contact="footprint", threshold_mm=0.01)
    yy, xx = np.mgrid[:80, :80]
    r2 = ((yy - 40.0) ** 2 + (xx - 40.0) ** 2) * 0.05**2
    shallow = np.maximum(0.03 - r2 / (2 * 4.0), 0).astype(np.float32)
    deep = np.maximum(0.12 - r2 / (2 * 4.0), 0).astype(np.float32)
    warm = ForceEstimator((80, 80), 0.05, **kw)
    warm(shallow)
    warm._op.solve_log = log = []
    after = warm(deep)
    cold = ForceEstimator((80, 80), 0.05, **kw)(deep)
    assert sum(b for _, _, b in log[0]) > 0                  # pixels were taken back
    peak = float(cold.pressure_kpa.max())
    assert np.abs(after.pressure_kpa - cold.pressure_kpa).max() <= 1e-3 * peak
    assert float(after.total_n[2]) == pytest.approx(float(cold.total_n[2]), rel=1e-4)
    assert np.count_nonzero(after.contact != cold.contact) <= 4


def test_the_default_path_end_to_end_matches_the_solvers_before(maps):
    """The new heights through the new solve against the old heights through the old: the
    totals within 0.5 %, plus the force of the pixels whose old height lies within 1e-4 of
    the heights' peak of the 0.02 mm threshold (frame 90, a 2 mN contact of 52 pixels: one
    at 0.0200001 mm, in or out as the heights' last digits fall)."""
    for i, _, h_old, _, f_old, f_end in maps:
        fz_old = float(f_old.total_n[2])
        if fz_old < 1e-3:
            assert abs(float(f_end.total_n[2])) < 1e-6, i
            continue
        undecided = np.abs(h_old - 0.02) <= 1e-4 * float(np.abs(h_old).max())
        either = float(f_old.forces_n[..., 2][undecided].sum())
        assert abs(float(f_end.total_n[2]) - fz_old) <= 5e-3 * fz_old + either, i
        if not undecided.any():
            assert np.array_equal(f_end.contact, f_old.contact) or np.count_nonzero(
                f_end.contact != f_old.contact) <= 0.001 * f_old.contact.sum(), i
