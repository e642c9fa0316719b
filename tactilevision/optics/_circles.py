"""Contact-circle detection in ball-press frames.

The rim of a ball contact is where the gel leaves the ball: the surface slope
drops abruptly, so the colour changes fastest there. The detector finds a
rough blob of strong colour difference against the reference, then fits a
circle to the strongest colour edge along rays from the blob centre (robust
least squares, three rounds).
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy.ndimage import map_coordinates

from .._checks import InputError, check_array
from ._features import channel_magnitude

__all__ = ["detect_contact_circle", "detect_contact_circles", "fit_circle"]


def fit_circle(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float]:
    """Algebraic least-squares circle through points (Kasa fit).

    Parameters
    ----------
    x, y : (M,) float ndarray
        Point coordinates, M >= 3.

    Returns
    -------
    cx, cy, r : float
        Centre and radius.
    """
    a = np.stack([x, y, np.ones_like(x)], axis=1)
    sol = np.linalg.lstsq(a, x * x + y * y, rcond=None)[0]
    cx, cy = sol[0] / 2.0, sol[1] / 2.0
    return float(cx), float(cy), float(np.sqrt(max(sol[2] + cx * cx + cy * cy, 0.0)))


def _fill_holes(mask: np.ndarray) -> np.ndarray:
    """Fill the holes of a binary blob (flood the background from the border)."""
    h, w = mask.shape
    flood = np.pad(mask, 1).astype(np.uint8)
    cv2.floodFill(flood, np.zeros((h + 4, w + 4), np.uint8), (0, 0), 1)
    return mask.astype(bool) | (flood[1:-1, 1:-1] == 0)


def detect_contact_circle(frame: np.ndarray, reference: np.ndarray, *,
                          n_rays: int = 90, iterations: int = 3, blob_fraction: float = 0.2,
                          min_change: float = 12.0
                          ) -> tuple[np.ndarray, float]:
    """Find the contact circle of one ball press.

    Parameters
    ----------
    frame, reference : (H, W, 3) uint8 ndarray
        Ball-press frame and no-contact reference, BGR.
    n_rays : int, default 90
        Rays along which the colour edge is searched.
    iterations : int, default 3
        Refinement rounds (new centre, new rays); 0 returns the blob's
        centroid and equivalent radius.
    blob_fraction : float, default 0.2
        The rough blob is where the colour difference exceeds this fraction
        of its 99.9th percentile (and 6 noise sigmas).
    min_change : float, default 12.0
        A frame whose 99.9th-percentile colour difference (8-bit counts)
        is below this, or below 4 noise sigmas, has no contact.

    Returns
    -------
    centre : (2,) float64 ndarray
        (x = column, y = row), px.
    radius : float
        Circle radius, px: where the colour change falls fastest going
        outwards, the outer edge of the visible contact. On the 48 GelSight
        frames of ``taxim`` it lies 7.3 +- 1.7 px (mean +- std) outside the
        hand-annotated circles (radius about 61 px), whose centres it
        matches to a median of 2.6 px: use a fraction of it (0.85) for
        calibration labels.

    Raises
    ------
    ValueError
        If no region of colour change is found (a frame without contact).
    """
    frame = check_array(frame, "frame", [("H", "W", 3)], dtype=np.uint8)
    reference = check_array(reference, "reference", [frame.shape], dtype=np.uint8)
    # absolute colour difference (not the ratio): the dark corners of a pad
    # give large, noisy ratios but small differences
    change = (cv2.GaussianBlur(frame, (0, 0), 1.5).astype(np.float32)
              - cv2.GaussianBlur(reference, (0, 0), 1.5).astype(np.float32))
    change -= np.median(change[::4, ::4].reshape(-1, 3), axis=0)
    mag = channel_magnitude(change)
    peak = float(np.percentile(mag, 99.9))
    noise = 1.4826 * float(np.median(np.abs(mag - np.median(mag))))
    if peak < max(min_change, 4.0 * noise):
        raise InputError(f"no contact found in frame (largest colour change {peak:.1f} is "
                         f"below {max(min_change, 4.0 * noise):.1f})")
    bw = (mag > max(blob_fraction * peak, 6.0 * noise)).astype(np.uint8)
    k = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (9, 9))
    bw = cv2.morphologyEx(bw, cv2.MORPH_CLOSE, k)
    n, labels, stats, _ = cv2.connectedComponentsWithStats(bw)
    if n < 2 or peak <= 0:
        raise InputError("no contact found in frame (no colour change against the reference)")
    k = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    blob = _fill_holes((labels == k).astype(np.uint8))
    ys, xs = np.nonzero(blob)
    cx, cy = float(xs.mean()), float(ys.mean())
    r0 = float(np.sqrt(blob.sum() / np.pi))
    if r0 < 3:
        raise InputError("no contact found in frame (colour change smaller than 3 px)")
    if iterations == 0:
        return np.array([cx, cy]), r0
    # the rim: where the colour change falls fastest going outwards (inner
    # edges between the coloured lobes of the contact do not fall)
    norm = np.sqrt(np.sum(change * change, axis=-1))
    theta = np.linspace(0.0, 2.0 * np.pi, n_rays, endpoint=False)
    rows = np.arange(n_rays)
    for _ in range(iterations):
        rs = np.arange(0.5 * r0, 1.5 * r0, 0.5)
        xs = cx + np.cos(theta)[:, None] * rs[None, :]
        ys = cy + np.sin(theta)[:, None] * rs[None, :]
        prof = map_coordinates(norm, [ys.ravel(), xs.ravel()], order=1, mode="nearest")
        fall = np.gradient(prof.reshape(xs.shape), axis=1)
        j = fall.argmin(axis=1)
        px, py = xs[rows, j], ys[rows, j]
        cx, cy, r0 = fit_circle(px, py)
        dist = np.abs(np.hypot(px - cx, py - cy) - r0)
        keep = dist <= np.percentile(dist, 70)
        cx, cy, r0 = fit_circle(px[keep], py[keep])
    return np.array([cx, cy]), float(r0)


def detect_contact_circles(frames: np.ndarray, reference: np.ndarray
                           ) -> tuple[np.ndarray, np.ndarray]:
    """Contact circles of a batch of ball presses.

    Parameters
    ----------
    frames : (N, H, W, 3) uint8 ndarray
        Ball-press frames, BGR.
    reference : (H, W, 3) uint8 ndarray
        No-contact reference frame, BGR.

    Returns
    -------
    centres : (N, 2) float64 ndarray
        (x, y) per press, px.
    radii : (N,) float64 ndarray
        Radii, px (see :func:`detect_contact_circle`).

    Raises
    ------
    ValueError
        Naming the index of a frame where no contact is found.
    """
    frames = check_array(frames, "frames", [("N", "H", "W", 3)], dtype=np.uint8)
    centres = np.zeros((len(frames), 2))
    radii = np.zeros(len(frames))
    for i, f in enumerate(frames):
        try:
            centres[i], radii[i] = detect_contact_circle(f, reference)
        except ValueError as exc:
            raise InputError(f"frames[{i}]: {exc}") from None
    return centres, radii
