"""Ball-press geometry: gradient labels for calibration and accuracy metrics.

A rigid ball of radius R pressed into the gel imposes its shape inside the
contact circle: with r the distance from the circle centre,
``depth(r) = sqrt(R^2 - r^2) + offset``, so

``d(depth)/dx = -(x - x_c) / sqrt(R^2 - r^2)``, ``d(depth)/dy = -(y - y_c) / sqrt(R^2 - r^2)``

(depth positive into the gel, x along columns, y along rows). All functions
here work in pixel units: gradients are unitless, heights and radii in px.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from .._checks import InputError, check_array

__all__ = [
    "SLOPE_PEAK_AT",
    "BallPressMetrics",
    "ball_gradients",
    "ball_press_metrics",
    "fit_ball_centre",
    "gradients_from_normals",
    "normal_angle_deg",
    "normals_from_gradients",
    "slope_peak_radius",
]


def ball_gradients(shape: tuple[int, int], centre_px: tuple[float, float],
                   contact_radius_px: float, ball_radius_px: float
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Surface gradients of a ball press inside its contact circle.

    Parameters
    ----------
    shape : tuple of int
        (H, W) of the frame.
    centre_px : (2,) float
        Contact-circle centre (x = column, y = row), px.
    contact_radius_px : float
        Contact-circle radius, px; must be smaller than ``ball_radius_px``.
    ball_radius_px : float
        Ball radius R, px.

    Returns
    -------
    gx, gy : (H, W) float32 ndarray
        d(depth)/dx and d(depth)/dy, unitless, zero outside the circle.
    inside : (H, W) bool ndarray
        The contact disc ``r < contact_radius_px``.

    Raises
    ------
    ValueError
        If the contact radius is not smaller than the ball radius.
    """
    if not 0 < contact_radius_px < ball_radius_px:
        raise InputError(f"contact radius {contact_radius_px:.3g} px must lie in "
                         f"(0, ball radius {ball_radius_px:.3g} px)")
    h, w = shape
    dx = np.arange(w, dtype=np.float32)[None, :] - np.float32(centre_px[0])
    dy = np.arange(h, dtype=np.float32)[:, None] - np.float32(centre_px[1])
    r2 = dx * dx + dy * dy
    inside = r2 < np.float32(contact_radius_px) ** 2
    s = np.sqrt(np.maximum(np.float32(ball_radius_px) ** 2 - r2, 1e-6))
    gx = np.where(inside, -dx / s, 0).astype(np.float32)
    gy = np.where(inside, -dy / s, 0).astype(np.float32)
    return gx, gy, inside


def normals_from_gradients(gx: np.ndarray, gy: np.ndarray) -> np.ndarray:
    """Unit surface normals (pointing out of the gel, towards the camera side).

    Parameters
    ----------
    gx, gy : (...) float ndarray
        Depth gradients, unitless.

    Returns
    -------
    n : (..., 3) float32 ndarray
        ``(-gx, -gy, 1) / sqrt(1 + gx^2 + gy^2)``.
    """
    gx = np.asarray(gx, np.float32)
    gy = np.asarray(gy, np.float32)
    inv = 1.0 / np.sqrt(1.0 + gx * gx + gy * gy)
    return np.stack([-gx * inv, -gy * inv, inv], axis=-1)


def normal_angle_deg(gx: np.ndarray, gy: np.ndarray, gx_ref: np.ndarray, gy_ref: np.ndarray
                     ) -> np.ndarray:
    """Angle between the surface normals of two gradient fields, degrees.

    Parameters
    ----------
    gx, gy, gx_ref, gy_ref : (...) float ndarray
        Depth gradients of the two surfaces, unitless, of one shape.

    Returns
    -------
    angle : (...) float32 ndarray
        ``arccos(n . n_ref)`` of their unit normals (:func:`normals_from_gradients`),
        degrees, in [0, 180].
    """
    n1 = normals_from_gradients(gx, gy)
    n2 = normals_from_gradients(gx_ref, gy_ref)
    return np.degrees(np.arccos(np.clip(np.sum(n1 * n2, axis=-1), -1.0, 1.0)))


def gradients_from_normals(nx: np.ndarray, ny: np.ndarray, *, max_slope: float = 6.0
                           ) -> tuple[np.ndarray, np.ndarray]:
    """Depth gradients from the in-plane normal components.

    Parameters
    ----------
    nx, ny : (...) float ndarray
        x and y components of the unit normal ``(-gx, -gy, 1) / norm``.
    max_slope : float, default 6.0
        Cap on the gradient magnitude (80.5 degrees): in-plane normals
        longer than ``max_slope / sqrt(1 + max_slope^2)`` (model noise can
        reach or pass 1) are shortened to that length first.

    Returns
    -------
    gx, gy : (...) float32 ndarray
        ``-nx / nz`` and ``-ny / nz`` with ``nz = sqrt(1 - nx^2 - ny^2)``.
    """
    nx = np.asarray(nx, np.float32)
    ny = np.asarray(ny, np.float32)
    s_max = np.float32(max_slope / np.sqrt(1.0 + max_slope * max_slope))  # |n_xy| at the cap
    norm = np.sqrt(nx * nx + ny * ny)
    shrink = np.minimum(np.float32(1.0), s_max / np.maximum(norm, np.float32(1e-12)))
    nx, ny = nx * shrink, ny * shrink
    inv_nz = 1.0 / np.sqrt(1.0 - nx * nx - ny * ny)
    return (-nx * inv_nz).astype(np.float32), (-ny * inv_nz).astype(np.float32)


@dataclass(frozen=True)
class BallPressMetrics:
    """Accuracy of a reconstruction inside one ball-press contact disc.

    Attributes
    ----------
    normal_angle_deg : float
        Mean angle between reconstructed and true surface normals, degrees.
    shape_rms_px : float
        RMS of (reconstructed - true) height after removing their mean
        difference (the unknown sink-in offset), px.
    fitted_radius_px : float
        Radius of the sphere least-squares fitted to the reconstructed
        height (centre, offset and radius free), px.
    shape_rms_placed_px : float
        RMS shape error against the true ball placed by least squares
        (centre and offset fitted, radius known), px: the shape error
        without the error of the given circle centre.
    n_pixels : int
        Pixels in the evaluated disc.
    """

    normal_angle_deg: float
    shape_rms_px: float
    fitted_radius_px: float
    shape_rms_placed_px: float
    n_pixels: int


def ball_press_metrics(gx: np.ndarray, gy: np.ndarray, height_px: np.ndarray,
                       centre_px: tuple[float, float], contact_radius_px: float,
                       ball_radius_px: float) -> BallPressMetrics:
    """Compare a reconstruction with the known ball shape inside the contact.

    Parameters
    ----------
    gx, gy : (H, W) float ndarray
        Reconstructed depth gradients, unitless.
    height_px : (H, W) float ndarray
        Reconstructed height (depth into the gel), px.
    centre_px : (2,) float
        Contact-circle centre (x, y), px.
    contact_radius_px : float
        Contact-circle radius, px; the disc evaluated.
    ball_radius_px : float
        True ball radius, px.

    Returns
    -------
    metrics : BallPressMetrics
    """
    gx = check_array(gx, "gx", [("H", "W")], dtype=np.floating)
    gy = check_array(gy, "gy", [gx.shape], dtype=np.floating)
    height_px = check_array(height_px, "height_px", [gx.shape], dtype=np.floating)
    tgx, tgy, inside = ball_gradients(gx.shape, centre_px, contact_radius_px, ball_radius_px)
    angle = normal_angle_deg(gx[inside], gy[inside], tgx[inside], tgy[inside])
    yy, xx = np.nonzero(inside)
    x = xx.astype(np.float64)
    y = yy.astype(np.float64)
    r2 = (x - centre_px[0]) ** 2 + (y - centre_px[1]) ** 2
    truth = np.sqrt(ball_radius_px**2 - r2)
    z = height_px[inside].astype(np.float64)
    err = z - truth
    err -= err.mean()

    def residual(p: np.ndarray) -> np.ndarray:
        x0, y0, z0, rad = p
        return z0 + np.sqrt(np.maximum(rad * rad - (x - x0) ** 2 - (y - y0) ** 2, 0.0)) - z

    p0 = np.array([centre_px[0], centre_px[1], float(np.mean(z - truth)), ball_radius_px])
    fit = least_squares(residual, p0, x_scale=[1, 1, 1, ball_radius_px])
    placed = least_squares(lambda p: residual(np.append(p, ball_radius_px)), p0[:3])
    return BallPressMetrics(
        normal_angle_deg=float(angle.mean()),
        shape_rms_px=float(np.sqrt(np.mean(err * err))),
        fitted_radius_px=float(fit.x[3]),
        shape_rms_placed_px=float(np.sqrt(np.mean(placed.fun**2))),
        n_pixels=int(inside.sum()),
    )


def fit_ball_centre(gx: np.ndarray, gy: np.ndarray, centre_px: tuple[float, float],
                    contact_radius_px: float, ball_radius_px: float, *,
                    core: float = 0.8) -> np.ndarray:
    """Refine a contact-circle centre from a gradient field.

    Least-squares fit of the centre (x_c, y_c) of the ball gradients
    ``-(p - c) / sqrt(R^2 - |p - c|^2)`` to the given gradients inside
    ``core * contact_radius_px`` of the initial centre. Used to correct
    hand-annotated or detected centres, which are often off by a few pixels.

    Parameters
    ----------
    gx, gy : (H, W) float ndarray
        Depth gradients, unitless.
    centre_px : (2,) float
        Initial centre (x, y), px.
    contact_radius_px, ball_radius_px : float
        Contact and ball radius, px.
    core : float, default 0.8
        Fraction of the contact radius used (the rim is steep and least sure).

    Returns
    -------
    centre : (2,) float64 ndarray
        Refined centre (x, y), px.
    """
    h, w = gx.shape
    cx, cy = float(centre_px[0]), float(centre_px[1])
    rc = core * contact_radius_px
    x0, x1 = max(int(cx - rc), 0), min(int(cx + rc) + 2, w)
    y0, y1 = max(int(cy - rc), 0), min(int(cy + rc) + 2, h)
    yy, xx = np.mgrid[y0:y1, x0:x1].astype(np.float64)
    m = (xx - cx) ** 2 + (yy - cy) ** 2 < rc * rc
    x, y = xx[m], yy[m]
    px, py = gx[y0:y1, x0:x1][m], gy[y0:y1, x0:x1][m]
    if x.size < 10:
        return np.array([cx, cy])

    def residual(p: np.ndarray) -> np.ndarray:
        dx, dy = x - p[0], y - p[1]
        s = np.sqrt(np.maximum(ball_radius_px**2 - dx * dx - dy * dy, 1.0))
        return np.concatenate([px + dx / s, py + dy / s])

    return least_squares(residual, np.array([cx, cy])).x


#: Where the radial slope of a reconstructed ball press peaks, as a fraction of its contact
#: radius, on circles annotated by hand: taxim's 48 real GelSight presses, read by a colour
#: table and by the network trained on them, both 0.952 (median over the 46 whose disc lies
#: 1.3 radii inside the image; 0.956 on the circles the contact-edge detector finds there).
#: The gel follows the ball up to the contact edge and falls away outside it, so the slope
#: peaks at the edge; the reconstruction's own blur puts the peak a little inside.
SLOPE_PEAK_AT = 0.952


def slope_peak_radius(gx: np.ndarray, gy: np.ndarray, centre_px: tuple[float, float],
                      radius_px: float, *, reach: float = 1.3) -> float:
    """Where the radial slope of a press's gradient field peaks, px from its centre.

    Parameters
    ----------
    gx, gy : (H, W) float ndarray
        Depth gradients, unitless (depth positive into the gel).
    centre_px : (2,) float
        Contact-circle centre (x, y), px.
    radius_px : float
        Contact-circle radius, px.
    reach : float, default 1.3
        Rings looked at out to this many radii.

    Returns
    -------
    rho_px : float
        The middle of the 1 px ring (their inner edges half a pixel apart) whose median
        slope away from the centre is largest; NaN where a ring beyond the radius runs off
        the image.
    """
    h, w = gx.shape
    cx, cy = float(centre_px[0]), float(centre_px[1])
    out = reach * float(radius_px)
    if cx - out < 0 or cx + out > w - 1 or cy - out < 0 or cy + out > h - 1:
        return float("nan")
    x0, x1, y0, y1 = int(cx - out), int(cx + out) + 2, int(cy - out), int(cy + out) + 2
    yy, xx = np.mgrid[y0:y1, x0:x1].astype(np.float64)
    d = np.hypot(xx - cx, yy - cy)
    slope = -((xx - cx) * gx[y0:y1, x0:x1] + (yy - cy) * gy[y0:y1, x0:x1]) / np.maximum(d, 1e-9)
    rings = np.arange(0.5, out, 0.5)
    prof = np.array([np.median(slope[(d >= a) & (d < a + 1.0)]) for a in rings])
    return float(rings[int(np.argmax(prof))]) + 0.5
