"""The mark's crossing forces: a force at a depth the frames certify apart from the force.

Under the mark rule each depth past the mark's w0 is read from the press's own force, so an
effect that changes the force between one indenter's presses (a stiffness that steps or
drifts over the session, a gel stiffer on one side) moves the depth with it and is
absorbed. But every press also crossed w0, and the frames say when: the F/T at that moment
(``force_w0_n``, bracketed by the frame period, its standard uncertainty
``force_w0_sem_n``) is the force at the depth w0 that the frames certify, whatever the
force law. Within one indenter w0 is the same for every press, so those forces differ
only by the noise they state and by whatever changed the gel between the presses. This
module tests them for that: each covariate that sets the press's conditions (time, press
order, position) as a stiffness trend (a relative change per unit), time and press order
as a step too, against the stated uncertainties alone (one noise model: what the
certification states is what is tested against), family-wise over every test and a
step's every place by the maximum statistic under that noise (Westfall and Young's
single-step maxT, which counts how alike the tests are: a trend along time and along
press order are nearly one test).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from scipy import stats

from .._checks import InputError

__all__ = ["CROSSING_ALPHA", "CROSSING_COLUMNS", "CROSSING_UNITS", "CrossingScan",
           "CrossingTest", "crossing_measurements", "crossing_sizes", "crossing_tests"]

#: Family-wise level of the crossing forces' tests (over all of them and a step's places).
CROSSING_ALPHA = 0.01
#: Conditions of a press a within-indenter effect can follow: its time and order (a
#: stiffness that drifts or steps over the session) and its position on the pad.
CROSSING_COLUMNS = ("time_s", "press", "x_mm", "y_mm")
#: What :func:`crossing_sizes` sizes: the parameter, its display unit and the factor from
#: the parameter's unit to it.
CROSSING_UNITS = {"stiffness_step:press": ("s", "%", 100.0),
                  "stiffness_trend:time_s": ("k", "%/min", 6000.0),
                  "spatial_nonuniformity": ("gx_per_mm", "%/mm", 100.0)}
#: Least presses (with a crossing force) in an indenter that takes part.
_MIN_PER_INDENTER = 2
#: Draws of the tests' joint null distribution behind the family-wise p-values, and their
#: seed (the same table gives the same p-values).
_FAMILY_DRAWS, _FAMILY_SEED = 10000, 20261126


@dataclass(frozen=True)
class CrossingTest:
    """One within-indenter test of the crossing forces.

    Attributes
    ----------
    column : str
    kind : {'trend', 'step'}
        A stiffness changing linearly along the column, or stepping once along it.
    size : float
        The relative change of the crossing force: per unit of the column (trend), or
        across the step (step, its side of larger values against the other).
    se : float
        Its standard error from the stated uncertainties.
    at : float
        The step's place (midway between the two presses it falls between); NaN for
        a trend.
    p_value : float
        Family-wise: the chance, under the stated uncertainties and no change, that
        some test of the scan (a step at any of its places) reaches a |size / se| this
        large (the single-step maxT of Westfall and Young, by seeded draws).
    significant : bool
        ``p_value`` below :data:`CROSSING_ALPHA`.
    """

    column: str
    kind: str
    size: float
    se: float
    at: float
    p_value: float
    significant: bool

    @property
    def effect(self) -> str:
        """The catalogue effect this structure is: ``spatial_nonuniformity`` along x or y,
        ``stiffness_step:<column>`` or ``stiffness_trend:<column>`` otherwise."""
        if self.column in ("x_mm", "y_mm"):
            return "spatial_nonuniformity"
        return f"stiffness_{self.kind}:{self.column}"


@dataclass(frozen=True)
class CrossingScan:
    """:func:`crossing_tests`' result.

    Attributes
    ----------
    n : int
        Presses with a crossing force in an indenter of two or more.
    n_indenters : int
    chi2 : float
        Scatter of the crossing forces about their indenters' means over the stated
        variances; `dof` degrees of freedom.
    dof : int
    p_scatter : float
        Upper tail of chi2: small when the crossing forces vary within indenters beyond
        what they state.
    tests : tuple of CrossingTest
        Best first (smallest p).
    """

    n: int
    n_indenters: int
    chi2: float
    dof: int
    p_scatter: float
    tests: tuple[CrossingTest, ...]

    def _rivals(self) -> tuple[CrossingTest | None, CrossingTest | None]:
        """The test found and its rival of the other shape along the same column (None
        where there is none), by Akaike's criterion (module docstring of `found`)."""
        sig = [t for t in self.tests if t.significant]
        if not sig:
            return None, None
        best = sig[0]
        rival = [t for t in sig if t.column == best.column and t.kind != best.kind]
        if not rival:
            return best, None
        step, trend = (best, rival[0]) if best.kind == "step" else (rival[0], best)
        return (step, trend) if self._aic_gain(step, trend) > 0 else (trend, step)

    @staticmethod
    def _aic_gain(step: CrossingTest, trend: CrossingTest) -> float:
        """How much better the step fits than the trend along one column, in AIC: the
        drop in chi2, ``z_step^2 - z_trend^2``, less 2 for its one parameter more (the
        change point)."""
        return (step.size / step.se) ** 2 - (trend.size / trend.se) ** 2 - 2.0

    @property
    def found(self) -> CrossingTest | None:
        """The most significant test, where one is; along its column, where a step and a
        trend are both significant, the one Akaike's criterion prefers (the step pays 2 for
        its change point; Akaike, IEEE Trans. Autom. Control 19, 716, 1974)."""
        return self._rivals()[0]

    @property
    def equivalent(self) -> tuple[CrossingTest, ...]:
        """The other shape along the found column where the data hardly prefer either
        (AIC within 2 of the found: Burnham and Anderson, Model Selection and Multimodel
        Inference, 2002, sec. 2.6); a gel that softens steadily fits a step at its middle
        nearly as well at a crossing's noise."""
        found, rival = self._rivals()
        if rival is None:
            return ()
        step, trend = (found, rival) if found.kind == "step" else (rival, found)
        return (rival,) if abs(self._aic_gain(step, trend)) <= 2.0 else ()

    def sentence(self) -> str:
        """What the crossing forces say, in one or two sentences."""
        head = (f"The crossing forces P(w0) ({self.n} presses of {self.n_indenters} indenters: "
                "each press's force where it crossed w0, a depth the frames certify apart "
                "from the force) scatter about their indenters' means "
                f"{np.sqrt(self.chi2 / max(self.dof, 1)):.2f} times what they state "
                f"(chi2 {self.chi2:.1f} on {self.dof}, p = {self.p_scatter:.2g})")
        t = self.found
        if t is None:
            return head + ", with no significant change along " + ", ".join(
                sorted({x.column for x in self.tests})) + "."
        what = (f"{100 * t.size:+.1f} % per unit of {t.column}" if t.kind == "trend" else
                f"{100 * t.size:+.1f} % after {t.column} {t.at:.4g}")
        also = "".join(f" (or {e.effect}, which fits them about as well)"
                       for e in self.equivalent)
        return (head + f"; they change within indenters: {what} (+-{100 * t.se:.1f} %, "
                f"p = {t.p_value:.2g}), which is {t.effect}{also}.")

    def to_json_dict(self) -> dict:
        def num(v: float) -> float | None:
            return float(v) if np.isfinite(v) else None
        return {"n": self.n, "n_indenters": self.n_indenters, "chi2": num(self.chi2),
                "dof": self.dof, "p_scatter": num(self.p_scatter),
                "found": None if self.found is None else self.found.effect,
                "equivalent": [t.effect for t in self.equivalent],
                "tests": [{"column": t.column, "kind": t.kind, "size": num(t.size),
                           "se": num(t.se), "at": num(t.at), "p_value": num(t.p_value),
                           "significant": t.significant} for t in self.tests]}


def _within(v: np.ndarray, groups: np.ndarray, w: np.ndarray) -> np.ndarray:
    """`v` less its weighted mean within each group."""
    out = np.empty_like(v)
    for g in np.unique(groups):
        m = groups == g
        out[m] = v[m] - np.sum(w[m] * v[m]) / np.sum(w[m])
    return out


def _slope(r: np.ndarray, z: np.ndarray, groups: np.ndarray, w: np.ndarray
           ) -> tuple[float, float]:
    """Weighted least squares of r on z with a mean per group, known variances 1/w:
    (slope, its se)."""
    zc = _within(z, groups, w)
    sxx = float(np.sum(w * zc * zc))
    if sxx <= 0:
        return float("nan"), float("inf")
    return float(np.sum(w * zc * r) / sxx), float(1.0 / np.sqrt(sxx))


def crossing_tests(columns: Mapping[str, np.ndarray]) -> CrossingScan | None:
    """Test each indenter's crossing forces for a change along the press's conditions.

    Parameters
    ----------
    columns : mapping of str to (N,) array_like
        A mark-certified measurements table: ``indenter``, ``force_w0_n``,
        ``force_w0_sem_n`` (rows without a finite, positive pair are left out) and
        any of :data:`CROSSING_COLUMNS`.

    Returns
    -------
    CrossingScan or None
        None where the table has no crossing forces, or fewer than two indenters with
        two presses each.
    """
    prep = _prepared(columns)
    if prep is None:
        return None
    ok, groups, r, w = prep
    rc = _within(r, groups, w)
    chi2, dof = float(np.sum(w * rc * rc)), int(r.size - len(np.unique(groups)))
    raw, rows = [], []
    for col, kind, z in _test_columns(columns, ok):
        if kind == "trend":
            b, s = _slope(rc, z, groups, w)
            if np.isfinite(b):
                raw.append((col, "trend", b, s, float("nan"), abs(b / s)))
                rows.append([_direction(z, groups, w)])
        else:
            got, places = _best_step(rc, z, groups, w, col)
            if places:
                raw.append(got)
                rows.append(places)
    p_family = _max_statistic_p([t[5] for t in raw], rows)
    tests = sorted((CrossingTest(col, kind, b, s, at, p, bool(p < CROSSING_ALPHA))
                    for (col, kind, b, s, at, _), p in zip(raw, p_family, strict=True)),
                   key=lambda t: (t.p_value, -abs(t.size / t.se)))
    return CrossingScan(n=int(r.size), n_indenters=len(np.unique(groups)), chi2=chi2, dof=dof,
                        p_scatter=float(stats.chi2.sf(chi2, dof)) if dof > 0 else float("nan"),
                        tests=tuple(tests))


def _prepared(columns: Mapping[str, np.ndarray]
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
    """The rows taking part (a finite, positive crossing force and sd, in an indenter of
    two or more), their indenters, relative crossing forces about their indenter's
    weighted mean and weights (inverse relative variances); None where fewer than two
    indenters take part."""
    need = ("indenter", "force_w0_n", "force_w0_sem_n")
    if any(k not in columns for k in need):
        return None
    ind = np.asarray(columns["indenter"])
    f = np.asarray(columns["force_w0_n"], np.float64)
    se = np.asarray(columns["force_w0_sem_n"], np.float64)
    ok = np.isfinite(f) & np.isfinite(se) & (se > 0) & (f > 0)
    counts = {g: int(np.sum(ok & (ind == g))) for g in np.unique(ind[ok])}
    ok &= np.array([counts.get(g, 0) >= _MIN_PER_INDENTER for g in ind])
    groups = ind[ok]
    if len(np.unique(groups)) < 2:
        return None
    f, se = f[ok], se[ok]
    mean = {g: np.sum(f[groups == g] / se[groups == g] ** 2)
            / np.sum(1 / se[groups == g] ** 2) for g in np.unique(groups)}
    scale = np.array([mean[g] for g in groups])
    return ok, groups, f / scale - 1.0, (scale / se) ** 2       # relative, known variances


def _test_columns(columns: Mapping[str, np.ndarray], ok: np.ndarray
                  ) -> list[tuple[str, str, np.ndarray]]:
    """The scan's tests in order, ``(column, kind, values)``: a trend along each of
    :data:`CROSSING_COLUMNS` present and not constant, a step along time and press order."""
    out = []
    for col in CROSSING_COLUMNS:
        if col not in columns:
            continue
        z = np.asarray(columns[col], np.float64)[ok]
        if not np.all(np.isfinite(z)) or np.ptp(z) == 0:
            continue
        out.append((col, "trend", z))
        if col in ("time_s", "press"):
            out.append((col, "step", z))
    return out


def _direction(x: np.ndarray, groups: np.ndarray, w: np.ndarray) -> np.ndarray:
    """The unit vector a with ``a . u`` the z statistic of a slope along `x` (a mean per
    group, known variances 1/w) for standard normal noise u: ``sqrt(w) x_c / |.|``."""
    a = np.sqrt(w) * _within(x, groups, w)
    norm = float(np.linalg.norm(a))
    return a / norm if norm > 0 else a


def _null_statistics(rows: list[list[np.ndarray]]) -> tuple[list[np.ndarray], np.ndarray]:
    """Each test's |z| statistic (a step's: its largest over its places), sorted, over
    :data:`_FAMILY_DRAWS` seeded draws of their joint normal distribution under the
    stated noise; and per draw the smallest of the tests' own p-values."""
    u = np.random.default_rng(_FAMILY_SEED).standard_normal((_FAMILY_DRAWS, rows[0][0].size))
    d = _FAMILY_DRAWS
    tops, least = [], np.ones(d)
    for r in rows:
        top = np.max(np.abs(u @ np.vstack(r).T), axis=1)
        srt = np.sort(top)
        tops.append(srt)
        least = np.minimum(least, (d - np.searchsorted(srt, top, side="left") + 1) / (d + 1))
    return tops, np.sort(least)


def _max_statistic_p(observed: list[float], rows: list[list[np.ndarray]]) -> list[float]:
    """Family-wise p-values of the tests' |z| statistics (a step's: its largest over its
    places) under the stated noise (:func:`_null_statistics`): each test's own p from its
    statistic's null distribution (a step's every place counted exactly, not by
    Bonferroni), then the family's by the smallest of those over the tests (Westfall and
    Young's single-step min-P, Resampling-Based Multiple Testing, 1993). It counts how
    alike the tests are (a trend along time and along press order are nearly one test)
    and weighs each test alike, however many places a step has."""
    if not observed:
        return []
    tops, least = _null_statistics(rows)
    d = _FAMILY_DRAWS
    own = [(d - np.searchsorted(srt, z, side="left") + 1) / (d + 1)
           for z, srt in zip(observed, tops, strict=True)]
    return [float((np.searchsorted(least, p, side="right") + 1) / (d + 1)) for p in own]


def crossing_sizes(columns: Mapping[str, np.ndarray], *, power: float = 0.95
                   ) -> dict[str, float]:
    """The smallest within-indenter changes the crossing tests name in `power` of sessions
    of this table's presses at their stated uncertainties.

    Parameters
    ----------
    columns : mapping of str to (N,) array_like
        As for :func:`crossing_tests` (the crossing forces' values only set their
        relative uncertainties, ``force_w0_sem_n / force_w0_n``).
    power : float, default 0.95

    Returns
    -------
    sizes : dict of str to float
        Where the table has the columns: ``'stiffness_step:press'``, the relative
        change s of a stiffness step half-way through the presses;
        ``'stiffness_trend:time_s'``, the trend k (1/s) of a stiffness changing
        steadily with time; ``'spatial_nonuniformity'``, the gradient gx (1/mm) along
        x. The catalogue's parametrisations (formats.md §5). Empty without crossings.

    Notes
    -----
    Each test's statistic is linear in the crossing forces, so an effect of size
    delta moves the statistic of its own test (a step at its true place, a trend
    along its column) by ``delta q`` (q the norm of the weighted, within-indenter
    centred effect shape) and the test names it with chance ``Phi(delta q - c)``,
    c the test's threshold under the family-wise level (:func:`_null_statistics`).
    So ``delta = (c + z_power) / q``. The other tests of the scan can only add to the
    power: the sizes are upper bounds of what is named in `power` of sessions.
    """
    prep = _prepared(columns)
    if prep is None:
        return {}
    ok, groups, _, w = prep
    tests = _test_columns(columns, ok)
    rows = [[_direction(z, groups, w)] if kind == "trend" else
            [_direction((z > lo).astype(np.float64), groups, w)
             for lo, _hi in itertools.pairwise(np.unique(z))]
            for _col, kind, z in tests]
    tops, least = _null_statistics(rows)
    p_crit = float(np.quantile(least, CROSSING_ALPHA))
    z_power = float(stats.norm.ppf(power))
    out = {}
    for (col, kind, z), srt in zip(tests, tops, strict=True):
        c = float(np.quantile(srt, 1.0 - p_crit))
        if kind == "step" and col == "press":
            shape, name = (z > np.median(z)).astype(np.float64), "stiffness_step:press"
        elif kind == "trend" and col in ("time_s", "x_mm"):
            shape = z
            name = "stiffness_trend:time_s" if col == "time_s" else "spatial_nonuniformity"
        else:
            continue
        q = float(np.linalg.norm(np.sqrt(w) * _within(shape, groups, w)))
        out[name] = (c + z_power) / q if q > 0 else math.inf
    return out


def _best_step(r: np.ndarray, z: np.ndarray, groups: np.ndarray, w: np.ndarray, col: str
               ) -> tuple[tuple, list[np.ndarray]]:
    """The step along `z` with the largest |size / se| over the places between its distinct
    values, ``(col, 'step', size, se, at, |size / se|)``, and each place's direction
    (:func:`_direction`) for the family-wise p-value."""
    best = (col, "step", float("nan"), float("inf"), float("nan"), 0.0)
    places = []
    for lo, hi in itertools.pairwise(np.unique(z)):
        after = (z > lo).astype(np.float64)
        b, s = _slope(r, after, groups, w)
        if not np.isfinite(b):
            continue
        places.append(_direction(after, groups, w))
        if abs(b / s) > best[5]:
            best = (col, "step", b, s, 0.5 * (lo + hi), abs(b / s))
    return best, places


#: Columns of a mark-certified table that belong to the press's window or its certified
#: depth, not to its crossing of w0: left out of :func:`crossing_measurements`.
_WINDOW_COLUMNS = ("depth_mm", "depth_std_mm", "depth_indenter_std_mm", "overshoot_mm",
                   "force_n", "force0_n", "force_std_n", "force_sem_n", "force_w0_n",
                   "force_w0_sem_n", "bevel_force_n", "fx_n", "fy_n", "hold_s")


def crossing_measurements(columns: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """A mark-certified table's crossing forces as a measurements table of their own.

    Each press crossed its indenter's w0 (``depth_mm - overshoot_mm``), a depth the frames
    certify apart from the force, at the force ``force_w0_n`` (bracketed by a frame period:
    ``force_w0_sem_n``). Those pairs are presses of the gel at known depths whatever the
    force law, so the model can be fitted to them, with the press's conditions as
    covariates, where the mark's certified depths (read through the force) have absorbed
    an effect. Their noise is larger (a frame period's bracket, 3 to 8 % of the force at
    15 frames/s): weigh them by ``1 / force_sem_n**2``.

    Parameters
    ----------
    columns : mapping of str to (N,) array_like
        A measurements table certified by the mark rule (formats.md §2: ``depth_mm``,
        ``overshoot_mm``, ``force_w0_n``, ``force_w0_sem_n``, and covariates).

    Returns
    -------
    table : dict of str to (M,) ndarray
        ``depth_mm`` (w0, mm), ``force_n`` (N), ``force_sem_n`` (N) and the table's
        covariates (``press``, ``indenter``, ``time_s``, ``x_mm``, ...; not the window's
        own columns), float64, for the M presses with a finite, positive crossing force
        and sd; ``row`` (int64), each one's row in `columns`.

    Raises
    ------
    InputError
        Without those columns (a table not certified by the mark rule), or with fewer
        than three distinct w0 among the presses kept.
    """
    need = ("depth_mm", "overshoot_mm", "force_w0_n", "force_w0_sem_n")
    missing = [k for k in need if k not in columns]
    if missing:
        raise InputError(f"no crossing forces: the table lacks {', '.join(missing)} "
                         "(calibrate writes them for presses certified by the mark rule)")
    w0 = (np.asarray(columns["depth_mm"], np.float64)
          - np.asarray(columns["overshoot_mm"], np.float64))
    f = np.asarray(columns["force_w0_n"], np.float64)
    se = np.asarray(columns["force_w0_sem_n"], np.float64)
    ok = np.isfinite(w0) & (w0 > 0) & np.isfinite(f) & (f > 0) & np.isfinite(se) & (se > 0)
    if np.unique(np.round(w0[ok], 6)).size < 3:
        raise InputError(f"the crossing forces of {int(ok.sum())} presses lie at "
                         f"{np.unique(np.round(w0[ok], 6)).size} distinct w0: the model needs "
                         "three or more")
    out = {k: np.asarray(v, np.float64)[ok] for k, v in columns.items()
           if k not in _WINDOW_COLUMNS}
    out.update(depth_mm=w0[ok], force_n=f[ok], force_sem_n=se[ok], row=np.flatnonzero(ok))
    return out

