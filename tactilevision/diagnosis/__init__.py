"""Where the model meets the data: the error ladder, its statistics and its verdicts.

A measurements table (formats.md §2) against the force law of
:mod:`tactilevision.mechanics` and the effects of its catalogue (formats.md §5):

- :func:`diagnose` -> :class:`Diagnosis`: where the model fails (residual structure,
  covariates, the noise budget) and which catalogue effect is missing, climbed as a
  ladder of models by BIC and cross-validation, on one noise model (each press's stated
  uncertainties and the error each indenter's presses share, :func:`indenter_shared`);
  a verdict of "nothing missing" says what it rules out (:func:`table_sensitivity`).
- The statistics it rests on: :func:`covariate_tests`, :func:`certification_tests`
  (the certification's own products, never physics), :func:`cross_validated_rmse`,
  :func:`noise_floor`, :func:`noise_budget`; :func:`crossing_tests`, each press's force
  at its crossing of the mark's w0 (a depth the frames certify apart from the force)
  tested for changes within indenters, which the mark rule's depths absorb
  (:func:`crossing_sizes`, the smallest such change they name; :func:`crossing_step_places`,
  a step's at each place along press order);
  :func:`holds_finding`, the force over each press's hold at the depth the stage keeps,
  which names a relaxing gel that a table read at one time of every hold cannot show.
- What a table of presses lets ``diagnose`` find: :func:`replay_sizes` and
  :func:`replay_power` replay its decisions over drawn sessions of a
  :class:`ReplaySetup` (the measured table's, :func:`table_sensitivity`; a design's,
  :mod:`tactilevision.planning`).
- Another indenter (a ball): :func:`diagnose_indenter` -> :class:`IndenterDiagnosis`,
  :func:`validate_indenter`.
- The paper's FEA check of a flat punch: :func:`validate_indentation`.

Effects of your own are :class:`tactilevision.mechanics.Effect` subclasses, passed
to :func:`diagnose` (``docs/custom_effects.md``).
"""

from ._budget import NoiseBudget, law_slope, noise_budget, stated_weights
from ._crossings import (
    CROSSING_UNITS,
    CrossingScan,
    CrossingTest,
    crossing_measurements,
    crossing_sizes,
    crossing_step_places,
    crossing_tests,
)
from ._diagnose import (
    CURVATURE_BIC,
    DELTA_BIC,
    EQUIVALENT_BIC,
    CertificationTest,
    CovariateTest,
    Diagnosis,
    certification_tests,
    covariate_tests,
    cross_validated_rmse,
    noise_floor,
    untestable_reason,
)
from ._diagnose_verdict import (
    ABSORBED_BY_MARK,
    DEPTH_ONLY,
    crossing_sensitivity,
    diagnose,
    indenter_shared,
)
from ._holds import HoldsFinding, holds_finding, holds_relaxation
from ._indenter_diagnose import (
    INDENTER_EFFECTS,
    IndenterDiagnosis,
    IndenterRung,
    IndenterValidation,
    diagnose_indenter,
    validate_indenter,
)
from ._replay import (
    NOMINAL_TAU_S,
    TANGENTIAL_FRACTION,
    EffectSensitivity,
    ReplaySetup,
    replay_power,
    replay_sizes,
    table_sensitivity,
)
from ._validate import IndentationValidation, validate_indentation

__all__ = [
    "ABSORBED_BY_MARK",
    "CROSSING_UNITS",
    "CURVATURE_BIC",
    "DELTA_BIC",
    "DEPTH_ONLY",
    "EQUIVALENT_BIC",
    "INDENTER_EFFECTS",
    "NOMINAL_TAU_S",
    "TANGENTIAL_FRACTION",
    "CertificationTest",
    "CovariateTest",
    "CrossingScan",
    "CrossingTest",
    "Diagnosis",
    "EffectSensitivity",
    "HoldsFinding",
    "IndentationValidation",
    "IndenterDiagnosis",
    "IndenterRung",
    "IndenterValidation",
    "NoiseBudget",
    "ReplaySetup",
    "certification_tests",
    "covariate_tests",
    "cross_validated_rmse",
    "crossing_measurements",
    "crossing_sensitivity",
    "crossing_sizes",
    "crossing_step_places",
    "crossing_tests",
    "diagnose",
    "diagnose_indenter",
    "holds_finding",
    "holds_relaxation",
    "indenter_shared",
    "law_slope",
    "noise_budget",
    "noise_floor",
    "replay_power",
    "replay_sizes",
    "stated_weights",
    "table_sensitivity",
    "untestable_reason",
    "validate_indentation",
    "validate_indenter",
]
