"""contact_mask(fill_holes=True): a flat face's ring of colour change that misses closure by
a gap under BRIDGED_GAP_PX still counts as closed (its inside taken in, the gap left out);
a wider gap does not."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tactilevision.io import read_session
from tactilevision.optics import DepthReconstructor, PhotometricCalibration
from tactilevision.optics._reconstructor import BRIDGED_GAP_PX

SESSION = Path(__file__).resolve().parents[1] / "sample_frames" / "gelsight_session"


@pytest.fixture(scope="module")
def recon():
    s = read_session(SESSION)
    cal = PhotometricCalibration.load(SESSION / "optics.npz")
    return DepthReconstructor(cal, reference=s.reference, boundary="contact")


def _ring(shape, gap_px: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A ring (radii 60 to 72 px) with a gap of `gap_px` on its right, as the grown mask
    of a punch's edge; its inside, and the gap."""
    rows, cols = np.indices(shape)
    y, x = rows - shape[0] / 2, cols - shape[1] / 2
    r = np.hypot(x, y)
    gap = (np.abs(y) < gap_px / 2) & (x > 0)
    ring = (r >= 60) & (r <= 72)
    return ring & ~gap, r < 60, ring & gap


@pytest.mark.parametrize("gap", [0, 14, BRIDGED_GAP_PX - 4])
def test_a_ring_with_a_gap_under_the_bridge_is_filled(recon, gap):
    ring, inside, gap_px = _ring(recon.shape, gap)
    filled = recon._filled(ring)
    assert filled[inside].mean() > 0.97
    assert gap == 0 or filled[gap_px].mean() < 0.5           # the gap itself mostly out
    assert not filled[~(ring | inside | gap_px)].any()


def test_a_ring_open_wider_than_the_bridge_stays_open(recon):
    ring, inside, _ = _ring(recon.shape, 2 * BRIDGED_GAP_PX)
    filled = recon._filled(ring)
    assert not filled[inside].any()
    assert np.array_equal(filled, ring)
