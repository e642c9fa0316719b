"""The footprint solve on blocks of pixels (``ForceEstimator(binning=...)``): a flat
punch's total against every pixel's, sharp and blurred edges, two pixel sizes; the block
size 'auto' picks; the maps' shape and support; bad values refused."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage as ndi

from tactilevision import InputError
from tactilevision.fem import ForceEstimator, auto_binning
from tactilevision.io import read_session
from tactilevision.optics import DepthReconstructor, PhotometricCalibration

A, H, NU, E, W = 2.5, 3.0, 0.45, 0.2, 0.05     # mm, mm, -, MPa, mm


def _punch(dx: float, n: int, blur_px: float) -> np.ndarray:
    yy, xx = np.indices((n, n))
    r = np.hypot(xx - (n - 1) / 2, yy - (n - 1) / 2) * dx
    u = np.where(r <= A, W, 0.0)
    return (ndi.gaussian_filter(u, blur_px) if blur_px else u).astype(np.float32)


@pytest.mark.parametrize(("dx", "n"), [(0.05, 360), (0.03, 600)])
@pytest.mark.parametrize("blur_px", [0.0, 1.5])
def test_auto_blocks_keep_a_flat_punchs_total_within_half_a_percent(dx, n, blur_px):
    u = _punch(dx, n, blur_px)
    kw = dict(thickness_mm=H, E_mpa=E, nu=NU, threshold_mm=W / 2)
    every = ForceEstimator((n, n), dx, binning=1, **kw)(u)
    auto = ForceEstimator((n, n), dx, **kw)(u)
    assert auto.total_n[2] == pytest.approx(every.total_n[2], rel=0.005)
    # the blocks 'auto' took: the punch's radius over 20, in pixels
    assert auto_binning(every.contact) == int(A / dx / 20)
    assert auto.forces_n.shape == every.forces_n.shape == (n, n, 3)
    assert auto.pressure_kpa.shape == (n, n) and auto.pressure_kpa.min() >= 0
    assert not np.any(auto.forces_n[..., 2][u <= W / 2])      # only on the footprint


def test_blocks_too_large_for_the_footprint_lose_force():
    """The rule's reason: blocks of a / 8 read a sharp punch several per cent low."""
    u = _punch(0.05, 360, 0.0)
    kw = dict(thickness_mm=H, E_mpa=E, nu=NU, threshold_mm=W / 2)
    every = ForceEstimator((360, 360), 0.05, binning=1, **kw)(u).total_n[2]
    coarse = ForceEstimator((360, 360), 0.05, binning=6, **kw)(u).total_n[2]
    assert coarse / every - 1 < -0.02


def test_auto_binning_reads_the_footprints_width():
    yy, xx = np.indices((400, 400))
    disc = np.hypot(xx - 200, yy - 200) <= 100          # radius 100 px
    assert auto_binning(disc) == 5
    strip = np.zeros((400, 400), bool)
    strip[:, 190:210] = True                            # 20 px wide: half-width 10
    assert auto_binning(strip) == 1
    assert auto_binning(np.zeros((10, 10), bool)) == 1
    big = np.ones((2000, 2000), bool)
    assert auto_binning(big) == 8                       # at most 8


def test_a_batch_and_a_float64_map_bin_as_single_frames():
    u = _punch(0.05, 240, 1.0)
    est = ForceEstimator((240, 240), 0.05, thickness_mm=H, E_mpa=E, nu=NU, threshold_mm=W / 2)
    one = est(u).total_n[2]
    batch = est(np.stack([u, 2 * u])).total_n[:, 2]
    assert batch[0] == pytest.approx(one, rel=1e-4)
    assert batch[1] == pytest.approx(2 * one, rel=0.01)
    assert est(u.astype(np.float64)).total_n[2] == pytest.approx(one, rel=1e-4)


@pytest.mark.parametrize("bad", [0, -2, 2.5, "fine", True])
def test_bad_binning_is_refused(bad):
    with pytest.raises(InputError, match="binning"):
        ForceEstimator((64, 64), 0.1, thickness_mm=3.0, E_mpa=0.2, nu=0.45, binning=bad)


@pytest.mark.parametrize("kw", [dict(contact="field"), dict(method="fem", grid=(6, 5)),
                                dict(mode="full")])
def test_blocks_where_they_do_not_apply_are_refused(kw):
    """The FEM on a coarse grid: what is checked is the refusal and the default's
    acceptance, not the FEM (the default 40 x 30 nodes take about 47 s to build from an
    empty cache on this project's 2-core machine)."""
    with pytest.raises(InputError, match="binning = 2 applies to"):
        ForceEstimator((64, 64), 0.1, thickness_mm=3.0, E_mpa=0.2, nu=0.45, binning=2, **kw)
    # 'auto' there is every pixel
    assert ForceEstimator((64, 64), 0.1, thickness_mm=3.0, E_mpa=0.2, nu=0.45, **kw)


SESSION = Path(__file__).resolve().parents[1] / "sample_frames" / "gelsight_session"


@pytest.fixture(scope="module")
def sample():
    s = read_session(SESSION)
    cal = PhotometricCalibration.load(SESSION / "optics.npz")
    truth = json.loads((SESSION / "truth.json").read_text())
    return s, cal, truth


def test_the_default_path_on_blocks_keeps_the_totals_of_every_pixel_within_1_percent(sample):
    """``forces``' default (heights and footprint on blocks) against every pixel, on hold
    frames of the sample session's presses 0.15 to 0.5 mm deep: -0.3 to -0.8 % when
    measured (frames 8, 39, 69, 131)."""
    s, cal, truth = sample
    kw = dict(thickness_mm=3.0, E_mpa=truth["E_mpa"], nu=truth["nu"], beta=0.82)
    mm = s.config.mm_per_px
    every = (DepthReconstructor(cal, reference=s.reference, boundary="contact"),
             ForceEstimator(cal.shape, mm, binning=1, **kw))
    est = ForceEstimator(cal.shape, mm, **kw)
    blocks = (DepthReconstructor(cal, reference=s.reference, boundary="contact",
                                 binning=est.blocks), est)
    for i in (8, 39, 69, 131):
        f = s.frame(i)
        a = every[1](every[0](f)).total_n[2]
        b = blocks[1](blocks[0](f)).total_n[2]
        assert a > 0.5
        assert b == pytest.approx(a, rel=0.01), (i, b / a)


def test_heights_on_blocks_are_constant_over_each_block_and_zero_outside(sample):
    s, cal, _ = sample
    f = s.frame(39)
    recon = DepthReconstructor(cal, reference=s.reference, boundary="contact", binning=4)
    z = recon(f)
    assert z.shape == cal.shape and z.dtype == np.float32
    blocks = z[:480 // 4 * 4, :640 // 4 * 4].reshape(120, 4, 160, 4)
    assert np.all(blocks == blocks[:, :1, :, :1])                    # one value a block
    every = DepthReconstructor(cal, reference=s.reference, boundary="contact")(f)
    assert float(np.median(z[z > 0.3])) == pytest.approx(float(np.median(every[every > 0.3])),
                                                          rel=0.02)
    # outside the contact region nothing but the blocks straddling its edge
    region = recon.contact_mask(f, threshold="frame", fill_holes=True)
    assert float(np.abs(z[~region]).max()) < 0.05


@pytest.mark.parametrize(("kw", "message"), [
    (dict(binning=2), "applies to boundary='contact' only"),
    (dict(boundary="contact", binning=0), "binning must be 'auto' or a positive integer"),
    (dict(boundary="contact", binning="x"), "binning must be 'auto' or a positive integer"),
])
def test_bad_height_blocks_are_refused(sample, kw, message):
    s, cal, _ = sample
    with pytest.raises(InputError, match=message):
        DepthReconstructor(cal, reference=s.reference, **kw)


@pytest.mark.parametrize("bad", [0, "x", 1.5])
def test_the_live_pipeline_checks_binning_without_forces(bad):
    from tactilevision.live import Pipeline

    with pytest.raises(InputError, match="binning must be 'auto' or a positive integer"):
        Pipeline(PhotometricCalibration.load(SESSION / "optics.npz"), reference="calibration",
                 binning=bad)
