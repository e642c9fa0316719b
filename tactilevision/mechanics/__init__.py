"""Mechanics of the gel pad: the contact laws, the models of effects and the fit of E and nu.

The method is C. Zhao, J. Ren, H. Yu and D. Ma's, "In-situ Mechanical
Calibration for Vision-based Tactile Sensors" (IEEE ICRA 2023,
doi:10.1109/ICRA48891.2023.10161153): presses of a flat cylindrical indenter of radius a to
certified depths w into a gel layer of thickness h bonded to a rigid base,
forces P, and the law eq. (5) ``P/w = c beta (w/h) + c``.

Tables (every literature number lives in one table with its source):

- :func:`kappa` -- kappa(nu, a/h): ``source='hayes'`` (:data:`HAYES_1972`,
  Hayes et al. 1972) or ``'fem'`` (our small-strain FEM, ``models/kappa_fem.npz``,
  frictionless or bonded punch).
- :func:`beta` -- beta(nu, a/h): ``source='fem'`` (our finite-strain
  Neo-Hookean FEM, ``models/beta_fem.npz``, bonded punch) or ``'paper'``
  (:data:`PAPER_BETA_RELATION`, the paper's relation (7) at a/h = 0.8);
  :func:`nu_from_beta`, :func:`beta_from_nu` and :func:`beta_relation` with
  ``table='fem' | 'paper'``.
- :func:`kappa_n` -- kappa_n(nu, a/h, w/h) of the finite-strain FEM table;
  :func:`kappa_n_grid` the same on a grid; :func:`fem_kappa_table` the FEM's
  kappa(nu, a/h) table; :func:`fem_table_meta` a stored table's provenance.

Fit:

- :func:`fit_indentation` -> :class:`IndentationFit`.
- Models of effects (formats.md §5): :class:`IndentationModel`, one
  :class:`Effect` class per catalogue name (:data:`EFFECTS`), fitted robustly
  (:class:`ModelFit`); :func:`fit_model` adds E and nu. Where a model fails and
  which effect is missing is :mod:`tactilevision.diagnosis`; what a session can
  show before it is pressed, :mod:`tactilevision.planning`.
- Effects of your own: subclass :class:`Effect` (parameters as :class:`Param`
  with bounds and units, the columns read, the physics in ``apply``) and pass
  the class to :class:`IndentationModel`, :func:`fit_model`,
  :func:`tactilevision.diagnosis.diagnose` or ``--effects package.module:ClassName``;
  :func:`register_effect` checks it and gives its name (``docs/custom_effects.md``).
- Indenters (one concept, :class:`Indenter`): :class:`FlatPunch` (the
  paper's) and :class:`Sphere` (a ball: the FEM table ``models/sphere_fem.npz``,
  :func:`sphere_force_ratio`, :func:`sphere_contact_ratio`), made from
  ``[indenter]`` by :func:`indenter_from_config`; :func:`fit_indenter` fits E
  (and nu where the presses pin it) to any indenter's presses ->
  :class:`IndenterFit`; :func:`assess_misfit` reads a fit's residuals against its
  stated noise and along depth (:class:`Misfit`), and the fits carry it into their
  intervals.
- :func:`neo_hookean_constants` -- Abaqus C10, D1 from E, nu.
- :func:`fit_relaxation` -- a standard linear solid fitted to the force over
  each press's hold (``holds.csv``) -> :class:`RelaxationFit`: g and tau,
  hence E_0 and the relaxed E_inf = (1 - g) E_0.
- :class:`Sphere` with ``friction`` takes Coulomb friction between ball and gel
  (``contact='coulomb'``, small strain), with ``dome_radius_mm`` a domed gel.
- :func:`sphere_surface_depth` -- the gel's surface around a pressed ball (its
  sink-in beyond the contact), from the small-strain FEM; :func:`hertz_surface_depth`
  Hertz's closed form on a half-space.
"""

from ._beta import (
    PAPER_BETA_RELATION,
    BetaRelation,
    beta,
    beta_from_nu,
    beta_relation,
    nu_from_beta,
)
from ._catalogue import EFFECTS, Effect, FemLaw, Param, effect_name, make_effect, register_effect
from ._effects import (
    EFFECT_NAMES,
    EFFECT_SIZE_PARAMS,
    FIT_EFFECTS,
    check_fit_effects,
    effect_names,
    model_label,
)
from ._fem_tables import (
    fem_force,
    fem_kappa_table,
    fem_table_meta,
    kappa_n,
    kappa_n_grid,
    kappa_n_nu_range,
)
from ._fit import (
    BETA_TABLE_REACH,
    MAX_W_OVER_H,
    carry_misfit,
    fit_indentation,
    past_beta_table_reach,
)
from ._fit_model import fit_model
from ._indenter import (
    INDENTERS,
    FlatPunch,
    Indenter,
    Sphere,
    indenter_from_config,
    pad_sweep_result,
    reach_of,
)
from ._indenter_fit import IndenterFit, apparent_modulus, fit_indenter, json_ready, paule_mandel
from ._kappa import HAYES_1972, KappaTable, kappa
from ._misfit import MISFIT_ALPHA, Misfit, assess_misfit
from ._model import IndentationModel, ModelFit, shared_groups
from ._neohookean import neo_hookean_constants
from ._pad_sweeps import PAD_SWEEPS_FILE, SHIPPED_PAD_SWEEPS, build_pad_sweeps, pad_sweep_key
from ._ramp import RampFit, fit_ramp
from ._relaxation import (
    APPARENT_E,
    APPARENT_E_WHY,
    RELAX_ALPHA,
    TAU_HOLD_RATIO,
    TAU_MIN_HOLD_FRACTION,
    RelaxationFit,
    elastic_force,
    fit_relaxation,
    hold_blocks,
    instantaneous_forces,
    ramp_factor,
    relaxed_moduli,
    straight_decay,
)
from ._relaxation_log import refine_relaxation
from ._result import IndentationFit
from ._specimens import SPECIMEN_ALPHA, SpecimenPool, pool_specimens
from ._sphere_surface import hertz_surface_depth, sphere_surface_depth
from ._sphere_table import (
    hertz_force_n,
    sphere_contact_ratio,
    sphere_force_ratio,
    sphere_reach,
    sphere_table_meta,
    table_reach,
)

__all__ = [
    "APPARENT_E",
    "APPARENT_E_WHY",
    "BETA_TABLE_REACH",
    "EFFECTS",
    "EFFECT_NAMES",
    "EFFECT_SIZE_PARAMS",
    "FIT_EFFECTS",
    "HAYES_1972",
    "INDENTERS",
    "MAX_W_OVER_H",
    "MISFIT_ALPHA",
    "PAD_SWEEPS_FILE",
    "PAPER_BETA_RELATION",
    "RELAX_ALPHA",
    "SHIPPED_PAD_SWEEPS",
    "SPECIMEN_ALPHA",
    "TAU_HOLD_RATIO",
    "TAU_MIN_HOLD_FRACTION",
    "BetaRelation",
    "Effect",
    "FemLaw",
    "FlatPunch",
    "IndentationFit",
    "IndentationModel",
    "Indenter",
    "IndenterFit",
    "KappaTable",
    "Misfit",
    "ModelFit",
    "Param",
    "RampFit",
    "RelaxationFit",
    "SpecimenPool",
    "Sphere",
    "apparent_modulus",
    "assess_misfit",
    "beta",
    "beta_from_nu",
    "beta_relation",
    "build_pad_sweeps",
    "carry_misfit",
    "check_fit_effects",
    "effect_name",
    "effect_names",
    "elastic_force",
    "fem_force",
    "fem_kappa_table",
    "fem_table_meta",
    "fit_indentation",
    "fit_indenter",
    "fit_model",
    "fit_ramp",
    "fit_relaxation",
    "hertz_force_n",
    "hertz_surface_depth",
    "hold_blocks",
    "indenter_from_config",
    "instantaneous_forces",
    "json_ready",
    "kappa",
    "kappa_n",
    "kappa_n_grid",
    "kappa_n_nu_range",
    "make_effect",
    "model_label",
    "neo_hookean_constants",
    "nu_from_beta",
    "pad_sweep_key",
    "pad_sweep_result",
    "past_beta_table_reach",
    "paule_mandel",
    "pool_specimens",
    "ramp_factor",
    "reach_of",
    "refine_relaxation",
    "register_effect",
    "relaxed_moduli",
    "shared_groups",
    "sphere_contact_ratio",
    "sphere_force_ratio",
    "sphere_reach",
    "sphere_surface_depth",
    "sphere_table_meta",
    "straight_decay",
    "table_reach",
]

#: Names that moved to :mod:`tactilevision.diagnosis` and :mod:`tactilevision.planning`
#: (2026-11-26): an import of one from here says where it went.
MOVED = {name: "tactilevision.diagnosis" for name in (
    "CertificationTest", "CovariateTest", "Diagnosis", "EffectSensitivity",
    "INDENTER_EFFECTS", "IndentationValidation", "IndenterDiagnosis", "IndenterRung",
    "IndenterValidation", "NOMINAL_TAU_S", "NoiseBudget", "TANGENTIAL_FRACTION",
    "certification_tests", "covariate_tests", "cross_validated_rmse", "diagnose",
    "diagnose_indenter", "indenter_shared", "noise_budget", "noise_floor",
    "table_sensitivity", "validate_indentation", "validate_indenter")}
MOVED.update({name: "tactilevision.planning" for name in (
    "Design", "DesignChange", "PlanPrediction", "Recommendation", "RelaxationPlan",
    "depth_uncertainty", "design_from_calibration", "design_toml", "effect_power",
    "effect_sensitivity", "error_totals", "plan", "plan_session", "planned_columns",
    "read_design", "recommend", "relaxation_identifiability", "untestable_in_table")})


def __getattr__(name: str):
    """``tactilevision.mechanics.diagnose`` and the like: an AttributeError naming the
    package the name moved to (mechanics does not import the packages above it)."""
    if name in MOVED:
        raise AttributeError(f"tactilevision.mechanics.{name} moved to {MOVED[name]}.{name} "
                             f"(from {MOVED[name]} import {name})")
    raise AttributeError(f"module 'tactilevision.mechanics' has no attribute {name!r}")
