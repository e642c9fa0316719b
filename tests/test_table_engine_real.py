"""The default (table) engine keeps the network's accuracy on held-out real presses.

Issue target: the default engine within 0.3 degrees of the exact one, median and 95th
percentile of the normal angle inside 0.8 of the contact radius, on held-out real presses
of the shared GelSight Mini and GelSlim 3.0. The truth is the ball's sphere on a contact
circle detected in the frame (no label of ours was drawn on these frames); the presses
are held out by the report's own split (:func:`holdout_presses`), the calibration trained
on the rest.
"""

from __future__ import annotations

import numpy as np
import pytest
from _data import (
    GELSIGHT_MINI,
    GELSIGHT_MINI_MM_PER_PX,
    GELSIGHT_MINI_REASON,
    GELSLIM,
    GELSLIM_BALL_RADIUS_MM,
    GELSLIM_MM_PER_PX,
    GELSLIM_REASON,
)

from tactilevision.io import read_ball_presses
from tactilevision.optics import (
    DepthReconstructor,
    PhotometricCalibration,
    ball_gradients,
    detect_contact_circles,
    holdout_presses,
    normal_angle_deg,
)

pytest.importorskip("torch")


def _angles(gx, gy, tgx, tgy, inside):
    return normal_angle_deg(gx[inside], gy[inside], tgx[inside], tgy[inside])


@pytest.mark.slow
@pytest.mark.parametrize("sensor", ["gelsight_mini", "gelslim3"])
def test_table_engine_is_within_0_3_degrees_of_the_exact_one(sensor, torch_one_thread):
    if sensor == "gelsight_mini":
        if not (GELSIGHT_MINI / "background.png").is_file():
            pytest.skip(GELSIGHT_MINI_REASON)
        ps = read_ball_presses(GELSIGHT_MINI)
        mm, ball_mm = GELSIGHT_MINI_MM_PER_PX, np.asarray(ps.ball_radius_mm)
    else:
        if not (GELSLIM / "set_2020_11").is_dir():
            pytest.skip(GELSLIM_REASON)
        ps = read_ball_presses(GELSLIM / "set_2020_11")
        mm, ball_mm = GELSLIM_MM_PER_PX, np.full(len(ps.frames), GELSLIM_BALL_RADIUS_MM)
    centres, radii = detect_contact_circles(ps.frames, ps.reference)
    ball_px = ball_mm / mm
    held = holdout_presses(centres, radii, ball_px, ps.reference.shape[:2], 0.25)
    train = np.flatnonzero(~held)
    # GelSlim's training presses: a smaller, quicker network than the default (64 units,
    # 15 epochs, as tests/test_optics_real.py); the check is the table against the exact
    # engine on the same network, whichever network it is
    small = {"hidden": 64, "epochs": 15} if sensor == "gelslim3" else {}
    cal = PhotometricCalibration.from_ball_presses(
        ps.reference, ps.frames[train], ball_radius_mm=ball_mm[train], mm_per_px=mm, **small)
    assert cal.position_cell_px > 0
    table, exact = DepthReconstructor(cal), DepthReconstructor(cal, engine="onnx")
    got = {"table": [], "exact": []}
    # inside 0.8 of the contact as the calibration reads it: the detected radii scaled to
    # where its first model's slope peaked (GelSlim's edge lies outside the contact)
    scale = cal.provenance["radius_scale"]
    for i in np.flatnonzero(held):
        tgx, tgy, inside = ball_gradients(cal.shape, centres[i], 0.8 * scale * radii[i],
                                          ball_px[i])
        for name, recon in (("table", table), ("exact", exact)):
            got[name].append(_angles(*recon.gradients(ps.frames[i]), tgx, tgy, inside))
    t, e = np.concatenate(got["table"]), np.concatenate(got["exact"])
    for q in (50, 95):
        # no worse than the exact engine by more than 0.3 degrees (better is allowed)
        assert np.percentile(t, q) <= np.percentile(e, q) + 0.3, (sensor, q)
    # and the two engines read the same pixels alike (colour quantisation only)
    assert np.median(t) < 6.0 and np.median(e) < 6.0
