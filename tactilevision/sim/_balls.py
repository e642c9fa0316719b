"""Ball presses of a simulated sensor, to calibrate its photometric stereo.

A real rig calibrates photometric stereo with a ball pressed into its own
gel; a simulated session's sensor is its shading table, so its optics are
calibrated the same way, on ball presses rendered through that table.
"""

from __future__ import annotations

import cv2
import numpy as np

from .._checks import InputError, check_positive
from ..io import BallPressSet
from ._render import ShadingTable

__all__ = ["render_ball_presses"]


def render_ball_presses(table: ShadingTable, reference: np.ndarray, *, n: int = 24,
                        radius_mm: float = 4.0, depth_mm: tuple[float, float] = (0.2, 2.0),
                        noise_dn: float = 2.0, jpeg_quality: int | None = 75,
                        partial: bool = False, seed: int = 0) -> BallPressSet:
    """Render `n` ball presses at random depths and positions.

    The gel takes the ball's spherical cap inside the contact circle of
    radius ``a = sqrt(2 R d - d^2)`` and stays flat outside it (the rigid-cap
    approximation used for photometric calibration; the circles are exact).

    Parameters
    ----------
    table : ShadingTable
        The sensor's renderer (:func:`taxim_shading`).
    reference : (H, W, 3) uint8 ndarray
        No-contact frame of the table's size.
    n : int, default 24
        Number of presses.
    radius_mm : float, default 4.0
        Ball radius R, mm. The slope at the contact edge is
        ``a / sqrt(R^2 - a^2)``: the defaults reach slopes up to 1.7, which
        a flat punch's edge wall needs (up to 3 at w/h = 0.2) more than the
        2 mm ball of a typical calibration set (under 0.6).
    depth_mm : (lo, hi), default (0.2, 2.0)
        Press depths d, uniform in [lo, hi), mm; ``hi < radius_mm``.
    noise_dn : float, default 2.0
        Camera noise, grey levels.
    jpeg_quality : int or None, default 75
        Re-encode each frame as JPEG at this quality (as recorded); None: raw.
    partial : bool, default False
        False: every contact circle lies inside the image (5 px margin).
        True: only the centres do (5 px margin), so contacts run off the
        image's edges as presses near a real pad's border do, and a
        position-aware model (``lut_cells`` or ``model='mlp'`` in
        :meth:`~tactilevision.optics.PhotometricCalibration.from_ball_presses`)
        sees steep slopes facing the borders too.
    seed : int, default 0

    Returns
    -------
    presses : BallPressSet
        Frames, the exact circle centres (x, y) and radii in px, names
        ``ball_000`` ...

    Raises
    ------
    InputError
        For a non-positive radius or depth, depths reaching the ball's
        radius, a ball that does not fit in the image, or a reference of
        the wrong size.
    """
    check_positive(radius_mm, "radius_mm")
    lo, hi = (float(v) for v in depth_mm)
    if not 0 < lo <= hi < radius_mm:
        raise InputError(f"depth_mm must satisfy 0 < lo <= hi < radius_mm = {radius_mm:g}, "
                         f"got {depth_mm}")
    if n < 1:
        raise InputError(f"n must be at least 1, got {n}")
    H, W = table.shape
    mm = table.mm_per_px
    ref = np.asarray(reference)
    if ref.shape != (H, W, 3) or ref.dtype != np.uint8:
        raise InputError(f"reference must be a ({H}, {W}, 3) uint8 frame, got {ref.shape} "
                         f"{ref.dtype}")
    a_max = np.sqrt(2 * radius_mm * hi - hi * hi) / mm
    if 2 * a_max + 10 >= min(H, W):
        raise InputError(f"a {radius_mm:g} mm ball pressed {hi:g} mm deep ({2 * a_max:.0f} px "
                         f"wide) does not fit in the {W} x {H} px image")
    rng = np.random.default_rng(seed)
    rows, cols = np.indices((H, W), dtype=np.float64)
    frames, centres, radii = [], [], []
    for _ in range(n):
        d = rng.uniform(lo, hi)
        a = np.sqrt(2 * radius_mm * d - d * d)
        a_px = a / mm
        margin = 5.0 if partial else a_px + 5
        cx = rng.uniform(margin, W - margin)
        cy = rng.uniform(margin, H - margin)
        r2 = ((cols - cx) ** 2 + (rows - cy) ** 2) * mm * mm
        z = np.where(r2 < a * a, np.sqrt(np.maximum(radius_mm ** 2 - r2, 0.0))
                     - (radius_mm - d), 0.0).astype(np.float32)
        img = table.render(z, ref, noise_dn=noise_dn, rng=rng)
        if jpeg_quality is not None:
            _ok, buf = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, int(jpeg_quality)])
            img = cv2.imdecode(buf, cv2.IMREAD_COLOR)
        frames.append(img)
        centres.append((cx, cy))
        radii.append(a_px)
    return BallPressSet(reference=ref.copy(), frames=np.stack(frames),
                        centers_px=np.asarray(centres), radii_px=np.asarray(radii),
                        names=[f"ball_{i:03d}" for i in range(n)])
