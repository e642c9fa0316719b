"""Certification of presses: clock sync, contact, footprint, bevel, force windows.

Pure functions on arrays (the session folder is read by :mod:`tactilevision.io`).
"""

from ._footprint import Footprint, fit_footprint, nearest_indenter
from ._force import ForceWindow, force_window
from ._mask import contact_mask, noise_level
from ._sync import ClockSync, contact_onsets, estimate_clock_offset, force_onsets

__all__ = ["ClockSync", "Footprint", "ForceWindow", "contact_mask", "contact_onsets",
           "estimate_clock_offset", "fit_footprint", "force_onsets", "force_window",
           "nearest_indenter", "noise_level"]
