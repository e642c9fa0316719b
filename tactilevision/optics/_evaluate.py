"""Accuracy of a reconstructor on held-out ball presses."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._ball import BallPressMetrics, ball_press_metrics
from ._reconstructor import DepthReconstructor

__all__ = ["BallPressReport", "evaluate_ball_presses"]


@dataclass(frozen=True)
class BallPressReport:
    """Metrics over a set of ball presses (pixel units; see :class:`BallPressMetrics`).

    Attributes
    ----------
    per_press : list of BallPressMetrics
    normal_angle_deg : float
        Mean over presses of the mean normal angle, degrees.
    shape_rms_px : float
        Mean over presses of the RMS shape error, px.
    fitted_radius_px : float
        Mean fitted ball radius, px.
    fitted_radius_std_px : float
        Standard deviation of the fitted radius across presses, px.
    shape_rms_placed_px : float
        Mean over presses of the RMS shape error against the ball placed by
        least squares (centre and offset fitted), px.
    """

    per_press: list[BallPressMetrics]
    normal_angle_deg: float
    shape_rms_px: float
    fitted_radius_px: float
    fitted_radius_std_px: float
    shape_rms_placed_px: float


def evaluate_ball_presses(recon: DepthReconstructor, frames: np.ndarray, centers_px: np.ndarray,
                          radii_px: np.ndarray, ball_radius_px: float, *,
                          disc_fraction: float = 1.0) -> BallPressReport:
    """Reconstruct ball presses and compare them with the ball's shape.

    Parameters
    ----------
    recon : DepthReconstructor
        The reconstructor under test.
    frames : (N, H, W, 3) uint8 ndarray
        Held-out ball presses, BGR.
    centers_px : (N, 2) float ndarray
        Contact-circle centres (x, y), px.
    radii_px : (N,) float ndarray
        Contact-circle radii, px.
    ball_radius_px : float
        True ball radius, px.
    disc_fraction : float, default 1.0
        Evaluate inside ``disc_fraction * radius``.

    Returns
    -------
    report : BallPressReport
    """
    mm = recon.calibration.mm_per_px
    per = []
    for f, c, r in zip(frames, centers_px, radii_px, strict=True):
        gx, gy = recon.gradients(f)
        height_px = recon(f) / mm
        per.append(ball_press_metrics(gx, gy, height_px, c, disc_fraction * r, ball_radius_px))
    radii = np.array([p.fitted_radius_px for p in per])
    return BallPressReport(
        per_press=per,
        normal_angle_deg=float(np.mean([p.normal_angle_deg for p in per])),
        shape_rms_px=float(np.mean([p.shape_rms_px for p in per])),
        fitted_radius_px=float(radii.mean()),
        fitted_radius_std_px=float(radii.std()),
        shape_rms_placed_px=float(np.mean([p.shape_rms_placed_px for p in per])),
    )
