"""Figures: depth-map images (more plots arrive with the reports)."""

from ._depth import depth_figure, nice_scale_bar_mm, save_depth_image

__all__ = ["depth_figure", "nice_scale_bar_mm", "save_depth_image"]
