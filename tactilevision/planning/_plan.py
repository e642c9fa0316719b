"""Before the first press: what a calibration session's design will measure.

A design is a ``session.toml`` (formats.md §1: gel thickness h, indenter radius a, the
gauge block's depths and bevel, the F/T window) plus a ``[plan]`` table of what a session
does not hold yet: the expected E and nu, the repeats per depth, the camera's frame rate
and the stage's speed at the bevel (for a mark), the F/T noise and zero stability, and
the hold length. :func:`plan_session` predicts, without drawing a single session:

- each press's depth uncertainty, random and shared, from the bevel (a vernier's band
  half-width read to :data:`VERNIER_EDGE_PX` once it reaches :data:`RESOLVED_PX`, only
  bounded before) or the mark (one frame's travel);
- the standard deviations of E and nu that :func:`fit_indentation` will give over
  repeated sessions of this design: every press's force and depth noise propagated
  through the fit itself to eq. (5)'s line (its derivatives taken on the design's
  noise-free table, the finite-strain FEM's forces), then E and nu integrated over that
  line's spread by Gauss-Hermite quadrature; and the biases that the shared errors
  leave;
- whether nu is identified at all (a/h where the beta table cannot tell nu, or a
  sigma of nu as wide as the physical range).

``benchmarks/bench_plan.py`` checks the predicted sigmas against the scatter of the
fit over generated sessions of each design in a grid.
"""

from __future__ import annotations

import csv
import json
import math
import tomllib
import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats

from .._checks import InputError, InputWarning
from ..diagnosis import EffectSensitivity
from ..io import KNOWN_KEYS, read_holds, warn_unknown_keys
from ..mechanics import (
    RELAX_ALPHA,
    TAU_HOLD_RATIO,
    TAU_MIN_HOLD_FRACTION,
    fit_indentation,
    hold_blocks,
    kappa_n_nu_range,
    ramp_factor,
    straight_decay,
)
from ._design import (
    VERNIER_EDGE_PX,
    Design,
    _positive,
    depth_uncertainty,
    design_table,
    design_toml,
    hold_lengths,
    indenter_speeds,
    planned_columns,
    press_indenters,
    read_design,
    read_schedule,
    untestable_effects,
    untestable_in_table,
)
from ._plan_effects import (
    crossing_effect_sizes,
    crossing_offset_sizes,
    effect_power,
    effect_sensitivity,
    larger_of,
    measured_bracket_periods,
)

__all__ = [
    "VERNIER_EDGE_PX",
    "Design",
    "PlanPrediction",
    "design_from_calibration",
    "design_toml",
    "plan",
    "plan_session",
    "planned_columns",
    "read_design",
    "untestable_effects",
    "untestable_in_table",
]

#: nu's physical range as this project's beta tables hold it: a sigma of nu beyond a
#: quarter of it leaves nu "not identified".
NU_RANGE = (0.30, 0.50)


@dataclass
class PlanPrediction:
    """What a design will measure (:func:`plan_session`).

    Attributes
    ----------
    design : Design
    n_presses : int
    depth_std_um : float
        Random sd of each press's certified depth, um.
    depth_shared_um : float
        Bound of a depth error every press shares, um (a mark's lag: up to one frame's
        travel; 0 for a vernier).
    depth_source : str
        How the depth sd was predicted.
    force_std_n : float
        Random sd of each press's force (window mean), N.
    E_sigma_mpa, nu_sigma : float
        Predicted sd of E and nu over repeated sessions of the design (random parts).
    E_sigma_pct : float
        ``E_sigma_mpa`` as a percentage of E.
    E_nu_corr : float
        Correlation of E's and nu's errors.
    bias : dict of str to (float, float)
        (E error in %, nu error): ``'model'``, the fit of the noise-free table (the
        fit's own error on the FEM's forces); ``'noise'``, the mean over sessions
        less the truth (the noise through the fit's curvature); and each shared
        error at its bound, either way: ``'depth_shared'`` and
        ``'depth_shared_minus'`` (every depth off by the shared bound),
        ``'force_zero'`` and ``'force_zero_minus'`` (every force off by the zero
        bound). NaN where the fit finds no E or nu.
    nu_identified : bool
        False when the beta table cannot tell nu at this a/h, or sigma(nu) exceeds a
        quarter of nu's range (0.3 to 0.5): the presses' scatter alone.
        :attr:`nu_identified_total` carries the shared errors too.
    notes : list of str
        Why, in words.
    relaxation : RelaxationPlan or None
        With ``relaxation_g`` and ``relaxation_tau_s`` in the design: whether
        ``fit_relaxation`` identifies them (:func:`relaxation_identifiability`).
    effect_sizes : dict of str to EffectSensitivity
        For each catalogue effect, the smallest size ``diagnose`` names in 95 % of
        sessions of the design (:func:`effect_sensitivity`; NaN where untestable).
    detect_power : dict of str to float
        For each effect size of the design's ``detect``, the share of sessions in which
        ``diagnose`` names it (:func:`effect_power`).
    untestable : dict of str to str
        The catalogue's effects (formats.md §5) that ``diagnose`` cannot test on a
        session of this design, and why (the column each needs is constant or missing
        in the design's table: :func:`planned_columns`).
    """

    design: Design
    n_presses: int
    depth_std_um: float
    depth_shared_um: float
    depth_source: str
    force_std_n: float
    E_sigma_mpa: float
    nu_sigma: float
    E_sigma_pct: float
    E_nu_corr: float
    bias: dict[str, tuple[float, float]]
    nu_identified: bool
    notes: list[str] = field(default_factory=list)
    untestable: dict[str, str] = field(default_factory=dict)
    relaxation: RelaxationPlan | None = None
    effect_sizes: dict[str, EffectSensitivity] = field(default_factory=dict)
    detect_power: dict[str, float] = field(default_factory=dict)

    @property
    def systematic_breaks(self) -> list[str]:
        """The shared errors (keys of :attr:`bias`) that, at their bound, leave the fit
        without E or nu (beta beyond the beta table)."""
        return [k for k, (e, n) in self.bias.items()
                if k not in ("model", "noise") and not (math.isfinite(e) and math.isfinite(n))]

    @property
    def nu_identified_total(self) -> bool:
        """One verdict: nu identified by the scatter and still with every shared error at
        its bound (what ``plan`` prints, and the total error of ``recommend``)."""
        return self.nu_identified and not self.systematic_breaks

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready dict (the ``plan --json`` output; NaN written as None)."""
        d = self.design
        return _no_nan({
            "design": {k: (list(v) if isinstance(v, tuple) else v)
                       for k, v in d.__dict__.items()} | {"a_over_h": d.a_over_h},
            "n_presses": self.n_presses,
            "depth_std_um": self.depth_std_um, "depth_shared_um": self.depth_shared_um,
            "depth_source": self.depth_source, "force_std_n": self.force_std_n,
            "E_sigma_mpa": self.E_sigma_mpa, "E_sigma_pct": self.E_sigma_pct,
            "nu_sigma": self.nu_sigma, "E_nu_corr": self.E_nu_corr,
            "bias": {k: {"E_pct": v[0], "nu": v[1]} for k, v in self.bias.items()},
            "nu_identified": self.nu_identified,
            "nu_identified_total": self.nu_identified_total,
            "systematic_breaks": self.systematic_breaks, "notes": list(self.notes),
            "untestable": dict(self.untestable),
            "relaxation": None if self.relaxation is None else dict(self.relaxation.__dict__),
            "effect_sizes": {k: {**v.__dict__, "at_places": v.to_json_dict()["at_places"]}
                             for k, v in self.effect_sizes.items()},
            "detect_power": dict(self.detect_power),
        })


def _no_nan(obj: Any) -> Any:
    """`obj` with every non-finite float replaced by None (JSON has no NaN)."""
    if isinstance(obj, dict):
        return {k: _no_nan(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_no_nan(v) for v in obj]
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def _fit(d: Design, w: np.ndarray, P: np.ndarray, u_mm: np.ndarray | None) -> np.ndarray:
    """(E, nu, c, c beta) of :func:`fit_indentation` on the presses (w, P)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        f = fit_indentation(w, P, thickness_mm=d.thickness_mm, radius_mm=d.radius_mm,
                            beta_table=d.beta_table, depth_std_mm=u_mm)
    return np.array([f.E_mpa, f.nu, f.c_n_per_mm, f.c_n_per_mm * f.beta])


#: Gauss-Hermite nodes per axis of the (c, c beta) quadrature.
QUADRATURE_NODES = 9


@dataclass(frozen=True)
class RelaxationPlan:
    """Whether ``fit_relaxation`` can identify g and tau from a design's holds.

    Attributes
    ----------
    g, tau_s : float
        The relaxation assumed (fraction, s).
    power : float
        Probability that the holds' curvature test rejects a straight decay at
        ``RELAX_ALPHA`` (noncentral F, 1 and n - P - 2 degrees of freedom), 0
        when tau lies outside the span the holds resolve.
    span_ok : bool
        tau within ``TAU_MIN_HOLD_FRACTION`` of the shortest hold to
        ``TAU_HOLD_RATIO`` times the longest.
    noncentrality : float
        ``RSS_line / sigma_b^2``: the straight decay's misfit to the noise-free
        holds over the block means' noise variance.
    why : str
        One sentence.
    """

    g: float
    tau_s: float
    power: float
    span_ok: bool
    noncentrality: float
    why: str


def relaxation_identifiability(d: Design, g: float, tau_s: float, *,
                               points_per_press: int = 100) -> RelaxationPlan:
    """Can :func:`~tactilevision.mechanics.fit_relaxation` identify g and tau from the
    design's holds?

    Parameters
    ----------
    d : Design
    g : float
        Relaxing fraction of the gel's force, in (0, 1).
    tau_s : float
        Relaxation time, s, > 0.
    points_per_press : int, default 100
        As in ``fit_relaxation``: each hold is averaged in this many blocks.

    Returns
    -------
    RelaxationPlan

    Raises
    ------
    InputError
        For g outside (0, 1) or tau_s not positive.

    Notes
    -----
    ``fit_relaxation`` calls g and tau identified when a straight decay
    ``F_i = A_i (1 + r t)`` (tau -> infinity at fixed g / tau) is rejected
    against the fitted standard linear solid by an F test at ``RELAX_ALPHA``
    and tau lies in the span the holds resolve. The holds are planned without
    noise: each press's force ``F_i(t) = P_i [(1 - g) + g phi(T_i / tau)
    exp(-t / tau)]`` (P_i the FEM force at its depth, T_i its loading time:
    ``w`` over the stage's speed, :func:`indenter_speeds`; phi
    :func:`ramp_factor`), sampled at ``rate_hz``
    over its hold and averaged in blocks as the fit does; ``force_noise_n`` per
    sample, white, gives the block means' variance sigma_b^2. The straight
    decay's least-squares misfit ``RSS_line`` to these noise-free holds over
    sigma_b^2 is the noncentrality of the test (the fitted model's own misfit is
    zero there), and the power is the noncentral F's tail beyond the test's
    critical value. The F/T noise of a real sensor is coloured: with fewer
    independent samples than assumed the power is lower.
    """
    if not 0 < g < 1:
        raise InputError(f"relaxation g must be in (0, 1), got {g!r}")
    tau = _positive(tau_s, "relaxation tau_s")
    w, P = design_table(d)
    hold = hold_lengths(d, w.size)
    ramp = w / indenter_speeds(d)[press_indenters(d)]
    curves, var_b = [], []
    for Pi, Ti, Hi in zip(P, ramp, hold, strict=True):
        n = max(round(Hi * d.rate_hz), 5)
        t = np.arange(n) / d.rate_hz
        f = Pi * ((1 - g) + g * float(ramp_factor(Ti, tau)) * np.exp(-t / tau))
        tb, fb = hold_blocks(t, f, points_per_press)          # as fit_relaxation averages
        curves.append((tb, fb, float(Ti)))
        var_b.append(np.full(tb.size, d.force_noise_n**2 / max(1, -(-n // points_per_press))))
    var_b = np.concatenate(var_b)
    s2 = float(np.mean(var_b))
    n_pts = var_b.size
    dof = max(n_pts - len(curves) - 2, 1)
    _, rss_line = straight_decay(curves)
    lam = rss_line / s2
    shortest, longest = float(hold.min()), float(hold.max())
    span_ok = TAU_MIN_HOLD_FRACTION * shortest <= tau <= TAU_HOLD_RATIO * longest
    crit = float(stats.f.isf(RELAX_ALPHA, 1, dof))
    power = float(stats.ncf.sf(crit, 1, dof, lam)) if span_ok else 0.0
    if not span_ok:
        why = (f"tau = {tau:g} s lies outside the span the holds resolve "
               f"({TAU_MIN_HOLD_FRACTION:g} of the shortest hold to {TAU_HOLD_RATIO:g} times the "
               f"longest: {TAU_MIN_HOLD_FRACTION * shortest:.3g} to "
               f"{TAU_HOLD_RATIO * longest:.3g} s): fit_relaxation will not identify g and tau; "
               + ("longer holds would" if tau > TAU_HOLD_RATIO * longest else
                  "a faster F/T window at the hold's start would"))
    else:
        why = (f"fit_relaxation identifies g = {g:g} and tau = {tau:g} s in {100 * power:.0f} % "
               f"of sessions (its curvature test at p < {RELAX_ALPHA:g}; noncentrality "
               f"{lam:.3g})" + ("" if power >= 0.95 else
                                ": longer holds, more presses or a quieter F/T would raise it"))
    return RelaxationPlan(g=float(g), tau_s=tau, power=power, span_ok=bool(span_ok),
                          noncentrality=float(lam), why=why)


def _line_covariance(d: Design, w: np.ndarray, P: np.ndarray, u: np.ndarray | None,
                     s_P: float, s_w: float) -> np.ndarray:
    """Covariance (2, 2) of the fit's intercept c and slope c beta (linear in the presses'
    P/w) from independent force noise `s_P` and depth noise `s_w` per press, by central
    differences of the fit in every press's force and depth.

    The noise-free table's repeats of a depth are the same press: the fit is symmetric
    in its presses, so its derivatives in each are equal, and one press per depth is
    differentiated."""
    n = w.size
    J_P = np.empty((2, n))
    J_w = np.empty((2, n))
    for x in np.unique(w):
        same = w == x
        i = int(np.flatnonzero(same)[0])
        for J, arr, step in ((J_P, P, 1e-4 * P[i]), (J_w, w, 1e-4 * w[i])):
            hi, lo = arr.copy(), arr.copy()
            hi[i] += step
            lo[i] -= step
            args_hi = (w, hi) if arr is P else (hi, P)
            args_lo = (w, lo) if arr is P else (lo, P)
            J[:, same] = ((_fit(d, *args_hi, u)[2:] - _fit(d, *args_lo, u)[2:])
                          / (2 * step))[:, None]
    return s_P**2 * J_P @ J_P.T + s_w**2 * J_w @ J_w.T


def _quadrature(d: Design, w: np.ndarray, P: np.ndarray, u: np.ndarray | None,
                cov_cs: np.ndarray) -> tuple[np.ndarray, float, float, float, float]:
    """Mean (E, nu), sd of E and nu, their correlation and the weight of the spread where
    the fit gives none, over the Gaussian of (c, c beta) with covariance `cov_cs`.

    E and nu are not linear in (c, c beta): nu(beta) bends and the table clips it. Gauss-
    Hermite quadrature, each node fitted as a table whose P/w is moved by that node's
    line (which moves the fit's line by exactly as much, its residuals unchanged)."""
    x = w / d.thickness_mm
    t, wt = np.polynomial.hermite_e.hermegauss(QUADRATURE_NODES)     # probabilists'
    wt = wt / wt.sum()
    L = np.linalg.cholesky(cov_cs + 1e-30 * np.eye(2))
    vals, weights = [], []
    for i, ti in enumerate(t):
        for j, tj in enumerate(t):
            dc, ds = L @ np.array([ti, tj])
            vals.append(_fit(d, w, P + w * (dc + ds * x), u)[:2])
            weights.append(wt[i] * wt[j])
    vals, weights = np.array(vals), np.array(weights)
    ok = np.isfinite(vals).all(axis=1)
    out_of_table = float(weights[~ok].sum())
    if not ok.any():
        nan = math.nan
        return np.full(2, nan), nan, nan, nan, 1.0
    wk = weights[ok] / weights[ok].sum()
    mean = wk @ vals[ok]
    dev = vals[ok] - mean
    cov = (dev * wk[:, None]).T @ dev
    sE, snu = (float(math.sqrt(max(v, 0.0))) for v in np.diag(cov))
    corr = float(cov[0, 1] / (sE * snu)) if sE > 0 and snu > 0 else 0.0
    return mean, sE, snu, corr, out_of_table


def _biases(d: Design, w: np.ndarray, P: np.ndarray, u: np.ndarray | None,
            base: np.ndarray, mean: np.ndarray, shared_um: float
            ) -> dict[str, tuple[float, float]]:
    """(E error %, nu error) of the noise-free fit, of the mean over sessions, and of each
    shared error at its bound, either way (:attr:`PlanPrediction.bias`)."""
    def err(est: np.ndarray) -> tuple[float, float]:
        return (float(100 * (est[0] / d.E_mpa - 1)), float(est[1] - d.nu))

    bias = {"model": err(base[:2]), "noise": err(mean)}
    if shared_um > 0:
        bias["depth_shared"] = err(_fit(d, w + shared_um * 1e-3, P, u)[:2])
        # a bound as deep as the shallowest gauge depth leaves no depth to fit: no E or nu
        bias["depth_shared_minus"] = (err(_fit(d, w - shared_um * 1e-3, P, u)[:2])
                                      if np.all(w - shared_um * 1e-3 > 0)
                                      else (math.nan, math.nan))
    if d.force_zero_n > 0:
        bias["force_zero"] = err(_fit(d, w, P + d.force_zero_n, u)[:2])
        bias["force_zero_minus"] = err(_fit(d, w, P - d.force_zero_n, u)[:2])
    return bias


def plan_session(design: Design, *, effect_sizes: bool = True) -> PlanPrediction:
    """Predict what a calibration session of this design will measure.

    Parameters
    ----------
    design : Design
    effect_sizes : bool, default True
        Also the smallest size of each catalogue effect ``diagnose`` names
        (:func:`effect_sensitivity`, about a second) and the ``detect`` sizes' power.

    Returns
    -------
    prediction : PlanPrediction

    Notes
    -----
    The fit is :func:`fit_indentation` on each press's (w, P), with each press's
    depth sd given (errors in both variables), as ``calibrate`` fits. Its intercept c
    and slope c beta are linear in the presses' P/w: their covariance is propagated
    from independent force noise s_P (the F/T sample sd over sqrt(window)) and depth
    noise s_w per press through central differences of the fit in every press's force
    (step 1e-4 P) and depth (step 1e-4 w) on the design's noise-free table
    (:func:`design_table`). E and nu are not linear in (c, c beta), and the beta table
    clips nu: their mean, sds and correlation are integrated over that Gaussian by
    Gauss-Hermite quadrature (:data:`QUADRATURE_NODES` per axis), each node a fit of
    the table moved by the node's line. The shared errors are fitted at their bounds,
    either way. With an ``unseen_share`` q the line's covariance is divided by 1 - q (the
    presses left, lost evenly over the depths).

    The effect sizes are :func:`effect_sensitivity`'s (``diagnose``'s decisions replayed
    over drawn noise) and the ``detect`` sizes' power :func:`effect_power`'s.

    Where the fit refuses the design's noise-free table (a/h outside the kappa table,
    or a bonded punch at an a/h where beta does not increase with nu), the sds are NaN,
    ``nu_identified`` is False and the note says why.
    """
    d = design
    w, P = design_table(d)
    sd_um, shared_um, how = depth_uncertainty(d)
    s_w = sd_um * 1e-3
    s_P = d.force_noise_n / math.sqrt(d.window_samples)
    u = np.full(w.size, s_w) if s_w > 0 else None
    notes: list[str] = []
    untest = untestable_effects(d)
    try:
        sizes = effect_sensitivity(d) if effect_sizes else {}
        seen = ({name: effect_power(d, name, float(size)) for name, size in d.detect}
                if effect_sizes else {})
        crossing = crossing_effect_sizes(d) if effect_sizes else {}
    except InputError as exc:           # the FEM table cannot give this design's forces
        sizes, seen, crossing = {}, {}, {}
        notes.append(f"no effect sizes: {exc}")
    sizes = {**sizes, **crossing}       # a mark's crossing forces size what its depths absorb
    if effect_sizes and crossing:
        # an offset along depth: named under the mark rule where the crossing forces name it
        try:
            offsets = crossing_offset_sizes(d)
        except InputError as exc:
            offsets = {}
            notes.append(f"the offsets along depth were not sized on the crossing forces: {exc}")
        sizes.update({k: larger_of(sizes[k], v) for k, v in offsets.items() if k in sizes})
    untest = {k: v for k, v in untest.items() if k not in crossing}
    relax = (None if d.relaxation_g is None else
             relaxation_identifiability(d, float(d.relaxation_g), float(d.relaxation_tau_s)))
    try:
        base = _fit(d, w, P, u)
    except InputError as exc:       # the tables cannot fit this a/h: nothing to predict
        why = str(exc)
    else:
        why = None if np.isfinite(base[:2]).all() else (
            f"the fit of the design's own noise-free presses finds no E or nu: their beta lies "
            f"outside the FEM beta table at a/h = {d.a_over_h:.2f}")
    if why is not None:
        nan = math.nan
        return PlanPrediction(d, w.size, sd_um, shared_um, how, s_P, nan, nan, nan, nan, {},
                              False, [f"nu is not identified by this design: {why}"],
                              untest, relax, sizes, seen)
    n = w.size
    # presses whose mark is not seen are lost to the fit too: the line's covariance over the
    # (1 - unseen_share) of them that remain, lost evenly over the depths
    cov_cs = _line_covariance(d, w, P, u, s_P, s_w) / (1.0 - d.unseen_share)
    if d.unseen_share > 0:
        notes.append(f"E's and nu's spread counts the {100 * (1 - d.unseen_share):.3g} % of "
                     "presses whose mark is expected to be seen ([plan] unseen_share)")
    mean, sE, snu, corr, out_of_table = _quadrature(d, w, P, u, cov_cs)
    if not np.isfinite(mean).all():
        nan = math.nan
        return PlanPrediction(d, n, sd_um, shared_um, how, s_P, nan, nan, nan, nan, {}, False,
                              ["nu is not identified by this design: beta falls outside the "
                               "FEM beta table over the whole predicted spread"], untest, relax,
                              sizes, seen)
    if out_of_table > 0.01:
        notes.append(f"beta falls outside the beta table in {100 * out_of_table:.0f} % of "
                     "sessions of this design (E and nu not computed there); the sds are "
                     "over the others")

    bias = _biases(d, w, P, u, base, mean, shared_um)
    beyond = [k for k, v in bias.items() if not np.isfinite(v).all()]
    if beyond:
        notes.append(f"{', '.join(beyond)}: the fit finds no E or nu there (beta beyond the "
                     "beta table): that shared error would leave nu undetermined")
    pinned = snu < 1e-6 < sE
    identified = bool(np.isfinite(base).all() and snu <= 0.25 * (NU_RANGE[1] - NU_RANGE[0])
                      and out_of_table <= 0.05 and not pinned)
    if pinned:
        notes.append(f"nu is not identified: the fit puts it at {mean[1]:.3f} whatever the "
                     f"presses (the beta table cannot tell nu at a/h = {d.a_over_h:.2f}); E's "
                     "sd is at that nu, and its bias is nu's")
    elif not identified and snu > 0.25 * (NU_RANGE[1] - NU_RANGE[0]):
        notes.append(f"nu is not identified: its predicted sd {snu:.3f} exceeds a quarter of "
                     f"its range {NU_RANGE[0]:g} to {NU_RANGE[1]:g}")
    elif not identified:
        notes.append("nu is not identified: beta falls outside the beta table in more than "
                     "5 % of sessions")
    return PlanPrediction(d, n, sd_um, shared_um, how, s_P, sE, snu, 100 * sE / d.E_mpa,
                          corr, bias, identified, notes, untest, relax, sizes, seen)


def plan(design: Design | str | Path) -> PlanPrediction:
    """What a calibration session of this design will measure (``tactilevision plan``).

    Parameters
    ----------
    design : Design, or str or Path of a design file (:func:`read_design`)

    Returns
    -------
    prediction : PlanPrediction

    Raises
    ------
    InputError
        For a bad design file or design (naming the key), or a design whose a/h the
        tables cannot fit.

    Examples
    --------
    >>> from tactilevision.planning import Design
    >>> p = plan(Design(thickness_mm=3.0, radius_mm=2.5,
    ...                 depths_mm=(0.15, 0.3, 0.4, 0.5, 0.6), bevel_angle_deg=5.0,
    ...                 overshoot_um=(30.0, 60.0)))
    >>> round(p.depth_std_um, 2)
    1.81
    """
    return plan_session(design if isinstance(design, Design) else read_design(design))


def design_from_calibration(folder: str | Path, session: str | Path | None = None
                            ) -> Design:
    """The design of a session that ``calibrate`` has run, to plan the next one from.

    Parameters
    ----------
    folder : str or Path
        The calibration folder (``fit.json``, ``measurements.csv``).
    session : str or Path, optional
        The session folder it calibrated (its ``session.toml`` gives the image scale,
        the bevel, the F/T window and its ``frames.csv`` the frame rate). Default: the
        one ``fit.json`` names, where it exists.

    Returns
    -------
    design : Design
        h and a, E and nu as fitted; the gauge block's depths w0 (each press's depth
        less its overshoot); the repeats per depth (presses over depths, rounded); the
        overshoot range the presses had, um; the stage's motion from the presses'
        loading times in ``holds.csv`` (``approach_s`` where every press took about the
        same time, else ``stage_speed_mm_s``); the F/T sample sd (median of
        ``force_std_n``); the zero's stability (the drift ``calibrate`` measured plus two
        of its standard errors); the session's ``presses.csv``, where it presses every
        depth equally often, as the ``schedule`` (and its repeats); under the mark rule,
        the frame periods its crossing brackets spanned on average
        (:func:`~tactilevision.planning.measured_bracket_periods`) and the share of its
        presses ``calibrate`` rejected (``unseen_share``, at most 0.45). What the folders
        do not hold keeps :class:`Design`'s default.

    Raises
    ------
    InputError
        A folder without ``fit.json`` or ``measurements.csv``, or a fit without E and nu.

    Warns
    -----
    InputWarning
        A fitted nu outside the FEM table's range (0.30 to 0.499,
        :func:`~tactilevision.mechanics.kappa_n_nu_range`; the paper's relation, eq. (7),
        reaches 0.5): planned at the range's nearer end, said so.
    """
    folder = Path(folder)
    try:
        fit = json.loads((folder / "fit.json").read_text())
        with open(folder / "measurements.csv", newline="") as fh:
            rows = list(csv.DictReader(fh))
    except FileNotFoundError as exc:
        raise InputError(f"{folder} is not a calibration folder: {exc.filename} is "
                         "missing") from None
    except (OSError, ValueError) as exc:
        raise InputError(f"{folder}: cannot read the calibration ({exc})") from None
    E, nu = fit.get("E_mpa"), fit.get("nu")
    if not (isinstance(E, int | float) and isinstance(nu, int | float)
            and math.isfinite(E) and math.isfinite(nu)):
        raise InputError(f"{folder}/fit.json has no E and nu to plan from")

    def col(name: str) -> np.ndarray:
        return np.array([float(r[name]) if r.get(name) not in (None, "") else np.nan
                         for r in rows])

    depth, over = col("depth_mm"), col("overshoot_mm")
    w0 = np.round(np.where(np.isfinite(over), depth - over, depth), 4)
    depths = tuple(float(v) for v in np.unique(w0[np.isfinite(w0)]))
    kw: dict[str, Any] = dict(
        thickness_mm=float(fit["thickness_mm"]), radius_mm=float(fit["radius_mm"]),
        depths_mm=depths, repeats=max(1, round(len(rows) / max(len(depths), 1))),
        E_mpa=float(E), nu=_plannable_nu(float(nu), folder))
    if np.isfinite(over).any():
        kw["overshoot_um"] = (max(0.0, float(np.nanmin(over)) * 1e3),
                              max(0.0, float(np.nanmax(over)) * 1e3))
    f_sd = col("force_std_n") if rows and "force_std_n" in rows[0] else np.array([])
    if np.isfinite(f_sd).any():
        kw["force_noise_n"] = float(np.nanmedian(f_sd))
    waits = col("wait_s") if rows and "wait_s" in rows[0] else np.array([])
    if np.isfinite(waits).any():
        kw["waits_s"] = tuple(round(float(v), 3) for v in waits[np.isfinite(waits)])
    if rows and "press" in rows[0]:
        kw.update(_stage_motion(folder / "holds.csv", depth, col("press")))
    relax = fit.get("relaxation")
    if isinstance(relax, dict) and relax.get("resolved") and 0 < float(relax.get("g") or 0) < 1:
        kw["relaxation_g"] = float(relax["g"])      # the relaxation it found, to plan for
        kw["relaxation_tau_s"] = float(relax["tau_s"])
    zero = fit.get("ft_zero")
    if isinstance(zero, dict) and isinstance(zero.get("drift_n"), int | float):
        kw["force_zero_n"] = abs(float(zero["drift_n"])) + 2 * float(zero.get("drift_se_n")
                                                                      or 0.0)
    where = Path(session) if session is not None else (
        Path(fit["session"]) if isinstance(fit.get("session"), str) else None)
    if where is not None and (where / "session.toml").is_file():
        try:
            doc = tomllib.loads((where / "session.toml").read_text())
        except (OSError, tomllib.TOMLDecodeError) as exc:
            raise InputError(f"{where / 'session.toml'}: {exc}") from None
        warn_unknown_keys(doc, where / "session.toml", KNOWN_KEYS)
        sensor, gauge = doc.get("sensor", {}), doc.get("gauge_block", {})
        force = doc.get("force_sensor", {})
        for key, table, name in (("mm_per_px", sensor, "mm_per_px"),
                                 ("bevel_angle_deg", gauge, "bevel_angle_deg"),
                                 ("rate_hz", force, "rate_hz"),
                                 ("window_samples", force, "window_samples")):
            if isinstance(table, dict) and isinstance(table.get(name), int | float):
                kw[key] = table[name]
        if force.get("window_at") in ("start", "end"):
            kw["window_at"] = force["window_at"]
        hold = col("hold_s")
        if kw.get("window_at") == "end" and np.isfinite(hold).all() and hold.size:
            half = 0.5 * kw.get("window_samples", 200) / kw.get("rate_hz", 1000.0)
            kw["holds_s"] = tuple(round(float(v) + half, 3) for v in hold)  # in press order
        frames = where / "frames.csv"
        if frames.is_file():
            with open(frames, newline="") as fh:
                t = np.array([float(r["t_s"]) for r in csv.DictReader(fh) if r.get("t_s")])
            dt = np.diff(np.sort(t))
            if dt.size and np.median(dt) > 0:
                kw["frame_rate_hz"] = float(1.0 / np.median(dt))
        schedule = _session_schedule(where, gauge, depths)
        if schedule is not None:
            kw["schedule"] = schedule
            kw["repeats"] = len(schedule) // len(depths)
    sem = col("force_w0_sem_n") if rows and "force_w0_sem_n" in rows[0] else None
    return _with_mark_brackets(Design(**kw), w0, sem, fit.get("n_rejected"))


def _plannable_nu(nu: float, folder: Path) -> float:
    """`nu` within the FEM table's range that the plan's forces are read from, with a
    warning naming ``fit.json`` where it lay outside (the paper's relation reaches 0.5,
    the table 0.499)."""
    lo, hi = kappa_n_nu_range()
    if not lo <= nu <= hi:
        warnings.warn(f"{folder}/fit.json: nu = {nu:.6g} lies outside the FEM table's "
                      f"{lo:g} to {hi:g}, which the plan's forces are read from: planned at "
                      f"{min(max(nu, lo), hi):g}", InputWarning, stacklevel=3)
    return min(max(nu, lo), hi)


def _with_mark_brackets(design: Design, w0: np.ndarray, sem: np.ndarray | None,
                        rejected: Any) -> Design:
    """`design` with a drawn mark's crossing brackets as the session had them: their mean
    frame periods (:func:`measured_bracket_periods`) and the share of its presses
    ``calibrate`` rejected (at most 0.45); unchanged without crossing forces."""
    periods = None if sem is None else measured_bracket_periods(design, w0, sem)
    if periods is None:
        return design
    lost = (float(rejected) / (rejected + len(w0))
            if isinstance(rejected, int) and rejected > 0 else 0.0)
    return replace(design, bracket_periods=periods, unseen_share=round(min(lost, 0.45), 4))


def _stage_motion(holds: Path, depth: np.ndarray, press: np.ndarray) -> dict[str, float]:
    """How the session's stage moved, from each press's loading time (``holds.csv``'s
    ``ramp_s``, from the force's rise to the hold) and depth: ``approach_s`` (the median
    loading time) where the presses took about the same time whatever their depth (a move
    of fixed duration), ``stage_speed_mm_s`` (the median depth over loading time) where
    the time grew with the depth, whichever leaves the smaller relative scatter; nothing
    without holds.csv or with fewer than 3 presses timed."""
    if not holds.is_file():
        return {}
    try:
        h = read_holds(holds)
    except InputError:
        return {}
    ids, first = np.unique(h["press"], return_index=True)
    ramp = dict(zip(ids.tolist(), h["ramp_s"][first].tolist(), strict=True))
    pairs = np.array([(w, ramp.get(int(p), np.nan)) for w, p in zip(depth, press, strict=True)
                      if np.isfinite(p)])
    if pairs.size:
        pairs = pairs[np.isfinite(pairs).all(axis=1) & (pairs > 0).all(axis=1)]
    if len(pairs) < 3:
        return {}
    w, r = pairs[:, 0], pairs[:, 1]
    v = w / r
    if np.std(r) / np.mean(r) <= np.std(v) / np.mean(v):
        return {"approach_s": round(float(np.median(r)), 4)}
    return {"stage_speed_mm_s": round(float(np.median(v)), 5)}


def _session_schedule(where: Path, gauge: Any, depths: tuple[float, ...]
                      ) -> tuple[tuple[int, float, float], ...] | None:
    """The session's ``presses.csv`` as the design's schedule (its indenters renumbered
    onto the design's depths), where it has one that presses every depth equally often;
    else None."""
    path = where / "presses.csv"
    block = gauge.get("depths_mm") if isinstance(gauge, dict) else None
    if not path.is_file() or not isinstance(block, list) or not depths:
        return None
    try:
        schedule = read_schedule(path, len(block))
        index = [depths.index(round(float(w), 4)) if round(float(w), 4) in depths else -1
                 for w in block]
    except (InputError, TypeError, ValueError):
        return None
    ind = np.array([index[i] for i, _, _ in schedule])
    counts = np.bincount(ind[ind >= 0], minlength=len(depths))
    if (ind < 0).any() or len(set(counts.tolist())) != 1:
        return None
    return tuple((int(i), x, y) for i, (_, x, y) in zip(ind, schedule, strict=True))
