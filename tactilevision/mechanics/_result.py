"""The result of the in-situ fit, with its ``fit --json`` form (formats.md §3)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from ._misfit import Misfit

__all__ = ["IndentationFit"]


@dataclass(frozen=True)
class IndentationFit:
    """Result of :func:`fit_indentation`. Units are in the names.

    The first ten attributes are the ``fit --json`` contract (formats.md §3).
    Out of the beta table's range, E, nu, C10, D1 and their intervals are NaN
    (``null`` in JSON) and `out_of_table` is set with a message.

    Attributes
    ----------
    E_mpa, nu : float
        Young's modulus (MPa) and Poisson's ratio.
    c_n_per_mm : float
        Intercept c of eq. (5), N/mm.
    beta : float
        Slope over intercept of eq. (5), dimensionless.
    E_ci95_mpa, nu_ci95 : (float, float)
        Intervals at `confidence` (0.95 by default; the names follow the
        contract whatever `confidence` is).
    rmse_n : float
        Root mean square of ``P - P_pred`` over the presses, N.
    n_presses : int
    effects : tuple of str
        ``('large_deformation',)``.
    effect_params : dict
        ``{'beta': beta}``.
    C10_mpa, D1_per_mpa : float
        Abaqus Neo-Hookean constants, MPa and 1/MPa.
    a_over_h, a_over_h_exact : float
        a/h used for kappa, and radius over thickness.
    thickness_mm, radius_mm, kappa : float
        h, a, and kappa(nu, a_over_h) from `kappa_source` (``'fem'``: the
        intercept of the FEM's finite-strain kappa_n line at the fitted depths).
    beta_table : str
        The beta table used (``'fem'`` or ``'paper'``).
    kappa_source : str
        ``'fem'`` (with the FEM beta table) or ``'hayes'`` (with the paper's).
    contact : str
        Punch condition of the FEM tables (``'frictionless'``).
    slope_n_per_mm, c_se_n_per_mm, slope_se_n_per_mm, corr_c_slope : float
        Slope c*beta of eq. (5), the standard errors and correlation of
        intercept and slope.
    beta_se, nu_se, E_se_mpa : float
        Standard errors; `beta_ci95` is the interval of beta.
    r_squared : float
        Coefficient of determination of P/w against w/h, as the paper's.
    confidence : float
    ci_method : str
    max_w_over_h : float
        Largest w/h among the presses.
    out_of_table : bool
    out_of_table_message : str or None
    notes : tuple of str
        Decisions and warnings in plain sentences.
    depth_std_used : bool
        Whether the certified depth uncertainties entered the fit (errors in
        both variables, effective variance); False by default.
    depth_std_median_mm : float
        Median depth uncertainty of the presses, mm; NaN when not used.
    sigma0_n : float
        Force scatter not explained by the depth uncertainties (the extra
        variance of the effective-variance fit), N; NaN when not used.
    unidentified : tuple of str
        Model parameters the data cannot determine (``ModelFit.unidentified``:
        along a null direction of the Jacobian, e.g. a relaxation's g and tau
        on a table whose hold_s is constant); empty when every parameter is
        identified. ``identified`` (a property, and a key of the JSON) is
        True when it is empty.
    nu_bound : str or None
        Where beta lies past the table's edge and nu is put there: the bound
        the presses put on nu (``'nu >= 0.47'``), not a value.
    misfit : Misfit or None
        The presses' residuals against the fit, along depth
        (:func:`~tactilevision.mechanics.carry_misfit`): their serial
        correlation and the apparent E's drift, carried into the intervals.
    """

    E_mpa: float
    nu: float
    c_n_per_mm: float
    beta: float
    E_ci95_mpa: tuple[float, float]
    nu_ci95: tuple[float, float]
    rmse_n: float
    n_presses: int
    effects: tuple[str, ...]
    effect_params: dict[str, float] = field(hash=False)
    C10_mpa: float
    D1_per_mpa: float
    a_over_h: float
    a_over_h_exact: float
    thickness_mm: float
    radius_mm: float
    kappa: float
    beta_table: str
    kappa_source: str
    contact: str
    slope_n_per_mm: float
    c_se_n_per_mm: float
    slope_se_n_per_mm: float
    corr_c_slope: float
    beta_se: float
    beta_ci95: tuple[float, float]
    nu_se: float
    E_se_mpa: float
    r_squared: float
    confidence: float
    ci_method: str
    max_w_over_h: float
    out_of_table: bool
    out_of_table_message: str | None
    notes: tuple[str, ...]
    depth_std_used: bool = False
    depth_std_median_mm: float = math.nan
    sigma0_n: float = math.nan
    unidentified: tuple[str, ...] = ()
    nu_bound: str | None = None
    misfit: Misfit | None = None

    @property
    def identified(self) -> bool:
        """Whether the data determine every parameter of the model fitted."""
        return not self.unidentified

    def to_json_dict(self) -> dict[str, Any]:
        """The ``fit --json`` object: the contract's keys first, then extras.

        Returns
        -------
        obj : dict
            JSON-ready: tuples become lists, NaN becomes ``None`` (``null``).
        """
        def clean(v: Any) -> Any:
            if isinstance(v, float):
                return v if math.isfinite(v) else None
            if isinstance(v, tuple | list):
                return [clean(x) for x in v]
            if isinstance(v, dict):
                return {k: clean(x) for k, x in v.items()}
            return v

        obj = {name: clean(getattr(self, name)) for name in self.__dataclass_fields__
               if name != "misfit"}
        obj["misfit"] = None if self.misfit is None else self.misfit.to_json_dict()
        obj["identified"] = self.identified
        return obj
