"""E and nu from a model of effects: the robust fit of c and beta, then the tables."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace

import numpy as np
from scipy import stats
from scipy.interpolate import PchipInterpolator

from .._checks import InputError
from ._catalogue import make_effect
from ._fem_tables import TABLE_EXTRAPOLATION, kappa_n_grid
from ._fit import (
    MAX_W_OVER_H,
    _geometry,
    _positive,
    carry_misfit,
    material_fit,
    nu_range_below,
    nu_range_reaching,
)
from ._model import IndentationModel, ModelFit
from ._neohookean import neo_hookean_constants
from ._result import IndentationFit

__all__ = ["fit_model"]

_CI_METHOD = ("delta method through the covariance of c and beta of the robust (soft_l1) "
              "least-squares fit of the whole model, Student t with n - k degrees of freedom")


def fit_model(columns: Mapping[str, np.ndarray], model: IndentationModel | str = "paper", *,
              thickness_mm: float, radius_mm: float, beta_table: str = "fem",
              a_over_h: float | None = None, contact: str = "bonded",
              confidence: float = 0.95, loss: str = "soft_l1",
              weights: np.ndarray | None = None, stated_noise: bool = False
              ) -> tuple[IndentationFit, ModelFit]:
    """Fit a model of effects, then derive E and nu from its c and beta.

    The intercept c and stiffening beta of eq. (5) are fitted freely with the
    effects' parameters (:meth:`IndentationModel.fit`); nu then comes from
    the beta table and E from eq. (4) (formats.md §4). With the FEM tables
    (the default) the lookup is made through the model itself: the same
    model is fitted to the FEM's P(w) at these depths for nu on a grid, so
    that the weighting and any depth effect (whose constant absorbs part of
    the law's curvature) read the table they were fitted with. The residuals
    never depend on the beta table.

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
    weights : (N,) array_like, optional
        Per-press weights of :meth:`IndentationModel.fit` (e.g. inverse stated
        variances of the forces); default equal. The FEM's forces that E and nu are
        read through are fitted with the same weights.
    stated_noise : bool, default False
        The `weights` are ``1 / sigma^2`` of the forces' stated uncertainties: the
        intervals are at least as wide as that noise makes them
        (:meth:`IndentationModel.fit`), wider where the residuals scatter more.

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
    (0.402, 0.246)
    """
    if model in ("paper", "layer"):
        model = IndentationModel(model)
    elif isinstance(model, str):
        names = tuple(n.strip() for n in model.split(",") if n.strip())
        model = IndentationModel("paper", tuple(n for n in names if n != "large_deformation"))
    if model.base == "fem":
        raise InputError("fit_model reads E and nu through eq. (5) or the layer; a model on "
                         "the FEM law (base 'fem') carries them as its own parameters: "
                         "diagnose(..., base='fem') reports them")
    h = _positive(thickness_mm, "thickness_mm")
    a = _positive(radius_mm, "radius_mm")
    if not 0 < confidence < 1:
        raise InputError(f"confidence must be in (0, 1), got {confidence!r}")
    w0 = np.asarray(columns.get("depth_mm", []), np.float64)
    top = MAX_W_OVER_H * TABLE_EXTRAPOLATION
    if beta_table == "fem" and w0.size and float(np.max(w0 / h)) > top + 1e-12:
        raise InputError(f"a press reaches w/h = {float(np.max(w0 / h)):.3f}, beyond the FEM "
                         f"beta table's w/h <= {top:g}: drop the deeper presses or use "
                         "beta_table='paper'")
    mf = model.fit(columns, thickness_mm=h, loss=loss, weights=weights,
                   stated_noise=stated_noise)
    w = np.asarray(columns["depth_mm"], np.float64) + mf.params.get("depth_offset.delta_mm", 0.0)
    if np.any(w <= 0):
        raise InputError("a depth corrected by depth_offset is not positive")
    names = list(mf.params)
    # stiffness_trend is exp(k x): c is the stiffness at x = 0; E and nu are given at
    # the table's mean of each such column
    scale = math.exp(sum(
        v * float(np.nanmean(np.asarray(columns[k.split(":", 1)[1].rsplit(".", 1)[0]],
                                        np.float64)))
        for k, v in mf.params.items() if k.startswith("stiffness_trend:")))
    c0 = mf.params["c_n_per_mm"]
    c = c0 * scale
    effect_params = {k: v for k, v in mf.params.items() if k != "c_n_per_mm"}
    notes = [f"model {', '.join(model.names) or 'layer'} fitted by {loss} least squares"]
    if mf.unidentified:
        notes.append(f"not identified by these data: {', '.join(mf.unidentified)} (they lie "
                     "along a null direction of the Jacobian, e.g. a relaxation far faster "
                     "than the shortest hold); intervals through them are not finite")
    if "large_deformation.beta" in mf.params:
        b = mf.params["large_deformation.beta"]
        effect_params = {"beta": b, **{k: v for k, v in effect_params.items()
                                       if k != "large_deformation.beta"}}
        ib = names.index("large_deformation.beta")
        cov_cb = mf.covariance[np.ix_([0, ib], [0, ib])]
        J = scale * np.array([[1.0, 0.0], [b, c0]])   # (c0, beta) -> (c, c beta)
        cov = J @ cov_cb @ J.T
        slope = c * b
    else:
        slope, cov = 0.0, np.full((2, 2), math.nan)
        notes.append("no large_deformation in the model: without beta, nu and E are not derived")
    if beta_table == "fem":
        # the table is read at the corrected depths, up to its last w/h
        w = np.minimum(w, MAX_W_OVER_H * TABLE_EXTRAPOLATION * h)
    ah, kappa_source, contact = _geometry(w, h, a, beta_table, a_over_h, contact)
    P = np.asarray(columns["force_n"], np.float64)
    tss = float(np.sum((P / w - np.mean(P / w)) ** 2))
    r2 = 1 - float(np.sum((mf.residuals_n / w) ** 2)) / tss if tss > 0 else 1.0
    fit = material_fit(c, slope, cov, depth_mm=w, thickness_mm=h, radius_mm=a, a_over_h=ah,
                       beta_table=beta_table, contact=contact, kappa_source=kappa_source,
                       confidence=confidence, dof=mf.n_presses - mf.n_params,
                       rmse_n=mf.rmse_n, r_squared=r2, effects=model.names,
                       effect_params=effect_params, a_over_h_given=a_over_h is not None,
                       extra_notes=tuple(notes), ci_method=_CI_METHOD)
    if beta_table == "fem" and "large_deformation.beta" in mf.params:
        fit = _consistent_material(fit, model, mf, columns, h=h, a=a, contact=contact,
                                   confidence=confidence, scale=scale)
    fit = replace(fit, notes=(*fit.notes, *_modulus_notes(mf.params, fit.E_mpa)),
                  unidentified=tuple(mf.unidentified))
    if "large_deformation.beta" not in mf.params:   # no beta: not "out of the table"
        fit = replace(fit, beta=math.nan, beta_ci95=(math.nan, math.nan), beta_se=math.nan,
                      out_of_table=False, out_of_table_message=None,
                      notes=tuple(n for n in fit.notes if n != fit.out_of_table_message))
    P_obs = np.asarray(columns["force_n"], np.float64)
    noise = None if weights is None else 1.0 / np.sqrt(np.asarray(weights, np.float64))
    # with the FEM table, E is read through the FEM's law fitted by the model at these
    # depths, which the model's own curve only approximates: its residuals' shape along
    # depth says nothing of E (the drift of the apparent E still does)
    fem_read = beta_table == "fem" and "large_deformation.beta" in mf.params
    fit = carry_misfit(fit, np.asarray(columns["depth_mm"], np.float64), P_obs,
                       P_obs - mf.residuals_n, noise_sd_n=noise, n_params=mf.n_params,
                       structure=not fem_read)
    return fit, mf


def _modulus_notes(params: Mapping[str, float], E: float) -> list[str]:
    """Which modulus E is, for effects that change the stiffness with a covariate."""
    out: list[str] = []
    if not math.isfinite(E):
        return out
    for k, v in params.items():
        eff, _, q = k.rpartition(".")
        if eff.startswith("stiffness_step:") and q == "s":
            col, at = eff.partition(":")[2], params[f"{eff}.at"]
            out.append(f"{eff}: E = {E:.4g} MPa is the gel's up to {col} = {at:g}; after it "
                       f"the stiffness is {1 + v:.4g} times that (E = {E * (1 + v):.4g} MPa)")
        if eff == "viscoelastic_relaxation" and q == "g":
            out.append(f"viscoelastic_relaxation: E = E_0 = {E:.4g} MPa is the instantaneous "
                       f"modulus (hold -> 0); the relaxed modulus (hold -> infinity) is "
                       f"E_inf = (1 - g) E_0 = {E * (1 - v):.4g} MPa (hold_s counts from the "
                       "end of the loading: E_0 is the gel's then, below an instant load's by "
                       "what relaxed during the ramp; fit --holds gives the latter)")
    return out


def _consistent_material(fit: IndentationFit, model: IndentationModel, mf: ModelFit,
                         columns: Mapping[str, np.ndarray], *, h: float, a: float,
                         contact: str, confidence: float, scale: float = 1.0,
                         n_grid: int = 12) -> IndentationFit:
    """E and nu read through the model itself.

    The FEM beta table holds the secant beta of eq. (5) alone fitted to the
    FEM's P/w. A model fitted otherwise (least squares on P, or with a
    ``depth_offset`` or ``force_offset``, whose constant takes up part of
    the FEM curve's own curvature) has another beta for the same gel. Here
    the same model is fitted (the same weights, least squares) to the FEM's
    noise-free P(w) at these depths and covariates for nu on a grid (E = 1),
    giving c(nu) and beta(nu) of this model; nu = beta^-1(beta fitted),
    E = c fitted / c(nu) (the generalisation of the paper's table lookup).

    The base and the additive effects (depth and force offsets, force
    drift: their terms can take up part of the law's curvature, as in the
    fit to the measurements) are fitted to the FEM curve; the stiffness
    factors (relaxation, recovery, aging, ...) are left out: they are one
    there, and fitting them anyway leaves degenerate directions free (a
    relaxation with tau -> 0 is a constant factor on c, which moved E by up
    to 40 % on generated tables).
    """
    rel_lo, rel_hi = 0.33, 0.495
    w = np.asarray(columns["depth_mm"], np.float64)
    ws, inv = np.unique(w, return_inverse=True)
    shape = IndentationModel(model.base, tuple(
        n for n in model.effects
        if make_effect(n).kind in ("depth", "force") or make_effect(n).columns == ("depth_mm",)))
    base = {k: np.asarray(columns[k], np.float64) for k in shape.columns if k != "force_n"}
    nus = np.linspace(rel_lo, rel_hi, n_grid)
    cg, bg = [], []
    k_grid = kappa_n_grid(nus, a / h, ws / h, contact=contact)       # (n_grid, len(ws))
    for nu, kn in zip(nus, k_grid, strict=True):
        P1 = 2 * a * ws * kn / (1 - nu**2)
        g = shape.fit({**base, "force_n": P1[inv]}, thickness_mm=h, loss="linear",
                      weights=mf.weights)
        cg.append(g.params["c_n_per_mm"])
        bg.append(g.params["large_deformation.beta"])
    cg, bg = np.array(cg), np.array(bg)
    b = mf.params["large_deformation.beta"]
    c = mf.params["c_n_per_mm"] * scale
    names = list(mf.params)
    ib = names.index("large_deformation.beta")
    cov = mf.covariance[np.ix_([0, ib], [0, ib])] * np.outer([scale, 1.0], [scale, 1.0])
    dof = max(mf.n_presses - mf.n_params, 1)
    tq = float(stats.t.ppf(0.5 + confidence / 2, dof))
    top = int(np.argmax(bg))  # the branch where beta rises with nu, up to its maximum
    lo = top
    while lo > 0 and bg[lo - 1] < bg[lo]:
        lo -= 1
    b_lo = b - tq * math.sqrt(cov[1, 1]) if np.isfinite(cov[1, 1]) else math.nan
    b_hi = b + tq * math.sqrt(cov[1, 1]) if np.isfinite(cov[1, 1]) else math.nan
    if top > lo and b > bg[top] and b_lo <= bg[top]:
        return _model_table_top(fit, model, nus, cg, bg, lo, top, b, b_lo, c, cov, tq,
                                confidence, a)
    if top > lo and b < bg[lo] and b_hi >= bg[lo]:
        return _model_table_bottom(fit, model, nus, cg, bg, lo, b, b_hi, c, cov, tq,
                                   confidence, a)
    nus, cg, bg = nus[lo:top + 1], cg[lo:top + 1], bg[lo:top + 1]
    rel_lo, rel_hi = float(nus[0]), float(nus[-1])
    if not (nus.size >= 2 and bg[0] <= b <= bg[-1]):
        msg = (f"beta = {b:.4g} of the model {', '.join(model.names)} is outside what the FEM "
               f"gives this model at these depths (beta {bg.min():.4g} to {bg.max():.4g} for nu "
               f"{rel_lo:.3f} to {rel_hi:.3f}): E and nu not computed")
        return replace(fit, E_mpa=math.nan, nu=math.nan, E_ci95_mpa=(math.nan, math.nan),
                       nu_ci95=(math.nan, math.nan), out_of_table=True,
                       out_of_table_message=msg,
                       notes=(msg, *(n for n in fit.notes if n != fit.out_of_table_message)))
    nu_of_b = PchipInterpolator(bg, nus)
    c_of_nu = PchipInterpolator(nus, cg)
    nu = float(nu_of_b(b))
    c1 = float(c_of_nu(nu))
    E = c / c1
    dnu_db = float(nu_of_b.derivative()(b))
    dlnc1_dnu = float(c_of_nu.derivative()(nu)) / c1
    g_nu = np.array([0.0, dnu_db])
    g_E = E * (np.array([1 / c, 0.0]) - dlnc1_dnu * g_nu)
    with np.errstate(invalid="ignore"):   # NaN covariance of unidentified parameters
        nu_se = float(np.sqrt(g_nu @ cov @ g_nu))
        E_se = float(np.sqrt(g_E @ cov @ g_E))
    C10, D1 = neo_hookean_constants(E, nu)
    kept = _kept_notes(fit)
    note = ("E and nu read through this model: fitted by it to the FEM's P(w) at these depths "
            "for nu on a grid, as the beta table is for eq. (5) alone")
    return replace(fit, E_mpa=E, nu=nu, E_ci95_mpa=(E - tq * E_se, E + tq * E_se),
                   nu_ci95=(nu - tq * nu_se, nu + tq * nu_se), nu_se=nu_se, E_se_mpa=E_se,
                   C10_mpa=C10, D1_per_mpa=D1, kappa=c * (1 - nu**2) / (2 * a * E),
                   out_of_table=False, out_of_table_message=None, notes=(*kept, note))


def _kept_notes(fit: IndentationFit) -> tuple[str, ...]:
    """The notes of eq. (5)'s fit that still hold once E and nu are read through a model."""
    return tuple(n for n in fit.notes if n != fit.out_of_table_message
                 and "interval of nu" not in n
                 and not n.startswith(("beta lies above", "beta lies below")))


def _model_table_top(fit: IndentationFit, model: IndentationModel, nus: np.ndarray,
                     cg: np.ndarray, bg: np.ndarray, lo: int, top: int, b: float, b_lo: float,
                     c: float, cov: np.ndarray, tq: float, confidence: float, a: float
                     ) -> IndentationFit:
    """E and nu for a model's beta above the largest the FEM gives it, within its interval.

    The same rule as eq. (5)'s own fit at the table's top (:func:`~tactilevision.mechanics.
    fit_indentation`): beta(nu) is flat near its peak, so a beta a little above it is the peak
    within the scatter. nu is put at the peak; its interval runs from the nu whose beta is
    beta's lower bound (rising branch) to the largest nu whose beta still reaches it
    (falling branch); E = c / c(nu) at the peak, its interval E over that range of nu with c
    at its own bounds.
    """
    nu_peak = float(nus[top])
    nu_lo, nu_hi = nu_range_reaching(PchipInterpolator(nus, bg), float(nus[lo]),
                                     float(nus[-1]), nu_peak, b_lo)
    note = (f"beta = {b:.4g} of the model {', '.join(model.names)} lies above the largest "
            f"beta the FEM gives this model at these depths ({bg[top]:.4g}, at nu = "
            f"{nu_peak:.3f}) but within its {confidence:.0%} interval (lower bound "
            f"{b_lo:.4g}): nu is put at the top, {nu_peak:.3f}, with the interval "
            f"[{nu_lo:.4f}, {nu_hi:.4f}] of the nu whose beta reaches that bound; E at "
            f"nu = {nu_peak:.3f}, its interval over that range")
    return _at_model_edge(fit, nus, cg, nu_peak, (nu_lo, nu_hi), c, cov, tq, a, note)


def _at_model_edge(fit: IndentationFit, nus: np.ndarray, cg: np.ndarray, nu: float,
                   nu_ci: tuple[float, float], c: float, cov: np.ndarray, tq: float, a: float,
                   note: str) -> IndentationFit:
    """`fit` with nu put at an edge of the model's FEM grid: E = c / c(nu), its interval E
    over ``nu_ci`` and nu with c at its own bounds, and `note`."""
    c_of_nu = PchipInterpolator(nus, cg)
    c_se = math.sqrt(cov[0, 0]) if np.isfinite(cov[0, 0]) else math.nan
    E = c / float(c_of_nu(nu))
    Es = [cc / float(c_of_nu(nn)) for cc in (c - tq * c_se, c + tq * c_se)
          for nn in (nu_ci[0], nu, nu_ci[1])]
    C10, D1 = neo_hookean_constants(E, nu)
    return replace(fit, E_mpa=E, nu=nu, E_ci95_mpa=(float(min(Es)), float(max(Es))),
                   nu_ci95=nu_ci, nu_se=math.nan, E_se_mpa=math.nan, C10_mpa=C10,
                   D1_per_mpa=D1, kappa=c * (1 - nu**2) / (2 * a * E), out_of_table=False,
                   out_of_table_message=None, notes=(*_kept_notes(fit), note))


def _model_table_bottom(fit: IndentationFit, model: IndentationModel, nus: np.ndarray,
                        cg: np.ndarray, bg: np.ndarray, lo: int, b: float, b_hi: float,
                        c: float, cov: np.ndarray, tq: float, confidence: float, a: float
                        ) -> IndentationFit:
    """E and nu for a model's beta below the smallest the FEM gives it, within its interval.

    The mirror of :func:`_model_table_top`, and the same rule as eq. (5)'s own fit at the
    table's bottom (:func:`~tactilevision.mechanics.fit_indentation`): nu is put at the
    start of the rising branch, ``nus[lo]`` (the smallest beta of the branch); its interval
    is the hull of the grid's nu whose beta is at most beta's upper bound `b_hi`; E =
    c / c(nu) there, its interval E over that range of nu with c at its own bounds.
    """
    nu_bottom = float(nus[lo])
    nu_lo, nu_hi = nu_range_below(PchipInterpolator(nus, bg), float(nus[0]), float(nus[-1]),
                                  nu_bottom, b_hi)
    note = (f"beta = {b:.4g} of the model {', '.join(model.names)} lies below the smallest "
            f"beta the FEM gives this model at these depths ({bg[lo]:.4g}, at nu = "
            f"{nu_bottom:.3f}) but within its {confidence:.0%} interval (upper bound "
            f"{b_hi:.4g}): nu is put at the bottom, {nu_bottom:.3f}, with the interval "
            f"[{nu_lo:.4f}, {nu_hi:.4f}] of the nu whose beta is at most that bound; E at "
            f"nu = {nu_bottom:.3f}, its interval over that range")
    return _at_model_edge(fit, nus, cg, nu_bottom, (nu_lo, nu_hi), c, cov, tq, a, note)
