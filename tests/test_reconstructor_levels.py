"""The reconstructor's levels: the reference is the flat gel by definition."""

from __future__ import annotations

import numpy as np

from tactilevision.optics import DepthReconstructor, PhotometricCalibration


def test_flat_reference_reads_the_reference_as_flat():
    cal = PhotometricCalibration.load("gelsight")
    plain = DepthReconstructor(cal)
    level = DepthReconstructor(cal, flat_reference=True)
    # the shipped network's own bias on its reference integrates to a bowl of ~0.1 mm rms
    assert np.sqrt(np.mean(plain(cal.reference) ** 2)) > 0.05
    assert np.abs(level(cal.reference)).max() < 1e-6
