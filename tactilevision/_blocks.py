"""Blocks of pixels for the contact-pinned heights and the footprint force solve: the block
side a footprint allows, and means over blocks and back (bottom layer: numpy and OpenCV)."""

from __future__ import annotations

import math

import cv2
import numpy as np

from ._errors import InputError

__all__ = ["AUTO_BIN_MAX", "AUTO_BIN_PER_WIDTH", "HEIGHT_BIN_PER_WIDTH", "auto_binning",
           "bin_blocks", "check_binning", "unbin_blocks"]

#: ``binning='auto'``: a frame's footprint solved on blocks whose side is at most its width
#: (twice its area over its perimeter: the radius of a disc) over this. On a flat punch
#: (a = 2.5 mm, h = 3 mm; pixels of 0.03 and 0.05 mm, edges sharp and blurred 1.5 px,
#: ``tests/test_forces_binning.py``) blocks up to a / 20 moved the total by at most 0.4 %
#: against every pixel, blocks of a / 12 by 1 to 4 %.
AUTO_BIN_PER_WIDTH = 20.0

#: ``binning='auto'`` of the contact-pinned heights: blocks at most the contact region's
#: width over this (the region holds the footprint and the sink-in round it: at most the
#: footprint's width over 20 while the footprint is half as wide as the region, or more).
#: On the sample session's hold frames the default path read its totals 0.4 % below every
#: pixel's (median; 0.9 % at most) with this, 0.7 % (1.9 %) with 30 and 1.3 % (3.7 %)
#: with 20 (``python benchmarks/bench_forces_default.py --blocks``).
HEIGHT_BIN_PER_WIDTH = 40.0

#: The largest block ``binning='auto'`` uses, pixels.
AUTO_BIN_MAX = 8


def auto_binning(footprint: np.ndarray, per_width: float = AUTO_BIN_PER_WIDTH) -> int:
    """The block side in pixels ``binning='auto'`` solves a footprint on: the largest k
    with k pixels at most its width over 20 (:data:`AUTO_BIN_PER_WIDTH`), its width twice
    its area over its perimeter (a disc's radius, a strip's half-width), from 1 to 8.

    Parameters
    ----------
    footprint : (H, W) bool ndarray
        The pixels in contact.
    per_width : float, default 20
        The block's side at most the width over this. The contact-pinned heights
        (:class:`~tactilevision.optics.DepthReconstructor`) take 40 of their contact
        region, which holds the footprint and the sink-in round it: blocks at most a
        footprint's width over 20 while the footprint is at least half as wide as the
        region.

    Returns
    -------
    int
        1 for an empty footprint.
    """
    m = np.ascontiguousarray(footprint, np.uint8)
    area = int(np.count_nonzero(m))
    if area == 0:
        return 1
    inner = cv2.erode(m, _CROSS, borderType=cv2.BORDER_CONSTANT, borderValue=0)
    perimeter = area - int(np.count_nonzero(inner))     # pixels with an outside 4-neighbour
    width = 2.0 * area / max(perimeter, 1)
    return int(min(AUTO_BIN_MAX, max(1, math.floor(width / per_width + 1e-9))))


_CROSS = cv2.getStructuringElement(cv2.MORPH_CROSS, (3, 3))


def check_binning(binning: object) -> int | str:
    """A `binning` value checked: 'auto', or a positive whole number (returned as int).

    Raises
    ------
    InputError
        For anything else (a bool, a fraction, zero or less, another string).
    """
    if isinstance(binning, str):
        if binning != "auto":
            raise InputError(f"binning must be 'auto' or a positive integer, got {binning!r}")
        return binning
    try:
        whole = float(binning) == int(binning)
    except (TypeError, ValueError):
        whole = False
    if isinstance(binning, bool) or not whole or int(binning) < 1:
        raise InputError(f"binning must be 'auto' or a positive integer, got {binning!r}")
    return int(binning)


def bin_blocks(a: np.ndarray, k: int, *, edge: str = "repeat") -> np.ndarray:
    """Means over k x k blocks of pixels of one (H, W) map: (ceil(H / k), ceil(W / k)).

    The last row and column of blocks, where H or W is not a multiple of k, over their
    pixels and the map's edge repeated (``edge='repeat'``: a mean over the pixels they
    hold) or zeros (``edge='zero'``: a sum over them, divided by k x k).
    """
    H, W = a.shape
    Hc, Wc = -(-H // k), -(-W // k)
    if (Hc * k, Wc * k) != (H, W):
        border = cv2.BORDER_REPLICATE if edge == "repeat" else cv2.BORDER_CONSTANT
        a = cv2.copyMakeBorder(a, 0, Hc * k - H, 0, Wc * k - W, border, value=0)
    return cv2.resize(a, (Wc, Hc), interpolation=cv2.INTER_AREA)


def unbin_blocks(a: np.ndarray, k: int, shape: tuple[int, int]) -> np.ndarray:
    """Each block's value on its pixels: (Hc, Wc) -> (H, W), float or bool (OpenCV's nearest
    resize by a whole factor repeats each value k x k, a fifth of numpy's two repeats)."""
    H, W = shape
    Hc, Wc = a.shape
    src = a.view(np.uint8) if a.dtype == np.bool_ else a
    out = cv2.resize(src, (Wc * k, Hc * k), interpolation=cv2.INTER_NEAREST)[:H, :W]
    return out.view(np.bool_) if a.dtype == np.bool_ else out
