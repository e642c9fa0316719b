"""What a ball's law misses: the error ladder of an indenter's presses, and the FEA check.

:func:`diagnose_indenter` starts from the small-strain law with the stated contact
and tries, one at a time, the changes that name a physical effect:

- ``large_deformation``: finite strain (the Neo-Hookean law instead of the linear);
- ``contact_slip``: the other contact condition (frictionless where the base ties
  the gel to the ball, tied where it slips);
- ``force_offset``: a constant force bias F0 (a bad tare), P + F0;
- ``depth_offset``: a constant depth error delta (a late or early contact point),
  P(w + delta).

Each model has E at the stated nu (linear in E) and its effect's parameter; it is
scored by its residuals and the BIC, and the change that lowers the BIC most (by more
than 2) is taken, until none does. Every rung reports each press's apparent E: flat
over depth when the model is right. One noise model runs through it: the presses'
own scatter about the model (least squares on P), and where presses repeat a depth,
their replicate scatter says whether the final model still leaves structure.

:func:`validate_indenter` is the paper's FEA check for any indenter: the depth the
law needs to reach each measured force, against the measured depth.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import optimize, stats

from .._checks import InputError, check_array
from ._indenter import Indenter

__all__ = ["INDENTER_EFFECTS", "IndenterDiagnosis", "IndenterRung", "IndenterValidation",
           "diagnose_indenter", "validate_indenter"]

#: The changes :func:`diagnose_indenter` tries, and what each stands for.
INDENTER_EFFECTS = {
    "large_deformation": "finite strain: the Neo-Hookean law instead of the linear",
    "contact_slip": "the other contact condition (slip where tied, tied where slipping)",
    "force_offset": "a constant force bias F0 (a bad tare): P + F0",
    "depth_offset": "a constant depth error delta (the contact point): P(w + delta)",
}
#: A change is taken when it lowers the BIC by more than this (positive evidence).
BIC_STEP = 2.0


@dataclass(frozen=True)
class IndenterRung:
    """One model of the ladder.

    Attributes
    ----------
    effects : tuple of str
        The changes taken so far (names of :data:`INDENTER_EFFECTS`).
    law, contact : str
    E_mpa : float
        At the stated nu.
    force_offset_n, depth_offset_mm : float
        The offsets' fitted values (0 when not in the model).
    rmse_n, bic : float
    n_params : int
    apparent_E_mpa : (N,) float64 ndarray
        Each press's own E with the model's offsets taken off.
    drift : float
        Relative change of the apparent E from the shallowest quarter of the presses to
        the deepest (0 for a flat profile).
    predicted_n : (N,) float64 ndarray
    """

    effects: tuple[str, ...]
    law: str
    contact: str
    E_mpa: float
    force_offset_n: float
    depth_offset_mm: float
    rmse_n: float
    bic: float
    n_params: int
    apparent_E_mpa: np.ndarray = field(repr=False)
    drift: float = 0.0
    predicted_n: np.ndarray = field(default=None, repr=False)


@dataclass(frozen=True)
class IndenterDiagnosis:
    """Result of :func:`diagnose_indenter`.

    Attributes
    ----------
    ladder : tuple of IndenterRung
        The base model, then one rung per change taken.
    missing_effects : tuple of str
        The changes taken, in order (empty: the base law explains the presses as well
        as any change).
    candidates : dict of str to dict
        Every change tried from the final model: ``rmse_n``, ``bic``, ``E_mpa``.
    nu : float
        The stated nu every model is fitted at.
    floor_n : float or None
        Replicate scatter (pooled sd of presses at one depth), N; None without
        repeated depths.
    floor_test : dict or None
        ``chi2``, ``dof``, ``p_value`` of the final model's residuals against the
        replicate scatter (an F test of lack of fit); None without replicates.
    message : str
    depth_mm, force_n : (N,) float64 ndarray
        The presses.
    not_tried : dict of str to str
        Changes that could not be fitted from the final model, and why (a FEM sweep
        that did not converge, an offset that leaves the table).
    """

    ladder: tuple[IndenterRung, ...]
    missing_effects: tuple[str, ...]
    candidates: dict
    nu: float
    floor_n: float | None
    floor_test: dict | None
    message: str
    depth_mm: np.ndarray = field(repr=False)
    force_n: np.ndarray = field(repr=False)
    not_tried: dict = field(default_factory=dict)

    def to_json_dict(self) -> dict:
        """JSON-ready: arrays as lists, NaN as None."""
        def clean(v):
            if isinstance(v, np.ndarray):
                return [clean(x) for x in v.tolist()]
            if isinstance(v, float | np.floating):
                return float(v) if math.isfinite(v) else None
            if isinstance(v, tuple | list):
                return [clean(x) for x in v]
            if isinstance(v, dict):
                return {k: clean(x) for k, x in v.items()}
            return v

        rungs = [{k: clean(getattr(r, k)) for k in r.__dataclass_fields__} for r in self.ladder]
        return {"ladder": rungs, "missing_effects": list(self.missing_effects),
                "candidates": clean(self.candidates), "nu": self.nu,
                "floor_n": clean(self.floor_n), "floor_test": clean(self.floor_test),
                "message": self.message, "depth_mm": clean(self.depth_mm),
                "force_n": clean(self.force_n), "not_tried": dict(self.not_tried)}


def _drift(depth: np.ndarray, apparent: np.ndarray) -> float:
    order = np.argsort(depth)
    k = max(1, depth.size // 4)
    lo, hi = float(np.mean(apparent[order[:k]])), float(np.mean(apparent[order[-k:]]))
    return hi / lo - 1.0 if lo > 0 else math.nan


class _Models:
    """The force columns of one indenter at one nu, by (law, contact), and the fits."""

    def __init__(self, indenter: Indenter, w: np.ndarray, P: np.ndarray, h: float,
                 nu: float) -> None:
        self.indenter, self.w, self.P, self.h, self.nu = indenter, w, P, h, nu
        self.reach = indenter.reach_mm(h)

    def g(self, law: str, contact: str, w: np.ndarray) -> np.ndarray:
        return self.indenter.force(w, E_mpa=1.0, nu=self.nu, thickness_mm=self.h, law=law,
                                   contact=contact)

    def fit(self, effects: tuple[str, ...], law: str, contact: str) -> IndenterRung:
        w, P, n = self.w, self.P, self.w.size
        delta = 0.0
        if "depth_offset" in effects:
            lo = -0.25 * float(w.min())     # a contact point off by a quarter of the first
            hi = min(self.reach - float(w.max()), 0.25 * float(w.min()))
            if not hi > lo:
                raise InputError("no depth offset keeps every press within the table")
            grid = np.linspace(lo, hi, 41)
            cost = [self._linear(self.g(law, contact, w + d), P, effects)[2] for d in grid]
            k = int(np.argmin(cost))
            a, b = grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]
            res = optimize.minimize_scalar(
                lambda d: self._linear(self.g(law, contact, w + d), P, effects)[2],
                bounds=(a, b), method="bounded", options={"xatol": 1e-7 * self.h})
            delta = float(res.x)
        g = self.g(law, contact, w + delta)
        E, F0, rss = self._linear(g, P, effects)
        k = 1 + ("force_offset" in effects) + ("depth_offset" in effects)
        pred = E * g + F0
        apparent = (P - F0) / g
        return IndenterRung(
            effects=effects, law=law, contact=contact, E_mpa=E, force_offset_n=F0,
            depth_offset_mm=delta, rmse_n=math.sqrt(rss / n),
            bic=n * math.log(max(rss / n, 1e-300)) + k * math.log(n), n_params=k,
            apparent_E_mpa=apparent, drift=_drift(w, apparent), predicted_n=pred)

    @staticmethod
    def _linear(g: np.ndarray, P: np.ndarray, effects: tuple[str, ...]
                ) -> tuple[float, float, float]:
        """Least squares of P = E g (+ F0): (E, F0, RSS)."""
        if "force_offset" in effects:
            X = np.column_stack([g, np.ones_like(g)])
            (E, F0), *_ = np.linalg.lstsq(X, P, rcond=None)
        else:
            E, F0 = float(g @ P / (g @ g)), 0.0
        r = P - E * g - F0
        return float(E), float(F0), float(r @ r)


def _floor(w: np.ndarray, resid: np.ndarray, n_params: int) -> tuple[float | None, dict | None]:
    """Replicate scatter of presses at one depth, and the lack-of-fit F test against it."""
    depths, inv = np.unique(np.round(w, 9), return_inverse=True)
    dof_pure = w.size - depths.size
    if dof_pure < 2:
        return None, None
    means = np.bincount(inv, resid) / np.bincount(inv)
    ss_pure = float(np.sum((resid - means[inv]) ** 2))
    ss_lack = float(np.sum(resid ** 2)) - ss_pure
    dof_lack = depths.size - n_params
    floor = math.sqrt(ss_pure / dof_pure)
    if dof_lack < 1 or ss_pure <= 0:
        return floor, None
    F = (ss_lack / dof_lack) / (ss_pure / dof_pure)
    return floor, {"F": F, "dof": [dof_lack, dof_pure],
                   "p_value": float(stats.f.sf(F, dof_lack, dof_pure))}


def diagnose_indenter(depth_mm: np.ndarray, force_n: np.ndarray, indenter: Indenter, *,
                      thickness_mm: float, contact: str | None = None,
                      nu: float = 0.5) -> IndenterDiagnosis:
    """The error ladder of an indenter's presses: which effect its law misses.

    Parameters
    ----------
    depth_mm, force_n : (N,) array_like of float
        Presses: depths w (mm, > 0, within the indenter's reach) and forces P (N).
        Three presses or more.
    indenter : Indenter
        A :class:`Sphere` (or any indenter with two contact conditions).
    thickness_mm : float
        h, mm.
    contact : str, optional
        The stated contact condition (the base model's); the indenter's default.
    nu : float, default 0.5
        The nu every model is fitted at (E is linear at a fixed nu; a ball's presses
        rarely identify nu, :func:`fit_indenter`).

    Returns
    -------
    IndenterDiagnosis

    Raises
    ------
    InputError
        For fewer than three presses, a depth <= 0 or past the reach (naming the
        press), a force <= 0, or a bad h.

    Notes
    -----
    BIC = n ln(RSS / n) + k ln n (Schwarz 1978) with k the model's parameters
    (E, and an offset's). A change of the law or the contact adds no parameter:
    it is taken when it lowers the residual sum of squares by a factor
    exp(2 / n) or more. Without repeated depths the presses' noise is not
    measured apart from the model, and the ladder ranks models by their
    residuals; with them, an F test of lack of fit (the final model's
    residuals against the replicate scatter) says whether structure is left.
    """
    w = check_array(depth_mm, "depth_mm", [("N",)], dtype=np.number, finite=True)
    P = check_array(force_n, "force_n", [(w.shape[0],)], dtype=np.number, finite=True)
    w, P = w.astype(np.float64), P.astype(np.float64)
    h = float(thickness_mm)
    if not (math.isfinite(h) and h > 0):
        raise InputError(f"thickness_mm must be positive, got {thickness_mm!r}")
    if w.size < 3:
        raise InputError(f"{w.size} presses: the ladder needs three or more")
    for name, arr in (("depth_mm", w), ("force_n", P)):
        bad = np.flatnonzero(arr <= 0)
        if bad.size:
            raise InputError(f"press {int(bad[0])}: {name} = {arr[bad[0]]:g} must be positive")
    base_contact = indenter._contact(contact)
    reach = indenter.reach_mm(h)
    bad = np.flatnonzero(w > reach * (1 + 1e-9))
    if bad.size:
        raise InputError(f"press {int(bad[0])}: depth {w[bad[0]]:.4g} mm is past the "
                         f"{indenter.shape}'s reach, {reach:.4g} mm on h = {h:g} mm")
    other = next((c for c in indenter.contacts if c != base_contact), None)
    models = _Models(indenter, w, P, h, float(nu))
    state = {"effects": (), "law": "linear", "contact": base_contact}
    rung = models.fit((), "linear", base_contact)
    ladder = [rung]
    tried: dict = {}
    while True:
        tried, not_tried = {}, {}
        for name in INDENTER_EFFECTS:
            if name in state["effects"] or (name == "contact_slip" and other is None):
                continue
            law = "neo_hookean" if name == "large_deformation" else state["law"]
            con = state["contact"]
            if name == "contact_slip":
                con = other if con == base_contact else base_contact
            eff = tuple(e for e in (*state["effects"], name)
                        if e in ("force_offset", "depth_offset"))
            try:
                tried[name] = (models.fit(eff, law, con), law, con)
            except InputError as exc:
                not_tried[name] = str(exc)
        if not tried:
            break
        best = min(tried, key=lambda k: tried[k][0].bic)
        if not tried[best][0].bic < rung.bic - BIC_STEP:
            break
        cand, law, con = tried[best]
        state = {"effects": (*state["effects"], best), "law": law, "contact": con}
        rung = IndenterRung(**{**{k: getattr(cand, k) for k in cand.__dataclass_fields__},
                               "effects": state["effects"]})
        ladder.append(rung)
    floor, test = _floor(w, P - rung.predicted_n, rung.n_params)
    candidates = {k: {"rmse_n": v[0].rmse_n, "bic": v[0].bic, "E_mpa": v[0].E_mpa}
                  for k, v in tried.items()}
    diag = IndenterDiagnosis(
        ladder=tuple(ladder), missing_effects=tuple(state["effects"]), candidates=candidates,
        nu=float(nu), floor_n=floor, floor_test=test, message="", depth_mm=w, force_n=P,
        not_tried=not_tried)
    return _with_message(diag)


def _with_message(d: IndenterDiagnosis) -> IndenterDiagnosis:
    base, last = d.ladder[0], d.ladder[-1]
    s = [f"The small-strain law with {base.contact} contact leaves an RMSE of "
         f"{base.rmse_n * 1e3:.4g} mN; its apparent E changes by {100 * base.drift:+.1f} % "
         f"from the shallowest presses to the deepest (E = {base.E_mpa:.4g} MPa at "
         f"nu = {d.nu:g})."]
    for r in d.ladder[1:]:
        s.append(f"Adding {r.effects[-1]} ({INDENTER_EFFECTS[r.effects[-1]]}): RMSE "
                 f"{r.rmse_n * 1e3:.4g} mN, apparent E drift {100 * r.drift:+.1f} %, "
                 f"E = {r.E_mpa:.4g} MPa.")
    if not d.missing_effects:
        s.append("No change tried lowers the BIC by more than 2: nothing in the ladder is "
                 "missing.")
    else:
        s.append(f"Missing: {', '.join(d.missing_effects)}.")
    for name, why in d.not_tried.items():
        s.append(f"Not tried: {name} ({why}).")
    if d.floor_test is None:
        s.append("No depth is repeated: the presses' noise is not measured apart from the "
                 "model, so the ladder ranks models by their residuals; it does not test "
                 f"that the final model is complete (its apparent E still drifts "
                 f"{100 * last.drift:+.1f} %).")
    elif d.floor_test["p_value"] < 0.001:
        s.append(f"The final model still misses something: its residuals exceed the replicate "
                 f"scatter ({d.floor_n * 1e3:.3g} mN; lack of fit p = "
                 f"{d.floor_test['p_value']:.2g}).")
    else:
        s.append(f"The final model's residuals are within the replicate scatter "
                 f"({d.floor_n * 1e3:.3g} mN; lack of fit p = {d.floor_test['p_value']:.2g}).")
    return IndenterDiagnosis(**{**{k: getattr(d, k) for k in d.__dataclass_fields__},
                                "message": " ".join(s)})


@dataclass(frozen=True)
class IndenterValidation:
    """Result of :func:`validate_indenter`: simulated against measured depth per press.

    Attributes
    ----------
    depth_mm, force_n : (N,) float64 ndarray
        The presses.
    simulated_depth_mm : (N,) float64 ndarray
        The depth the law needs to reach each measured force (NaN past its reach).
    depth_error : (N,) float64 ndarray
        (simulated - measured) / measured.
    max_abs_error, mean_abs_error : float
    E_mpa, nu : float
    law, contact : str
    curve_depth_mm, curve_force_n : (M,) float64 ndarray
        The law's P(w) from 0 to past the deepest press, for figures.
    """

    depth_mm: np.ndarray
    force_n: np.ndarray
    simulated_depth_mm: np.ndarray
    depth_error: np.ndarray
    max_abs_error: float
    mean_abs_error: float
    E_mpa: float
    nu: float
    law: str
    contact: str
    curve_depth_mm: np.ndarray = field(default=None, repr=False)
    curve_force_n: np.ndarray = field(default=None, repr=False)

    @property
    def rel_error(self) -> np.ndarray:
        """The same as `depth_error` (the name :class:`IndentationValidation` uses)."""
        return self.depth_error


def validate_indenter(depth_mm: np.ndarray, force_n: np.ndarray, indenter: Indenter, *,
                      thickness_mm: float, E_mpa: float, nu: float,
                      law: str = "neo_hookean", contact: str | None = None
                      ) -> IndenterValidation:
    """The paper's FEA check for any indenter: the depth at each measured force.

    Parameters
    ----------
    depth_mm, force_n : (N,) array_like of float
    indenter : Indenter
    thickness_mm, E_mpa, nu : float
    law : {'neo_hookean', 'linear'}, default 'neo_hookean'
    contact : str, optional

    Returns
    -------
    IndenterValidation

    Raises
    ------
    InputError
        For a force <= 0 or a non-positive E.
    """
    w = check_array(depth_mm, "depth_mm", [("N",)], dtype=np.number, finite=True)
    P = check_array(force_n, "force_n", [(w.shape[0],)], dtype=np.number, finite=True)
    if not (math.isfinite(E_mpa) and E_mpa > 0):
        raise InputError(f"E_mpa must be positive, got {E_mpa!r}")
    bad = np.flatnonzero(P <= 0)
    if bad.size:
        raise InputError(f"press {int(bad[0])}: force_n = {P[bad[0]]:g} must be positive")
    h = float(thickness_mm)
    c = indenter._contact(contact)
    top = indenter.reach_mm(h, law)

    def force(x: float) -> float:
        return float(indenter.force(np.array([x]), E_mpa=E_mpa, nu=nu, thickness_mm=h,
                                    law=law, contact=c)[0])

    p_top = force(top)
    sim = np.array([optimize.brentq(lambda x, p=p: force(x) - p, 1e-9 * h, top, xtol=1e-10)
                    if p <= p_top else math.nan for p in P])
    err = (sim - w) / w
    curve = np.linspace(0.0, min(top, 1.1 * float(np.max(w))), 60)
    return IndenterValidation(
        depth_mm=w.astype(np.float64), force_n=P.astype(np.float64), simulated_depth_mm=sim,
        depth_error=err, max_abs_error=float(np.nanmax(np.abs(err))),
        mean_abs_error=float(np.nanmean(np.abs(err))), E_mpa=float(E_mpa), nu=float(nu),
        law=law, contact=c, curve_depth_mm=curve,
        curve_force_n=indenter.force(curve, E_mpa=E_mpa, nu=nu, thickness_mm=h, law=law,
                                     contact=c))
