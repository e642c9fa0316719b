"""What to change in a calibration session's design, and the cheapest design that meets a
target (``tactilevision plan --recommend``, ``--target-E-pct``, ``--target-nu``).

Each change is one edit of the design (more repeats, depths added deeper or shallower,
a wider indenter for nu, a steeper or shallower bevel, a vernier instead of a mark, a
faster camera or a slower stage, a longer F/T window, a tare, varied holds, rests,
days or positions), planned again with :func:`~tactilevision.planning.plan_session`.
Its gain is the fall of the total error of E and of nu: the random sd and the
systematic part (the noise's bias plus the largest shared error's, at its bound) added
in quadrature. Changes that only let ``diagnose`` test more effects are listed after,
with the effects they open.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field, replace

from .._checks import InputError
from ._design import Design, readable_overshoot_um
from ._plan import PlanPrediction, _no_nan, plan_session

__all__ = ["DesignChange", "Recommendation", "error_totals", "recommend"]

#: Most repeats per depth the cheapest-design search tries.
MAX_REPEATS = 30

#: Bevel angles a change proposes, deg: the range over which the vernier's depth model
#: was compared with frames Taxim rendered (docs/validation/plan.md, "The depth model
#: against Taxim's frames").
#: A shallower bevel reads finer but its band runs longer (an overshoot over tan theta),
#: and the pad and the camera's view bound it: the design does not hold them.
BEVEL_RANGE_DEG = (3.0, 15.0)

#: Most changes the cheapest-design search chains (:func:`_greedy_path`).
GREEDY_STEPS = 4

#: Smallest gain (fall of the binding error) for which a change is recommended.
MIN_GAIN = 0.02

#: Deepest depth a change adds, as w/h (below the FEM beta table's reach, 0.23, and the
#: paper's 0.2 for the linear law).
DEEPEST_W_OVER_H = 0.19
#: Shallowest depth a change adds, as w/h.
SHALLOWEST_W_OVER_H = 0.05
#: a/h of the wider indenter a change proposes for nu (the FEM beta tables tell nu
#: within 0.003 from about 1.2 on: docs/method.md).
NU_A_OVER_H = 1.2


@dataclass(frozen=True)
class DesignChange:
    """One change of a design and what it predicts.

    Attributes
    ----------
    what : str
        The change, in words.
    design : Design
        The changed design.
    n_presses : int
        Presses of the changed design.
    E_total_pct, nu_total : float
        Total error of E (% of E) and of nu (:func:`error_totals`); inf where nu is not
        identified.
    gain : float
        How much the binding error falls: 1 - r / r0, r the larger of the two totals'
        ratios to the targets (where given, else to the design's own totals) and r0
        the design's own; 0.3: the binding error 30 % smaller. -inf where nu is not
        identified after the change.
    opens : tuple of str
        Catalogue effects ``diagnose`` can test after the change and not before.
    prediction : PlanPrediction
    """

    what: str
    design: Design
    n_presses: int
    E_total_pct: float
    nu_total: float
    gain: float
    opens: tuple[str, ...]
    prediction: PlanPrediction

    @property
    def gains(self) -> bool:
        """Recommended for its gain (:data:`MIN_GAIN` or more), not only for what it opens."""
        return self.gain >= MIN_GAIN


@dataclass
class Recommendation:
    """Ranked changes of a design and the cheapest design meeting the targets.

    Attributes
    ----------
    base : PlanPrediction
        The design as given.
    E_total_pct, nu_total : float
        Its total errors.
    changes : list of DesignChange
        Those that lower the binding total error by :data:`MIN_GAIN` or more, by
        predicted gain; then those that only open effects to ``diagnose``.
    target_E_pct, target_nu : float or None
    cheapest : DesignChange or None
        The design with the fewest presses found to meet both targets (None: no
        design of the search does, or no target).
    why : str
        One sentence on the search.
    """

    base: PlanPrediction
    E_total_pct: float
    nu_total: float
    changes: list[DesignChange] = field(default_factory=list)
    target_E_pct: float | None = None
    target_nu: float | None = None
    cheapest: DesignChange | None = None
    why: str = ""

    def as_dict(self) -> dict:
        """JSON-ready dict (``plan --json``'s ``recommendation``; NaN and inf as None)."""
        def ch(c: DesignChange) -> dict:
            return {"what": c.what, "n_presses": c.n_presses, "E_total_pct": c.E_total_pct,
                    "nu_total": c.nu_total, "gain": c.gain, "opens": list(c.opens),
                    "E_sigma_pct": c.prediction.E_sigma_pct, "nu_sigma": c.prediction.nu_sigma,
                    "nu_identified": c.prediction.nu_identified}

        return _no_nan({"E_total_pct": self.E_total_pct, "nu_total": self.nu_total,
                "target_E_pct": self.target_E_pct, "target_nu": self.target_nu,
                "changes": [ch(c) for c in self.changes],
                "cheapest": None if self.cheapest is None else
                ch(self.cheapest) | {"design": {
                    k: (list(v) if isinstance(v, tuple) else v)
                    for k, v in self.cheapest.design.__dict__.items()}},
                "why": self.why})


def error_totals(p: PlanPrediction) -> tuple[float, float, float, float]:
    """Total errors of E (%) and nu, and their systematic parts.

    The systematic part is the noise's bias (the fit's curvature) plus the largest of
    the shared errors' biases at their bounds (``PlanPrediction.bias``: a mark's shared
    lag, the F/T zero's drift); the total adds the random sd in quadrature. Both inf
    where nu is not identified.

    Returns
    -------
    E_total_pct, nu_total, E_systematic_pct, nu_systematic : float
    """
    if not p.nu_identified or not math.isfinite(p.E_sigma_pct):
        return math.inf, math.inf, math.inf, math.inf
    shared = [v for k, v in p.bias.items() if k not in ("model", "noise")]
    e_sh = max((abs(v[0]) for v in shared), default=0.0)
    n_sh = max((abs(v[1]) for v in shared), default=0.0)
    if not (math.isfinite(e_sh) and math.isfinite(n_sh)):
        return math.inf, math.inf, math.inf, math.inf
    e_sys = abs(p.bias.get("noise", (0.0, 0.0))[0]) + e_sh
    n_sys = abs(p.bias.get("noise", (0.0, 0.0))[1]) + n_sh
    return math.hypot(p.E_sigma_pct, e_sys), math.hypot(p.nu_sigma, n_sys), e_sys, n_sys


def _changes(d: Design) -> list[tuple[str, Design, bool]]:
    """(what, changed design, whether the gauge block or its reading changed) for each
    change that applies to `d`."""
    h = d.thickness_mm
    out: list[tuple[str, Design, bool]] = [
        (f"{2 * d.repeats} repeats per depth (was {d.repeats})",
         replace(d, repeats=2 * d.repeats, schedule=None), False)]
    depths = sorted(d.depths_mm)
    if depths[-1] / h < DEEPEST_W_OVER_H - 0.02:
        extra = [round(depths[-1] + (DEEPEST_W_OVER_H * h - depths[-1]) * k / 2, 4)
                 for k in (1, 2)]
        out.append((f"depths {', '.join(f'{x:g}' for x in extra)} mm added (deeper, to w/h "
                    f"{DEEPEST_W_OVER_H:g})",
                    replace(d, depths_mm=tuple(depths + extra), schedule=None), True))
    if depths[0] / h > SHALLOWEST_W_OVER_H + 0.02:
        x = round(SHALLOWEST_W_OVER_H * h, 4)
        out.append((f"a depth of {x:g} mm added (shallower, w/h {SHALLOWEST_W_OVER_H:g})",
                    replace(d, depths_mm=tuple([x, *depths]), schedule=None), True))
    if d.a_over_h < NU_A_OVER_H - 0.05:
        a = round(NU_A_OVER_H * h, 3)
        out.append((f"an indenter of radius {a:g} mm (a/h {NU_A_OVER_H:g}, was "
                    f"{d.a_over_h:.2f}) for nu", replace(d, radius_mm=a), True))
    if d.bevel_angle_deg > 0:
        # a band is read once RESOLVED_PX long: the stage stopping past that reads them all
        o_r = readable_overshoot_um(d)
        lo, hi = d.overshoot_um
        if lo < o_r:
            span = max(hi - lo, 10.0)
            new = (math.ceil(o_r + 5.0), math.ceil(o_r + 5.0 + span))
            out.append((f"the stage stopping {new[0]:g} to {new[1]:g} um past w0 (was {lo:g} "
                        f"to {hi:g}), every band long enough to read",
                        replace(d, overshoot_um=(float(new[0]), float(new[1]))), True))
        steep = min(2 * d.bevel_angle_deg, BEVEL_RANGE_DEG[1])
        shallow = max(d.bevel_angle_deg / 2, BEVEL_RANGE_DEG[0])
        if steep > d.bevel_angle_deg:
            out.append((f"a steeper bevel, {steep:g} deg (was {d.bevel_angle_deg:g})",
                        replace(d, bevel_angle_deg=steep), True))
        if shallow < d.bevel_angle_deg:
            out.append((f"a shallower bevel, {shallow:g} deg (was {d.bevel_angle_deg:g})",
                        replace(d, bevel_angle_deg=shallow), True))
    else:
        out += [("a vernier bevel at 5 deg instead of the mark",
                 replace(d, bevel_angle_deg=5.0), True),
                (f"the camera at {3 * d.frame_rate_hz:g} frames/s (was {d.frame_rate_hz:g})",
                 replace(d, frame_rate_hz=3 * d.frame_rate_hz), True),
                _slower_stage(d)]
    shortest = min(d.holds_s) if d.holds_s else (d.hold_s if d.hold_s is not None else 1.0)
    if 2 * d.window_samples / d.rate_hz <= shortest:
        out.append((f"an F/T window of {2 * d.window_samples} samples (was {d.window_samples})",
                    replace(d, window_samples=2 * d.window_samples), True))
    if d.force_zero_n > 0:
        out.append(("a tare before each press (the F/T zero measured, not a drift of up to "
                    f"{1e3 * d.force_zero_n:.2g} mN)", replace(d, force_zero_n=0.0), True))
    return out


def _slower_stage(d: Design) -> tuple[str, Design, bool]:
    """The stage three times slower past the mark: its speed, or its move's duration."""
    if d.approach_s is None:
        return (f"the stage at {d.stage_speed_mm_s / 3:.3g} mm/s past the mark (was "
                f"{d.stage_speed_mm_s:g})", replace(d, stage_speed_mm_s=d.stage_speed_mm_s / 3),
                True)
    return (f"each press's approach in {3 * d.approach_s:g} s, the stage three times slower "
            f"past the mark (was {d.approach_s:g} s)", replace(d, approach_s=3 * d.approach_s),
            True)


def _opening_changes(d: Design, untestable: dict[str, str]) -> list[tuple[str, Design]]:
    """Changes that let ``diagnose`` test the effects it cannot on `d`."""
    out = []
    if "viscoelastic_relaxation" in untestable and 0.5 >= d.window_samples / d.rate_hz:
        out.append(("holds of 0.5, 2 and 5 s with the F/T window at each hold's end",
                    replace(d, holds_s=(0.5, 2.0, 5.0), hold_s=None, window_at="end")))
    if "incomplete_recovery" in untestable:
        out.append(("rests of 1, 3 and 10 s between presses", replace(d, waits_s=(1.0, 3.0, 10.0))))
    if "aging" in untestable:
        out.append(("the presses spread over 3 days", replace(d, days=3)))
    if "spatial_nonuniformity" in untestable:
        out.append(("presses at 6 positions of the pad",
                    replace(d, positions=6, schedule=None)))
    return out


def _ratio(e_t: float, n_t: float, ref: tuple[float, float]) -> float:
    """The larger of the totals' ratios to the reference."""
    return max(e_t / ref[0], n_t / ref[1])


def _planned(d: Design, plans: dict[Design, PlanPrediction]) -> PlanPrediction:
    """The plan of `d` (no effect sizes), once per :func:`recommend` call: the ranking,
    the greedy path and the repeats search meet the same designs."""
    if d not in plans:
        plans[d] = plan_session(d, effect_sizes=False)
    return plans[d]


def _change(what: str, d: Design, ref: tuple[float, float], base_untestable: dict[str, str],
            r0: float, plans: dict[Design, PlanPrediction]) -> DesignChange:
    p = _planned(d, plans)
    e_t, n_t, _, _ = error_totals(p)
    ratio = _ratio(e_t, n_t, ref)
    if not math.isfinite(ratio):
        gain = -math.inf
    else:
        gain = 1.0 - ratio / r0 if math.isfinite(r0) else math.inf
    opens = tuple(k for k in base_untestable if k not in p.untestable)
    return DesignChange(what, d, p.n_presses, e_t, n_t, gain, opens, p)


def _meets(c: DesignChange, tE: float, tnu: float) -> bool:
    return c.E_total_pct <= tE and c.nu_total <= tnu


def _cheapest_repeats(what: str, d: Design, tE: float, tnu: float,
                      base_untestable: dict[str, str], ref: tuple[float, float], r0: float,
                      plans: dict[Design, PlanPrediction]) -> DesignChange | None:
    """The fewest repeats of the design meeting the targets: the random sds fall as
    1/sqrt(repeats) and the systematic parts stay, which gives the repeats to try; the
    plan at those repeats confirms (one more repeat at a time, up to three)."""
    p = _planned(d, plans)
    _, _, e_sys, n_sys = error_totals(p)
    if not (math.isfinite(e_sys) and e_sys < tE and n_sys < tnu):
        return None
    need = max(d.repeats * p.E_sigma_pct ** 2 / (tE ** 2 - e_sys ** 2),
               d.repeats * p.nu_sigma ** 2 / (tnu ** 2 - n_sys ** 2), 2.0)
    r = max(2, math.ceil(need - 1e-9))
    for _ in range(4):
        if r > MAX_REPEATS:
            return None
        label = f"{what}, {r} repeats per depth" if what else f"{r} repeats per depth"
        c = _change(label, replace(d, repeats=r, schedule=None), ref, base_untestable, r0, plans)
        if _meets(c, tE, tnu):
            return c
        r += 1
    return None


def recommend(design: Design, *, target_E_pct: float | None = None,
              target_nu: float | None = None) -> Recommendation:
    """Rank the changes of a design by predicted gain; find the cheapest design meeting
    the targets.

    Parameters
    ----------
    design : Design
    target_E_pct : float, optional
        Total error of E to reach, % of E (> 0).
    target_nu : float, optional
        Total error of nu to reach (> 0).

    Returns
    -------
    Recommendation

    Raises
    ------
    InputError
        For a target that is not a positive number.

    Notes
    -----
    Each change is planned with :func:`plan_session` (no effect sizes), and ranked by
    its gain (:class:`DesignChange`). The cheapest design is searched, with both
    targets given (one alone: the other is not constrained), among the design as
    given, each single change of the gauge block or its reading, and the designs
    reached by chaining the best such change up to :data:`GREEDY_STEPS` times; each
    at the fewest repeats per depth (up to :data:`MAX_REPEATS`) whose plan meets the
    targets. Cheapest: fewest presses, then
    the smaller total error of E. A design whose systematic part alone exceeds a
    target (a mark's shared lag, an F/T zero's drift) meets it at no number of repeats.
    """
    for key, v in (("target_E_pct", target_E_pct), ("target_nu", target_nu)):
        if v is not None and not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
            raise InputError(f"{key} must be a positive number, got {v!r}")
    plans: dict[Design, PlanPrediction] = {}
    base = _planned(design, plans)
    e0, n0, _, _ = error_totals(base)
    tE = float(target_E_pct) if target_E_pct is not None else math.inf
    tnu = float(target_nu) if target_nu is not None else math.inf
    ref = (tE if math.isfinite(tE) else e0, tnu if math.isfinite(tnu) else n0)
    if not math.isfinite(ref[0]) or not math.isfinite(ref[1]):
        ref = (1.0, 0.01)                     # nu not identified: any identified design gains
    r0 = _ratio(e0, n0, ref)
    precision, opening = [], []
    for what, d, _ in _changes(design):
        try:
            precision.append(_change(what, d, ref, base.untestable, r0, plans))
        except InputError:
            continue                                   # a change the tables cannot plan
    for what, d in _opening_changes(design, base.untestable):
        try:
            opening.append(_change(what, d, ref, base.untestable, r0, plans))
        except InputError:
            continue
    # a gain of at least MIN_GAIN: less is within the plan's own approximations
    better = sorted((c for c in precision if c.gain >= MIN_GAIN), key=lambda c: -c.gain)
    rec = Recommendation(base, e0, n0, better + [c for c in opening if c.opens],
                         target_E_pct, target_nu)
    if target_E_pct is None and target_nu is None:
        rec.why = "no target given: the changes are ranked against the design's own errors"
        return rec
    found, n_pool = _search(design, "", tE, tnu, base.untestable, ref, r0, plans)
    best = min(found, key=_cost) if found else None
    # the search again from the design it found, until it finds nothing cheaper: so that
    # --recommend on its own recommendation proposes no further change (a greedy path can
    # miss a change, e.g. a tare, that pays only once another has been made)
    for _ in range(FIXED_POINT_ROUNDS):
        if best is None:
            break
        path = re.sub(r"(, )?\d+ repeats per depth$", "", best.what)   # the block's changes
        more, n_more = _search(best.design, path, tE, tnu, base.untestable, ref, r0, plans)
        n_pool += n_more
        again = min(more, key=_cost) if more else None
        if again is None or not _cost(again) < _cost(best):
            break
        best = again
    if best is not None:
        rec.cheapest = best
        rec.why = (f"the fewest presses meeting the targets among {n_pool} gauge blocks "
                   f"and readings at 2 to {MAX_REPEATS} repeats per depth")
    else:
        rec.why = (f"no design of the search ({n_pool} gauge blocks and readings at 2 to "
                   f"{MAX_REPEATS} repeats per depth) meets the targets: their systematic "
                   "errors or nu's identifiability stand in the way")
    return rec


#: Times the search for the cheapest design is run again from the design it found.
FIXED_POINT_ROUNDS = 3


def _cost(c: DesignChange) -> tuple[int, float]:
    """Cheapest: fewest presses, then the smaller total error of E."""
    return c.n_presses, c.E_total_pct


def _search(design: Design, prefix: str, tE: float, tnu: float,
            base_untestable: dict[str, str], ref: tuple[float, float], r0: float,
            plans: dict[Design, PlanPrediction]) -> tuple[list[DesignChange], int]:
    """Each design of the search from `design` (itself, its single changes of the gauge
    block or reading, its greedy path) at the fewest repeats meeting the targets; the
    changes described after `prefix`; and how many designs were searched."""
    pool: list[tuple[str, Design]] = [("", design)]
    pool += [(what, d) for what, d, block in _changes(design) if block]
    pool += _greedy_path(design, ref, base_untestable, plans)
    found = []
    for what, d in pool:
        label = "; ".join(x for x in (prefix, what) if x)
        try:
            c = _cheapest_repeats(label, d, tE, tnu, base_untestable, ref, r0, plans)
        except InputError:
            continue
        if c is not None:
            found.append(c)
    return found, len(pool)


def _greedy_path(design: Design, ref: tuple[float, float], base_untestable: dict[str, str],
                 plans: dict[Design, PlanPrediction], steps: int = GREEDY_STEPS
                 ) -> list[tuple[str, Design]]:
    """Designs reached by taking, again and again, the change of the gauge block or its
    reading with the largest gain on the design reached so far (while it gains
    :data:`MIN_GAIN`): a mark's lag may hide what a wider punch gains until a vernier
    replaces the mark."""
    out: list[tuple[str, Design]] = []
    cur, label = design, []
    cur_r = _ratio(*error_totals(_planned(design, plans))[:2], ref)
    for _ in range(steps):
        best = None
        for what, d, block in _changes(cur):
            if not block:
                continue
            try:
                c = _change(what, d, ref, base_untestable, cur_r, plans)
            except InputError:
                continue
            if c.gain >= MIN_GAIN and (best is None or c.gain > best.gain):
                best = c
        if best is None:
            break
        label.append(best.what)
        cur = best.design
        cur_r = _ratio(best.E_total_pct, best.nu_total, ref)
        out.append(("; ".join(label), cur))
    return out
