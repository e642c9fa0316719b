"""The reconstructor's levels: the reference is the flat gel by definition."""

from __future__ import annotations

import numpy as np
import pytest

from tactilevision.optics import DepthReconstructor, PhotometricCalibration


def test_flat_reference_reads_the_reference_as_flat():
    cal = PhotometricCalibration.load("gelsight")
    plain = DepthReconstructor(cal)
    level = DepthReconstructor(cal, flat_reference=True)
    # the shipped network's own bias on its reference integrates to a bowl of ~0.1 mm rms
    assert np.sqrt(np.mean(plain(cal.reference) ** 2)) > 0.05
    assert np.abs(level(cal.reference)).max() < 1e-6


def test_far_field_level_removes_a_bowl_outside_the_contact():
    """A height map = bowl (degree 2) + a 0.3 mm cap inside a disc whose colour
    changes: the far-field level leaves the cap and zero around it."""
    cal = PhotometricCalibration.load("gelsight")
    recon = DepthReconstructor(cal, level="far_field", level_degree=2)
    h, w = cal.shape
    rows, cols = np.indices((h, w), dtype=np.float64)
    r = np.hypot(cols - 400, rows - 200)
    frame = cal.reference.copy()
    disc = r < 60
    frame[disc] = np.clip(frame[disc].astype(int) + 40, 0, 255).astype(np.uint8)
    x, y = cols / w - 0.5, rows / h - 0.5
    bowl = 3.0 * x**2 + 2.0 * y**2 - 1.5 * x * y + 0.7 * x + 0.4       # px of height
    cap = np.where(disc, 10.0 * (1 - (r / 60) ** 2), 0.0)
    levelled = recon._level_far_field((bowl + cap).astype(np.float32),
                                      recon._contact_small(frame))
    far = r > 80
    assert np.abs(levelled[far]).max() < 1e-3
    np.testing.assert_allclose(levelled[disc], cap[disc], atol=1e-3)


def test_far_field_level_flattens_the_no_contact_frame():
    cal = PhotometricCalibration.load("gelsight")
    frame = np.clip(cal.reference.astype(np.int16) + 3, 0, 255).astype(np.uint8)
    median = DepthReconstructor(cal)(frame)
    far = DepthReconstructor(cal, level="far_field")(frame)
    assert np.sqrt(np.mean(far**2)) < 0.25 * np.sqrt(np.mean(median**2))
    with pytest.raises(ValueError, match="level"):
        DepthReconstructor(cal, level="border")
