"""E and nu from a model of effects: the robust fit of c and beta, then the tables."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace

import numpy as np

from .._checks import InputError
from ._fit import MAX_W_OVER_H, _geometry, _positive, material_fit
from ._model import IndentationModel, ModelFit
from ._result import IndentationFit

__all__ = ["fit_model"]

_CI_METHOD = ("delta method through the covariance of c and beta of the robust (soft_l1) "
              "least-squares fit of the whole model, Student t with n - k degrees of freedom")


def fit_model(columns: Mapping[str, np.ndarray], model: IndentationModel | str = "paper", *,
              thickness_mm: float, radius_mm: float, beta_table: str = "fem",
              a_over_h: float | None = None, contact: str = "bonded",
              confidence: float = 0.95, loss: str = "soft_l1"
              ) -> tuple[IndentationFit, ModelFit]:
    """Fit a model of effects, then derive E and nu from its c and beta.

    The intercept c and stiffening beta of eq. (5) are fitted freely with the
    effects' parameters (:meth:`IndentationModel.fit`); nu then comes from
    the beta table and E from eq. (4), as in :func:`fit_indentation`
    (formats.md §4). The residuals never depend on the beta table.

    Parameters
    ----------
    columns : mapping of str to (N,) array_like
        A measurements table's columns (``depth_mm``, ``force_n`` and what
        the effects need).
    model : IndentationModel or str, default 'paper'
        The model, a base (``'paper'``, ``'layer'``), or a comma-separated
        list of effect names added to the paper's base
        (``'incomplete_recovery,force_offset'``).
    thickness_mm, radius_mm : float
        h and a, mm.
    beta_table : {'fem', 'paper'}, default 'fem'
    a_over_h : float, optional
    contact : {'bonded', 'frictionless'}, default 'bonded'
    confidence : float, default 0.95
    loss : str, default 'soft_l1'
        Robust loss of :meth:`IndentationModel.fit`.

    Returns
    -------
    fit : IndentationFit
        E, nu and intervals; ``effects`` the model's names, ``effect_params``
        ``beta`` and every ``<effect>.<param>``. Without ``large_deformation``
        (``base='layer'``) there is no beta: E and nu are NaN with a note.
    model_fit : ModelFit
        The model's parameters, residuals, BIC.

    Raises
    ------
    InputError
        For an unknown effect, a missing column (named), a non-positive h or
        a, or a/h outside the kappa table.

    Examples
    --------
    >>> import numpy as np
    >>> w = np.repeat([0.15, 0.3, 0.45, 0.6], 5)
    >>> wait = np.tile([0.5, 1.0, 2.0, 5.0, 30.0], 4)
    >>> P = 3.5 * w * (1 + 0.75 * w / 3) * (1 + 0.1 * np.exp(-wait / 2.0))
    >>> fit, mf = fit_model({"depth_mm": w, "force_n": P, "wait_s": wait},
    ...                     "incomplete_recovery", thickness_mm=3, radius_mm=2.5)
    >>> round(mf.params["incomplete_recovery.r"], 3), round(fit.beta, 3)
    (0.1, 0.75)
    >>> round(fit.nu, 3), round(fit.E_mpa, 3)
    (0.435, 0.223)
    """
    if model in ("paper", "layer"):
        model = IndentationModel(model)
    elif isinstance(model, str):
        names = tuple(n.strip() for n in model.split(",") if n.strip())
        model = IndentationModel("paper", tuple(n for n in names if n != "large_deformation"))
    h = _positive(thickness_mm, "thickness_mm")
    a = _positive(radius_mm, "radius_mm")
    if not 0 < confidence < 1:
        raise ValueError(f"confidence must be in (0, 1), got {confidence!r}")
    w0 = np.asarray(columns.get("depth_mm", []), np.float64)
    if beta_table == "fem" and w0.size and float(np.max(w0 / h)) > MAX_W_OVER_H + 1e-12:
        raise InputError(f"a press reaches w/h = {float(np.max(w0 / h)):.3f}, beyond the FEM "
                         f"beta table's w/h <= {MAX_W_OVER_H:g}: drop the deeper presses or use "
                         "beta_table='paper'")
    mf = model.fit(columns, thickness_mm=h, loss=loss)
    w = np.asarray(columns["depth_mm"], np.float64) + mf.params.get("depth_offset.delta_mm", 0.0)
    if np.any(w <= 0):
        raise InputError("a depth corrected by depth_offset is not positive")
    names = list(mf.params)
    c = mf.params["c_n_per_mm"]
    effect_params = {k: v for k, v in mf.params.items() if k != "c_n_per_mm"}
    notes = [f"model {', '.join(model.names) or 'layer'} fitted by {loss} least squares"]
    if "large_deformation.beta" in mf.params:
        b = mf.params["large_deformation.beta"]
        effect_params = {"beta": b, **{k: v for k, v in effect_params.items()
                                       if k != "large_deformation.beta"}}
        ib = names.index("large_deformation.beta")
        cov_cb = mf.covariance[np.ix_([0, ib], [0, ib])]
        J = np.array([[1.0, 0.0], [b, c]])   # (c, beta) -> (c, c beta)
        cov = J @ cov_cb @ J.T
        slope = c * b
    else:
        slope, cov = 0.0, np.full((2, 2), math.nan)
        notes.append("no large_deformation in the model: without beta, nu and E are not derived")
    if beta_table == "fem":
        # the table is read at the corrected depths, up to its last w/h
        w = np.minimum(w, MAX_W_OVER_H * h)
    ah, kappa_source, contact = _geometry(w, h, a, beta_table, a_over_h, contact)
    P = np.asarray(columns["force_n"], np.float64)
    tss = float(np.sum((P / w - np.mean(P / w)) ** 2))
    r2 = 1 - float(np.sum((mf.residuals_n / w) ** 2)) / tss if tss > 0 else 1.0
    if not np.isfinite(slope):
        slope = 0.0
    fit = material_fit(c, slope, cov, depth_mm=w, thickness_mm=h, radius_mm=a, a_over_h=ah,
                       beta_table=beta_table, contact=contact, kappa_source=kappa_source,
                       confidence=confidence, dof=mf.n_presses - mf.n_params,
                       rmse_n=mf.rmse_n, r_squared=r2, effects=model.names,
                       effect_params=effect_params, a_over_h_given=a_over_h is not None,
                       extra_notes=tuple(notes), ci_method=_CI_METHOD)
    if "large_deformation.beta" not in mf.params:   # no beta: not "out of the table"
        fit = replace(fit, beta=math.nan, beta_ci95=(math.nan, math.nan), beta_se=math.nan,
                      out_of_table=False, out_of_table_message=None,
                      notes=tuple(n for n in fit.notes if n != fit.out_of_table_message))
    return fit, mf
