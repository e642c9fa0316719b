"""Marker dots: find them, keep them out of calibration, fill them in.

Many gels carry a grid of black markers for tracking lateral motion; they
hide the shading under them. A marker is a pixel much darker than its
neighbourhood: the grey image against its morphological closing (a local
background without the dots).
"""

from __future__ import annotations

import cv2
import numpy as np

from .._checks import check_array

__all__ = ["fill_masked", "marker_mask"]


def marker_mask(frame: np.ndarray, *, size_px: int = 11, contrast: float = 0.25,
                dilate_px: int = 1) -> np.ndarray:
    """Mask of dark marker dots.

    Parameters
    ----------
    frame : (H, W, 3) uint8 ndarray
        Frame, BGR.
    size_px : int, default 11
        Closing kernel size: larger than a marker, smaller than the spacing.
    contrast : float, default 0.25
        A pixel is a marker when ``grey < (1 - contrast) * closing(grey)``.
    dilate_px : int, default 1
        Grow the mask by this many pixels (the dark halo of a marker).

    Returns
    -------
    mask : (H, W) bool ndarray
        True on markers.
    """
    frame = check_array(frame, "frame", [("H", "W", 3)], dtype=np.uint8)
    grey, background = grey_and_background(frame, size_px)
    return _mask_from(grey, background, contrast, dilate_px)


def grey_and_background(frame: np.ndarray, size_px: int) -> tuple[np.ndarray, np.ndarray]:
    """(H, W) float32 grey image and its closing (the local background without dots)."""
    grey = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY).astype(np.float32)
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (size_px, size_px))
    return grey, cv2.morphologyEx(grey, cv2.MORPH_CLOSE, kernel)


def _mask_from(grey: np.ndarray, background: np.ndarray, contrast: float,
               dilate_px: int) -> np.ndarray:
    mask = (grey < (1.0 - contrast) * background).astype(np.uint8)
    if dilate_px > 0:
        k = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * dilate_px + 1, 2 * dilate_px + 1))
        mask = cv2.dilate(mask, k)
    return mask.astype(bool)


def fill_masked(values: np.ndarray, mask: np.ndarray, *, sigma: float = 3.0) -> np.ndarray:
    """Fill masked pixels by normalised convolution of their neighbours.

    Parameters
    ----------
    values : (H, W) or (H, W, C) float32 ndarray
        Field to fill (a gradient component, a colour change).
    mask : (H, W) bool ndarray
        Pixels to replace.
    sigma : float, default 3.0
        Gaussian width (px) of the neighbourhood.

    Returns
    -------
    filled : same shape as ``values``, float32
        ``blur(values * valid) / blur(valid)`` on masked pixels, values
        elsewhere.
    """
    values = np.asarray(values, np.float32)
    valid = (~mask).astype(np.float32)
    num = cv2.GaussianBlur(values * (valid if values.ndim == 2 else valid[..., None]),
                           (0, 0), sigma)
    den = cv2.GaussianBlur(valid, (0, 0), sigma)
    if values.ndim == 3:
        den = den[..., None]
    fill = num / np.maximum(den, 1e-6)
    m = mask if values.ndim == 2 else mask[..., None]
    return np.where(m, fill, values).astype(np.float32)
