"""The main job as a pipeline of named steps: a session folder in, E and nu out.

:func:`calibrate_session` runs them all; each is public so that a user can run
them one by one and look at what each returns:

1. read: :func:`tactilevision.io.read_session`;
2. decode, sync, certify: :func:`tactilevision.contact.certify_session`;
3. the F/T's zero: :func:`take_off_zero`;
4. relaxation: :func:`relaxation_step`;
5. depth and fit: :func:`vernier_rule`, :func:`mark_rule`, :func:`nominal_rule`,
   :func:`land_rule` (on a :class:`DepthState`, fitted by a :class:`Fitter`), the
   shared depth error by :func:`with_shared_depth`;
6. report: :class:`CalibrationResult` (``save`` and ``load`` of the output folder)
   and :func:`write_calibration` (the folder with its figures and report).

A ball's session (``[indenter] shape = "sphere"``, no gauge block) is
:func:`calibrate_ball_session`'s: its presses from
:func:`tactilevision.contact.find_ball_presses`, each depth from the contact
circle (:func:`ball_press_depths`), E by
:func:`tactilevision.mechanics.fit_indenter`; :func:`write_ball_calibration`
writes its folder. With an optics calibration each press's height-map cap is a
cross-check of its depth (:func:`ball_press_caps`).
"""

from ._calibrate import calibrate_session
from ._calibration import HOLD_SEARCH_S, SessionCalibration, hold_curves, hold_spans
from ._rules import (
    MARK_BETA,
    DepthState,
    depth_half95,
    land_rule,
    mark_rule,
    nominal_rule,
    vernier_rule,
)
from ._shared import with_shared_depth
from ._steps import Fitter, frame_period, relaxation_step, take_off_zero

__all__ = ["HOLD_SEARCH_S", "MARK_BETA", "DepthState", "Fitter", "SessionCalibration",
           "calibrate_session", "depth_half95", "frame_period", "hold_curves", "hold_spans",
           "land_rule", "mark_rule", "nominal_rule", "relaxation_step", "take_off_zero",
           "vernier_rule", "with_shared_depth"]

from ._result import (
    CALIBRATION_FILES,
    CalibrationResult,
    read_material,
    result_dict,
    session_reconstructor,
    write_calibration,
)

__all__ += ["CALIBRATION_FILES", "CalibrationResult", "read_material", "result_dict",
            "session_reconstructor", "write_calibration"]

# a ball as its own gauge: depth from the contact circle
from ._ball import BallDepths, ball_press_depths  # noqa: E402
from ._ball_caps import CAP_PRESS_SD, CAP_SCALE_SD, BallCaps, ball_press_caps  # noqa: E402

__all__ += ["CAP_PRESS_SD", "CAP_SCALE_SD", "BallCaps", "BallDepths", "ball_press_caps",
            "ball_press_depths"]

# a ball session: presses found in the frames and the F/T log, depths from the circles
from ._ball_session import (  # noqa: E402
    BALL_CALIBRATION_FILES,
    E_PLAUSIBLE_MPA,
    BallCalibration,
    ball_indenter,
    calibrate_ball_session,
    calibrate_dead_weights,
    circle_depths,
    write_ball_calibration,
)

__all__ += ["BALL_CALIBRATION_FILES", "E_PLAUSIBLE_MPA", "BallCalibration", "ball_indenter",
            "calibrate_ball_session", "calibrate_dead_weights", "circle_depths",
            "write_ball_calibration"]
