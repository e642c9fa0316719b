"""The smallest size of each catalogue effect ``diagnose`` names: its decisions replayed.

:func:`replay_sizes` answers, for a session's presses and noise (a :class:`ReplaySetup`:
a measured table, :func:`table_sensitivity`, or a planned design,
:func:`tactilevision.planning.effect_sensitivity`), how large each effect of the
catalogue (formats.md §5) must be for :func:`~tactilevision.diagnosis.diagnose` to name
it in 95 % of sessions at its default thresholds. It does not run ``diagnose``: it
draws the noise of many sessions and replays ``diagnose``'s decisions on each,
linearized:

- the base law is eq. (5), fitted by least squares to the session's finite-strain FEM
  forces (its own misfit to them is in every drawn session, as in a real one);
- each candidate effect enters as the columns of its force change at zero size, taken
  on the fitted eq.-5 law as ``diagnose`` takes it (a depth offset's dP/dw of the law,
  a stiffness effect's law x its factor's derivative, a force effect's own term); an
  effect's time constant (relaxation, recovery) is searched over a grid, as
  ``IndentationModel.fit`` searches it by gradient, and counts in the BIC;
- the hidden effect's signal is its force change on the FEM's forces (a depth offset's
  exactly, P(w + delta) - P(w));
- every coefficient is kept within its catalogue parameter's bounds, as
  ``IndentationModel.fit`` keeps it (an active set: a coefficient past its bound is held
  there and the others refitted), so that, e.g., relaxation's g cannot turn negative
  and an offset at its bound fits worse than one inside;
- the law's own curvature, eq. (5) times (1 + gamma (w/h)^2), is linearized at the
  gamma the fit of the mean session reaches downhill from gamma = 0 (the fit's start),
  not at gamma = 0: beside a force offset gamma reaches 10 or more, where its
  linearization at 0 fits far better than the real curvature does, and there can be
  two minima, the farther one mimicking the offset (an offset's power then falls
  again past the first size found: :func:`effect_sensitivity` reports the size from
  which it holds, and the dip);
- a candidate passes with a BIC lower by more than ``DELTA_BIC``; an effect along depth
  alone (``depth_offset``, ``force_offset``) must also beat the law's own curvature by
  ``CURVATURE_BIC``; the best passing candidate joins the model (the law's curvature as a
  rung, not a verdict) and the others within ``EQUIVALENT_BIC`` are its equivalents, for
  up to ``max_steps`` rungs;
- the hidden effect is *found* when it joins the model or is listed as equivalent to the
  one that does (``benchmarks/bench_diagnose_power.py``'s rule).

Left out: the cross-validation check (it passes whenever the BIC does, on tables of
this size), the robust loss, the stiffness change points (``stiffness_step``) and the
generic trends, which compete only for effects they mimic. A measured table whose
crossing forces do not size a stiffness changing over the session
(``ReplaySetup.column_effects``) has it replayed too: the trend along time
(``force_drift``'s counterpart, which passes only where the drift passes, or is named by
the covariate scan where the climb names nothing) and the steps along press order and
time; the trend and the press-order step are sized.
``benchmarks/bench_plan_effects.py`` checks the predicted sizes against ``diagnose``
itself on generated sessions of several designs, ``benchmarks/bench_rules_out.py`` the
sizes on measured tables.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import stats

from .._checks import InputError
from ..mechanics import EFFECT_SIZE_PARAMS, fem_force, make_effect
from ._crossings import CROSSING_UNITS
from ._diagnose import CURVATURE_BIC, DELTA_BIC, EQUIVALENT_BIC, EQUIVALENT_RMSE
from ._diagnose_stats import (
    ALPHA,
    _covariate_names,
    _group_means,
    _groups,
    _testable,
    scan_regressors,
)

__all__ = ["COLUMN_SIZE_EFFECTS", "NOMINAL_TAU_S", "TANGENTIAL_FRACTION", "EffectSensitivity",
           "ReplaySetup", "replay_power", "replay_sizes", "table_sensitivity"]

#: Time constant of relaxation and recovery the sizes are given at, s (the catalogue's
#: starting values; a design's ``relaxation_tau_s`` replaces relaxation's).
NOMINAL_TAU_S = {"viscoelastic_relaxation": 1.0, "incomplete_recovery": 2.0}

#: The grid over which a time constant is searched in the replayed fits, s.
TAU_GRID_S = np.geomspace(1e-2, 1e2, 25)

#: Tangential forces, as a fraction of the normal force (sd, random direction): the
#: plan's stand-in for ``fx_n`` and ``fy_n``, which a design does not hold
#: (``tactilevision.sim.make_measurement_table``'s, 2 %).
TANGENTIAL_FRACTION = 0.02

#: Draws of the tangential forces over which the crosstalk's power is replayed.
TANGENTIAL_DRAWS = 8

#: Most rungs replayed (``diagnose``'s ``max_steps``).
MAX_STEPS = 3

#: A stiffness that changes over the session, replayed on a measured table whose crossing
#: forces do not size it (``ReplaySetup.column_effects``): ``diagnose`` tries them as the
#: trend along time (the counterpart of ``force_drift``) and the change point along press
#: order. Sized as :data:`~tactilevision.diagnosis.CROSSING_UNITS` gives them.
COLUMN_SIZE_EFFECTS = ("stiffness_trend:time_s", "stiffness_step:press")


def _size_unit(name: str) -> tuple[str, str, float]:
    """An effect's size parameter, its display unit and the factor to it."""
    if name in EFFECT_SIZE_PARAMS:
        return EFFECT_SIZE_PARAMS[name]
    return CROSSING_UNITS[name]


@dataclass(frozen=True)
class EffectSensitivity:
    """The smallest size of one catalogue effect a session lets ``diagnose`` find.

    Attributes
    ----------
    effect : str
        Catalogue name (formats.md §5).
    parameter : str
        The effect's parameter that sizes it (:data:`EFFECT_SIZE_PARAMS`).
    unit : str
        Unit of ``size``.
    size : float
        The smallest size found in ``power`` of sessions (in ``unit``; NaN where the
        design cannot test the effect, inf where no size within the parameter's reach
        is found that often).
    size_param : float
        ``size`` in the parameter's own unit (the catalogue's: mm, N, N/s, ...).
        inf where the size would pass the parameter's bound in the catalogue (which
        ``diagnose``'s fit keeps to) or, for a depth offset, take the deepest press
        past the FEM table (w/h 0.23).
    power : float
        The power asked for (0.95).
    snr : float
        That size as ``bench_diagnose_power``'s signal-to-noise ratio: the RMS over the
        presses of the force change eq. (5) cannot take up, over the replicate noise.
    why : str
        One sentence.
    dip : str
        Where the power falls again past a smaller size already found (an offset the
        law's curvature mimics there), what it is there; '' where it does not.
    at_places : tuple of (float, float)
        For ``stiffness_step:press``: ``(after, size)``, the smallest step (in ``unit``)
        just after press number ``after``, ordered by ``after``; ``size`` is the step
        half-way. From the crossing forces, at every place the scan tests
        (:func:`~tactilevision.diagnosis.crossing_step_places`); from the table's
        replay, half-way and at the first and the last places ``diagnose`` searches,
        where a step has the fewest presses on one side and its power is least (on a
        generated table of 60 presses: 2.35 %, 0.876 % and 1.82 % there, 0.89 to
        1.48 % at every fifth place between). Empty for other effects.
    """

    effect: str
    parameter: str
    unit: str
    size: float
    size_param: float
    power: float
    snr: float
    why: str
    dip: str = ""
    at_places: tuple[tuple[float, float], ...] = ()

    def places_sentence(self) -> str:
        """Where a step elsewhere than half-way needs more: '' without ``at_places``."""
        if not self.at_places:
            return ""
        after, size = max(self.at_places, key=lambda p: p[1])
        lo, hi = self.at_places[0][0], self.at_places[-1][0]
        most = (f"{size:.3g} {self.unit}" if math.isfinite(size)
                else "not at any size the parameter allows")
        return (f"half-way through the presses; anywhere after presses {lo:g} to {hi:g}: "
                f"{most}, the most after press {after:g}")

    def to_json_dict(self) -> dict:
        """``parameter``, ``unit``, ``size`` (null where not finite), ``power``, ``why``
        and ``at_places`` (``[{"after_press", "size"}]``, a size null where not finite;
        null where none)."""
        return {"parameter": self.parameter, "unit": self.unit,
                "size": self.size if math.isfinite(self.size) else None,
                "power": self.power, "why": self.why,
                "at_places": [{"after_press": a, "size": s if math.isfinite(s) else None}
                              for a, s in self.at_places] or None}


@dataclass
class _Candidate:
    name: str
    k: int                         # parameters counted in the BIC
    cols: list[np.ndarray]         # one (n, m) column block per grid value of tau
    fixed: np.ndarray | None = None  # the block once in the model (at the nominal tau)
    depth_only: bool = False       # along depth alone: must beat the law's curvature
    rung: bool = False             # the law's own curvature: a rung, never a verdict
    bounds: np.ndarray | None = None  # (m, 2): each column's parameter bounds
    # a counterpart: passes only where one of these passes (its named effect, and a
    # stiffness change point along its own column)
    partner: tuple[str, ...] = ()
    generic: bool = False          # a trend: never listed as equivalent, named when best

    def __post_init__(self) -> None:
        # each column's coefficient is one catalogue parameter (not tau_s, which is
        # searched over the grid): diagnose's fit keeps it within the parameter's bounds
        # (nor a change point's place, searched over the blocks)
        qs = [q for q in make_effect(self.name).params if q.name not in ("tau_s", "at")]
        self.bounds = np.array([(q.lower, q.upper) for q in qs], np.float64)


def _fem_force(d: ReplaySetup, w: np.ndarray) -> np.ndarray:
    """The session's finite-strain FEM force at each depth w (mm), N."""
    return fem_force(d.E_mpa, d.nu, d.radius_mm, d.thickness_mm, w)


def _slope(d: ReplaySetup, w: np.ndarray) -> np.ndarray:
    """dP/dw of the finite-strain FEM at each depth, N/mm (central difference)."""
    step = 1e-4 * d.thickness_mm
    lo = np.maximum(w - step, 0.0)
    return (_fem_force(d, w + step) - _fem_force(d, lo)) / (w + step - lo)


def _effect_columns(name: str, cols: dict[str, np.ndarray], law: np.ndarray,
                    dlaw: np.ndarray, tangential: tuple[np.ndarray, np.ndarray],
                    tau_nominal: float | None) -> _Candidate:
    """The candidate's linearized columns: its force change at zero size as ``diagnose``
    fits it, on the fitted eq.-5 law (`law`, N; its slope `dlaw`, N/mm)."""
    one = np.ones_like(law)
    if name == "depth_offset":
        return _Candidate(name, 1, [dlaw[:, None]], depth_only=True)
    if name == "force_offset":
        return _Candidate(name, 1, [one[:, None]], depth_only=True)
    if name == "force_drift":
        t = cols["time_s"]
        return _Candidate(name, 2, [np.column_stack([t, t * t])])
    if name == "aging":
        return _Candidate(name, 1, [(law * cols["day"])[:, None]])
    if name == "spatial_nonuniformity":
        return _Candidate(name, 2, [np.column_stack([law * cols["x_mm"],
                                                     law * cols["y_mm"]])])
    if name == "force_crosstalk":
        return _Candidate(name, 2, [np.column_stack(tangential)])
    grid = [_timed(name, cols, law, t)[:, None] for t in TAU_GRID_S]
    return _Candidate(name, 2, grid, fixed=_timed(name, cols, law, tau_nominal)[:, None])


def _timed(name: str, cols: dict[str, np.ndarray], P: np.ndarray,
           tau: float | None) -> np.ndarray:
    """Force change per unit size of relaxation or recovery at time constant `tau`, N."""
    if name == "viscoelastic_relaxation":
        return -P * (1 - np.exp(-cols["hold_s"] / float(tau)))
    if name == "incomplete_recovery":
        wait = np.nan_to_num(cols["wait_s"], nan=np.inf)
        return P * np.exp(-wait / float(tau))
    raise InputError(f"no plan for effect {name!r}")


def _effect_signal(name: str, cols: dict[str, np.ndarray], P: np.ndarray,
                   dPdw: np.ndarray, tangential: tuple[np.ndarray, np.ndarray],
                   tau_nominal: float | None) -> np.ndarray:
    """The effect's force change per unit size in a session (on the FEM's forces `P`, N;
    a depth offset's linearized, ``_Replay.found`` takes it exactly)."""
    if name == "depth_offset":
        return dPdw
    if name == "force_offset":
        return np.ones_like(P)
    if name == "force_drift":
        return cols["time_s"]
    if name == "aging":
        return P * cols["day"]
    if name == "spatial_nonuniformity":
        return P * cols["x_mm"]
    if name == "force_crosstalk":
        return tangential[0]
    return _timed(name, cols, P, tau_nominal)


def _rss(basis: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """Residual sum of squares of each column of Y (n, M) on the basis (n, p)."""
    q, _ = np.linalg.qr(basis)
    R = Y - q @ (q.T @ Y)
    return np.einsum("ij,ij->j", R, R)


def _rss_bounded(bases: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                 Y: np.ndarray) -> np.ndarray:
    """As :func:`_rss` on each basis of `bases` (G, n, p), each coefficient kept within
    [lo, hi] (p,) as ``diagnose``'s bounded fit keeps its parameters: a coefficient
    past its bound is held there and the others refitted, until none is past (an
    active set that only grows). Returns (G, M).

    Held at v, the coefficients S cost (b_S - v)' [C_SS]^-1 (b_S - v) more than the
    unbounded fit b, C = (X'X)^-1, and move the others by -C_FS [C_SS]^-1 (b_S - v)."""
    p = bases.shape[2]
    norm = np.linalg.norm(bases, axis=1)                    # (G, p): unit columns
    norm[norm == 0] = 1.0
    q, r = np.linalg.qr(bases / norm[:, None, :])
    qty = np.swapaxes(q, 1, 2) @ Y                          # (G, p, M)
    rss = np.einsum("nm,nm->m", Y, Y)[None] - np.einsum("gpm,gpm->gm", qty, qty)
    if not (np.isfinite(lo) | np.isfinite(hi)).any():
        return rss
    diag = np.abs(np.diagonal(r, axis1=1, axis2=2))
    ok = diag.min(axis=1) > 1e-10 * diag.max(axis=1)        # a degenerate basis: as is
    eye = np.eye(p)
    rinv = np.linalg.inv(np.where(ok[:, None, None], r, eye))
    b = rinv @ qty
    LO, HI = lo[None] * norm, hi[None] * norm
    past = ((b < LO[:, :, None]) | (b > HI[:, :, None])).any(axis=1) & ok[:, None]
    gi, mi = np.nonzero(past)
    if gi.size == 0:
        return rss
    C = (rinv @ np.swapaxes(rinv, 1, 2))[gi]                # (K, p, p)
    bk, LOk, HIk = b[gi, :, mi], LO[gi], HI[gi]
    held = np.zeros(bk.shape, bool)
    value = np.zeros(bk.shape)
    coef = bk.copy()
    extra = np.zeros(gi.size)
    for _ in range(p):
        new = ~held & ((coef < LOk) | (coef > HIk))
        if not new.any():
            break
        held |= new
        value = np.where(new, np.clip(coef, LOk, HIk), value)
        dv = np.where(held, bk - value, 0.0)
        Adv = dv / np.diagonal(C, axis1=1, axis2=2)          # one held: [C_SS]^-1 = 1/C_jj
        many = held.sum(axis=1) > 1
        if many.any():
            both = held[many, :, None] & held[many, None, :]
            A = np.linalg.pinv(np.where(both, C[many], eye * ~held[many, :, None]))
            Adv[many] = np.einsum("kij,kj->ki", A, dv[many])
        Adv = np.where(held, Adv, 0.0)
        extra = np.einsum("ki,ki->k", dv, Adv)
        coef = np.where(held, value, bk - np.einsum("kij,kj->ki", C, Adv))
    rss[gi, mi] += extra
    return rss


@dataclass(frozen=True)
class ReplaySetup:
    """A session as the replay draws it: its presses, columns and noise, and the gel.

    Attributes
    ----------
    E_mpa, nu : float
        The gel (a measured table: what its base fit found; a design: its stated gel);
        the replay's noise-free forces are the finite-strain FEM's at the presses.
    radius_mm, thickness_mm : float
        a and h, mm.
    depths_mm : tuple of float
        The session's depths (the deepest bounds a depth offset's reach).
    w : (N,) float ndarray
        Each press's depth, mm.
    cols : dict of str to (N,) ndarray
        The table's columns the effects read (formats.md section 2).
    sigma : (N,) float ndarray or None
        Each press's force noise, N; None: from `force_sd_n` and `depth_sd_mm`
        through the FEM's dP/dw, sqrt(s_P^2 + (dP/dw s_w)^2).
    untestable : dict of str to str
        Effects the session cannot test, and why.
    relaxation_tau_s : float, optional
        Relaxation's time constant the size is given at (default 1 s).
    force_sd_n, depth_sd_mm : float
        The force's and the depth's sd per press, with ``sigma=None``.
    own_tangential : bool
        True: the table's ``fx_n``, ``fy_n`` are the tangential forces of every drawn
        session (a measured table); False: drawn at :data:`TANGENTIAL_FRACTION` of the
        normal force (a design).
    column_effects : bool
        Also replay a stiffness changing over the session (:data:`COLUMN_SIZE_EFFECTS`:
        a trend along ``time_s``, a step half-way through the presses), which ``diagnose``
        tries as candidates beside the catalogue's (a measured table whose crossing
        forces do not size them); False (a design): as before, the catalogue's alone.
    """

    E_mpa: float
    nu: float
    radius_mm: float
    thickness_mm: float
    depths_mm: tuple[float, ...]
    w: np.ndarray
    cols: dict
    sigma: np.ndarray | None
    untestable: dict
    relaxation_tau_s: float | None = None
    force_sd_n: float = 0.0
    depth_sd_mm: float = 0.0
    own_tangential: bool = True
    column_effects: bool = False


class _SessionScan:
    """``diagnose``'s covariate scan along ``time_s`` and ``press``
    (:func:`~tactilevision.diagnosis.covariate_tests`: an F test of the residual on z,
    z^2, q z, q z^2 within the groups of repeated presses, each column below ALPHA over
    the columns scanned), on eq. (5)'s least squares residuals of drawn sessions."""

    def __init__(self, cols: dict, law: np.ndarray) -> None:
        w = np.asarray(cols["depth_mm"], np.float64)
        self.q0, _ = np.linalg.qr(np.column_stack([w, w * w]))
        self.grp = _groups(cols)
        m = max(len(_testable(_covariate_names(cols), np.zeros(w.size), cols)), 1)
        G = int(self.grp.max()) + 1
        self.bases = []
        for col in ("time_s", "press"):
            x = np.asarray(cols.get(col, np.full(w.shape, np.nan)), np.float64)
            if not (np.all(np.isfinite(x)) and np.unique(x).size > 8):
                continue
            u, sv, _ = np.linalg.svd(scan_regressors(x, law, self.grp), full_matrices=False)
            B = u[:, sv > 1e-10 * sv.max()]
            df2 = w.size - G - B.shape[1]
            if B.shape[1] and df2 >= 1:
                f = stats.f.isf(ALPHA / m, B.shape[1], df2)
                self.bases.append((B, f * B.shape[1] / df2))

    def flags(self, Y: np.ndarray) -> np.ndarray:
        """(M,) bool: the sessions Y (n, M) whose scan flags time or press order."""
        R = Y - self.q0 @ (self.q0.T @ Y)
        if R.shape[1]:
            R = R - _group_means(R, self.grp)
        rss0 = np.einsum("ij,ij->j", R, R)
        hit = np.zeros(R.shape[1], bool)
        for B, crit in self.bases:
            explained = np.sum((B.T @ R) ** 2, axis=0)
            hit |= explained > crit * (rss0 - explained)      # F above its critical value
        return hit


class _Replay:
    """``diagnose``'s decisions, linearized, over many drawn sessions of a
    :class:`ReplaySetup` (a design's, or one measured table's own presses and noise)."""

    def __init__(self, d: ReplaySetup, draws: int, seed: int) -> None:
        self.d = d
        w, cols, untest = d.w, d.cols, d.untestable
        P = _fem_force(d, w)
        self.dPdw = _slope(d, w)
        if d.sigma is None:
            self.sigma = np.sqrt(d.force_sd_n ** 2 + (self.dPdw * d.depth_sd_mm) ** 2)
        else:
            self.sigma = np.asarray(d.sigma, np.float64)
        self.n = n = w.size
        rng = np.random.default_rng(seed)
        self.noise = self.sigma[:, None] * rng.standard_normal((n, draws))
        # each session has its own tangential forces: the crosstalk's own power is
        # replayed over several draws of them (the first also serves the others), from
        # a stream of their own (the same whatever the number of sessions)
        rng_t = np.random.default_rng([seed, 1])
        self.tangential = [(TANGENTIAL_FRACTION * P * rng_t.standard_normal(n),
                            TANGENTIAL_FRACTION * P * rng_t.standard_normal(n))
                           for _ in range(TANGENTIAL_DRAWS)]
        if d.own_tangential and {"fx_n", "fy_n"} <= set(cols):
            # a measured table's own tangential forces, in every drawn session
            self.tangential = [(np.asarray(cols["fx_n"], np.float64),
                                np.asarray(cols["fy_n"], np.float64))] * TANGENTIAL_DRAWS
        tang = self.tangential[0]
        x = w / d.thickness_mm
        self.X0 = np.column_stack([w, w * x])               # eq. (5): c w + c beta w^2 / h
        self.P = P
        self.w = w
        # diagnose fits its candidates on its own fitted law, not on the FEM's forces
        coef = np.linalg.lstsq(self.X0, P, rcond=None)[0]
        law = self.X0 @ coef
        dlaw = coef[0] + 2 * coef[1] * x
        self.cols = cols
        self.untestable = untest
        self.cands: dict[str, _Candidate] = {}
        self.signal: dict[str, np.ndarray] = {}
        tau_relax = d.relaxation_tau_s if d.relaxation_tau_s is not None else \
            NOMINAL_TAU_S["viscoelastic_relaxation"]
        for name in EFFECT_SIZE_PARAMS:
            if name in untest:
                continue
            tau = tau_relax if name == "viscoelastic_relaxation" else NOMINAL_TAU_S.get(name)
            self.cands[name] = _effect_columns(name, cols, law, dlaw, tang, tau)
            self.signal[name] = _effect_signal(name, cols, P, self.dPdw, tang, tau)
        if d.column_effects:
            self._add_column_effects(law, P)
        self.x2 = x * x
        self.gamma_bounds = tuple(_Candidate("law_curvature", 1, []).bounds[0])
        # the law's curvature: its columns are the law's own (``_law``), not a block
        self.cands["law_curvature"] = _Candidate("law_curvature", 1,
                                                 [(law * x * x)[:, None]], rung=True)
        # the design's own misfit: eq. (5) against the FEM's forces, in every session
        self.base_y = P

    def _add_column_effects(self, law: np.ndarray, P: np.ndarray) -> None:
        """The stiffness trend along time and the steps along press order and time, as
        ``diagnose`` fits them (the law times exp(k t), linearized; the law times 1 + s
        [x > at], ``at`` searched over :meth:`StiffnessStep.profile`'s places and counted
        in the BIC), and the signals of the two sized (a trend about the session's mean
        time, a step half-way through the presses) on the FEM's forces."""
        cols = self.cols
        t = np.asarray(cols.get("time_s", np.full(P.shape, np.nan)), np.float64)
        name = COLUMN_SIZE_EFFECTS[0]
        if "force_drift" in self.cands and np.all(np.isfinite(t)) and np.ptp(t) > 0:
            # force_drift's counterpart: it competes only where the drift passes, or the
            # change point along time (as diagnose: then it is that change's other shape)
            self.cands[name] = _Candidate(name, 1, [(law * t)[:, None]],
                                          partner=("force_drift", "stiffness_step:time_s"),
                                          generic=True)
            self.signal[name] = P * (t - t.mean())
            self.scan = _SessionScan(cols, law)
        for col in ("press", "time_s"):
            # the step along time competes as diagnose tries it (a softening is often
            # named a step along time), sized along press order only
            name = f"stiffness_step:{col}"
            x = np.asarray(cols.get(col, np.full(P.shape, np.nan)), np.float64)
            if name in self.untestable or not np.all(np.isfinite(x)):
                continue
            places = make_effect(name).profile({col: x})["at"]
            after = x > np.median(x)
            if places.size and 0 < after.sum() < after.size:
                # once in the model, at its place half-way (the signal's)
                # s, and the place counted twice (found by search), as the fit counts it
                self.cands[name] = _Candidate(name, 3, [(law * (x > at))[:, None]
                                                        for at in places],
                                              fixed=(law * after)[:, None])
                if col == "press":
                    self.signal[name] = P * after

    def _block(self, name: str) -> np.ndarray:
        c = self.cands[name]
        return c.fixed if c.fixed is not None else c.cols[0]

    def _bic(self, cur: tuple[str, ...], new: str | None, Y: np.ndarray,
             at: tuple[float, np.ndarray] | None = None) -> np.ndarray:
        """BIC (up to a constant) on each column of Y of eq. (5) plus the effects `cur`
        (at their nominal time constants) and `new` (its time constant searched), each
        effect's parameters within their catalogue bounds. The law's curvature, where
        it is in the model, is eq. (5) times (1 + gamma x^2) linearized at `at` (gamma
        and the law there, :meth:`_curvature_at`)."""
        n = self.n
        others = [a for a in cur if a != "law_curvature"]
        curved = "law_curvature" in (*cur, new)
        base, base_bounds = self._law(at if curved else None)
        fixed = [base] + [self._block(a) for a in others]
        bounds = [base_bounds] + [self.cands[a].bounds for a in others]
        k = 2 + sum(self.cands[a].k for a in cur)
        if new is not None:
            k += self.cands[new].k
        if new is None or new == "law_curvature":
            rss = self._rss([fixed], bounds, Y)[0]
        else:
            bounds = [*bounds, self.cands[new].bounds]
            rss = self._rss([[*fixed, blk] for blk in self.cands[new].cols], bounds,
                            Y).min(axis=0)
        return n * np.log(np.maximum(rss / n, 1e-300)) + k * math.log(n)

    def _law(self, at: tuple[float, np.ndarray] | None) -> tuple[np.ndarray, np.ndarray]:
        """The law's columns and their coefficients' bounds: eq. (5), or eq. (5) times
        (1 + gamma x^2) linearized at `at` = (gamma0, the law there, N): its columns at
        gamma0 and the law's change per unit gamma, whose coefficient gamma - gamma0
        keeps gamma within its bounds."""
        if at is None:
            return self.X0, np.array([[-np.inf, np.inf]] * 2)
        gamma0, law = at
        B = self.X0 * (1 + gamma0 * self.x2)[:, None]
        lo, hi = self.gamma_bounds
        return (np.column_stack([B, law * self.x2]),
                np.array([[-np.inf, np.inf]] * 2 + [[lo - gamma0, hi - gamma0]]))

    def _curvature_at(self, cur: tuple[str, ...], Y: np.ndarray
                      ) -> tuple[float, np.ndarray]:
        """The law's curvature gamma fitted to the mean of the sessions Y (n, m) with the
        effects `cur` (on a grid within the bounds, the minimum reached downhill from
        gamma = 0, refined by a parabola), and the law there, N (n,)."""
        y = Y.mean(axis=1)
        lo, hi = self.gamma_bounds
        grid = np.linspace(lo, hi, 201)
        other = [self._block(a) for a in cur if a != "law_curvature"]
        C = np.column_stack(other) if other else np.zeros((self.n, 0))
        B = np.concatenate([self.X0[None] * (1 + grid[:, None, None] * self.x2[None, :, None]),
                            np.broadcast_to(C, (grid.size, *C.shape))], axis=2)
        q, _ = np.linalg.qr(B)                              # (grid, n, p), stacked
        rss = y @ y - np.sum(np.einsum("gni,n->gi", q, y) ** 2, axis=1)
        # as the fit descends from gamma = 0 (the catalogue's start): the nearest minimum
        # downhill, not the grid's lowest (beside an offset there can be two)
        i = int(np.argmin(np.abs(grid)))
        step = 1 if rss[min(i + 1, grid.size - 1)] < rss[i] else -1
        while 0 < i + step < grid.size and rss[i + step] < rss[i]:
            i += step
        g0 = float(grid[i])
        if 0 < i < grid.size - 1:
            r0, r1, r2 = rss[i - 1], rss[i], rss[i + 1]
            den = r0 - 2 * r1 + r2
            if den > 0:
                g0 += 0.5 * (grid[1] - grid[0]) * (r0 - r2) / den
        B = np.column_stack([self.X0 * (1 + g0 * self.x2)[:, None], C])
        coef = np.linalg.lstsq(B, y, rcond=None)[0]
        return g0, self.X0 @ coef[:2]

    @staticmethod
    def _rss(bases: list[list[np.ndarray]], bounds: list[np.ndarray], Y: np.ndarray
             ) -> np.ndarray:
        """(G, M) bounded RSS on each basis (a list of column blocks) of `bases`."""
        b = np.vstack(bounds)
        return _rss_bounded(np.stack([np.column_stack(x) for x in bases]), b[:, 0], b[:, 1],
                            Y)

    def found(self, hidden: str, size: float, max_steps: int = MAX_STEPS,
              draws: int | None = None, start: int = 0) -> np.ndarray:
        """(draws,) bool: sessions in which ``diagnose`` (replayed) names `hidden` at
        `size` (the parameter's own unit)."""
        if hidden == "depth_offset":                        # exact: P(w + delta) - P(w)
            change = _fem_force(self.d, self.w + size) - self.P
        else:
            change = size * self.signal[hidden]
        stop = None if draws is None else start + draws
        Y = (self.base_y + change)[:, None] + self.noise[:, start:stop]
        M = Y.shape[1]
        hit = np.zeros(M, bool)
        state: list[tuple[str, ...]] = [()] * M
        done = np.zeros(M, bool)
        for _ in range(max_steps):
            groups: dict[tuple[str, ...], list[int]] = {}
            for j in np.flatnonzero(~done):
                groups.setdefault(state[j], []).append(j)
            if not groups:
                break
            for cur, idx in groups.items():
                idx = np.asarray(idx)
                Yg = Y[:, idx]
                at = (self._curvature_at(cur, Yg) if "law_curvature" in self.cands
                      else None)
                b0 = self._bic(cur, None, Yg, at)
                names = [c for c in self.cands if c not in cur]
                if not names:
                    done[idx] = True
                    continue
                dbic = {c: self._bic(cur, c, Yg, at) - b0 for c in names}
                curv = dbic.get("law_curvature", np.full(idx.size, np.inf))
                passing = {}
                for c, db in dbic.items():
                    ok = db < -DELTA_BIC
                    if self.cands[c].depth_only and "law_curvature" in names:
                        ok &= db < curv - CURVATURE_BIC
                    passing[c] = np.where(ok, db, np.inf)
                for c in passing:                   # a counterpart needs its effect
                    ps = self.cands[c].partner
                    if ps:
                        ok = np.zeros(idx.size, bool)
                        for p in ps:
                            ok |= np.isfinite(passing.get(p, np.inf))
                        passing[c] = np.where(ok, passing[c], np.inf)
                order = list(passing)
                table = np.vstack([passing[c] for c in order])          # (C, m)
                best = np.argmin(table, axis=0)
                best_val = table[best, np.arange(idx.size)]
                none = ~np.isfinite(best_val)
                if hidden in order:
                    hv = table[order.index(hidden)]
                    named_best = np.array([not self.cands[order[b]].rung for b in best])
                    # as diagnose: as good by BIC, or (replayed with the column effects,
                    # whose steps cost three parameters) leaving the same residual (the
                    # BICs less their parameters' price, n log RSS, within 2 n log 1.01)
                    with np.errstate(invalid="ignore"):
                        # a trend is named only as the best (diagnose lists no trend as
                        # equivalent to a named effect that beats it)
                        close = (hv <= best_val if self.cands[hidden].generic
                                 else hv - best_val < EQUIVALENT_BIC)
                        if self.d.column_effects and not self.cands[hidden].generic:
                            k = np.array([self.cands[c].k for c in order], np.float64)
                            price = math.log(self.n) * (self.cands[hidden].k - k[best])
                            close |= (hv - best_val - price
                                      <= 2 * self.n * math.log1p(EQUIVALENT_RMSE))
                    equiv = np.isfinite(hv) & close & named_best
                    hit[idx] |= equiv & ~none
                # found, or nothing passes: the climb ends for that session
                done[idx] |= none | hit[idx]
                for jj, j in enumerate(idx):
                    if not done[j]:
                        state[j] = (*cur, order[best[jj]])
        if hidden == COLUMN_SIZE_EFFECTS[0]:
            # where the climb named nothing, the left-over scan flags the trend's column
            bare = np.array([not s for s in state]) & ~hit
            hit[bare] = self.scan.flags(Y[:, bare])
        return hit

    def power(self, hidden: str, size: float, draws: int | None = None) -> float:
        """Share of the sessions (the first `draws`, default all) that find `hidden`;
        the crosstalk's over :data:`TANGENTIAL_DRAWS` draws of the tangential forces,
        an equal share of the sessions each."""
        m = self.noise.shape[1] if draws is None else draws
        if hidden != "force_crosstalk" or "force_crosstalk" not in self.cands:
            return float(np.mean(self.found(hidden, size, draws=m)))
        keep = self.cands[hidden], self.signal[hidden]
        edges = np.linspace(0, m, TANGENTIAL_DRAWS + 1).astype(int)
        hits = []
        try:
            for tang, a, b in zip(self.tangential, edges[:-1], edges[1:], strict=True):
                self.cands[hidden] = _Candidate(hidden, 2, [np.column_stack(tang)])
                self.signal[hidden] = tang[0]
                hits.append(self.found(hidden, size, draws=b - a, start=a))
        finally:
            self.cands[hidden], self.signal[hidden] = keep
        return float(np.mean(np.concatenate(hits)))

    def snr(self, hidden: str, size: float) -> float:
        """``bench_diagnose_power``'s signal-to-noise ratio of `hidden` at `size`."""
        g = size * self.signal[hidden]
        r = _rss(self.X0, g[:, None])[0]
        return float(math.sqrt(r / self.n) / np.sqrt(np.mean(self.sigma ** 2)))


def _reach(d: ReplaySetup, name: str) -> float:
    """The largest size of the effect ``diagnose`` can fit: its parameter's upper bound in
    the catalogue (``IndentationModel.fit`` stays within it) and, for a depth offset,
    the FEM table's reach past the deepest press (w/h 0.23)."""
    param = _size_unit(name)[0]
    bound = next(q.upper for q in make_effect(name).params if q.name == param)
    if name == "depth_offset":
        # a hair inside the table's edge: w + bound / h would round past 0.23 (an error)
        bound = min(bound, 0.23 * (1 - 1e-9) * d.thickness_mm - max(d.depths_mm))
    return float(bound)


def _size_for_power(rep: _Replay, name: str, target: float, upper: float) -> float:
    """Smallest size (parameter unit) replayed as found in `target` of sessions: from
    the size at snr 1, down by halving or up in steps of 1.5 to the first size found
    (up to `upper`: the power falls again near a bound, where the fit is held), then
    bisection in log size."""
    unit_snr = rep.snr(name, 1.0)
    if unit_snr <= 0 or upper <= 0:
        return math.inf
    lo = hi = min(1.0 / unit_snr, upper)
    if rep.power(name, hi) >= target:
        while lo > hi / 64:
            lo /= 2
            if rep.power(name, lo) < target:
                break
        else:
            return lo
        hi = 2 * lo
    else:
        while True:
            if hi >= upper:
                return math.inf
            lo, hi = hi, min(1.5 * hi, upper)
            if rep.power(name, hi) >= target:
                break
    return _bisect(rep, name, target, lo, hi)


def _bisect(rep: _Replay, name: str, target: float, lo: float, hi: float,
            steps: int = 10, ratio: float = 1.02) -> float:
    """Bisection in log size between `lo` (found in less than `target` of sessions) and
    `hi` (in `target` or more), at most `steps` halvings, until hi / lo < `ratio`;
    returns the upper end."""
    for _ in range(steps):
        mid = math.sqrt(lo * hi)
        if rep.power(name, mid) >= target:
            hi = mid
        else:
            lo = mid
        if hi / lo < ratio:
            break
    return hi


def replay_power(setup: ReplaySetup, effect: str, size: float, *, draws: int = 2000,
                 seed: int = 0) -> float:
    """Share of drawn sessions in which ``diagnose`` (replayed, linearized) names
    `effect` at `size`.

    Parameters
    ----------
    setup : ReplaySetup
    effect : str
        A catalogue effect of :data:`~tactilevision.mechanics.EFFECT_SIZE_PARAMS`.
    size : float
        The effect's size in its display unit (``EFFECT_SIZE_PARAMS``).
    draws : int, default 2000
        Sessions drawn.
    seed : int, default 0

    Returns
    -------
    power : float
        In [0, 1]; 0 where the session cannot test the effect.

    Raises
    ------
    InputError
        For an effect without a size parameter.
    """
    if effect not in EFFECT_SIZE_PARAMS:
        raise InputError(f"no plan for effect {effect!r}: choose from "
                         f"{', '.join(EFFECT_SIZE_PARAMS)}")
    rep = _Replay(setup, draws, seed)
    if effect not in rep.cands:
        return 0.0
    return rep.power(effect, size / EFFECT_SIZE_PARAMS[effect][2])


def replay_sizes(setup: ReplaySetup, *, power: float = 0.95, draws: int = 1000,
                 seed: int = 0) -> dict[str, EffectSensitivity]:
    """The smallest size of each catalogue effect ``diagnose`` names in `power` of the
    drawn sessions of `setup`.

    Parameters
    ----------
    setup : ReplaySetup
    power : float, default 0.95
        In (0, 1).
    draws : int, default 1000
        Sessions drawn (the sizes' own Monte Carlo error is about 3 % at 1000).
    seed : int, default 0

    Returns
    -------
    sizes : dict of str to EffectSensitivity
        For every effect of ``EFFECT_SIZE_PARAMS``, in catalogue order.

    Raises
    ------
    InputError
        For `power` outside (0, 1).

    Notes
    -----
    See the module's docstring: ``diagnose``'s BIC rule, its curvature gate and its
    equivalences replayed on the drawn noise, each effect linearized at zero size.
    Relaxation is sized at the setup's ``relaxation_tau_s`` (else 1 s), recovery at
    2 s.
    """
    if not 0 < power < 1:
        raise InputError(f"power must be in (0, 1), got {power!r}")
    return _sizes(_Replay(setup, draws, seed), setup, power)


def table_sensitivity(columns: dict, *, thickness_mm: float, radius_mm: float,
                      E_mpa: float, nu: float, sigma_n: np.ndarray,
                      untestable: dict[str, str], power: float = 0.95, draws: int = 1000,
                      seed: int = 0, relaxation_tau_s: float | None = None,
                      column_effects: bool = False) -> dict[str, EffectSensitivity]:
    """The smallest size of each catalogue effect ``diagnose`` would have named on this
    very table: :func:`replay_sizes` on the measured presses.

    Parameters
    ----------
    columns : dict of str to (N,) ndarray
        The table (formats.md section 2): its depths, and the columns the effects read.
    thickness_mm, radius_mm : float
        h and a, mm.
    E_mpa, nu : float
        The gel the table's base fit found (the replay's noise-free forces are the FEM's
        at these, at the table's depths).
    sigma_n : (N,) float ndarray
        Each press's force noise, N: the noise ``diagnose`` tested against.
    untestable : dict of str to str
        Effects the table cannot test, and why (``diagnose``'s own list).
    power, draws, seed :
        As :func:`replay_sizes`.
    relaxation_tau_s : float, optional
        Relaxation's time constant the size is given at (default 1 s).
    column_effects : bool, default False
        Also size a stiffness changing over the session (:data:`COLUMN_SIZE_EFFECTS`),
        tried as ``diagnose`` tries it (:attr:`ReplaySetup.column_effects`): for a table
        whose crossing forces do not size it.

    Returns
    -------
    sizes : dict of str to EffectSensitivity
        Keyed by the catalogue's names; with `column_effects`, also
        ``'stiffness_trend:time_s'`` (k, in %/min) and ``'stiffness_step:press'`` (s, in
        %) where the table has the column.

    Raises
    ------
    InputError
        For `power` outside (0, 1) or a `sigma_n` not one positive number per press.
    """
    if not 0 < power < 1:
        raise InputError(f"power must be in (0, 1), got {power!r}")
    w = np.asarray(columns["depth_mm"], np.float64)
    sig = np.asarray(sigma_n, np.float64)
    if sig.shape != w.shape or not np.all(np.isfinite(sig) & (sig > 0)):
        raise InputError("sigma_n must hold one positive force noise per press")
    setup = ReplaySetup(E_mpa=float(E_mpa), nu=float(nu), radius_mm=float(radius_mm),
                        thickness_mm=float(thickness_mm), depths_mm=(float(w.max()),),
                        w=w, cols={k: np.asarray(v, np.float64) for k, v in columns.items()},
                        sigma=sig, untestable=dict(untestable),
                        relaxation_tau_s=relaxation_tau_s, column_effects=column_effects)
    return _sizes(_Replay(setup, draws, seed), setup, power)


def _sizes(rep: _Replay, design: ReplaySetup, power: float
           ) -> dict[str, EffectSensitivity]:
    """:func:`replay_sizes`' answer from a replay."""
    out = {}
    names = [*EFFECT_SIZE_PARAMS, *(c for c in COLUMN_SIZE_EFFECTS if c in rep.cands)]
    for name in names:
        param, unit, scale = _size_unit(name)
        if name not in rep.cands:
            why = rep.untestable.get(name, "not testable on this design")
            out[name] = EffectSensitivity(name, param, unit, math.nan, math.nan, power,
                                          math.nan, f"cannot be tested: {why}")
            continue
        upper = _reach(design, name)
        s = _size_for_power(rep, name, power, upper)
        if not math.isfinite(s):
            out[name] = EffectSensitivity(name, param, unit, math.inf, math.inf, power,
                                          math.inf, f"not found in {100 * power:.0f} % of "
                                          "sessions at any size the parameter allows (up "
                                          f"to {_reach(design, name) * scale:.3g}"
                                          f"{' ' + unit if unit else ''})")
            continue
        u = f" {unit}" if unit else ""
        dip = _dip(rep, name, s, power, upper) if rep.cands[name].depth_only else None
        note = ""
        if dip is not None:
            s_first, (s_low, p_low) = s, dip[1]
            s = dip[0]
            note = (f"already {100 * power:.0f} % at {s_first * scale:.3g}{u}, but only "
                    f"{100 * p_low:.0f} % at {s_low * scale:.3g}{u}, where the law's "
                    "curvature mimics it")
        if not math.isfinite(s):
            out[name] = EffectSensitivity(name, param, unit, math.inf, math.inf, power,
                                          math.inf, f"not found in {100 * power:.0f} % of "
                                          f"sessions at every size up to the reach "
                                          f"{upper * scale:.3g}{u}"
                                          + (f"; {note}" if note else ""), note)
            continue
        snr = rep.snr(name, s)
        ends = (tuple((a, e * scale) for a, e in _step_at_ends(rep, power, upper))
                if name == "stiffness_step:press" else ())
        out[name] = EffectSensitivity(
            name, param, unit, s * scale, s, power, snr,
            f"found in {100 * power:.0f} % of sessions from {param} = {s * scale:.3g}{u} "
            f"(snr {snr:.2g})" + (f"; {note}" if note else ""), note,
            at_places=tuple(sorted({*ends, (_after(rep, name), s * scale)})) if ends else ())
    return out


def _after(rep: _Replay, name: str, at: float | None = None) -> float:
    """The press number after which a step at `at` falls (half-way: the signal's)."""
    x = np.asarray(rep.cols["press"], np.float64)
    if at is None:
        at = float(np.median(x))
    return float(np.max(x[x <= at]))


def _step_at_ends(rep: _Replay, power: float, upper: float) -> list[tuple[float, float]]:
    """A step along press order at the first and the last place ``diagnose`` searches
    (:meth:`StiffnessStep.profile`; the fewest presses on one side): ``(after, size)``,
    each size found as the half-way one is, the signal moved there (inf where none)."""
    name = "stiffness_step:press"
    x = np.asarray(rep.cols["press"], np.float64)
    places = make_effect(name).profile({"press": x})["at"]
    keep = rep.signal[name]
    out = []
    try:
        for at in sorted({float(places[0]), float(places[-1])}):
            rep.signal[name] = rep.P * (x > at)
            out.append((_after(rep, name, at), _size_for_power(rep, name, power, upper)))
    finally:
        rep.signal[name] = keep
    return out


#: Multiples of the first size found at which an offset's power is checked again.
_DIP_FACTORS = (1.15, 1.3, 1.5, 1.75, 2.0, 2.5, 3.0, 4.0)

#: Sessions of the first look for a dip (a fall below the target by more than 0.05,
#: over 3 sd of a share near 0.95 over 300 sessions).
_DIP_DRAWS = 300


def _dip(rep: _Replay, name: str, s: float, target: float, upper: float
         ) -> tuple[float, tuple[float, float]] | None:
    """An offset's power need not grow with its size: beside a large offset the law's
    curvature has a second minimum, which the fit reaches from gamma = 0 and which
    mimics the offset. Past the first size `s` found in `target` of sessions, the
    power is checked at :data:`_DIP_FACTORS` times it (up to `upper`); where it falls
    below, returns the size from which it holds again (bisected past the last size
    that falls; inf where none up to `upper` holds) and (that size, its power).
    None where it holds at every multiple."""
    sizes = [s * f for f in _DIP_FACTORS if s * f <= upper]
    # a first look on a third of the sessions; a dip is a fall well below the target
    powers = [rep.power(name, x, draws=_DIP_DRAWS) for x in sizes]
    low = [i for i, pw in enumerate(powers) if pw < target - 0.05]
    if not low:
        return None
    i = low[-1]
    worst = min(low, key=lambda k: powers[k])
    if i + 1 == len(sizes):
        return math.inf, (sizes[worst], powers[worst])
    return (_bisect(rep, name, target, sizes[i], sizes[i + 1], steps=6,
                    ratio=1.0),
            (sizes[worst], powers[worst]))
