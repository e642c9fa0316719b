"""The contact-pinned heights look their gradients up only where the solve reads them
(issue 85 item 1: the masked integration solved where the contact is).

A table's lookup of a window is the whole frame's lookup there, value for value; the
contact-pinned heights from the window's gradients are those from the whole frame's: the
same to the bit on every pixel's grid and on fixed blocks, within the solve's own
tolerance (1e-4 of the peak) on the blocks that follow the contact (``binning='auto'``,
whose block means OpenCV sums in another order on a smaller array).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tactilevision.io import read_session
from tactilevision.optics import DepthReconstructor, PhotometricCalibration

SESSION = Path(__file__).resolve().parents[1] / "sample_frames" / "gelsight_session"
CALIBRATION = Path(__file__).resolve().parents[1] / "calibration" / "gelsight.npz"

#: A deep press reaching the image's bottom and left edges (40), the frame after it, a
#: shallow contact (90), a press being released (70) and a frame without contact (0).
FRAMES = (40, 41, 90, 70, 0)


@pytest.fixture(scope="module")
def session():
    return read_session(SESSION)


@pytest.mark.parametrize("source, kernel", [("lut", "numpy"), ("mlp_order1", "numpy"),
                                            ("mlp_order1", "numba")])
def test_a_window_looks_up_what_the_whole_frame_does_there(session, source, kernel):
    if kernel == "numba":
        pytest.importorskip("numba", reason="the compiled first-order kernel needs numba")
    if source == "lut":
        cal = PhotometricCalibration.load(SESSION / "optics.npz")
        recon = DepthReconstructor(cal, reference=session.reference)
    else:           # a network's first-order table, numpy's whole-image operations or numba's
        cal = PhotometricCalibration.load(CALIBRATION)
        recon = DepthReconstructor(cal, reference=session.reference, table_order=1,
                                   kernel=kernel)
    frame = session.frame(40)
    gx, gy = recon.gradients(frame)
    H, W = recon.shape
    for window in ((0, H, 0, W), (100, 260, 37, 301), (400, H, 0, 90), (0, 1, W - 1, W)):
        r0, r1, c0, c1 = window
        wx, wy = recon._table.gradients(frame, normalise_gain=cal.normalise_gain,
                                        kernel=kernel, window=window)
        assert wx.shape == (r1 - r0, c1 - c0)
        np.testing.assert_array_equal(wx, gx[r0:r1, c0:c1])
        np.testing.assert_array_equal(wy, gy[r0:r1, c0:c1])


def _whole_frame(recon: DepthReconstructor) -> DepthReconstructor:
    """The same reconstructor looking every frame's gradients up over the whole frame
    (the path before the window)."""
    recon._gradient_window = lambda mask, k: None
    return recon


@pytest.mark.parametrize("binning, flat", [(1, False), (3, False), ("auto", False),
                                           (1, True)])
def test_the_contact_heights_from_the_window_are_the_whole_frames(session, binning, flat):
    """(`flat`: the optics model's gradient on the reference subtracted, over the window.)"""
    cal = PhotometricCalibration.load(SESSION / "optics.npz")
    kw = dict(reference=session.reference, boundary="contact", binning=binning,
              flat_reference=flat)
    win = DepthReconstructor(cal, **kw)
    whole = _whole_frame(DepthReconstructor(cal, **kw))
    for i in FRAMES:
        frame = session.frame(i)
        a, b = win(frame), whole(frame)
        assert a.shape == b.shape == cal.shape
        if binning == "auto":
            peak = float(np.abs(b).max())
            assert np.abs(a - b).max() <= 1e-4 * max(peak, 1e-6), i
        else:
            np.testing.assert_array_equal(a, b)
    assert not np.any(win(session.frame(0)))          # no contact: zero everywhere
