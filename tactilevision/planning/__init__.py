"""What a session can show, before it is pressed: the design of experiments.

A design (:class:`Design`: the gel, the gauge block's depths and repeats, holds, rests,
the F/T sensor and the camera; a ``design.toml``, :func:`read_design`) is judged by
what its session would certify and find:

- :func:`plan` and :func:`plan_session` -> :class:`PlanPrediction`: the intervals of
  E and nu the session would give, whether nu is identified, and the smallest size of
  each catalogue effect ``diagnose`` would name (:func:`effect_sensitivity`,
  :func:`effect_power`: :mod:`tactilevision.diagnosis`'s replay on the design's drawn
  sessions; a drawn mark's crossing forces, :func:`crossing_effect_sizes`
  (and :func:`crossing_offset_sizes`, the offsets along depth they must also show), size what
  its depths absorb within an indenter, its brackets :data:`BRACKET_PERIODS` frame
  periods wide on average unless the design says: :func:`press_bracket_periods`);
  relaxation's own identifiability
  (:func:`relaxation_identifiability`).
- :func:`recommend` -> :class:`Recommendation`: the change to the design that buys most
  (:class:`DesignChange`, :func:`error_totals`).
- From a calibration: :func:`design_from_calibration`; to a file: :func:`design_toml`.
"""

from ._design import (
    BRACKET_PERIODS,
    depth_uncertainty,
    indenter_speeds,
    planned_columns,
    read_schedule,
    readable_overshoot_um,
)
from ._plan import (
    Design,
    PlanPrediction,
    RelaxationPlan,
    design_from_calibration,
    design_toml,
    plan,
    plan_session,
    read_design,
    relaxation_identifiability,
    untestable_in_table,
)
from ._plan_effects import (
    crossing_effect_sizes,
    crossing_offset_sizes,
    crossing_sessions,
    crossing_table,
    design_setup,
    effect_power,
    effect_sensitivity,
    measured_bracket_periods,
    press_bracket_periods,
)
from ._plan_recommend import DesignChange, Recommendation, error_totals, recommend

__all__ = [
    "BRACKET_PERIODS",
    "Design",
    "DesignChange",
    "PlanPrediction",
    "Recommendation",
    "RelaxationPlan",
    "crossing_effect_sizes",
    "crossing_offset_sizes",
    "crossing_sessions",
    "crossing_table",
    "depth_uncertainty",
    "design_from_calibration",
    "design_setup",
    "design_toml",
    "effect_power",
    "effect_sensitivity",
    "error_totals",
    "indenter_speeds",
    "measured_bracket_periods",
    "plan",
    "plan_session",
    "planned_columns",
    "press_bracket_periods",
    "read_design",
    "read_schedule",
    "readable_overshoot_um",
    "recommend",
    "relaxation_identifiability",
    "untestable_in_table",
]
