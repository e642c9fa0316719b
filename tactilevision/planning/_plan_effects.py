"""Before the first press: the smallest size of each catalogue effect ``diagnose`` will find.

:func:`effect_sensitivity` answers, for a design (:class:`Design`), how large each
effect of the catalogue (formats.md §5) must be for
:func:`~tactilevision.diagnosis.diagnose` to name it in 95 % of sessions at its default
thresholds: the design's presses, columns and noise as a
:class:`~tactilevision.diagnosis.ReplaySetup`, and ``diagnose``'s decisions replayed on
many drawn sessions of it (:func:`~tactilevision.diagnosis.replay_sizes`; the method in
that module's docstring). The noise per press is the F/T window's sd and the certified
depth's (:func:`plan_session`'s) through the FEM's dP/dw, white; tangential forces at
2 % of the normal force, random.
"""

from __future__ import annotations

import math

from ..diagnosis import EffectSensitivity, ReplaySetup, replay_power, replay_sizes
from ._design import (
    Design,
    depth_uncertainty,
    design_table,
    planned_columns,
    untestable_effects,
)

__all__ = ["design_setup", "effect_power", "effect_sensitivity"]


def design_setup(design: Design) -> ReplaySetup:
    """The design's presses, columns and noise as the replay draws them."""
    w, _ = design_table(design)
    sd_um, _, _ = depth_uncertainty(design)
    return ReplaySetup(
        E_mpa=design.E_mpa, nu=design.nu, radius_mm=design.radius_mm,
        thickness_mm=design.thickness_mm, depths_mm=tuple(design.depths_mm), w=w,
        cols=planned_columns(design), sigma=None, untestable=untestable_effects(design),
        relaxation_tau_s=design.relaxation_tau_s,
        force_sd_n=design.force_noise_n / math.sqrt(design.window_samples),
        depth_sd_mm=sd_um * 1e-3, own_tangential=False)


def effect_power(design: Design, effect: str, size: float, *, draws: int = 2000,
                 seed: int = 0) -> float:
    """Share of sessions of the design in which ``diagnose`` (replayed, linearized)
    names `effect` at `size`: :func:`~tactilevision.diagnosis.replay_power` on the
    design's sessions (:func:`design_setup`); its parameters, return value and errors.
    """
    return replay_power(design_setup(design), effect, size, draws=draws, seed=seed)


def effect_sensitivity(design: Design, *, power: float = 0.95, draws: int = 1000,
                       seed: int = 0) -> dict[str, EffectSensitivity]:
    """The smallest size of each catalogue effect ``diagnose`` names in `power` of the
    sessions of a design: :func:`~tactilevision.diagnosis.replay_sizes` on the design's
    sessions (:func:`design_setup`: the F/T window's sd and the certified depth's,
    :func:`plan_session`'s, through the FEM's dP/dw, white; tangential forces at 2 % of
    the normal force, random); its parameters, return value and errors.
    """
    return replay_sizes(design_setup(design), power=power, draws=draws, seed=seed)
