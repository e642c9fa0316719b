"""Mechanics of the gel pad: kappa and beta tables, the in-situ fit of E and nu.

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
- Models of effects (formats.md §4): :class:`IndentationModel`, one
  :class:`Effect` class per catalogue name (:data:`EFFECTS`), fitted robustly
  (:class:`ModelFit`); :func:`fit_model` adds E and nu; :func:`diagnose`
  finds where a model fails and which effect is missing (:class:`Diagnosis`).
- Effects of your own: subclass :class:`Effect` (parameters as :class:`Param`
  with bounds and units, the columns read, the physics in ``apply``) and pass
  the class to :class:`IndentationModel`, :func:`fit_model`, :func:`diagnose`
  or ``--effects package.module:ClassName``; :func:`register_effect` checks
  it and gives its name (``docs/custom_effects.md``).
- Indenters (one concept, :class:`Indenter`): :class:`FlatPunch` (the
  paper's) and :class:`Sphere` (a ball: the FEM table ``models/sphere_fem.npz``,
  :func:`sphere_force_ratio`, :func:`sphere_contact_ratio`), made from
  ``[indenter]`` by :func:`indenter_from_config`; :func:`fit_indenter` fits E
  (and nu where the presses pin it) to any indenter's presses ->
  :class:`IndenterFit`.
- :func:`neo_hookean_constants` -- Abaqus C10, D1 from E, nu.
- :func:`fit_relaxation` -- a standard linear solid fitted to the force over
  each press's hold (``holds.csv``) -> :class:`RelaxationFit`: g and tau,
  hence E_0 and the relaxed E_inf = (1 - g) E_0.

Validation (the paper's FEA check):

- :func:`validate_indentation` -> :class:`IndentationValidation`.
"""

from ._beta import (
    PAPER_BETA_RELATION,
    BetaRelation,
    beta,
    beta_from_nu,
    beta_relation,
    nu_from_beta,
)
from ._budget import NoiseBudget, noise_budget
from ._catalogue import EFFECTS, Effect, FemLaw, Param, make_effect, register_effect
from ._design import EFFECT_SIZE_PARAMS, depth_uncertainty, planned_columns
from ._diagnose import Diagnosis, noise_floor
from ._diagnose_stats import (
    CertificationTest,
    CovariateTest,
    certification_tests,
    covariate_tests,
    cross_validated_rmse,
)
from ._diagnose_verdict import diagnose, indenter_shared
from ._effects import EFFECT_NAMES, FIT_EFFECTS, check_fit_effects, effect_names, model_label
from ._fem_tables import fem_force, fem_kappa_table, fem_table_meta, kappa_n, kappa_n_grid
from ._fit import MAX_W_OVER_H, fit_indentation
from ._fit_model import fit_model
from ._indenter import INDENTERS, FlatPunch, Indenter, Sphere, indenter_from_config
from ._indenter_diagnose import (
    INDENTER_EFFECTS,
    IndenterDiagnosis,
    IndenterRung,
    IndenterValidation,
    diagnose_indenter,
    validate_indenter,
)
from ._indenter_fit import IndenterFit, apparent_modulus, fit_indenter
from ._kappa import HAYES_1972, KappaTable, kappa
from ._model import IndentationModel, ModelFit
from ._neohookean import neo_hookean_constants
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
    NOMINAL_TAU_S,
    TANGENTIAL_FRACTION,
    EffectSensitivity,
    effect_power,
    effect_sensitivity,
    table_sensitivity,
)
from ._plan_recommend import DesignChange, Recommendation, error_totals, recommend
from ._ramp import RampFit, fit_ramp
from ._relaxation import (
    RelaxationFit,
    elastic_force,
    fit_relaxation,
    instantaneous_forces,
    ramp_factor,
    relaxed_moduli,
)
from ._relaxation_log import refine_relaxation
from ._result import IndentationFit
from ._sphere_table import (
    hertz_force_n,
    sphere_contact_ratio,
    sphere_force_ratio,
    sphere_reach,
    sphere_table_meta,
)
from ._validate import IndentationValidation, validate_indentation

__all__ = [
    "EFFECTS",
    "EFFECT_NAMES",
    "EFFECT_SIZE_PARAMS",
    "FIT_EFFECTS",
    "HAYES_1972",
    "INDENTERS",
    "INDENTER_EFFECTS",
    "MAX_W_OVER_H",
    "NOMINAL_TAU_S",
    "PAPER_BETA_RELATION",
    "TANGENTIAL_FRACTION",
    "BetaRelation",
    "CertificationTest",
    "CovariateTest",
    "Design",
    "DesignChange",
    "Diagnosis",
    "Effect",
    "EffectSensitivity",
    "FemLaw",
    "FlatPunch",
    "IndentationFit",
    "IndentationModel",
    "IndentationValidation",
    "Indenter",
    "IndenterDiagnosis",
    "IndenterFit",
    "IndenterRung",
    "IndenterValidation",
    "KappaTable",
    "ModelFit",
    "NoiseBudget",
    "Param",
    "PlanPrediction",
    "RampFit",
    "Recommendation",
    "RelaxationFit",
    "RelaxationPlan",
    "Sphere",
    "apparent_modulus",
    "beta",
    "beta_from_nu",
    "beta_relation",
    "certification_tests",
    "check_fit_effects",
    "covariate_tests",
    "cross_validated_rmse",
    "depth_uncertainty",
    "design_from_calibration",
    "design_toml",
    "diagnose",
    "diagnose_indenter",
    "effect_names",
    "effect_power",
    "effect_sensitivity",
    "elastic_force",
    "error_totals",
    "fem_force",
    "fem_kappa_table",
    "fem_table_meta",
    "fit_indentation",
    "fit_indenter",
    "fit_model",
    "fit_ramp",
    "fit_relaxation",
    "hertz_force_n",
    "indenter_from_config",
    "indenter_shared",
    "instantaneous_forces",
    "kappa",
    "kappa_n",
    "kappa_n_grid",
    "make_effect",
    "model_label",
    "neo_hookean_constants",
    "noise_budget",
    "noise_floor",
    "nu_from_beta",
    "plan",
    "plan_session",
    "planned_columns",
    "ramp_factor",
    "read_design",
    "recommend",
    "refine_relaxation",
    "register_effect",
    "relaxation_identifiability",
    "relaxed_moduli",
    "sphere_contact_ratio",
    "sphere_force_ratio",
    "sphere_reach",
    "sphere_table_meta",
    "table_sensitivity",
    "untestable_in_table",
    "validate_indentation",
    "validate_indenter",
]
