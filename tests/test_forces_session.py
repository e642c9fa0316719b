"""Frames -> height maps -> forces on the sample session (issue 6's end-to-end
path): the session-matched optics (colour-only and per position cell), the
contact-pinned integration, and the finite-strain factor, against the
session's truth and F/T log."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.fem import ForceEstimator
from tactilevision.io import read_session
from tactilevision.mechanics import beta_from_nu
from tactilevision.optics import DepthReconstructor, PhotometricCalibration
from tactilevision.sim import render_ball_presses, taxim_shading

pytest.importorskip("taxim")

SESSION = Path(__file__).resolve().parents[1] / "sample_frames" / "gelsight_session"


@pytest.fixture(scope="module")
def session():
    return read_session(SESSION), json.loads((SESSION / "truth.json").read_text())


@pytest.fixture(scope="module")
def balls(session):
    s, _ = session
    table, _ = taxim_shading()
    return render_ball_presses(table, s.reference, n=24, radius_mm=4.0, depth_mm=(0.2, 2.0),
                               seed=5)


@pytest.fixture(scope="module")
def recon(session, balls):
    s, _ = session
    cal = PhotometricCalibration.from_ball_presses(
        balls.reference, balls.frames, balls.centers_px, balls.radii_px, ball_radius_mm=4.0,
        mm_per_px=s.config.mm_per_px, model="lut", use_position=False)
    return DepthReconstructor(cal, reference=s.reference, boundary="contact")


def _hold_frame(s, press):
    return int(np.argmin(np.abs(s.frame_times_s - (press["hold_from_s"] + 0.25))))


def _off_bevel(s, press):
    """Pixels away from the bevel's band (the gauge block's ridge touches the gel there too:
    a second, small contact 9 mm from the indenter on the +x side)."""
    mm = s.config.mm_per_px
    rows, cols = np.indices(s.shape)
    cx = press["x_mm"] / mm + (s.shape[1] - 1) / 2
    cy = press["y_mm"] / mm + (s.shape[0] - 1) / 2
    u = (cols - cx) * mm - s.config.bevel_offset_mm
    v = (rows - cy) * mm
    return ~((np.abs(u) < 2.0) & (np.abs(v) < 0.5 * s.config.bevel_length_mm + 1.0))


def _radius_mm(s, press):
    mm = s.config.mm_per_px
    rows, cols = np.indices(s.shape)
    cx = press["x_mm"] / mm + (s.shape[1] - 1) / 2
    cy = press["y_mm"] / mm + (s.shape[0] - 1) / 2
    return np.hypot(cols - cx, rows - cy) * mm


def test_ball_presses_have_exact_circles(balls, session):
    s, _ = session
    assert balls.frames.shape == (24, *s.shape, 3)
    for f, (cx, cy), r in zip(balls.frames[:4], balls.centers_px, balls.radii_px, strict=False):
        change = np.abs(f.astype(int) - s.reference.astype(int)).max(axis=-1)
        rows, cols = np.indices(s.shape)
        d = np.hypot(cols - cx, rows - cy)
        assert change[d < r - 3].mean() > 3 * change[d > r + 20].mean()
    # slopes at the contact edge a / sqrt(R^2 - a^2) up to 1.7 at 2 mm deep
    a = balls.radii_px * s.config.mm_per_px
    assert (a / np.sqrt(16 - a**2)).max() > 1.0


def test_ball_presses_bad_input(session):
    s, _ = session
    table, _ = taxim_shading()
    with pytest.raises(InputError, match="depth_mm"):
        render_ball_presses(table, s.reference, depth_mm=(0.5, 4.0), radius_mm=4.0)
    with pytest.raises(InputError, match="does not fit"):
        render_ball_presses(table, s.reference, radius_mm=40.0, depth_mm=(1, 30))
    with pytest.raises(InputError, match="reference"):
        render_ball_presses(table, s.reference[:-1])
    with pytest.raises(InputError, match="radius_mm"):
        render_ball_presses(table, s.reference, radius_mm=-1)


def test_contact_mask_from_frame_noise_covers_the_punch_face(session, recon):
    """The flat face has no colour change; its ring does. With the frame's own
    noise level and holes filled the mask covers the face; the calibration's
    level (set on cleaner or noisier frames) need not."""
    s, truth = session
    p = truth["presses"][1]                                   # w0 0.4 mm, a 2.5 mm
    frame = s.frame(_hold_frame(s, p))
    r = _radius_mm(s, p)
    m = recon.contact_mask(frame, threshold="frame", fill_holes=True)
    assert m[r < 2.5].mean() > 0.99
    area = m.sum() * s.config.mm_per_px**2
    off = _off_bevel(s, p)
    area = (m & off).sum() * s.config.mm_per_px**2
    assert np.pi * 2.5**2 < area < 3 * np.pi * 2.5**2
    assert not m[(r > 7) & off].any()
    assert m[~off].any()                                       # the bevel's band is contact
    ring = recon.contact_mask(frame, threshold="frame")
    assert ring[r < 1.5].mean() < 0.1                          # the face itself is unchanged
    with pytest.raises(ValueError, match="threshold"):
        recon.contact_mask(frame, threshold="noise")
    with pytest.raises(ValueError, match="positive"):
        recon.contact_mask(frame, threshold=-0.1)


@pytest.mark.parametrize("press", [4, 0, 1, 6])                # w0 0.15, 0.3, 0.4, 0.5 mm
def test_session_face_depth_from_frames(session, recon, press):
    """The punch face's depth from the frame, session-matched optics and
    contact-pinned integration: within 12 % of the truth (presses 4, 0, 1, 6 at
    x = -2.3 to -5.1 mm; the colour-only LUT reads presses on the image's far
    left low, -17.7 % for press 2 at x = -6.3 mm: Taxim's shading depends on
    position); outside the contact (and the bevel's band) exactly 0."""
    s, truth = session
    p = truth["presses"][press]
    hm = recon(s.frame(_hold_frame(s, p)))
    r = _radius_mm(s, p)
    face = float(np.median(hm[r < 2.0]))
    assert face == pytest.approx(p["depth_mm"], rel=0.12)
    assert np.all(hm[(r > 8) & _off_bevel(s, p)] == 0)


def test_beta_scales_by_the_contact_depth():
    est0 = ForceEstimator((64, 64), 0.1, thickness_mm=3.0, E_mpa=0.2, nu=0.45,
                          contact="footprint", threshold_mm=0.01)
    est1 = ForceEstimator((64, 64), 0.1, thickness_mm=3.0, E_mpa=0.2, nu=0.45,
                          contact="footprint", threshold_mm=0.01, beta=0.8)
    u = np.zeros((64, 64))
    u[24:40, 24:40] = 0.3
    f0, f1 = est0(u), est1(u)
    assert f1.total_n[2] == pytest.approx(f0.total_n[2] * (1 + 0.8 * 0.3 / 3.0), rel=1e-9)
    np.testing.assert_allclose(f1.pressure_kpa, f0.pressure_kpa * 1.08, rtol=1e-9, atol=1e-12)
    with pytest.raises(InputError, match="beta"):
        ForceEstimator((64, 64), 0.1, thickness_mm=3.0, E_mpa=0.2, nu=0.45, beta=-0.1,
                       contact="field")


# -- position-cell optics: the end-to-end force per press ---------------------------------

@pytest.fixture(scope="module")
def edge_balls(session):
    """128 presses of a 2 mm ball up to 1.4 mm deep (edge slopes to 3, the punch
    walls'), centres anywhere in the image: contacts run off its edges."""
    s, _ = session
    table, _ = taxim_shading()
    return render_ball_presses(table, s.reference, n=128, radius_mm=2.0, depth_mm=(0.2, 1.4),
                               partial=True, seed=5)


@pytest.fixture(scope="module")
def cell_recon(session, edge_balls):
    s, _ = session
    cal = PhotometricCalibration.from_ball_presses(
        edge_balls.reference, edge_balls.frames, edge_balls.centers_px, edge_balls.radii_px,
        ball_radius_mm=2.0, mm_per_px=s.config.mm_per_px, model="lut", lut_cells=(8, 6))
    return DepthReconstructor(cal, reference=s.reference, boundary="contact")


@pytest.mark.slow
def test_partial_ball_presses_reach_the_image_edges(session, edge_balls):
    s, _ = session
    (H, W), c, r = s.shape, edge_balls.centers_px, edge_balls.radii_px
    assert np.all((c >= 5) & (c <= np.array([W - 5, H - 5])))
    off = (c[:, 0] < r) | (c[:, 0] > W - 1 - r) | (c[:, 1] < r) | (c[:, 1] > H - 1 - r)
    assert off.mean() > 0.25                       # many contacts cross an edge
    a = r * s.config.mm_per_px
    assert (a / np.sqrt(4.0 - a**2)).max() > 2.5   # edge slope a / sqrt(R^2 - a^2)


@pytest.fixture(scope="module")
def estimator(session):
    """True E and nu, beta of the bonded punch from the FEM table (0.80)."""
    s, truth = session
    h = truth["thickness_mm"]
    beta = beta_from_nu(truth["nu"], table="fem", a_over_h=2.5 / h)
    return ForceEstimator(s.shape, s.config.mm_per_px, thickness_mm=h, E_mpa=truth["E_mpa"],
                          nu=truth["nu"], contact="footprint", threshold_mm=0.02, beta=beta)


def _ft_force(s, truth, i):
    return float(np.interp(s.frame_times_s[i], s.force_times_s - truth["clock_offset_s"],
                           s.forces_n[:, 2]))


# the deeper presses among the first 20 (w0 0.4 to 0.6 mm) at x > -5.5 mm; the two at the
# image's far left (2 at x -6.3 mm, 15 at -5.6, within 3.9 mm of its edge) read 0.943 and
# 0.935 through the 8 x 6 cells (the balls' contacts cover that edge least)
DEEP = [1, 6, 8, 9, 12, 16, 17, 19]


@pytest.mark.slow
def test_session_forces_within_5_percent_with_position_cells(session, cell_recon, estimator):
    """Frames -> heights (a LUT per cell of 8 x 6) -> force (spectral, footprint,
    beta) against the F/T log, one hold frame per press: all within 5 % (measured
    0.975 to 1.030 on these eight; the F/T log holds the bevel band's few mN too, and
    so does the height map). ``python benchmarks/bench_forces_session.py`` runs every
    press."""
    s, truth = session
    ratios = []
    for k in DEEP:
        p = truth["presses"][k]
        i = _hold_frame(s, p)
        ratios.append(float(estimator(cell_recon(s.frame(i))).total_n[2]) / _ft_force(s, truth, i))
    ratios = np.array(ratios)
    assert np.all(np.abs(ratios - 1) < 0.05), ratios


def test_colour_only_table_misses_5_percent_on_the_left(session, recon, estimator):
    """A press on the image's far left through the colour-only table (24 presses of a
    4 mm ball, contacts inside the image): x = -6.3 mm reads about 17 % low (0.832
    measured); the position cells take it to 0.943."""
    s, truth = session
    p = truth["presses"][2]
    i = _hold_frame(s, p)
    ratio = float(estimator(recon(s.frame(i))).total_n[2]) / _ft_force(s, truth, i)
    assert 0.78 < ratio < 0.9
