"""Contact masks against a no-contact reference, on synthetic frames with known noise."""

from __future__ import annotations

import numpy as np
import pytest

from tactilevision import InputError, ShapeError
from tactilevision.contact import contact_mask, noise_level

SHAPE, SIGMA = (120, 160), 2.0


def frames(seed=0, change=20.0, radius=20.0, center=(80.0, 60.0)):
    rng = np.random.default_rng(seed)
    rows, cols = np.indices(SHAPE)
    base = np.stack([100 + 0.3 * cols, 120 + 0.2 * rows, 90 + 0.1 * (rows + cols)], axis=2)
    ref = base + rng.normal(0, SIGMA, base.shape)
    disc = np.hypot(cols - center[0], rows - center[1]) <= radius
    frame = base + rng.normal(0, SIGMA, base.shape)
    frame[disc] += np.array([change, -change, 0.5 * change])
    return np.clip(frame, 0, 255).astype(np.uint8), np.clip(ref, 0, 255).astype(np.uint8), disc


def test_noise_level_is_the_channel_sum_sd():
    f, r, _ = frames(change=0.0)
    # difference of two noisy frames: per channel sd sqrt(2) SIGMA, summed over 3 channels;
    # uint8 rounding adds 1/12 per frame and channel
    expected = np.sqrt(3 * 2 * (SIGMA**2 + 1 / 12))
    assert noise_level(f, r) == pytest.approx(expected, rel=0.1)


def test_mask_finds_the_disc():
    f, r, disc = frames()
    m = contact_mask(f, r)
    iou = (m & disc).sum() / (m | disc).sum()
    assert iou > 0.9


def test_no_contact_no_mask_and_specks_dropped():
    f, r, _ = frames(change=0.0)
    assert not contact_mask(f, r).any()
    f[10, 10] = 255          # a hot pixel
    f[50:53, 20:23] = 0      # a 3 x 3 speck of dust
    assert not contact_mask(f, r).any()


def test_bad_input():
    f, r, _ = frames()
    with pytest.raises(ShapeError, match="reference"):
        contact_mask(f, r[:, :-1])
    with pytest.raises(InputError, match="k_sigma"):
        contact_mask(f, r, k_sigma=0)
