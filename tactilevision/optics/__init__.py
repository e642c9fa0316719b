"""Photometric stereo: tactile frame -> surface gradient -> height map.

The public names live in small private modules and are re-exported here.
"""

from ._absolute import (
    AbsoluteDepthMetrics,
    BallCapFit,
    absolute_depth_metrics,
    fit_ball_cap,
)
from ._accuracy import (
    CIRCLE_ERROR,
    CircleError,
    calibration_accuracy,
    cap_prediction,
    edge_cut,
    holdout_presses,
    max_tilt_deg,
    press_folds,
)
from ._ball import (
    SLOPE_PEAK_AT,
    BallPressMetrics,
    ball_gradients,
    ball_press_metrics,
    fit_ball_centre,
    gradients_from_normals,
    normal_angle_deg,
    normals_from_gradients,
    slope_peak_radius,
)
from ._calibration import PhotometricCalibration
from ._circles import (
    detect_contact_circle,
    detect_contact_circles,
    fit_circle,
    locate_contact_edge,
)
from ._engine import (
    CAP_DEG,
    ENGINES,
    MIN_MARGIN_PRESSES,
    MIN_NETWORK_PRESSES,
    UNDECIDED,
    Engine,
    engine_candidates,
    engine_cost,
    engine_margin,
    pooled_cost,
    pooled_presses,
    position_cells,
    undecided_choice,
)
from ._evaluate import BallPressReport, evaluate_ball_presses
from ._features import colour_change, frame_gain, reference_inverse
from ._lut import ColourLUT, fit_cell_luts, fit_colour_lut
from ._marker_flow import MarkerFlow, lateral_displacement, marker_centres, track_markers
from ._markers import fill_masked, marker_mask
from ._mlp import (
    MLPGradientModel,
    cell_position_inputs,
    default_position_cell_px,
    mlp_inputs,
    mlp_layers,
    train_mlp,
)
from ._poisson import PoissonSolver, divergence, integrate_poisson, integrate_poisson_masked
from ._press_check import (
    NON_BALL_FLOOR_DEG,
    NON_BALL_RATIO,
    ball_press_angles,
    non_ball_presses,
)
from ._reconstructor import DepthReconstructor
from ._table_kernel import KERNELS, first_order_kernel

__all__ = [
    "CAP_DEG",
    "CIRCLE_ERROR",
    "ENGINES",
    "KERNELS",
    "MIN_MARGIN_PRESSES",
    "MIN_NETWORK_PRESSES",
    "NON_BALL_FLOOR_DEG",
    "NON_BALL_RATIO",
    "SLOPE_PEAK_AT",
    "UNDECIDED",
    "AbsoluteDepthMetrics",
    "BallCapFit",
    "BallPressMetrics",
    "BallPressReport",
    "CircleError",
    "ColourLUT",
    "DepthReconstructor",
    "Engine",
    "MLPGradientModel",
    "MarkerFlow",
    "PhotometricCalibration",
    "PoissonSolver",
    "absolute_depth_metrics",
    "ball_gradients",
    "ball_press_angles",
    "ball_press_metrics",
    "calibration_accuracy",
    "cap_prediction",
    "cell_position_inputs",
    "colour_change",
    "default_position_cell_px",
    "detect_contact_circle",
    "detect_contact_circles",
    "divergence",
    "edge_cut",
    "engine_candidates",
    "engine_cost",
    "engine_margin",
    "evaluate_ball_presses",
    "fill_masked",
    "first_order_kernel",
    "fit_ball_cap",
    "fit_ball_centre",
    "fit_cell_luts",
    "fit_circle",
    "fit_colour_lut",
    "frame_gain",
    "gradients_from_normals",
    "holdout_presses",
    "integrate_poisson",
    "integrate_poisson_masked",
    "lateral_displacement",
    "locate_contact_edge",
    "marker_centres",
    "marker_mask",
    "max_tilt_deg",
    "mlp_inputs",
    "mlp_layers",
    "non_ball_presses",
    "normal_angle_deg",
    "normals_from_gradients",
    "pooled_cost",
    "pooled_presses",
    "position_cells",
    "press_folds",
    "reference_inverse",
    "slope_peak_radius",
    "track_markers",
    "train_mlp",
    "undecided_choice",
]
