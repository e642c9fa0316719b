"""Where a frame differs from the no-contact reference by more than the camera noise."""

from __future__ import annotations

import numpy as np

from .._checks import InputError, check_array

__all__ = ["contact_mask", "noise_level"]


def noise_level(frame: np.ndarray, reference: np.ndarray) -> float:
    """Robust standard deviation of the colour difference frame - reference.

    Parameters
    ----------
    frame, reference : (H, W, 3) array_like of uint8 or float
        Same shape; colour channels in any order.

    Returns
    -------
    sigma : float
        Standard deviation of the per-pixel difference summed over channels,
        over the pixels within 4 robust deviations (1.4826 MAD, at least 0.5)
        of the median, in the frames' units: the camera noise where most of
        the frame is out of contact (true for a press). The clipped standard
        deviation avoids the MAD's quantisation on 8-bit frames.

    Raises
    ------
    ShapeError
        For frames of different shapes or not (H, W, 3).
    """
    f = check_array(frame, "frame", [("H", "W", 3)], dtype=np.number).astype(np.float32)
    r = check_array(reference, "reference", [f.shape], dtype=np.number).astype(np.float32)
    d = (f - r).sum(axis=2).ravel()
    med = float(np.median(d))
    s0 = max(1.4826 * float(np.median(np.abs(d - med))), 0.5)   # MAD: robust, but quantised
    core = d[np.abs(d - med) < 4.0 * s0]                         # then the sd of the core
    return float(core.std()) if core.size > 1 else s0


def contact_mask(frame: np.ndarray, reference: np.ndarray, *, k_sigma: float = 6.0,
                 min_area_px: int = 30, sigma: float | None = None) -> np.ndarray:
    """Pixels whose colour change exceeds `k_sigma` noise levels, cleaned of specks.

    Parameters
    ----------
    frame, reference : (H, W, 3) array_like of uint8 or float
    k_sigma : float, default 6.0
        Threshold on the colour-change magnitude (Euclidean over channels),
        in units of the noise level.
    min_area_px : int, default 30
        Connected regions smaller than this are dropped (noise, dust).
    sigma : float, optional
        Noise level (per channel-sum, as :func:`noise_level`); estimated from
        this frame when not given (give the session's own for frames with
        large contacts).

    Returns
    -------
    mask : (H, W) bool ndarray

    Raises
    ------
    ShapeError
        For frames of different shapes.
    InputError
        For a non-positive `k_sigma`.

    Notes
    -----
    The magnitude ``|frame - reference|`` over the three channels is compared
    with ``k_sigma * sigma / sqrt(3)`` (a channel sum of three independent
    noises has sd sqrt(3) times one channel's), after a 3 x 3 median filter
    that removes isolated hot pixels; then a morphological opening and the
    area filter (scipy.ndimage).
    """
    from scipy import ndimage

    if not k_sigma > 0:
        raise InputError(f"k_sigma must be positive, got {k_sigma!r}")
    f = check_array(frame, "frame", [("H", "W", 3)], dtype=np.number).astype(np.float32)
    r = check_array(reference, "reference", [f.shape], dtype=np.number).astype(np.float32)
    s = noise_level(f, r) if sigma is None else float(sigma)
    s = max(s, 1e-6)
    mag = np.sqrt(((f - r) ** 2).sum(axis=2))
    mag = ndimage.median_filter(mag, size=3)
    mask = mag > k_sigma * s / np.sqrt(3.0)
    mask = ndimage.binary_opening(mask, structure=np.ones((3, 3), bool))
    labels, n = ndimage.label(mask)
    if n:
        sizes = ndimage.sum(mask, labels, index=np.arange(1, n + 1))
        keep = np.concatenate([[False], sizes >= min_area_px])
        mask = keep[labels]
    return mask
