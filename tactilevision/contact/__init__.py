"""Certification of presses: clock sync, contact, footprint, bevel, force windows.

Pure functions on arrays, plus :func:`certify_session`, which runs them over a
session read by :mod:`tactilevision.io`.
"""

from ._ball_presses import BallPress, BallPresses, find_ball_presses
from ._bevel import bevel_score, footprint_from_frame
from ._certify import certified_depths, certify_session
from ._footprint import Footprint, fit_footprint, nearest_indenter
from ._force import ForceWindow, force_window, window_standard_error
from ._holds import approach_start, hold_end, hold_start
from ._land import bulge_at, bulge_height, land_contact_depth, land_contact_depths_mm
from ._mark import (
    CLOCK_SD_S,
    CROSSING_CHECK_P,
    STIFFNESS_REL,
    crossing_consistency,
    crossing_forces,
    mark_depths,
    mark_shared_mm,
)
from ._mask import contact_mask, noise_level
from ._onset import crossing_bracket
from ._results import Certification, CertifiedPress, Rejection
from ._stage import STAGE_Z, StageReading, stage_depths, touch_time
from ._sync import (
    ClockSync,
    contact_onsets,
    estimate_clock_offset,
    force_onsets,
    press_clock_offset,
    refine_clock_offset,
)
from ._vernier import (
    RESOLVED_PX,
    BevelGeometry,
    BevelProfile,
    BevelReading,
    bevel_force,
    bevel_profile,
    read_bevel,
)
from ._vernier_presses import (
    CREST_CHECK_P,
    EDGE_SHARED_FRACTION,
    crest_consistency,
    readable_overshoot_mm,
    unresolved_closure,
    vernier_shared_mm,
)
from ._zero import ForceZero, force_zero

__all__ = [
    "CLOCK_SD_S",
    "CREST_CHECK_P",
    "CROSSING_CHECK_P",
    "EDGE_SHARED_FRACTION",
    "RESOLVED_PX",
    "STAGE_Z",
    "STIFFNESS_REL",
    "BallPress",
    "BallPresses",
    "BevelGeometry",
    "BevelProfile",
    "BevelReading",
    "Certification",
    "CertifiedPress",
    "ClockSync",
    "Footprint",
    "ForceWindow",
    "ForceZero",
    "Rejection",
    "StageReading",
    "approach_start",
    "bevel_force",
    "bevel_profile",
    "bevel_score",
    "bulge_at",
    "bulge_height",
    "certified_depths",
    "certify_session",
    "contact_mask",
    "contact_onsets",
    "crest_consistency",
    "crossing_bracket",
    "crossing_consistency",
    "crossing_forces",
    "estimate_clock_offset",
    "find_ball_presses",
    "fit_footprint",
    "footprint_from_frame",
    "force_onsets",
    "force_window",
    "force_zero",
    "hold_end",
    "hold_start",
    "land_contact_depth",
    "land_contact_depths_mm",
    "mark_depths",
    "mark_shared_mm",
    "nearest_indenter",
    "noise_level",
    "press_clock_offset",
    "read_bevel",
    "readable_overshoot_mm",
    "refine_clock_offset",
    "stage_depths",
    "touch_time",
    "unresolved_closure",
    "vernier_shared_mm",
    "window_standard_error",
]
