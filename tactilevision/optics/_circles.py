"""Contact-circle detection in ball-press frames.

The rim of a ball contact is where the gel leaves the ball: inside, the tilt
grows with the distance from the centre; outside, it falls. The detector finds
a rough blob of strong colour difference against the reference, then fits a
circle to the strongest fall of the colour change along rays from the blob
centre (robust least squares, three rounds): the *colour edge*, a few pixels
outside the contact. :func:`locate_contact_edge` moves it in to the *contact
edge*, the shoulder where the colour change stops growing and begins to fall.
"""

from __future__ import annotations

import warnings
from typing import Literal

import cv2
import numpy as np
from scipy.ndimage import gaussian_filter1d, map_coordinates

from .._checks import InputError, check_array
from ._features import channel_magnitude

__all__ = ["detect_contact_circle", "detect_contact_circles", "fit_circle",
           "locate_contact_edge"]

EdgeKind = Literal["colour", "contact"]


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


def _colour_difference(frame: np.ndarray, reference: np.ndarray, sigma: float) -> np.ndarray:
    """Frame less reference (H, W, 3) float32, both blurred by `sigma` px (0: not blurred),
    less the median difference (a global brightness change is no contact)."""
    if sigma > 0:
        frame = cv2.GaussianBlur(frame, (0, 0), sigma)
        reference = cv2.GaussianBlur(reference, (0, 0), sigma)
    change = frame.astype(np.float32) - reference.astype(np.float32)
    change -= np.median(change[::4, ::4].reshape(-1, 3), axis=0)
    return change


def _fill_holes(mask: np.ndarray) -> np.ndarray:
    """Fill the holes of a binary blob (flood the background from the border)."""
    h, w = mask.shape
    flood = np.pad(mask, 1).astype(np.uint8)
    cv2.floodFill(flood, np.zeros((h + 4, w + 4), np.uint8), (0, 0), 1)
    return mask.astype(bool) | (flood[1:-1, 1:-1] == 0)


def detect_contact_circle(frame: np.ndarray, reference: np.ndarray, *,
                          n_rays: int = 90, iterations: int = 3, blob_fraction: float = 0.2,
                          min_change: float = 12.0, edge: EdgeKind = "colour"
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
        of its 99.9th percentile (and 6 noise sigmas); of several such regions,
        the one of strongest change (the sum of the squared excess over that
        threshold), so that a wide faint change (a reference a few levels off)
        is not taken for a small contact.
    min_change : float, default 12.0
        A frame whose 99.9th-percentile colour difference (8-bit counts)
        is below this, or below 4 noise sigmas, has no contact.
    edge : {'colour', 'contact'}, default 'colour'
        Which circle to return: ``'colour'``, where the colour change falls
        fastest going outwards, the outer edge of the visible contact; or
        ``'contact'``, that circle moved in to the contact edge by
        :func:`locate_contact_edge`.

    Returns
    -------
    centre : (2,) float64 ndarray
        (x = column, y = row), px.
    radius : float
        Circle radius, px. The colour edge: on the 48 GelSight frames of
        ``taxim`` it lies 7.3 +- 1.7 px (mean +- std) outside the
        hand-annotated circles (radius about 61 px), whose centres it
        matches to a median of 2.6 px. The contact edge: see
        :func:`locate_contact_edge`.

    Raises
    ------
    ValueError
        If no region of colour change is found (a frame without contact),
        or, for ``edge='contact'``, no contact edge.
    """
    if edge not in ("colour", "contact"):
        raise InputError(f"edge must be 'colour' or 'contact', got {edge!r}")
    frame = check_array(frame, "frame", [("H", "W", 3)], dtype=np.uint8)
    reference = check_array(reference, "reference", [frame.shape], dtype=np.uint8)
    # absolute colour difference (not the ratio): the dark corners of a pad
    # give large, noisy ratios but small differences
    change = _colour_difference(frame, reference, 1.5)
    mag = channel_magnitude(change)
    peak = float(np.percentile(mag, 99.9))
    noise = 1.4826 * float(np.median(np.abs(mag - np.median(mag))))
    if peak < max(min_change, 4.0 * noise):
        raise InputError(f"no contact found in frame (largest colour change {peak:.1f} is "
                         f"below {max(min_change, 4.0 * noise):.1f})")
    bw = (mag > max(blob_fraction * peak, 6.0 * noise)).astype(np.uint8)
    k = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (9, 9))
    bw = cv2.morphologyEx(bw, cv2.MORPH_CLOSE, k)
    n, labels = cv2.connectedComponents(bw)
    if n < 2 or peak <= 0:
        raise InputError("no contact found in frame (no colour change against the reference)")
    # the contact is the region of strongest change, not the widest: a reference a few
    # levels off over wide patches (lighting drift; Taxim's renderer, up to 14 levels)
    # makes large faint regions, a contact a compact strong one
    thr = max(blob_fraction * peak, 6.0 * noise)
    excess = np.bincount(labels.ravel(), np.maximum(mag - thr, 0.0).ravel() ** 2,
                         minlength=n)
    k = 1 + int(np.argmax(excess[1:]))
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
    if edge == "contact":
        return locate_contact_edge(frame, reference, (cx, cy), r0)
    return np.array([cx, cy]), float(r0)


def detect_contact_circles(frames: np.ndarray, reference: np.ndarray, *,
                           edge: EdgeKind = "colour") -> tuple[np.ndarray, np.ndarray]:
    """Contact circles of a batch of ball presses.

    Parameters
    ----------
    frames : (N, H, W, 3) uint8 ndarray
        Ball-press frames, BGR.
    reference : (H, W, 3) uint8 ndarray
        No-contact reference frame, BGR.
    edge : {'colour', 'contact'}, default 'colour'
        The colour edge or the contact edge (:func:`detect_contact_circle`,
        :func:`locate_contact_edge`). A press whose contact edge is not found
        (too few of its rays inside the image) keeps its colour-edge circle
        scaled by the median ratio of contact to colour radius over the
        others, with a warning naming it.

    Returns
    -------
    centres : (N, 2) float64 ndarray
        (x, y) per press, px.
    radii : (N,) float64 ndarray
        Radii, px (see :func:`detect_contact_circle`).

    Raises
    ------
    ValueError
        Naming the index of a frame where no contact is found, or, for
        ``edge='contact'``, saying that no press's contact edge was found (an
        ``InputError``).
    """
    if edge not in ("colour", "contact"):
        raise InputError(f"edge must be 'colour' or 'contact', got {edge!r}")
    frames = check_array(frames, "frames", [("N", "H", "W", 3)], dtype=np.uint8)
    centres = np.zeros((len(frames), 2))
    radii = np.zeros(len(frames))
    for i, f in enumerate(frames):
        try:
            centres[i], radii[i] = detect_contact_circle(f, reference)
        except ValueError as exc:
            raise InputError(f"frames[{i}]: {exc}") from None
    if edge == "colour":
        return centres, radii
    located = np.zeros(len(frames), bool)
    ratio = np.ones(len(frames))
    for i, f in enumerate(frames):
        try:
            c, r = locate_contact_edge(f, reference, centres[i], radii[i])
        except ValueError:
            continue
        ratio[i] = r / radii[i]
        centres[i], radii[i], located[i] = c, r, True
    if not located.any():
        raise InputError(f"no contact edge found on any of the {len(frames)} presses")
    if not located.all():
        missed = np.flatnonzero(~located)
        radii[missed] *= float(np.median(ratio[located]))
        warnings.warn(f"contact edge not found on frames {missed.tolist()}: their colour-edge "
                      f"circles scaled by the median ratio {np.median(ratio[located]):.3f} of "
                      "the others", stacklevel=2)
    return centres, radii


def locate_contact_edge(frame: np.ndarray, reference: np.ndarray,
                        centre_px: tuple[float, float] | np.ndarray, radius_px: float, *,
                        shoulder: float = 0.03, floor: float = 0.85, n_rays: int = 120,
                        iterations: int = 2, sigma: float = 1.0,
                        change: np.ndarray | None = None) -> tuple[np.ndarray, float]:
    """Move a ball press's colour-edge circle in to the contact edge.

    Inside the contact the gel takes the ball's shape and its tilt grows
    outwards; where the gel leaves the ball the tilt is largest, and beyond
    it falls. Along a ray from the centre the colour change against the
    reference therefore grows, levels off at a shoulder and then falls; the
    fall's steepest point (the colour edge, :func:`detect_contact_circle`)
    lies outside the contact by the width of the fall. The contact edge is
    taken at the shoulder: the outermost point before the steepest fall at
    which the colour change is still within `shoulder` of its largest value
    on that ray. A circle is fitted to those points over `n_rays` rays
    (robust least squares: the 70 % nearest the first fit), and the rays are
    cast again from its centre.

    A blurred image moves the colour's peak, and so the shoulder, inwards by
    about the blur's width: on the GelSlim 3.0 frames (contacts about 25 px
    across their radius, blurred over several px) the shoulder lies at 0.76
    of the colour edge (median over set_2020_11's presses) against 0.90 on
    the sharp GelSight frames of ``taxim``, where it matches the annotated
    circles. The radius is therefore never put inside ``floor`` times the
    first radius: 0.85, the fraction of the colour edge that calibrations
    labelled before the contact edge was located.

    Parameters
    ----------
    frame, reference : (H, W, 3) uint8 ndarray
        Ball-press frame and no-contact reference, BGR.
    centre_px : (2,) float
        A first centre (x = column, y = row), px: the colour edge's.
    radius_px : float
        A first radius, px: the colour edge's (the steepest fall is searched
        within 20 % of it).
    shoulder : float, default 0.03
        Relative drop from the ray's largest colour change that ends the
        shoulder. Measured on the 48 real GelSight presses of ``taxim``
        against their hand-annotated circles: 0.02 gives 0.993, 0.03 1.005,
        0.05 1.022 of the annotated radius (median over presses; sd 0.022);
        the colour edge lies at 1.115 (``benchmarks/bench_contact_edge.py``).
        On presses drawn by Taxim's renderer without shadows, 0.03 gives
        1.010 (sd 0.058) of the radius where Taxim's own gel leaves the ball.
    floor : float, default 0.85
        The smallest radius returned, as a fraction of `radius_px`; 0 turns
        the bound off.
    n_rays : int, default 120
        Rays cast from the centre.
    iterations : int, default 2
        Rounds of rays and circle fit.
    sigma : float, default 1.0
        Gaussian blur (px) of frame and reference before the colour change.
    change : (H, W, 3) float ndarray, optional
        The colour change to read instead of the frame less the reference (less their
        median difference): e.g. :func:`~tactilevision.optics.drift_free_change`'s, a
        global drift of brightness and colour taken off (`sigma` is then not used).

    Returns
    -------
    centre : (2,) float64 ndarray
        Contact-edge centre (x, y), px.
    radius : float
        Contact-edge radius, px.

    Raises
    ------
    ValueError
        If fewer than 12 rays reach the colour edge inside the image or the
        shoulder is not found on them (an ``InputError``).
    """
    frame = check_array(frame, "frame", [("H", "W", 3)], dtype=np.uint8)
    reference = check_array(reference, "reference", [frame.shape], dtype=np.uint8)
    if not (np.isfinite(radius_px) and radius_px > 2):
        raise InputError(f"radius_px must be a finite radius above 2 px, got {radius_px!r}")
    if not 0 < shoulder < 1:
        raise InputError(f"shoulder must lie in (0, 1), got {shoulder!r}")
    if not 0 <= floor <= 1:
        raise InputError(f"floor must lie in [0, 1], got {floor!r}")
    if change is None:
        change = _colour_difference(frame, reference, sigma)
    else:
        change = check_array(change, "change", [frame.shape])
    norm = np.sqrt(np.sum(change * change, axis=-1))
    h, w = norm.shape
    theta = np.linspace(0.0, 2.0 * np.pi, n_rays, endpoint=False)
    rows = np.arange(n_rays)
    cx, cy, rc = float(centre_px[0]), float(centre_px[1]), float(radius_px)
    step = 0.25                                   # px along each ray
    for _ in range(iterations):
        rs = np.arange(0.5 * rc, 1.4 * rc, step)      # about the colour edge, each round
        xs = cx + np.cos(theta)[:, None] * rs[None, :]
        ys = cy + np.sin(theta)[:, None] * rs[None, :]
        prof = map_coordinates(norm, [ys.ravel(), xs.ravel()], order=1,
                               mode="nearest").reshape(xs.shape)
        prof = gaussian_filter1d(prof, 0.5 / step, axis=1)          # 0.5 px along the ray
        inside = (xs >= 0) & (xs <= w - 1) & (ys >= 0) & (ys <= h - 1)
        # samples up to the first one outside the image
        in_run = np.cumprod(inside, axis=1).astype(bool)
        fall = np.gradient(prof, axis=1)
        near = np.abs(rs - rc) <= 0.2 * rc
        window = in_run & near[None, :]
        jf = np.where(window, fall, np.inf).argmin(axis=1)
        j = np.arange(rs.size)[None, :]
        before = j <= jf[:, None]
        jp = np.where(before, prof, -np.inf).argmax(axis=1)
        peak = prof[rows, jp]
        ok = (window[rows, jf] & in_run[rows, np.minimum(jf + 8, rs.size - 1)]
              & (fall[rows, jf] < 0) & (jp > 0))
        on = before & (j >= jp[:, None]) & (prof >= (1.0 - shoulder) * peak[:, None])
        js = np.where(on, j, -1).max(axis=1)
        ok &= js > 0
        if np.count_nonzero(ok) < 12:
            raise InputError(f"no contact edge found: {np.count_nonzero(ok)} of {n_rays} rays "
                             "reach the colour edge inside the image (12 needed)")
        px, py = xs[rows, js][ok], ys[rows, js][ok]
        cx, cy, r0 = fit_circle(px, py)
        dist = np.abs(np.hypot(px - cx, py - cy) - r0)
        keep = dist <= np.percentile(dist, 70)
        cx, cy, r0 = fit_circle(px[keep], py[keep])
    return np.array([cx, cy]), float(max(r0, floor * rc))
