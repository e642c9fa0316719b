"""A GelSlim 3.0 session rendered on the fly from the real GelSlim frames (CC BY-NC,
never committed): the shading table is fitted to the real ball presses of the
release's set_2020_11 ($TACTILEVISION_GELSLIM; a forward model, unlike the reconstructor),
the session runs at the sensor's 90 frames/s on its 427 x 320 reference."""

from __future__ import annotations

import numpy as np
import pytest
from _data import GELSLIM, GELSLIM_BALL_RADIUS_MM, GELSLIM_MM_PER_PX, GELSLIM_REASON

from tactilevision import calibrate_session

pytestmark = pytest.mark.skipif(not GELSLIM.is_dir(), reason=GELSLIM_REASON)


@pytest.fixture(scope="module")
def gelslim_table():
    from tactilevision.io import read_ball_presses
    from tactilevision.optics import detect_contact_circles
    from tactilevision.sim import fit_shading_table

    ps = read_ball_presses(GELSLIM / "set_2020_11")
    centres, radii = detect_contact_circles(ps.frames, ps.reference)
    return ps, centres, radii, fit_shading_table(
        ps.reference, ps.frames[::2], centres[::2], radii[::2],
        ball_radius_mm=GELSLIM_BALL_RADIUS_MM, mm_per_px=GELSLIM_MM_PER_PX)


def test_gelslim_shading_table_predicts_held_out_presses(gelslim_table):
    """Fitted on the even presses, it renders the odd ones to a median 22% of
    their colour change (17% to 67% measured)."""
    ps, centres, radii, table = gelslim_table
    ball_px = GELSLIM_BALL_RADIUS_MM / GELSLIM_MM_PER_PX
    rows, cols = np.indices(table.shape)
    ratios = []
    for i in range(1, len(ps.frames), 2):
        r2 = (cols - centres[i][0]) ** 2 + (rows - centres[i][1]) ** 2
        cap = np.sqrt(np.maximum(ball_px ** 2 - r2, 0)) - np.sqrt(ball_px ** 2 - radii[i] ** 2)
        z = np.where(r2 < radii[i] ** 2, cap, 0) * GELSLIM_MM_PER_PX
        inside = r2 < (0.9 * radii[i]) ** 2
        real = ps.frames[i].astype(float) - ps.reference
        err = table.shading(z) - real
        ratios.append(np.sqrt(np.mean(err[inside] ** 2)) / np.sqrt(np.mean(real[inside] ** 2)))
    assert np.median(ratios) < 0.3


@pytest.mark.slow
def test_gelslim_session(gelslim_table, tmp_path):
    from tactilevision.sim import GaugeBlock, SessionSpec, make_session, press_profile

    ps, _, _, table = gelslim_table
    prof = press_profile(2.5 / 3, 0.47, w_over_h_max=0.22, steps=8, cell=0.5,
                         edge_refinements=5)
    # the vernier on GelSlim's coarser pixels (0.0806 mm): a flatter bevel, 3 deg, so that
    # one pixel of the band is 4.2 um of depth; the stage stops 10 to 50 um past w0
    block = GaugeBlock(bevel_angle_deg=3.0, bevel_length_mm=4.0)
    spec = SessionSpec(E_mpa=0.25, nu=0.47, repeats=2, fps=90.0, clock_offset_s=0.05,
                       block=block, sensor_name="gelslim3", misaligned=(4,), seed=3,
                       overshoot_mm=(0.01, 0.05), wait_s=(0.4, 0.8))   # short rests: fewer frames
    truth = make_session(tmp_path / "s", spec, shading=(table, ps.reference), profile=prof)
    cal = calibrate_session(tmp_path / "s")
    c = cal.certification
    tp = {p["press"]: p for p in truth["presses"]}
    assert c.clock_offset_s == pytest.approx(0.05, abs=0.003)
    assert {r.press: r.reason for r in c.rejected}.get(4) == "misaligned"
    assert len(c.presses) >= 7
    m = cal.measurements()
    for p, d, f, b in zip(c.presses, cal.depth_mm, m["force_n"], m["bevel_force_n"],
                          strict=True):
        assert p.indenter == tp[p.press]["indenter"]
        assert p.rule == "vernier"
        assert abs(d - tp[p.press]["depth_mm"]) < 0.010
        # the F/T reads the bevel's band too (tens of mN for this long, flat ridge);
        # certification takes it off at the fitted E
        assert abs(b - tp[p.press]["bevel_force_n"]) < 0.2 * tp[p.press]["bevel_force_n"] + 0.003
        assert abs(f - tp[p.press]["force_n"]) < 0.01
        assert p.footprint.radius_ok
