"""Figures: depth-map images, force-depth validation (more with the reports)."""

from ._calibration import (
    bevel_panels,
    calibration_figures,
    figures_html,
    fitted_forces,
    html_head,
    pyplot,
    write_calibration_report,
)
from ._depth import depth_figure, nice_scale_bar_mm, save_depth_image
from ._diagnosis import diagnosis_figures, write_diagnosis_report
from ._forces import force_figure, save_force_image
from ._validation import save_validation_figure, validation_figure

__all__ = ["bevel_panels", "calibration_figures", "depth_figure", "diagnosis_figures",
           "figures_html", "fitted_forces", "force_figure", "html_head", "nice_scale_bar_mm",
           "pyplot", "save_depth_image", "save_force_image", "save_validation_figure",
           "validation_figure",
           "write_calibration_report", "write_diagnosis_report"]
from ._viewer import downsample_map, viewer_figure, write_viewer

__all__ += ["downsample_map", "viewer_figure", "write_viewer"]

# a ball's diagnosis (diagnose of a sphere's table)
from ._indenter import (  # noqa: E402
    ball_calibration_figure,
    indenter_figure,
    write_indenter_report,
)

__all__ += ["ball_calibration_figure", "indenter_figure", "write_indenter_report"]
