"""tactilevision._morphology.fill_holes against SciPy's binary_fill_holes."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage as ndi

from tactilevision import InputError
from tactilevision._morphology import fill_holes


def test_fill_holes_equals_scipys_on_random_masks():
    rng = np.random.default_rng(11)
    for _ in range(200):
        shape = tuple(int(n) for n in rng.integers(1, 40, 2))
        mask = rng.random(shape) < rng.uniform(0.2, 0.8)
        np.testing.assert_array_equal(fill_holes(mask), ndi.binary_fill_holes(mask))


def test_a_ring_is_filled_and_a_ring_open_to_the_border_is_not():
    yy, xx = np.mgrid[:60, :80]
    r = np.hypot(yy - 30, xx - 40)
    ring = (r > 10) & (r < 14)
    filled = fill_holes(ring)
    assert filled[30, 40] and filled.sum() == np.count_nonzero(r < 14)
    # the same ring cut open by a 4-connected gap: the inside reaches the border
    cut = ring.copy()
    cut[30, 50:] = False
    assert not fill_holes(cut)[30, 40]
    # a hole closed only diagonally stays a hole for SciPy's (4-connected) background
    diag = np.zeros((5, 5), bool)
    diag[1, 2] = diag[2, 1] = diag[2, 3] = diag[3, 2] = True
    assert fill_holes(diag)[2, 2] and ndi.binary_fill_holes(diag)[2, 2]


def test_fill_holes_refuses_a_stack():
    with pytest.raises(InputError, match="2-D"):
        fill_holes(np.zeros((2, 5, 5), bool))
