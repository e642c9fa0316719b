"""Only ball presses are ball presses: a frame whose contact is not the stated ball's is
refused before a calibration trains on it or scores it.

Each press is read by a colour table built from the *other* presses (leave one out: the
table's bins summed over every press, less the press's own), and the surface normals it
gives inside 0.8 of the press's circle are compared with the ball's there. A ball press
reads like the others; a ring, a flat punch or a screw head, whose colours mean other
slopes at other places, reads several times farther off than the set's median. The
table is colour-only and coarse (16 bins a channel): it is a screen, not a calibration.
"""

from __future__ import annotations

import numpy as np

from .._checks import InputError
from ._ball import ball_gradients, normals_from_gradients
from ._features import colour_change, reference_inverse

__all__ = ["NON_BALL_FLOOR_DEG", "NON_BALL_RATIO", "ball_press_angles", "non_ball_presses"]

#: A press is refused when its leave-one-out angle exceeds this many times the set's
#: median... On real ball presses the largest was 2.5 times the median with circles
#: annotated by hand and 3.0 with detected ones (taxim's 48 GelSight presses: 12.7 and
#: 15.6 deg against 5.0 and 5.2), 2.4 on the shared GelSight Mini's 22, 2.0 and 1.6 on
#: GelSlim 3.0's 75 and 39 (circles detected); Taxim's renders of a ring, a flat punch and a
#: slotted screw head among 12 of its ball presses and a cone read 7.1 to 13.0 times the
#: median with the circles drawn for them and 4.9 to 6.1 with detected ones (issue 55).
NON_BALL_RATIO = 3.5
#: ... and this many degrees (a set read within a few degrees is not held to a few more).
NON_BALL_FLOOR_DEG = 12.0
#: Only this share of a press's disc inside 0.8 of its radius (pixels in colour bins the
#: other presses fill) lets it be scored at all.
_MIN_COVERED = 0.2


def _checked_pixels(reference, frames, centers_px, radii_px, ball_radius_px) -> list:
    """:func:`_press_pixels` of at least two presses, their circles as float arrays."""
    if len(frames) < 2:
        raise InputError("checking the presses needs at least two")
    return _press_pixels(reference, frames, np.asarray(centers_px, np.float64).reshape(-1, 2),
                         np.asarray(radii_px, np.float64).reshape(-1),
                         np.asarray(ball_radius_px, np.float64).reshape(-1))


def _press_pixels(reference: np.ndarray, frames: np.ndarray, centers_px: np.ndarray,
                  radii_px: np.ndarray, ball_radius_px: np.ndarray):
    """Each press's colour change and the ball's in-plane normal inside 0.8 of its
    circle."""
    ri = reference_inverse(reference)
    shape = reference.shape[:2]
    out = []
    for i, frame in enumerate(frames):
        r = float(min(radii_px[i], 0.999 * ball_radius_px[i]))
        gx, gy, inside = ball_gradients(shape, tuple(centers_px[i]), r, float(ball_radius_px[i]))
        yy, xx = np.nonzero(inside)
        rho = np.hypot(xx - centers_px[i][0], yy - centers_px[i][1])
        keep = rho < 0.8 * r
        yy, xx = yy[keep], xx[keep]
        n = normals_from_gradients(gx[yy, xx], gy[yy, xx])
        out.append((colour_change(frame, ri)[yy, xx], n[:, :2].astype(np.float64)))
    return out


def ball_press_angles(reference: np.ndarray, frames: np.ndarray, centers_px: np.ndarray,
                      radii_px: np.ndarray, ball_radius_px: np.ndarray, *, bins: int = 16
                      ) -> np.ndarray:
    """Each press's median normal angle inside 0.8 of its circle, read by a colour table
    of the other presses (module docstring).

    Parameters
    ----------
    reference : (H, W, 3) uint8 ndarray
        No-contact frame, BGR.
    frames : (N, H, W, 3) uint8 ndarray
        The presses, BGR (N >= 2).
    centers_px : (N, 2) float ndarray
        Contact-circle centres (x, y), px.
    radii_px : (N,) float ndarray
        Contact-circle radii, px.
    ball_radius_px : (N,) float ndarray
        Each press's ball radius, px.
    bins : int, default 16
        Table cells per colour channel.

    Returns
    -------
    angle_deg : (N,) float64 ndarray
        Median angle, degrees; NaN where under a fifth of the disc falls in colour bins
        the other presses fill (a contact unlike any other: refused by
        :func:`non_ball_presses` too).

    Raises
    ------
    InputError
        With fewer than two presses.
    """
    per = _checked_pixels(reference, frames, centers_px, radii_px, ball_radius_px)
    return _table_angles(per, np.ones(len(per), bool), bins)


def _table_angles(per: list, member: np.ndarray, bins: int = 16) -> np.ndarray:
    """Each press's median angle read by the colour table of the `member` presses, less
    its own pixels where it is one (the table's bins summed once; each press's taken off)."""
    table = [c for (c, _), m in zip(per, member, strict=True) if m]
    allc = np.concatenate(table) if table else np.zeros((0, 3))
    if allc.shape[0] == 0:
        return np.full(len(per), np.nan)
    lo, hi = np.percentile(allc, 0.5, axis=0), np.percentile(allc, 99.5, axis=0)
    span = np.maximum(hi - lo, 1e-9)
    m = bins ** 3
    cells, sums = [], np.zeros((3, m))
    for (c, n), mem in zip(per, member, strict=True):
        q = np.clip(((c - lo) / span * bins).astype(np.int64), 0, bins - 1)
        k = (q[:, 0] * bins + q[:, 1]) * bins + q[:, 2]
        own = np.stack([np.bincount(k, minlength=m), np.bincount(k, n[:, 0], m),
                        np.bincount(k, n[:, 1], m)])
        cells.append((k, own if mem else 0.0))
        if mem:
            sums += own
    out = np.full(len(per), np.nan)
    for i, ((k, own), (_, n)) in enumerate(zip(cells, per, strict=True)):
        rest = sums - own
        sel = rest[0][k] > 0
        if k.size == 0 or sel.mean() < _MIN_COVERED:
            continue
        kk = k[sel]
        nx, ny = rest[1][kk] / rest[0][kk], rest[2][kk] / rest[0][kk]
        nz = np.sqrt(np.clip(1.0 - nx * nx - ny * ny, 0.0, 1.0))
        tx, ty = n[sel, 0], n[sel, 1]
        tz = np.sqrt(np.clip(1.0 - tx * tx - ty * ty, 0.0, 1.0))
        dot = (nx * tx + ny * ty + nz * tz) / np.maximum(np.sqrt(nx * nx + ny * ny + nz * nz),
                                                         1e-12)
        out[i] = float(np.median(np.degrees(np.arccos(np.clip(dot, -1.0, 1.0)))))
    return out


def non_ball_presses(reference: np.ndarray, frames: np.ndarray, centers_px: np.ndarray,
                     radii_px: np.ndarray, ball_radius_px: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, float]:
    """The presses whose contact is not the stated ball's.

    :func:`ball_press_angles`' reading twice: by the table of every press, then by the
    table of those it did not refuse (a refused press's colours no longer in the table
    that reads the others; each refused press read again by the kept ones' table).

    Parameters
    ----------
    reference, frames, centers_px, radii_px, ball_radius_px
        As :func:`ball_press_angles`.

    Returns
    -------
    refused : (N,) bool ndarray
        Angle above ``max(NON_BALL_RATIO x median, NON_BALL_FLOOR_DEG)`` (the median over
        the kept presses), or not readable at all (NaN).
    angle_deg : (N,) float64 ndarray
        Each press's angle, the second round's.
    threshold_deg : float
        The angle above which a press was refused.

    Raises
    ------
    InputError
        With fewer than two presses.
    """
    per = _checked_pixels(reference, frames, centers_px, radii_px, ball_radius_px)
    ang = _table_angles(per, np.ones(len(per), bool))

    def cut(a: np.ndarray) -> float:
        return max(NON_BALL_RATIO * float(np.nanmedian(a)), NON_BALL_FLOOR_DEG)

    refused = ~(ang <= cut(ang))
    kept = np.flatnonzero(~refused)
    if refused.any() and kept.size >= 2:
        # the kept presses' table: each kept press less its own pixels, each refused one
        # read by it whole
        ang = _table_angles(per, ~refused)
        refused = ~(ang <= cut(ang[kept]))
    if np.all(np.isnan(ang)):
        return refused, ang, float("nan")
    return refused, ang, cut(ang[~refused]) if (~refused).any() else float("nan")
