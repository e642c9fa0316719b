"""Depth images: PNG size from figsize and dpi; round scale bars."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from tactilevision import ShapeError
from tactilevision.viz import depth_figure, nice_scale_bar_mm, save_depth_image

H, W = 60, 80


def bump() -> np.ndarray:
    y, x = np.mgrid[0:H, 0:W]
    return (0.5 * np.exp(-((x - 40) ** 2 + (y - 30) ** 2) / 50.0)).astype(np.float32)


@pytest.mark.parametrize(("with_frame", "dpi"), [(False, 100), (True, 100), (False, 50)])
def test_save_depth_image_size(tmp_path, with_frame, dpi):
    # one panel is 5.2 x 4.3 inches, two panels 10.4 x 4.3: pixels = inches * dpi
    frame = np.zeros((H, W, 3), np.uint8) if with_frame else None
    path = save_depth_image(tmp_path / "sub" / "d.png", bump(), mm_per_px=0.03, frame=frame,
                            title="t", credit="CC BY-NC 4.0", dpi=dpi)
    assert path == tmp_path / "sub" / "d.png"
    img = cv2.imread(str(path))
    assert img is not None
    panels = 2 if with_frame else 1
    assert img.shape[:2] == (round(4.3 * dpi), round(5.2 * panels * dpi))
    # the figure is not blank: the colour map spans several colours
    assert len(np.unique(img.reshape(-1, 3), axis=0)) > 20


def test_depth_figure_checks_inputs():
    with pytest.raises(ShapeError, match="height_mm"):
        depth_figure(np.zeros((2, H, W), np.float32), mm_per_px=0.03)
    with pytest.raises(ShapeError, match="height_mm"):
        depth_figure(np.zeros((H, W), np.int64), mm_per_px=0.03)
    with pytest.raises(ShapeError, match="frame"):
        depth_figure(bump(), mm_per_px=0.03, frame=np.zeros((H, W + 1, 3), np.uint8))


def test_depth_figure_colour_scale():
    import matplotlib.pyplot as plt

    fig = depth_figure(bump(), mm_per_px=0.03, vmax_mm=0.2)
    im = fig.axes[0].images[0]
    assert im.get_clim() == (0.0, 0.2)  # vmin: min(0, 0.1th percentile) = 0 for a bump
    plt.close(fig)


@pytest.mark.parametrize(("width", "want"), [(5.0, 1.0), (10.0, 2.0), (25.0, 5.0),
                                             (18.88, 2.0), (12.8, 2.0), (0.3, 0.05),
                                             (640 * 0.0295, 2.0), (49.9, 5.0), (50.0, 10.0)])
def test_nice_scale_bar_known(width, want):
    assert nice_scale_bar_mm(width) == pytest.approx(want)


@given(st.floats(1e-3, 1e4))
def test_nice_scale_bar_is_round_and_near_a_fifth(width):
    length = nice_scale_bar_mm(width)
    k = math.floor(math.log10(length) + 1e-9)
    mantissa = length / 10**k
    assert min(abs(mantissa - m) for m in (1.0, 2.0, 5.0)) < 1e-9
    # the largest 1-2-5 value not above width / 5 is more than 0.4 of it
    # (worst gap: from 2 up to just under 5)
    target = width / 5
    assert 0.4 * target < length <= target * (1 + 1e-12)
