"""Simulated sessions with known truth: gel height maps of gauge-block presses
from the FEM, frames rendered from them through Taxim's fitted shading, F/T
logs, and whole session folders with their ``truth.json``; measurements tables
with one hidden physical effect (:func:`make_measurement_table`), and a planned
design's tables with a catalogue effect of a known size
(:func:`design_measurement_table`); a ball's session drawn by Sneddon's closed
form (:func:`make_ball_session`)."""

from ..fem import PressProfile, press_profile
from ._ball_session import (
    make_ball_session,
    make_dead_weight_session,
    sneddon_sphere,
    sneddon_sphere_radius,
    sphere_press_surface,
)
from ._balls import render_ball_presses
from ._block import GaugeBlock, press_surface
from ._design_tables import design_measurement_table
from ._render import ShadingTable, fit_shading_table, taxim_shading
from ._schedule import PressSchedule, depth_trajectory, ft_log, press_schedule
from ._session import SessionSpec, make_session
from ._tables import HIDDEN_EFFECTS, HiddenTable, make_measurement_table

__all__ = [
    "HIDDEN_EFFECTS",
    "GaugeBlock",
    "HiddenTable",
    "PressProfile",
    "PressSchedule",
    "SessionSpec",
    "ShadingTable",
    "depth_trajectory",
    "design_measurement_table",
    "fit_shading_table",
    "ft_log",
    "make_ball_session",
    "make_dead_weight_session",
    "make_measurement_table",
    "make_session",
    "press_profile",
    "press_schedule",
    "press_surface",
    "render_ball_presses",
    "sneddon_sphere",
    "sneddon_sphere_radius",
    "sphere_press_surface",
    "taxim_shading",
]
