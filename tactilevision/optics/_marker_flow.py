"""Marker tracking: dot centres, their motion between frames, a dense lateral field.

Gels with a grid of dark markers show the lateral (in-plane) motion of the gel
surface that photometric stereo cannot see. Three steps, each a pure function:

1. :func:`marker_centres`: the dots of a frame (the mask of :func:`marker_mask`, connected
   components of plausible area, darkness-weighted centroids);
2. :func:`track_markers`: each reference dot followed into a frame by pyramidal
   Lucas-Kanade optical flow (OpenCV), checked by tracking back;
3. :func:`lateral_displacement`: the valid tracks interpolated to every pixel,
   in mm, the ``lateral_mm`` of :class:`~tactilevision.fem.ForceEstimator`
   with ``mode='full'``.

Sign convention (the force estimator's): x along columns (positive to the
right), y along rows (positive down); a displacement is where a point of the
gel surface is in the frame minus where it was in the reference.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from scipy.interpolate import LinearNDInterpolator, NearestNDInterpolator, RBFInterpolator

from .._checks import InputError, check_array, check_positive
from ._markers import _mask_from, grey_and_background

__all__ = ["MarkerFlow", "lateral_displacement", "marker_centres", "track_markers"]


@dataclass(frozen=True)
class MarkerFlow:
    """Marker tracks from a reference frame into one frame.

    Attributes
    ----------
    positions_px : (M, 2) float32 ndarray
        Marker centres in the reference, (x = column, y = row), px.
    displacement_px : (M, 2) float32 ndarray
        Position in the frame minus position in the reference, (dx, dy), px;
        NaN where the track was lost.
    valid : (M,) bool ndarray
        Tracks that Lucas-Kanade kept, that stay inside the image and that
        come back within ``max_fb_px`` of their start when tracked back.
    fb_error_px : (M,) float32 ndarray
        Forward-backward error: distance between the start and the end of
        the track followed back from the frame to the reference, px; inf
        where either direction was lost.
    """

    positions_px: np.ndarray
    displacement_px: np.ndarray
    valid: np.ndarray
    fb_error_px: np.ndarray


def _contrast_image(frame: np.ndarray, size_px: int) -> np.ndarray:
    """(H, W) uint8: grey over its closing (the local background without dots), x 255."""
    grey, background = grey_and_background(frame, size_px)
    ratio = grey * (255.0 / np.maximum(background, 1.0))
    return np.clip(ratio, 0, 255).astype(np.uint8)


def marker_centres(frame: np.ndarray, *, size_px: int = 11, contrast: float = 0.25,
                   min_area_px: int = 8, max_area_px: int | None = None) -> np.ndarray:
    """Centres of the dark marker dots of a frame.

    Parameters
    ----------
    frame : (H, W, 3) uint8 ndarray
        Frame, BGR.
    size_px : int, default 11
        Closing kernel of :func:`marker_mask`: larger than a dot, smaller
        than the dot spacing.
    contrast : float, default 0.25
        Darkness threshold of :func:`marker_mask`.
    min_area_px : int, default 8
        Smaller blobs (noise, fragments of dots cut by the image border)
        are dropped.
    max_area_px : int, optional
        Larger blobs (dots merged with a dark patch) are dropped; default
        ``size_px ** 2``, the most a dot the closing can find covers.

    Returns
    -------
    centres : (M, 2) float32 ndarray
        (x = column, y = row) of each dot, px, in row-major order of the
        blobs' first pixels: the centroid of the blob (the mask grown by one
        pixel) weighted by the darkness ``closing(grey) - grey``, which
        gives sub-pixel centres. Blobs touching the image border are
        dropped (their centroid is biased). M may be 0.

    Raises
    ------
    ShapeError
        If `frame` is not (H, W, 3) uint8.
    InputError
        If `size_px` is not an odd integer >= 3 or the area bounds are not
        positive with ``min_area_px <= max_area_px``.

    Examples
    --------
    >>> import cv2, numpy as np
    >>> img = np.full((40, 60, 3), 200, np.uint8)
    >>> _ = cv2.circle(img, (20, 15), 3, (40, 40, 40), -1)
    >>> marker_centres(img).round(2).tolist()
    [[20.0, 15.0]]
    """
    frame = check_array(frame, "frame", [("H", "W", 3)], dtype=np.uint8)
    if int(size_px) != size_px or size_px < 3 or size_px % 2 == 0:
        raise InputError(f"size_px must be an odd integer >= 3, got {size_px!r}")
    max_area = size_px * size_px if max_area_px is None else max_area_px
    if not (0 < min_area_px <= max_area):
        raise InputError(f"need 0 < min_area_px <= max_area_px, got {min_area_px!r} and "
                         f"{max_area!r}")
    grey, background = grey_and_background(frame, size_px)
    mask = _mask_from(grey, background, contrast, 1)
    n, labels, stats, _ = cv2.connectedComponentsWithStats(mask.astype(np.uint8),
                                                           connectivity=8)
    if n < 2:
        return np.zeros((0, 2), np.float32)
    dark = np.maximum(background - grey, 0.0)
    dark = np.where(mask, dark, 0.0).ravel().astype(np.float64) + 1e-9 * mask.ravel()
    h, w = mask.shape
    rows, cols = np.indices((h, w))
    lab = labels.ravel()
    sw = np.bincount(lab, dark, minlength=n)
    cx = np.bincount(lab, dark * cols.ravel(), minlength=n) / np.maximum(sw, 1e-300)
    cy = np.bincount(lab, dark * rows.ravel(), minlength=n) / np.maximum(sw, 1e-300)
    x0, y0 = stats[:, cv2.CC_STAT_LEFT], stats[:, cv2.CC_STAT_TOP]
    x1 = x0 + stats[:, cv2.CC_STAT_WIDTH]
    y1 = y0 + stats[:, cv2.CC_STAT_HEIGHT]
    area = stats[:, cv2.CC_STAT_AREA]
    keep = ((area >= min_area_px) & (area <= max_area) & (x0 > 0) & (y0 > 0)
            & (x1 < w) & (y1 < h))
    keep[0] = False  # the background label
    return np.column_stack([cx[keep], cy[keep]]).astype(np.float32)


def track_markers(reference: np.ndarray, frame: np.ndarray, *,
                  positions_px: np.ndarray | None = None, window_px: int = 15,
                  levels: int = 2, max_fb_px: float = 0.5, normalise: bool = True,
                  size_px: int = 11) -> MarkerFlow:
    """Follow the reference's markers into a frame (pyramidal Lucas-Kanade).

    Parameters
    ----------
    reference, frame : (H, W, 3) uint8 ndarray
        No-contact reference and the frame, BGR, the same size.
    positions_px : (M, 2) float array_like, optional
        Marker centres in the reference, (x, y) px; default
        :func:`marker_centres` of the reference (with `size_px`).
    window_px : int, default 15
        Lucas-Kanade window side, px: about a dot and its margin, under the
        dot spacing (set_2020_09: dots about 8 x 5 px, 18 to 24 px apart).
    levels : int, default 2
        Pyramid levels above full resolution (motion up to about
        ``window_px * 2 ** levels / 2`` px).
    max_fb_px : float, default 0.5
        Largest forward-backward error of a valid track, px.
    normalise : bool, default True
        Track on the grey image divided by its morphological closing (the
        dots' contrast against the local background) rather than on grey:
        the shading a contact adds changes the brightness around a dot but
        hardly its contrast. On the 39 set_2020_09 presses, grey tracking
        lost 0 to 20 of the 252 dots per press, the contrast image 0 or 1.
    size_px : int, default 11
        Closing kernel for the contrast image and the default centres.

    Returns
    -------
    MarkerFlow

    Raises
    ------
    ShapeError
        If an image is not (H, W, 3) uint8 or the two differ in size, or
        `positions_px` is not (M, 2) finite.
    InputError
        If no marker is found in the reference (or `positions_px` is
        empty), or a parameter is out of range.
    """
    reference = check_array(reference, "reference", [("H", "W", 3)], dtype=np.uint8)
    frame = check_array(frame, "frame", [reference.shape], dtype=np.uint8)
    if int(window_px) != window_px or window_px < 5:
        raise InputError(f"window_px must be an integer >= 5, got {window_px!r}")
    if int(levels) != levels or levels < 0:
        raise InputError(f"levels must be a non-negative integer, got {levels!r}")
    max_fb = check_positive(max_fb_px, "max_fb_px")
    if positions_px is None:
        p0 = marker_centres(reference, size_px=size_px)
        if len(p0) == 0:
            raise InputError("no marker dots found in the reference frame: is this a gel "
                             "with markers? (try a larger size_px or a smaller contrast)")
    else:
        p0 = check_array(positions_px, "positions_px", [(None, 2)], dtype=np.number,
                         finite=True).astype(np.float32)
        if len(p0) == 0:
            raise InputError("positions_px is empty: no markers to track")
    if normalise:
        a, b = _contrast_image(reference, size_px), _contrast_image(frame, size_px)
    else:
        a = cv2.cvtColor(reference, cv2.COLOR_BGR2GRAY)
        b = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
    lk = dict(winSize=(int(window_px), int(window_px)), maxLevel=int(levels),
              criteria=(cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 30, 0.01))
    start = np.ascontiguousarray(p0.reshape(-1, 1, 2))
    p1, st1, _ = cv2.calcOpticalFlowPyrLK(a, b, start, None, **lk)
    back, st2, _ = cv2.calcOpticalFlowPyrLK(b, a, p1, None, **lk)
    p1, back = p1.reshape(-1, 2), back.reshape(-1, 2)
    ok = (st1.ravel() == 1) & (st2.ravel() == 1)
    h, w = reference.shape[:2]
    inside = (p1[:, 0] >= 0) & (p1[:, 0] <= w - 1) & (p1[:, 1] >= 0) & (p1[:, 1] <= h - 1)
    fb = np.where(ok, np.linalg.norm(back - p0, axis=1), np.inf).astype(np.float32)
    valid = ok & inside & (fb <= max_fb)
    disp = np.where(ok[:, None], p1 - p0, np.nan).astype(np.float32)
    return MarkerFlow(positions_px=p0, displacement_px=disp, valid=valid, fb_error_px=fb)


def lateral_displacement(flow: MarkerFlow, shape: tuple[int, int], mm_per_px: float, *,
                         method: str = "tps", smoothing: float = 0.0,
                         step_px: int = 4) -> np.ndarray:
    """Dense lateral displacement of the gel surface from marker tracks.

    Parameters
    ----------
    flow : MarkerFlow
        Tracks of :func:`track_markers`; only the valid ones are used.
    shape : (H, W)
        Image shape, rows and columns.
    mm_per_px : float
        Image scale on the gel, mm per px.
    method : {'tps', 'linear'}, default 'tps'
        'tps': a thin-plate spline through the tracks
        (:class:`scipy.interpolate.RBFInterpolator`, with its affine part),
        smooth everywhere and extended smoothly (to first order) beyond the
        outermost markers. 'linear': piecewise linear on the tracks'
        Delaunay triangles, the nearest track outside their convex hull.
        The spline is the default: the field's derivatives become shear
        traction in :class:`~tactilevision.fem.ForceEstimator`, and the
        linear field's slope jumps at every triangle edge become lines of
        traction (on two set_2020_09 presses the part of the shear traction
        finer than a 3 px Gaussian is 2.2 to 2.4 times larger with it); on
        the smooth synthetic field of ``tests/test_marker_flow.py`` (dots
        20 px apart) the spline is also the more accurate, 0.025 against
        0.065 px rms.
    smoothing : float, default 0.0
        'tps' only: the spline's smoothing (0 interpolates exactly); raise it
        to damp tracking noise.
    step_px : int, default 4
        'tps' only: the spline is evaluated every `step_px` pixels and
        bilinearly resampled to every pixel (1: at every pixel, about 10
        times slower at 427 x 320). The field varies over a dot spacing
        (about 20 px): 4 px against 1 px changes it by at most 0.014 px on
        the synthetic field of the tests and 0.06 to 0.12 px on set_2020_09
        presses that move the gel 4 to 12 px.

    Returns
    -------
    lateral_mm : (H, W, 2) float32 ndarray
        (ux, uy), mm: ux along columns (positive to the right), uy along
        rows (positive down), the surface's position in the frame minus its
        position in the reference.

    Raises
    ------
    ShapeError
        If the arrays of `flow` disagree in length or shape.
    InputError
        For a bad shape, scale, method or step, non-finite valid tracks, or
        fewer than 3 valid tracks ('linear' and 'tps' with its affine part
        need 3 not on one line).
    """
    try:
        H, W = (int(s) for s in shape)
    except (TypeError, ValueError):
        raise InputError(f"shape must be (H, W), got {shape!r}") from None
    if H < 2 or W < 2:
        raise InputError(f"shape must be at least (2, 2), got {shape!r}")
    mm = check_positive(mm_per_px, "mm_per_px")
    if method not in ("tps", "linear"):
        raise InputError(f"method must be 'tps' or 'linear', got {method!r}")
    if int(step_px) != step_px or step_px < 1:
        raise InputError(f"step_px must be a positive integer, got {step_px!r}")
    if not (np.isfinite(smoothing) and smoothing >= 0):
        raise InputError(f"smoothing must be >= 0, got {smoothing!r}")
    pos = check_array(flow.positions_px, "flow.positions_px", [("M", 2)], dtype=np.number)
    disp = check_array(flow.displacement_px, "flow.displacement_px", [(len(pos), 2)],
                       dtype=np.number)
    valid = check_array(flow.valid, "flow.valid", [(len(pos),)], dtype=np.bool_)
    pts = pos[valid].astype(np.float64)
    val = disp[valid].astype(np.float64)
    if not (np.all(np.isfinite(pts)) and np.all(np.isfinite(val))):
        raise InputError("flow holds NaN or inf on tracks marked valid")
    if len(pts) < 3:
        raise InputError(f"need at least 3 valid marker tracks for a lateral field, got "
                         f"{len(pts)}")
    if method == "linear":
        rows, cols = np.mgrid[0:H, 0:W]
        q = np.column_stack([cols.ravel(), rows.ravel()]).astype(np.float64)
        out = LinearNDInterpolator(pts, val)(q)
        hole = ~np.isfinite(out[:, 0])
        if hole.any():
            out[hole] = NearestNDInterpolator(pts, val)(q[hole])
        field = out.reshape(H, W, 2)
    else:
        try:
            rbf = RBFInterpolator(pts, val, kernel="thin_plate_spline",
                                  smoothing=float(smoothing))
        except np.linalg.LinAlgError:
            raise InputError("the valid marker tracks are degenerate (all on one line?)") \
                from None
        xs = np.arange(0, W - 1 + step_px, step_px, dtype=np.float64)
        ys = np.arange(0, H - 1 + step_px, step_px, dtype=np.float64)
        gx, gy = np.meshgrid(xs, ys)
        coarse = rbf(np.column_stack([gx.ravel(), gy.ravel()])).reshape(len(ys), len(xs), 2)
        if step_px == 1:
            field = coarse
        else:
            # pixel (r, c) sits at coarse index (r / step, c / step)
            mx = np.broadcast_to(np.arange(W, dtype=np.float32) / step_px, (H, W))
            my = np.broadcast_to(np.arange(H, dtype=np.float32)[:, None] / step_px, (H, W))
            field = cv2.remap(coarse.astype(np.float32), np.ascontiguousarray(mx),
                              np.ascontiguousarray(my), cv2.INTER_LINEAR)
    return (np.asarray(field, np.float32) * np.float32(mm)).astype(np.float32)
