"""Marker dots: find them, keep them out of calibration, fill them in.

Many gels carry a grid of black markers for tracking lateral motion; they
hide the shading under them. A marker is a pixel much darker than its
neighbourhood: the grey image against its morphological closing (a local
background without the dots).
"""

from __future__ import annotations

import math

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
    grey = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (size_px, size_px))
    # closing on the 8-bit image (exact: max and min of integers; half the time of float32)
    background = cv2.morphologyEx(grey, cv2.MORPH_CLOSE, kernel)
    return grey.astype(np.float32), background.astype(np.float32)


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
        Gaussian width (px) of the neighbourhood (the kernel is truncated at
        2 sigma: 13 px at the default, under half the time of OpenCV's
        default 8 sigma support, and dots are a few px across).

    Returns
    -------
    filled : same shape as ``values``, float32
        ``blur(values * valid) / blur(valid)`` on masked pixels, values
        elsewhere.
    """
    values = np.asarray(values, np.float32)
    if values.ndim == 2:
        return fill_masked_fields([values], mask, sigma=sigma)[0]
    return np.stack(fill_masked_fields([values[..., c] for c in range(values.shape[-1])],
                                       mask, sigma=sigma), axis=-1)


def fill_masked_fields(fields: list[np.ndarray], mask: np.ndarray, *,
                       sigma: float = 3.0) -> list[np.ndarray]:
    """:func:`fill_masked` on several (H, W) fields sharing one mask (one weight blur).

    Returns new float32 arrays, contiguous; the masked pixels only are
    replaced (the frame -> gradients path fills gx and gy this way).
    """
    k = 2 * math.ceil(2.0 * sigma) + 1
    valid = (~mask).astype(np.float32)
    den = cv2.GaussianBlur(valid, (k, k), sigma)
    idx = np.flatnonzero(mask)
    den_m = np.maximum(den.ravel()[idx], 1e-6)
    out = []
    for v in fields:
        v = np.asarray(v, np.float32)
        num = cv2.GaussianBlur(v * valid, (k, k), sigma)
        o = v.copy()
        o.ravel()[idx] = num.ravel()[idx] / den_m
        out.append(o)
    return out
