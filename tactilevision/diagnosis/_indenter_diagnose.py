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

from .._checks import InputError, check_array, check_presses
from ..mechanics import Indenter, json_ready, reach_of
from ._indenter_noise import PressNoise, best_shift, press_noise, weighted_linear

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
    shared_shift : float
        Where the depths' shared error was fitted, as a fraction of its bound (-1 to 1;
        0 without one): every depth at (w + shared_shift s)(1 + shared_shift r).
    chi2 : float
        The weighted residual sum (variances of :attr:`IndenterDiagnosis.noise`; the
        plain sum of squares, N^2, when no uncertainty is stated).
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
    shared_shift: float = 0.0
    chi2: float = math.nan


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
        ``F``, ``dof``, ``p_value`` of the final model's residuals (weighted by the
        noise model) against the replicate scatter (an F test of lack of fit); None
        without replicates.
    message : str
    depth_mm, force_n : (N,) float64 ndarray
        The presses.
    not_tried : dict of str to str
        Changes that could not be fitted from the final model, and why (a FEM sweep
        that did not converge, an offset that leaves the table).
    noise : dict
        The noise model every rung was fitted with: ``stated`` (uncertainties given),
        ``sigma0_n`` (the force scatter they leave unexplained, Paule-Mandel, N),
        ``shared`` (a shared depth error fitted within its bound), ``shared_shift``
        (where the final model put it, -1 to 1), ``test`` (the final model's chi2
        against the stated uncertainties alone: ``chi2``, ``dof``, ``p_value`` of too
        much scatter, ``p_low`` of too little; None without them).
    not_testable : dict of str to str
        Changes the presses cannot tell from the depths' shared error, and why.
    equivalent_effects : dict of str to dict
        For each change taken, the others that lowered the BIC by more than 2 as well
        and came within 2 of it (``E_mpa``, ``bic``, their offsets): the presses cannot
        tell them apart; each is named beside the one taken.
    offset_bounds : (float, float)
        The range a depth offset was searched in, mm (a quarter of the shallowest
        depth each way, the reach on the deep side): an offset at either end is a
        bound, not a value.
    not_ruled_out : dict of str to dict
        The changes of the last round, none taken, whose BIC lies within 2 of the
        final model's (``E_mpa``, ``bic``, their offsets): the presses do not rule
        them out, and E under each is named beside the final model's. With few
        presses a real offset can fall here (four presses need the BIC to fall by
        more than 2 for one more parameter).
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
    noise: dict = field(default_factory=dict)
    not_testable: dict = field(default_factory=dict)
    equivalent_effects: dict = field(default_factory=dict)
    offset_bounds: tuple[float, float] = (math.nan, math.nan)
    not_ruled_out: dict = field(default_factory=dict)

    def to_json_dict(self) -> dict:
        """JSON-ready: arrays as lists, NaN as None; with the ``diagnose --json`` contract's
        keys (``model``, ``params``, ``rmse_n``, ``cv_rmse_n``, ``noise_floor_n``,
        ``covariates``, ``verdict``) beside the ladder's own."""
        clean = json_ready
        rungs = [{k: clean(getattr(r, k)) for k in r.__dataclass_fields__} for r in self.ladder]
        last = self.ladder[-1]
        first = self.missing_effects[0] if self.missing_effects else None
        verdict = {"missing_effect": first,
                   "equivalent_effects": sorted(self.equivalent_effects.get(first, {})),
                   "unexplained_covariate": None}
        return {"model": ["sphere", *last.effects],
                "params": {"E_mpa": clean(last.E_mpa), "nu": self.nu},
                "rmse_n": clean(last.rmse_n), "cv_rmse_n": None,
                "noise_floor_n": clean(self.floor_n), "covariates": [], "verdict": verdict,
                "ladder": rungs, "missing_effects": list(self.missing_effects),
                "candidates": clean(self.candidates), "nu": self.nu,
                "floor_n": clean(self.floor_n), "floor_test": clean(self.floor_test),
                "message": self.message, "depth_mm": clean(self.depth_mm),
                "force_n": clean(self.force_n), "not_tried": dict(self.not_tried),
                "noise": clean(self.noise), "not_testable": dict(self.not_testable),
                "equivalent_effects": clean(self.equivalent_effects),
                "offset_bounds_mm": clean(self.offset_bounds),
                "not_ruled_out": clean(self.not_ruled_out)}


def _drift(depth: np.ndarray, apparent: np.ndarray) -> float:
    order = np.argsort(depth)
    k = max(1, depth.size // 4)
    lo, hi = float(np.mean(apparent[order[:k]])), float(np.mean(apparent[order[-k:]]))
    return hi / lo - 1.0 if lo > 0 else math.nan


class _Models:
    """The force columns of one indenter at one nu, by (law, contact), and the fits, all
    against one noise model (:class:`PressNoise`)."""

    def __init__(self, indenter: Indenter, w: np.ndarray, P: np.ndarray, h: float,
                 nu: float, noise: PressNoise) -> None:
        self.indenter, self.w, self.P, self.h, self.nu = indenter, w, P, h, nu
        self.noise = noise
        self.reach = indenter.reach_mm(h)

    def g(self, law: str, contact: str, w: np.ndarray) -> np.ndarray:
        return self.indenter.force(w, E_mpa=1.0, nu=self.nu, thickness_mm=self.h, law=law,
                                   contact=contact)

    def _chi2(self, law: str, contact: str, w: np.ndarray, offset: bool) -> float:
        if np.any(w <= 0) or np.any(w > self.reach):
            return math.inf
        return weighted_linear(self.g(law, contact, w), self.P, self.noise.var, offset)[2]

    def _offset(self, law: str, contact: str, ws: np.ndarray, offset: bool) -> float:
        """The depth offset delta of the smallest chi2 for depths `ws` (a contact point off
        by at most a quarter of the first depth, every press within the table)."""
        lo = -0.25 * float(self.w.min())
        hi = min(self.reach - float(ws.max()), 0.25 * float(self.w.min()))
        if not hi > lo:
            raise InputError("no depth offset keeps every press within the table")
        return best_shift(lambda d: self._chi2(law, contact, ws + d, offset), lo, hi, 41)

    def fit(self, effects: tuple[str, ...], law: str, contact: str, *,
            shared: bool = True) -> IndenterRung:
        """One rung: E (and the effects' offsets) by weighted least squares, the shared
        depth error fitted within its bound where one is stated and `shared`."""
        w, P, n, noise = self.w, self.P, self.w.size, self.noise
        offset = "force_offset" in effects
        moved = "depth_offset" in effects

        def delta_at(lam: float) -> float:
            return self._offset(law, contact, noise.depths(w, lam), offset) if moved else 0.0

        def cost(lam: float) -> float:
            ws = noise.depths(w, lam)
            try:
                return self._chi2(law, contact, ws + delta_at(lam), offset)
            except InputError:
                return math.inf

        lam = best_shift(cost, -1.0, 1.0, 11) if shared and noise.has_shared else 0.0
        ws = noise.depths(w, lam)
        delta = delta_at(lam)
        if not math.isfinite(self._chi2(law, contact, ws + delta, offset)):
            raise InputError("the shared depth error leaves no depth within the table")
        g = self.g(law, contact, ws + delta)
        E, F0, chi2 = weighted_linear(g, P, noise.var, offset)
        k = 1 + offset + moved
        pred = E * g + F0
        apparent = (P - F0) / g
        r = P - pred
        return IndenterRung(
            effects=effects, law=law, contact=contact, E_mpa=E, force_offset_n=F0,
            depth_offset_mm=delta, rmse_n=math.sqrt(float(r @ r) / n),
            bic=n * math.log(max(chi2 / n, 1e-300)) + k * math.log(n), n_params=k,
            apparent_E_mpa=apparent, drift=_drift(w, apparent), predicted_n=pred,
            shared_shift=lam, chi2=chi2)


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
                      nu: float = 0.5, depth_std_mm: np.ndarray | None = None,
                      force_std_n: np.ndarray | None = None,
                      depth_shared_mm: float | np.ndarray = 0.0,
                      depth_shared_rel: float = 0.0) -> IndenterDiagnosis:
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
    depth_std_mm, force_std_n : (N,) array_like of float, optional
        Each press's stated depth and force standard uncertainties, mm and N, >= 0
        (the ``depth_std_mm`` and ``force_sem_n`` columns): the noise model of
        :func:`fit_indenter`, each press weighted by its effective variance
        s0^2 + (dP/dw u)^2 + s_P^2, s0 by the Paule-Mandel rule at the base model.
    depth_shared_mm : float or (N,) array_like of float, default 0.0
        A depth error every press shares, its bound (one, or how far each depth moves at
        the bound: the ``depth_shared_mm`` column of a ball's circles), mm, >= 0.
    depth_shared_rel : float, default 0.0
        A shared depth error in proportion to each depth, its bound as a fraction.

    Returns
    -------
    IndenterDiagnosis

    Raises
    ------
    InputError
        For fewer than three presses, a depth <= 0 or past the reach (naming the
        press), a force <= 0, an uncertainty < 0 (naming the press), or a bad h.

    Notes
    -----
    BIC = n ln(chi2 / n) + k ln n (Schwarz 1978) with chi2 the weighted residual
    sum and k the model's parameters (E, and an offset's). A change of the law or
    the contact adds no parameter: it is taken when it lowers chi2 by a factor
    exp(2 / n) or more. A shared depth error is fitted within its bound in every
    rung (a nuisance common to all, so it adds to no k); a change that would be
    taken with the depths as read but not once the shared error is fitted is
    listed in ``not_testable``: on these presses it cannot be told from the
    certification's own error. With stated uncertainties the final model's chi2
    against them alone (s0 left out) is tested; with repeated depths, an F test of
    lack of fit against the replicate scatter says whether structure is left.
    """
    w, P, h = _checked(depth_mm, force_n, thickness_mm)
    base_contact = indenter._contact(contact)
    reach = indenter.reach_mm(h)
    bad = np.flatnonzero(w > reach * (1 + 1e-9))
    if bad.size:
        raise InputError(f"press {int(bad[0])}: depth {w[bad[0]]:.4g} mm is past the "
                         f"{indenter.shape}'s reach, {reach:.4g} mm on h = {h:g} mm")
    noise = press_noise(
        w, P, lambda x: indenter.force(x, E_mpa=1.0, nu=float(nu), thickness_mm=h,
                                       law="linear", contact=base_contact),
        depth_std_mm=depth_std_mm, force_std_n=force_std_n,
        depth_shared_mm=depth_shared_mm, depth_shared_rel=depth_shared_rel)
    models = _Models(indenter, w, P, h, float(nu), noise)
    ladder, state, tried, not_tried, equivalent = _climb(models, base_contact)
    rung = ladder[-1]
    not_testable = (_confounded(models, state, base_contact, tried) if noise.has_shared
                    else {})
    resid = P - rung.predicted_n
    floor, _ = _floor(w, resid, rung.n_params)
    _, test = _floor(w, resid / np.sqrt(noise.var), rung.n_params)
    candidates = {k: {"rmse_n": v[0].rmse_n, "bic": v[0].bic, "E_mpa": v[0].E_mpa}
                  for k, v in tried.items()}
    diag = IndenterDiagnosis(
        ladder=tuple(ladder), missing_effects=tuple(state["effects"]), candidates=candidates,
        nu=float(nu), floor_n=floor, floor_test=test, message="", depth_mm=w, force_n=P,
        not_tried=not_tried, noise=_noise_summary(noise, resid, rung),
        not_testable=not_testable,
        equivalent_effects={k: {e: _rung_words(r) for e, r in v.items()}
                            for k, v in equivalent.items() if v},
        offset_bounds=(-0.25 * float(w.min()), min(reach - float(w.max()),
                                                   0.25 * float(w.min()))),
        not_ruled_out={k: _rung_words(v[0]) for k, v in tried.items()
                       if v[0].bic < rung.bic + BIC_STEP})
    return _with_message(diag)


def _rung_words(r: IndenterRung) -> dict:
    """What the message and the JSON say of a candidate model: E, BIC and offsets."""
    return {"E_mpa": r.E_mpa, "bic": r.bic, "depth_offset_mm": r.depth_offset_mm,
            "force_offset_n": r.force_offset_n}


def _checked(depth_mm, force_n, thickness_mm) -> tuple[np.ndarray, np.ndarray, float]:
    w, P, h = check_presses(depth_mm, force_n, thickness_mm)
    if w.size < 3:
        raise InputError(f"{w.size} presses: the ladder needs three or more")
    for name, arr in (("depth_mm", w), ("force_n", P)):
        bad = np.flatnonzero(arr <= 0)
        if bad.size:
            raise InputError(f"press {int(bad[0])}: {name} = {arr[bad[0]]:g} must be positive")
    return w, P, h


def _step(models: _Models, state: dict, base_contact: str, *, shared: bool = True
          ) -> tuple[dict, dict]:
    """Every change not yet taken, fitted from `state`: {name: (rung, law, contact)}, and
    {name: why} for those that could not be fitted."""
    other = next((c for c in models.indenter.contacts if c != base_contact), None)
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
            tried[name] = (models.fit(eff, law, con, shared=shared), law, con)
        except InputError as exc:
            not_tried[name] = str(exc)
    return tried, not_tried


def _climb(models: _Models, base_contact: str) -> tuple[list, dict, dict, dict, dict]:
    """The ladder: take the change that lowers the BIC most (by more than BIC_STEP) until
    none does. Returns the rungs, the final state, the last round's fits and failures, and
    for each change taken the others within BIC_STEP of it that would have been taken too
    (the presses cannot tell them apart): {taken: {other: rung}}."""
    state = {"effects": (), "law": "linear", "contact": base_contact}
    rung = models.fit((), "linear", base_contact)
    ladder = [rung]
    equivalent: dict[str, dict] = {}
    while True:
        tried, not_tried = _step(models, state, base_contact)
        if not tried:
            break
        best = min(tried, key=lambda k: tried[k][0].bic)
        if not tried[best][0].bic < rung.bic - BIC_STEP:
            break
        equivalent[best] = {k: v[0] for k, v in tried.items()
                            if k != best and v[0].bic < rung.bic - BIC_STEP
                            and v[0].bic < tried[best][0].bic + BIC_STEP}
        cand, law, con = tried[best]
        state = {"effects": (*state["effects"], best), "law": law, "contact": con}
        rung = IndenterRung(**{**{k: getattr(cand, k) for k in cand.__dataclass_fields__},
                               "effects": state["effects"]})
        ladder.append(rung)
    return ladder, state, tried, not_tried, equivalent


def _confounded(models: _Models, state: dict, base_contact: str, free: dict) -> dict:
    """Changes the final model would take with the depths as read (the shared error held
    at 0) but not once the shared error is fitted within its bound (`free`, the last
    round of the ladder, where none was taken): not testable on these presses."""
    base = models.fit(tuple(e for e in state["effects"]
                            if e in ("force_offset", "depth_offset")),
                      state["law"], state["contact"], shared=False)
    fixed, _ = _step(models, state, base_contact, shared=False)
    out = {}
    for name, (cand, *_) in fixed.items():
        step = base.bic - cand.bic
        if step > BIC_STEP and name in free:
            out[name] = (f"the depths' shared error (within its stated bound) explains as "
                         f"much: the BIC falls by {step:.1f} with the depths as read, but "
                         "by no more than 2 once the shared error is fitted")
    return out


def _noise_summary(noise: PressNoise, resid: np.ndarray, rung: IndenterRung) -> dict:
    """What the diagnosis weighed the presses with, and the final model's chi2 against the
    stated uncertainties alone (``test``: chi2, dof, p of too much scatter, p of too
    little; None where nothing, or a zero uncertainty, was stated)."""
    out = {"stated": noise.stated is not None, "sigma0_n": noise.sigma0_n,
           "shared": noise.has_shared, "shared_shift": rung.shared_shift, "test": None}
    if noise.stated is not None and np.all(noise.stated > 0):
        dof = resid.size - rung.n_params - int(noise.has_shared)
        if dof >= 1:
            chi2 = float(np.sum(resid ** 2 / noise.stated))
            out["test"] = {"chi2": chi2, "dof": dof, "p_value": float(stats.chi2.sf(chi2, dof)),
                           "p_low": float(stats.chi2.cdf(chi2, dof))}
    return out


def _with_message(d: IndenterDiagnosis) -> IndenterDiagnosis:
    base = d.ladder[0]
    s = [f"The small-strain law with {base.contact} contact leaves an RMSE of "
         f"{base.rmse_n * 1e3:.4g} mN; its apparent E changes by {100 * base.drift:+.1f} % "
         f"from the shallowest presses to the deepest (E = {base.E_mpa:.4g} MPa at "
         f"nu = {d.nu:g})."]
    s += _noise_sentences(d.noise)
    for r in d.ladder[1:]:
        s.append(f"Adding {r.effects[-1]} ({INDENTER_EFFECTS[r.effects[-1]]}): RMSE "
                 f"{r.rmse_n * 1e3:.4g} mN, apparent E drift {100 * r.drift:+.1f} %, "
                 f"E = {r.E_mpa:.4g} MPa.")
    if not d.missing_effects:
        s.append("No change tried lowers the BIC by more than 2: nothing in the ladder is "
                 "missing.")
    else:
        s.append(f"Missing: {', '.join(d.missing_effects)}.")
    for taken, others in d.equivalent_effects.items():
        s.append(f"In place of {taken}, " + "; ".join(
            f"{e} ({_offset_words(v, d.offset_bounds)}E = {v['E_mpa']:.4g} MPa)"
            for e, v in others.items())
                 + " explain the presses as well (the BIC within 2): these presses cannot "
                 "tell them apart.")
    last = d.ladder[-1]
    if "depth_offset" in last.effects:
        words = _offset_words({"depth_offset_mm": last.depth_offset_mm}, d.offset_bounds)
        s.append(f"The final model puts {words.removeprefix('a ')[:-2]}.")
    if d.not_ruled_out:
        es = [last.E_mpa, *(v["E_mpa"] for v in d.not_ruled_out.values())]
        s.append("Not ruled out by these presses (their BIC within 2 of the final model's, "
                 "none lower by more than 2): " + "; ".join(
                     f"{e} ({_offset_words(v, d.offset_bounds)}E = {v['E_mpa']:.4g} MPa)"
                     for e, v in d.not_ruled_out.items())
                 + f". E lies between {min(es):.4g} and {max(es):.4g} MPa across these "
                 "models and the final one.")
    for name, why in d.not_tried.items():
        s.append(f"Not tried: {name} ({why}).")
    for name, why in d.not_testable.items():
        s.append(f"Not testable on these presses: {name} ({why}).")
    s += _completeness(d)
    return IndenterDiagnosis(**{**{k: getattr(d, k) for k in d.__dataclass_fields__},
                                "message": " ".join(s)})


def _offset_words(rung: dict, bounds: tuple[float, float]) -> str:
    """A candidate's offsets in words ('a depth offset of +0.050 mm, '), an offset at the
    end of its search range said to be a bound."""
    out = ""
    delta = rung.get("depth_offset_mm", 0.0) or 0.0
    if delta:
        lo, hi = bounds
        edge = (f" (at the end of the range searched, {lo:+.3f} to {hi:+.3f} mm: a bound, "
                f"not a value)" if math.isfinite(lo) and min(abs(delta - lo),
                                                             abs(delta - hi)) < 1e-6 else "")
        out += f"a depth offset of {delta:+.3f} mm{edge}, "
    force = rung.get("force_offset_n", 0.0) or 0.0
    if force:
        out += f"a force offset of {force * 1e3:+.4g} mN, "
    return out


def _noise_sentences(noise: dict) -> list[str]:
    out = []
    if noise.get("stated"):
        out.append(f"Every model weighs each press by its stated uncertainties, as the fit "
                   f"does (force scatter they leave unexplained: "
                   f"{1e3 * noise['sigma0_n']:.3g} mN).")
    if noise.get("shared"):
        lam = noise["shared_shift"]
        out.append(f"The depths' shared error is fitted within its stated bound in every "
                   f"model (the final model puts it at {lam:+.2f} of the bound"
                   + (", at the bound)." if abs(lam) > 0.99 else ")."))
    return out


def _completeness(d: IndenterDiagnosis) -> list[str]:
    """Whether the final model leaves structure: against the stated uncertainties, against
    the replicate scatter, or neither (then said)."""
    out, test, last = [], d.noise.get("test"), d.ladder[-1]
    if test is not None:
        red = f"chi2/dof = {test['chi2'] / test['dof']:.3g}"
        if test["p_value"] < 0.001:
            out.append(f"The final model's residuals exceed what the stated uncertainties "
                       f"explain ({red}, p = {test['p_value']:.2g}): something is still "
                       "missing, or the uncertainties are understated.")
        elif test["p_low"] < 0.001:
            out.append(f"The stated uncertainties are larger than the presses' scatter "
                       f"({red}; p = {test['p_low']:.2g} of so little): an effect of their "
                       "size would hide in them, so the ladder ranked the models by the "
                       "presses' own scatter.")
        else:
            out.append(f"The final model's residuals are what the stated uncertainties "
                       f"explain ({red}, p = {test['p_value']:.2g}).")
    if d.floor_test is not None and d.floor_test["p_value"] < 0.001:
        out.append(f"The final model still misses something: its residuals exceed the "
                   f"replicate scatter ({d.floor_n * 1e3:.3g} mN; lack of fit p = "
                   f"{d.floor_test['p_value']:.2g}).")
    elif d.floor_test is not None:
        out.append(f"The final model's residuals are within the replicate scatter "
                   f"({d.floor_n * 1e3:.3g} mN; lack of fit p = "
                   f"{d.floor_test['p_value']:.2g}).")
    elif test is None:
        out.append("No depth is repeated and no uncertainty is stated: the presses' noise is "
                   "not measured apart from the model, so the ladder ranks models by their "
                   "residuals; it does not test that the final model is complete (its "
                   f"apparent E still drifts {100 * last.drift:+.1f} %).")
    return out


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
    top = reach_of(indenter, h, law, c)

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
