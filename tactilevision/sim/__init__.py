"""Simulated sessions with known truth: gel height maps of presses from the FEM
(and, later, frames rendered from them and F/T logs)."""

from ._press import PressProfile, press_profile
from ._schedule import PressSchedule, depth_trajectory, ft_log, press_schedule

__all__ = ["PressProfile", "PressSchedule", "depth_trajectory", "ft_log", "press_profile",
           "press_schedule"]
