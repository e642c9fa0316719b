"""The shipped calibration by name from any folder; references are never silently replaced."""

from __future__ import annotations

import numpy as np
import pytest

from tactilevision import KNOWN_SENSORS, InputError, ShapeError
from tactilevision.optics import DepthReconstructor, PhotometricCalibration


def test_shipped_calibration_loads_by_name_from_any_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)                 # no calibration/ folder here
    assert "gelsight" in KNOWN_SENSORS
    cal = PhotometricCalibration.load("gelsight")
    # the shipped GelSight model: Taxim's GelSight, 640 x 480 at 0.0295 mm/px
    assert cal.shape == (480, 640)
    assert cal.mm_per_px == pytest.approx(0.0295, rel=1e-3)


def test_a_file_named_like_a_sensor_wins_over_the_shipped_one(tmp_path, monkeypatch):
    cal = PhotometricCalibration.load("gelsight")
    small = PhotometricCalibration(model=cal.model, reference=cal.reference, mm_per_px=0.05,
                                   lut=cal.lut, onnx_bytes=cal.onnx_bytes,
                                   use_position=cal.use_position)
    small.save(tmp_path / "gelsight.npz")
    (tmp_path / "gelsight.npz").rename(tmp_path / "gelsight")
    monkeypatch.chdir(tmp_path)
    assert PhotometricCalibration.load("gelsight").mm_per_px == pytest.approx(0.05)


def test_unknown_name_names_the_shipped_ones():
    with pytest.raises(InputError, match="'gelsight'"):
        PhotometricCalibration.load("gelslim")


def test_reference_is_never_silently_replaced():
    cal = PhotometricCalibration.load("gelsight")
    with pytest.raises(InputError, match=r"cv2\.imread returns None"):
        DepthReconstructor(cal, reference=None)
    with pytest.raises(ShapeError, match=r"\(480, 640, 3\)"):
        DepthReconstructor(cal, reference=np.zeros((320, 427, 3), np.uint8))
    with pytest.raises(InputError, match="'calibration'"):
        DepthReconstructor(cal, reference="reference.png")
    # the calibration's own reference when asked for (the default)
    frame = np.clip(cal.reference.astype(np.int16) + 12, 0, 255).astype(np.uint8)
    own = DepthReconstructor(cal, reference="calibration")(frame)
    other = DepthReconstructor(cal, reference=frame)(frame)
    np.testing.assert_array_equal(own, DepthReconstructor(cal)(frame))
    assert np.abs(own - other).max() > 1e-3


def test_a_second_reconstructor_reuses_the_tabulated_network():
    """The MLP's gradient table is built once per network, reference and bins and kept for
    the next reconstructor of the same sensor (read only); another reference gets its own
    table; the heights are the same from the reused table as from the one built."""
    cal = PhotometricCalibration.load("gelsight")
    frame = np.clip(cal.reference.astype(np.int16) + 12, 0, 255).astype(np.uint8)
    first = DepthReconstructor(cal)         # built here, or by an earlier test of this worker
    again = DepthReconstructor(cal)
    assert again._table is first._table
    assert not first._table.gx_table.flags.writeable
    np.testing.assert_array_equal(first(frame), again(frame))
    other = DepthReconstructor(cal, reference=frame)
    assert other._table is not first._table
