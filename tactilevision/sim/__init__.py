"""Simulated sessions with known truth: gel height maps of presses from the FEM
(and, later, frames rendered from them and F/T logs)."""

from ._press import PressProfile, press_profile

__all__ = ["PressProfile", "press_profile"]
