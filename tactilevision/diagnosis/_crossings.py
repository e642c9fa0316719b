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
as a step too, on the brackets the certification states (one noise model: the crossing
uniform over its frame period is what the tests read and what their null draws:
:mod:`~tactilevision.diagnosis._brackets`), family-wise over every test and a step's
every place by the min-P over brackets drawn from that model (Westfall and Young's
single-step min-P, which counts how alike the tests are: a trend along time and along
press order are nearly one test).
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np
from scipy import stats

from .._checks import InputError
from ._brackets import (
    BRACKET_DELTAS,
    bracket_draws,
    bracket_gains,
    residual_scatter,
    worst_residual,
)

__all__ = ["CROSSING_ALPHA", "CROSSING_COLUMNS", "CROSSING_UNITS", "CrossingScan",
           "CrossingTest", "crossing_measurements", "crossing_sizes", "crossing_step_places",
           "crossing_tests"]

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
#: Least presses on each side of a step's place, counted in the indenters pressed on both
#: sides (where a step shows within an indenter): a step that one press alone carries is
#: that press's own error as well (a mark's onset misread), which the crossing forces
#: cannot tell from a change of the gel.
_MIN_STEP_SIDE = 2
#: Draws of the tests' joint null distribution behind the family-wise p-values, and their
#: seed (the same table gives the same p-values).
_BRACKET_DRAWS, _FAMILY_SEED = 10000, 20261126
#: Draws under each of a fitted trend and step behind :func:`_shape_fits`, and the level
#: below which a fitted change is taken not to explain the brackets' scatter
#: (:func:`residual_scatter`).
_SHAPE_DRAWS, _SHAPE_ALPHA = 400, 0.05
#: The level below which Cox's test (:func:`_shape_fits`) takes one shape not to explain
#: the brackets where the other does: naming a trend for a step (damage for a drift) is a
#: claim the user acts on, so it is made at 1 %. At 5 % (before 2026-11-28), on 200
#: tables drawn from a Taxim session's design (251's, `benchmarks/bench_shape_choice.py`)
#: with a 6.6 % step after the 10th press, the trend was named alone in 14 (the fitted
#: step's search over its places makes its own draws' statistic large, so a true step
#: failed its Cox test more often than 5 %); at 1 %, in 3, the step listed as equivalent
#: in 26 instead of 15. With a 10.8 % softening over the session: a step alone 5 and 0.
_CHOICE_ALPHA = 0.01
#: Draws behind each size :func:`crossing_sizes` tries.
_SIZE_DRAWS = 1000
#: Draws behind the scatter left after a found change (:func:`residual_scatter`), and the
#: most times :func:`crossing_tests` scales the statement; the level below which that
#: scatter exceeds the statement is :data:`_SHAPE_ALPHA` (a change that leaves it does not
#: explain the brackets).
_RESIDUAL_DRAWS, _MAX_RESCALES = 4000, 3
#: The most presses :func:`crossing_tests` leaves out as brackets that do not hold their
#: crossing (:func:`worst_residual` beyond every draw).
_MAX_LEFT_OUT = 2


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
        across the step (step, its side of larger values against the other); the
        weighted least squares of the brackets' midpoints.
    se : float
        Its standard error from the stated uncertainties (sd width / sqrt(12)).
    at : float
        The step's place (midway between the two presses it falls between, the one the
        brackets' likelihood prefers); NaN for a trend.
    p_value : float
        Family-wise: the chance, under the stated brackets and no change, that some test
        of the scan (a step at any of its places) gains this much likelihood
        (:mod:`~tactilevision.diagnosis._brackets`; the single-step min-P of Westfall
        and Young, by seeded draws).
    significant : bool
        ``p_value`` below :data:`CROSSING_ALPHA`.
    gain : float
        The brackets' log-likelihood gain at the test's best size over none.
    """

    column: str
    kind: str
    size: float
    se: float
    at: float
    p_value: float
    significant: bool
    gain: float = float("nan")

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
        Best first: smallest p, and among equal p (the draws' floor) the best AIC on the
        brackets' likelihood (:func:`_order`).
    p_trend_fits, p_step_fits : float
        Where a trend and a step along the most significant test's column are both
        significant: the chance that the fitted trend's brackets favour the best step over
        the trend as much as these do, and that the fitted step's favour it this little
        (:func:`_shape_fits`); NaN otherwise.
    p_residual : float
        Where a change is found: the chance, under the statement the tests read, that the
        crossing forces scatter as much as they do after it (:func:`residual_scatter`);
        NaN otherwise.
    statement_scale : float
        The factor the tests scaled the stated sds by (1: as stated). Where the change
        found under the stated sds leaves a scatter beyond them (``p_residual`` under
        :data:`_SHAPE_ALPHA`), the brackets are narrower than the forces' scatter: a
        certification problem, not physics; the scan is run again with the sds scaled by
        the scatter that change leaves (its sqrt(chi2 / dof)), and again while the change
        then found leaves too much, up to :data:`_MAX_RESCALES` times.
    stated_found : CrossingTest or None
        Where the statement was scaled or a press left out: the change found under the
        stated sds on every press (not named on its own: it did not explain the scatter,
        or one press carried it).
    stated_p_residual : float
        Where the statement was scaled: the ``p_residual`` that made it (of the presses
        kept); NaN otherwise.
    left_out : tuple of (press, z, p_value)
        Presses whose crossing force lay farther from their indenter's, about the change
        found, than every one of the brackets drawn from the statement
        (:func:`worst_residual`: p = 1 / (:data:`_RESIDUAL_DRAWS` + 1); at most
        :data:`_MAX_LEFT_OUT`, in the order left out): brackets that do not hold their
        crossing, left out of the tests (``press`` is the table's ``press``, its row where
        it has none).
    """

    n: int
    n_indenters: int
    chi2: float
    dof: int
    p_scatter: float
    tests: tuple[CrossingTest, ...]
    p_trend_fits: float = float("nan")
    p_step_fits: float = float("nan")
    p_residual: float = float("nan")
    statement_scale: float = 1.0
    stated_found: CrossingTest | None = None
    stated_p_residual: float = float("nan")
    left_out: tuple[tuple[float, float, float], ...] = ()

    def _rivals(self, alpha: float) -> tuple[CrossingTest | None, CrossingTest | None, bool]:
        """The test found, its rival of the other shape along the same column (None where
        there is none), and whether the rival explains the brackets about as well (the
        shapes told apart at `alpha`)."""
        sig = [t for t in self.tests if t.significant]
        if not sig:
            return None, None, False
        best = sig[0]
        rival = [t for t in sig if t.column == best.column and t.kind != best.kind]
        if not rival:
            return best, None, False
        step, trend = (best, rival[0]) if best.kind == "step" else (rival[0], best)
        # Akaike on the brackets' own likelihood (the tests' noise model): twice the step's
        # gain over the trend's, less 2 for its change point (:func:`_aic_gain`)
        aic = 2.0 * (_aic_gain(step) - _aic_gain(trend))
        by_aic = (step, trend) if aic > 0 else (trend, step)
        if not np.isfinite(self.p_trend_fits):
            return (*by_aic, abs(aic) <= 2.0)
        trend_ok = self.p_trend_fits >= alpha
        step_ok = self.p_step_fits >= alpha
        if trend_ok == step_ok:
            # both explain them (or neither): the shape under whose own draws the observed
            # statistic is the more typical (the larger of the two Cox p-values)
            by_p = ((trend, step) if self.p_trend_fits >= self.p_step_fits
                    else (step, trend))
            return (*by_p, trend_ok)
        return (trend, step, False) if trend_ok else (step, trend, False)

    @property
    def found(self) -> CrossingTest | None:
        """The most significant test, where one is; along its column, where a step and a
        trend are both significant, the one that explains the brackets where the other
        does not (``p_trend_fits``, ``p_step_fits``: Cox's test of separate families, at
        :data:`_CHOICE_ALPHA`), and
        where both do (or neither), the one under whose own draws the observed statistic is
        the more typical (the larger of the two p-values: the draws count the step's search
        over its places, which a nominal penalty does not). Without those p-values (one
        shape not significant), Akaike's criterion on the brackets' likelihood (twice each
        shape's log-likelihood gain; the step pays 2 for its change point; Akaike, IEEE
        Trans. Autom. Control 19, 716, 1974)."""
        return self.shapes_at(_CHOICE_ALPHA)[0]

    @property
    def equivalent(self) -> tuple[CrossingTest, ...]:
        """The other shape along the found column where the data hardly prefer either: both
        explain the brackets (``p_trend_fits`` and ``p_step_fits`` at least
        :data:`_CHOICE_ALPHA`); without those, where their AIC on the brackets lie within 2
        (Burnham and Anderson, Model Selection and Multimodel Inference, 2002, sec. 2.6).
        A gel that softens steadily fits a step at its middle nearly as well at a
        crossing's noise. And any other effect whose AIC lies within 2 of the found one's
        (:meth:`_alike_elsewhere`)."""
        return self.shapes_at(_CHOICE_ALPHA)[1]

    def shapes_at(self, alpha: float) -> tuple[CrossingTest | None, tuple[CrossingTest, ...]]:
        """:attr:`found` and :attr:`equivalent` as they read with a step and a trend told
        apart by Cox's test at `alpha` instead of :data:`_CHOICE_ALPHA` (0.05: the rule
        before 2026-11-28; ``benchmarks/bench_shape_choice.py`` reads both).

        Parameters
        ----------
        alpha : float
            The level in (0, 1) below which a shape's Cox p-value (``p_trend_fits``,
            ``p_step_fits``) takes it not to explain the brackets.

        Returns
        -------
        found : CrossingTest or None
        equivalent : tuple of CrossingTest
            Empty or the other shape along the found column.

        Raises
        ------
        InputError
            Where `alpha` is not in (0, 1).
        """
        if not 0.0 < alpha < 1.0:
            raise InputError(f"alpha must lie in (0, 1), got {alpha!r}")
        found, rival, alike = self._rivals(alpha)
        same = (rival,) if rival is not None and alike else ()
        return found, same + self._alike_elsewhere(found, same)

    def _alike_elsewhere(self, found: CrossingTest | None,
                         already: tuple[CrossingTest, ...]) -> tuple[CrossingTest, ...]:
        """Tests of other effects whose AIC on the brackets lies within 2 of `found`'s
        (:func:`_aic_gain`; Burnham and Anderson, sec. 2.6), whatever their family-wise p:
        the data do not tell them apart (a gradient across the pad on presses that crossed
        it in time order fits a step along time about as well). The family-wise p says
        whether the crossing forces change at all, and it charges a step for its search
        over places; which change explains them is the likelihood's to say. (Listing
        only tests at the found one's own p, the draws' floor, as this did before: on two
        of ten drawn Taxim designs (seed 14632, designs 2 and 5, their gel
        softening 10 % over the session) a gradient across the pad was named alone while
        the softening fitted the crossing forces within 0.2 and 0.4 of its
        log-likelihood, its p 0.0036 and 0.016 against the gradient's 0.0021 and
        0.0073.) A step along press order is not listed beside the same along time."""
        if found is None:
            return ()
        named = [found, *already]
        out = []
        for t in self.tests:
            twin = any(t.effect == u.effect or (t.kind == u.kind and {t.column, u.column}
                                                <= {"time_s", "press"}) for u in named)
            if not twin and abs(_aic_gain(found) - _aic_gain(t)) <= 1.0:
                out.append(t)
                named.append(t)
        return tuple(out)

    def sentence(self) -> str:
        """What the crossing forces say, in one to three sentences."""
        text = (f"The crossing forces P(w0) ({self.n} presses of {self.n_indenters} indenters: "
                "each press's force where it crossed w0, a depth the frames certify apart "
                "from the force) scatter about their indenters' means "
                f"{np.sqrt(self.chi2 / max(self.dof, 1)):.2f} times what they state "
                f"(chi2 {self.chi2:.1f} on {self.dof}, p = {self.p_scatter:.2g})")
        t, then = self.found, "; "
        if self.stated_found is not None:
            text += (f"; at the sds they state the best change is {_what(self.stated_found)} "
                     f"({self.stated_found.effect}, p = {self.stated_found.p_value:.2g})")
            for press, z, p in self.left_out:
                text += (f"; press {press:g}'s lies {z:+.1f} sds from its indenter's about "
                         f"it, farther than the statement puts any (p = {p:.2g}): its "
                         "bracket does not hold its crossing (a mark's onset misread), a "
                         "certification problem, and it is left out")
            then = ". Without " + ("them" if len(self.left_out) > 1 else "it") + ", "
            if self.statement_scale != 1.0:
                text += ("; " + ("the others" if self.left_out else "they") + " scatter "
                         "beyond their statement even about the change found (p = "
                         f"{self.stated_p_residual:.2g}): their brackets are narrower than "
                         "the forces' scatter, a certification problem (a mark's onset read "
                         "late or early on some presses), not physics")
                then = f". With the stated sds scaled by {self.statement_scale:.2f}, "
        if t is None:
            lead = ", with " if then == "; " else then
            return (text + lead + ("no significant change" if then == "; " else
                                   "no change within indenters is significant")
                    + " along " + ", ".join(sorted({x.column for x in self.tests})) + ".")
        also = "".join(f" (or {e.effect}, which fits them about as well)"
                       for e in self.equivalent)
        return (text + then + f"they change within indenters: {_what(t)} "
                f"(+-{100 * t.se:.1f} %, p = {t.p_value:.2g}), which is {t.effect}{also}.")

    def to_json_dict(self) -> dict:
        def num(v: float) -> float | None:
            return float(v) if np.isfinite(v) else None
        return {"n": self.n, "n_indenters": self.n_indenters, "chi2": num(self.chi2),
                "dof": self.dof, "p_scatter": num(self.p_scatter),
                "found": None if self.found is None else self.found.effect,
                "equivalent": [t.effect for t in self.equivalent],
                "p_trend_fits": num(self.p_trend_fits), "p_step_fits": num(self.p_step_fits),
                "p_residual": num(self.p_residual), "statement_scale": self.statement_scale,
                "stated_found": (None if self.stated_found is None
                                 else self.stated_found.effect),
                "stated_p_residual": num(self.stated_p_residual),
                "left_out": [{"press": float(k), "z": float(z), "p_value": float(p)}
                             for k, z, p in self.left_out],
                "tests": [{"column": t.column, "kind": t.kind, "size": num(t.size),
                           "se": num(t.se), "at": num(t.at), "p_value": num(t.p_value),
                           "significant": t.significant, "log_likelihood_gain": num(t.gain)}
                          for t in self.tests]}


def _what(t: CrossingTest) -> str:
    """A test's change in words: its size per unit of its column, or after its place."""
    return (f"{100 * t.size:+.1f} % per unit of {t.column}" if t.kind == "trend" else
            f"{100 * t.size:+.1f} % after {t.column} {t.at:.4g}")


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


@dataclass(frozen=True)
class _Brackets:
    """A table's tests as shapes for the brackets' likelihood: every trend and every place
    of a step (``shapes`` (K, N), ``owner`` (K,) each one's test, ``at`` (K,) a step's
    place), the presses' indenters 0 to G - 1 and their brackets' widths relative to
    their readings (three figures: tables of one design at one precision share their
    null draws)."""

    shapes: np.ndarray
    owner: np.ndarray
    at: list[float]
    groups: np.ndarray
    width: np.ndarray

    @classmethod
    def of(cls, columns: Mapping[str, np.ndarray], ok: np.ndarray, groups: np.ndarray,
           w: np.ndarray, tests: list[tuple[str, str, np.ndarray]]) -> _Brackets:
        shapes, owner, at = [], [], []
        for j, (_col, kind, z) in enumerate(tests):
            if kind == "trend":
                shapes.append((z - z.mean()) / np.ptp(z))
                at.append(float("nan"))
            else:
                for lo, hi in _step_places(z, groups):
                    shapes.append((z > lo).astype(np.float64))
                    at.append(0.5 * (lo + hi))
            owner += [j] * (len(shapes) - len(owner))
        f = np.asarray(columns["force_w0_n"], np.float64)[ok]
        se = np.asarray(columns["force_w0_sem_n"], np.float64)[ok]
        width = np.array([float(f"{v:.3g}") for v in np.sqrt(12.0) * se / f])
        _, gid = np.unique(groups, return_inverse=True)
        return cls(np.vstack(shapes), np.array(owner, np.int64), at, gid.astype(np.int64),
                   width)

    def _key(self) -> tuple[bytes, bytes, bytes, bytes]:
        return (self.width.tobytes(), self.groups.tobytes(), self.shapes.tobytes(),
                self.owner.tobytes())

    def null(self) -> np.ndarray:
        """Each test's largest gain over its places (D, T) with nothing changing."""
        return _bracket_null(*self._key())

    def min_p(self) -> tuple[np.ndarray, np.ndarray]:
        """:func:`_min_p` of :meth:`null` (sorted once per design, as the null is drawn)."""
        return _bracket_min_p(*self._key())

    def thresholds(self) -> np.ndarray:
        """Each test's gain (T,) that names it at the family-wise :data:`CROSSING_ALPHA`
        (min-P: the tests' own p-value that the family's level allows)."""
        null = self.null()
        _, least = self.min_p()
        p_crit = float(np.quantile(least, CROSSING_ALPHA))
        return np.quantile(null, 1.0 - p_crit, axis=0)


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

    Notes
    -----
    Each crossing force is the bracket ``force_w0_n -+ sqrt(3) force_w0_sem_n`` the
    certification states; each test (a trend along a column, a step at each place along
    time and press order) is the brackets' likelihood ratio
    (:mod:`~tactilevision.diagnosis._brackets`), its family-wise p-value by the min-P
    over :data:`_BRACKET_DRAWS` seeded draws of brackets from the same model. The sizes
    and standard errors reported are the weighted least squares of the brackets'
    midpoints (sd width / sqrt(12)), which also gives the scatter's chi2.

    A change found must also explain the forces' scatter: where the scatter left about it
    exceeds what the brackets state (:func:`residual_scatter`, p under
    :data:`_SHAPE_ALPHA`), the brackets are narrower than the forces vary, which a change
    of the gel does not explain (on a Taxim session without the renderer's shadows the
    mark's onset was read a frame late on some presses, their forces up to 4.8 sds high,
    and a step along time was found on a session with nothing changing). The scan is then
    run again with every sd scaled by that scatter's sqrt(chi2 / dof) (Birge's ratio;
    Birge, Phys. Rev. 40, 207, 1932), and a change is named only where it stays
    significant and explains the scatter at the scaled sds (``statement_scale``,
    ``stated_found``). Where the change found explains the scatter but one press lies
    farther from its indenter's about it than every bracket drawn from the statement
    (:func:`worst_residual`, at the sds as scaled), that press's bracket does not hold its
    crossing: it is left out and the whole scan run again, at most :data:`_MAX_LEFT_OUT`
    times (``left_out``). And a step needs :data:`_MIN_STEP_SIDE` presses on each side
    (:func:`_step_places`), so no single press carries one. These rules were written
    after two Taxim sessions without shadows were seen (a step along time named on their
    nulls: late onsets on one, one press read 7 sds low on the other); on brackets drawn
    with 30 % of the presses read a frame late and nothing changing, a change was named on
    30 of 30 tables at the stated sds and on 8 of 30 with the scaling.
    """
    stated = _scan(columns)
    if stated is None or stated.found is None:
        return stated
    cols, scan, left = dict(columns), stated, []
    while True:
        scale, p_made = 1.0, math.nan
        if scan.found is None:
            break
        scan, scale, p_made = _rescaled(cols, scan)
        if scan.found is None or len(left) >= _MAX_LEFT_OUT:
            break
        # the change explains the scatter (at the sds as scaled): does one press carry it,
        # its bracket farther from its indenter's than any the statement draws?
        sem = np.asarray(cols["force_w0_sem_n"], np.float64) * scale
        ok, groups, r, w = _prepared({**cols, "force_w0_sem_n": sem})
        k, z, p = worst_residual(r, groups, w, _shape_of(cols, ok, scan.found),
                                 _RESIDUAL_DRAWS, np.random.default_rng(_FAMILY_SEED + 4))
        row = int(np.flatnonzero(ok)[k])
        fewer = _without(cols, row)
        again = _scan(fewer) if p * (_RESIDUAL_DRAWS + 1) < 1.5 else None
        if again is None:
            break
        left.append((float(np.asarray(cols["press"])[row]) if "press" in cols else row, z, p))
        cols, scan = fewer, again
    if scale == 1.0 and not left:
        return scan
    return replace(scan, n=stated.n, n_indenters=stated.n_indenters, chi2=stated.chi2,
                   dof=stated.dof, p_scatter=stated.p_scatter, statement_scale=scale,
                   stated_found=stated.found, stated_p_residual=p_made,
                   left_out=tuple(left))


def _rescaled(columns: Mapping[str, np.ndarray], scan: CrossingScan
              ) -> tuple[CrossingScan, float, float]:
    """`scan` (its change found) checked against the scatter it leaves, and rerun with the
    stated sds scaled while that exceeds them: ``(scan, scale, p)``, `p` the first
    ``p_residual`` (the one that scaled them; NaN where they stand)."""
    sem = np.asarray(columns["force_w0_sem_n"], np.float64)
    chi2, dof, p = _scatter_after(columns, scan.found)
    scan, first, scale = replace(scan, p_residual=p), p, 1.0
    for _ in range(_MAX_RESCALES):
        if p >= _SHAPE_ALPHA or dof <= 0:
            break
        scale *= math.sqrt(chi2 / dof)
        cols = {**columns, "force_w0_sem_n": sem * scale}
        scan = _scan(cols)
        if scan.found is None:
            break
        chi2, dof, p = _scatter_after(cols, scan.found)
        scan = replace(scan, p_residual=p)
    return scan, scale, first if scale != 1.0 else math.nan


def _without(columns: Mapping[str, np.ndarray], row: int) -> dict[str, np.ndarray]:
    """`columns` without the press in `row`."""
    return {k: np.delete(np.asarray(v), row) for k, v in columns.items()}


def _shape_of(columns: Mapping[str, np.ndarray], ok: np.ndarray, t: CrossingTest
              ) -> np.ndarray:
    """The change `t` as a shape over the presses taking part: its column (a trend), 0 and
    1 about its place (a step)."""
    z = np.asarray(columns[t.column], np.float64)[ok]
    return z if t.kind == "trend" else (z > t.at).astype(np.float64)


def _scatter_after(columns: Mapping[str, np.ndarray], t: CrossingTest
                   ) -> tuple[float, int, float]:
    """:func:`residual_scatter` of the table's crossing forces about the change `t`."""
    ok, groups, r, w = _prepared(columns)
    return residual_scatter(r, groups, w, _shape_of(columns, ok, t), _RESIDUAL_DRAWS,
                            np.random.default_rng(_FAMILY_SEED + 3))


def _scan(columns: Mapping[str, np.ndarray]) -> CrossingScan | None:
    """:func:`crossing_tests` at the table's stated sds."""
    prep = _prepared(columns)
    if prep is None:
        return None
    ok, groups, r, w = prep
    rc = _within(r, groups, w)
    chi2, dof = float(np.sum(w * rc * rc)), int(r.size - len(np.unique(groups)))
    tests = _test_columns(columns, ok)
    if not tests:
        return CrossingScan(n=int(r.size), n_indenters=len(np.unique(groups)), chi2=chi2,
                            dof=dof, p_scatter=float(stats.chi2.sf(chi2, dof)) if dof > 0
                            else float("nan"), tests=())
    setup = _Brackets.of(columns, ok, groups, w, tests)
    shape_a, owner_a, at, gid, width = (setup.shapes, setup.owner, setup.at, setup.groups,
                                        setup.width)
    half = np.sqrt(3.0) / np.sqrt(w)                 # half-widths relative to the indenter's
    obs, _ = bracket_gains((r + 1.0 - half)[None], (r + 1.0 + half)[None], gid, shape_a)
    best = [int(np.flatnonzero(owner_a == j)[np.argmax(obs[0, owner_a == j])])
            for j in range(len(tests))]
    observed = np.array([obs[0, k] for k in best])
    p_family = _family_p(observed, *setup.min_p())
    # each test's best shape's gain on a fine grid about its best size (what the step and
    # the trend are weighed by; the p-values compare the coarse grid with its null)
    fine = [_fine_gain(r + 1.0 - half, r + 1.0 + half, gid, shape_a[k]) for k in best]
    out = []
    for (col, kind, _z), k, p, (gain, _d) in zip(tests, best, p_family, fine, strict=True):
        if kind == "trend":
            b, s = _slope(rc, np.asarray(columns[col], np.float64)[ok], groups, w)
        else:
            b, s = _slope(rc, shape_a[k], groups, w)
        out.append(CrossingTest(col, kind, b, s, at[k], float(p), bool(p < CROSSING_ALPHA),
                                gain))
    shape_p = (float("nan"), float("nan"))
    sig = sorted((t for t in out if t.significant), key=_order)
    if sig:
        j_of = {(t[0], t[1]): j for j, t in enumerate(tests)}
        col = sig[0].column
        if all((col, kind) in j_of and any(t.column == col and t.kind == kind for t in sig)
               for kind in ("trend", "step")):
            jt, js = j_of[(col, "trend")], j_of[(col, "step")]
            shape_p = _shape_fits(r + 1.0 - half, r + 1.0 + half, gid, width,
                                  shape_a[owner_a == jt][0], shape_a[owner_a == js],
                                  fine[jt][1], shape_a[best[js]], fine[js][1])
    out.sort(key=_order)
    return CrossingScan(n=int(r.size), n_indenters=len(np.unique(groups)), chi2=chi2, dof=dof,
                        p_scatter=float(stats.chi2.sf(chi2, dof)) if dof > 0 else float("nan"),
                        tests=tuple(out), p_trend_fits=shape_p[0], p_step_fits=shape_p[1])


def _aic_gain(t: CrossingTest) -> float:
    """A test's log-likelihood gain less what Akaike's criterion charges its extra
    parameters: a step's place costs 1 (AIC = 2 k - 2 log L; Akaike, IEEE Trans. Autom.
    Control 19, 716, 1974)."""
    return t.gain - (1.0 if t.kind == "step" else 0.0)


def _order(t: CrossingTest) -> tuple[float, float]:
    """The tests' order: family-wise p, then, among tests the draws cannot order (their p
    at the draws' floor, 1 / (:data:`_BRACKET_DRAWS` + 1)), Akaike's criterion on the
    brackets' likelihood (:func:`_aic_gain`): the raw gain would favour a step, whose
    place is fitted too."""
    return (t.p_value, -_aic_gain(t))


def _shape_fits(lo: np.ndarray, hi: np.ndarray, groups: np.ndarray, width: np.ndarray,
                trend: np.ndarray, steps: np.ndarray, d_trend: float, step: np.ndarray,
                d_step: float) -> tuple[float, float]:
    """Whether a trend or a step along one column explains the brackets, each tested against
    the other by what the other predicts (Cox's test of separate families, by parametric
    bootstrap: Cox, Proc. 4th Berkeley Symp. 1, 105, 1961): the statistic is how much more
    the best step gains than the trend, on the coarse grid; ``(p_trend, p_step)``, the chance
    of a statistic this large under the fitted trend, and this small under the fitted step
    (:data:`_SHAPE_DRAWS` draws of brackets of the table's widths about each)."""
    shapes = np.vstack([trend[None], steps])

    def stat(lo_, hi_):
        g, _ = bracket_gains(lo_, hi_, groups, shapes)
        return g[:, 1:].max(axis=1) - g[:, 0]

    observed = float(stat(lo[None], hi[None])[0])
    rng = np.random.default_rng(_FAMILY_SEED + 1)
    out = []
    for z, d, upper in ((trend, d_trend, True), (step, d_step, False)):
        lo0, hi0 = bracket_draws(width, _SHAPE_DRAWS, rng)
        true = 1.0 + d * z
        draws = stat(lo0 * true, hi0 * true)
        hits = np.sum(draws >= observed) if upper else np.sum(draws <= observed)
        out.append(float((hits + 1) / (_SHAPE_DRAWS + 1)))
    return out[0], out[1]


def _fine_gain(lo: np.ndarray, hi: np.ndarray, groups: np.ndarray, shape: np.ndarray
               ) -> tuple[float, float]:
    """The brackets' largest log-likelihood gain along `shape` and the size that reaches
    it: a coarse pass, then 201 sizes between its best's neighbours."""
    _, d = bracket_gains(lo[None], hi[None], groups, shape[None])
    j = int(np.argmin(np.abs(BRACKET_DELTAS - d[0, 0])))
    ends = BRACKET_DELTAS[max(j - 1, 0)], BRACKET_DELTAS[min(j + 1, BRACKET_DELTAS.size - 1)]
    near = np.r_[0.0, np.linspace(*ends, 201)]
    gain, best = bracket_gains(lo[None], hi[None], groups, shape[None], near)
    return float(gain[0, 0]), float(best[0, 0])


@functools.lru_cache(maxsize=16)
def _bracket_null(width: bytes, groups: bytes, shapes: bytes, owner: bytes) -> np.ndarray:
    """Each test's largest gain over its places (D, T) in :data:`_BRACKET_DRAWS` seeded
    draws of brackets of these relative widths with nothing changing (arrays as bytes:
    float64 widths (N,), int64 groups (N,), float64 shapes (K, N), int64 owner (K,), each
    shape's test)."""
    w = np.frombuffer(width, np.float64)
    z = np.frombuffer(shapes, np.float64).reshape(-1, w.size)
    own = np.frombuffer(owner, np.int64)
    lo, hi = bracket_draws(w, _BRACKET_DRAWS, np.random.default_rng(_FAMILY_SEED))
    gain, _ = bracket_gains(lo, hi, np.frombuffer(groups, np.int64), z)
    return np.stack([gain[:, own == j].max(axis=1) for j in range(int(own.max()) + 1)], 1)


def _family_p(observed: np.ndarray, srt: np.ndarray, least: np.ndarray) -> np.ndarray:
    """Family-wise p-values of the tests' statistics `observed` (T,) from their joint null
    draws, larger being more extreme (`srt`, `least`: :func:`_min_p` of the draws): each
    test's own p from its null, then the family's by the smallest of those over the tests
    (Westfall and Young's single-step min-P, Resampling-Based Multiple Testing, 1993)."""
    d = srt.shape[0]
    own = np.array([(d - np.searchsorted(srt[:, j], observed[j], side="left") + 1) / (d + 1)
                    for j in range(srt.shape[1])])
    return (np.searchsorted(least, own, side="right") + 1) / (d + 1)


@functools.lru_cache(maxsize=16)
def _bracket_min_p(width: bytes, groups: bytes, shapes: bytes, owner: bytes
                   ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_min_p` of :func:`_bracket_null` (the same arguments), read-only."""
    srt, least = _min_p(_bracket_null(width, groups, shapes, owner))
    srt.flags.writeable = least.flags.writeable = False
    return srt, least


def _min_p(null: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each test's null sorted (D, T), and per draw the smallest of the tests' own p-values
    (D,), sorted: the min-P's null."""
    d = null.shape[0]
    srt = np.sort(null, axis=0)
    own = np.stack([(d - np.searchsorted(srt[:, j], null[:, j], side="left") + 1) / (d + 1)
                    for j in range(null.shape[1])], axis=1)
    return srt, np.sort(own.min(axis=1))


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


def _step_places(z: np.ndarray, groups: np.ndarray) -> list[tuple[float, float]]:
    """A step's places along `z`: each pair of neighbouring values it can fall between
    with at least :data:`_MIN_STEP_SIDE` presses on each side in the indenters (`groups`)
    pressed on both."""
    out = []
    for lo, hi in itertools.pairwise(np.unique(z)):
        after = z > lo
        both = [g for g in np.unique(groups) if 0 < np.sum(after[groups == g])
                < np.sum(groups == g)]
        inside = np.isin(groups, both)
        if min(np.sum(after & inside), np.sum(~after & inside)) >= _MIN_STEP_SIDE:
            out.append((float(lo), float(hi)))
    return out


def _test_columns(columns: Mapping[str, np.ndarray], ok: np.ndarray
                  ) -> list[tuple[str, str, np.ndarray]]:
    """The scan's tests in order, ``(column, kind, values)``: a trend along each of
    :data:`CROSSING_COLUMNS` present and not constant, a step along time and press order
    where it has a place (:func:`_step_places`)."""
    groups = np.asarray(columns["indenter"])[ok]
    out = []
    for col in CROSSING_COLUMNS:
        if col not in columns:
            continue
        z = np.asarray(columns[col], np.float64)[ok]
        if not np.all(np.isfinite(z)) or np.ptp(z) == 0:
            continue
        out.append((col, "trend", z))
        if col in ("time_s", "press") and _step_places(z, groups):
            out.append((col, "step", z))
    return out


def crossing_sizes(columns: Mapping[str, np.ndarray], *, power: float = 0.95,
                   sessions: Sequence[tuple[np.ndarray, np.ndarray]] | None = None
                   ) -> dict[str, float]:
    """The smallest within-indenter changes the crossing tests name in `power` of sessions
    of this table's presses at their stated uncertainties.

    Parameters
    ----------
    columns : mapping of str to (N,) array_like
        As for :func:`crossing_tests` (the crossing forces' values only set their
        brackets' relative widths, ``force_w0_sem_n / force_w0_n``).
    power : float, default 0.95
    sessions : sequence of (keep, sem), optional
        Sessions of the table's design that differ from it, drawn by the caller (a plan's:
        :func:`~tactilevision.planning.crossing_sessions`): ``keep`` (N,) bool, the
        presses such a session certifies, and ``sem`` (M, N) float, the stated sds of
        ``force_w0_n`` in each of its M draws. The :data:`_SIZE_DRAWS` draws are then
        theirs, the tests' thresholds the table's own. Default: the table as it is.

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
    For each effect, brackets of the table's widths are drawn about crossing forces
    changed by it (:data:`_SIZE_DRAWS` draws, the same for every size tried), and its
    own test (a step along press order at its true place, a trend along time or x)
    names it where its gain passes that test's family-wise threshold
    (:meth:`_Brackets.thresholds`); the size named in `power` of the draws is found by
    bisection. The step's other places and the scan's other tests can only add to the
    power: the sizes are upper bounds of what is named in `power` of sessions.
    """
    sized = _size_setup(columns, sessions)
    if sized is None:
        return {}
    tests, _, crit, parts = sized
    out = {}
    for j, (col, kind, z) in enumerate(tests):
        if kind == "step" and col == "press":
            out["stiffness_step:press"] = _step_size(parts, j, crit[j], float(np.median(z)),
                                                     power)
        elif kind == "trend" and col in ("time_s", "x_mm"):
            name = "stiffness_trend:time_s" if col == "time_s" else "spatial_nonuniformity"

            effects = [t[j][2] - t[j][2].mean() for _, t, _ in parts]
            shapes = [setup.shapes[setup.owner == j] for setup, _, _ in parts]

            def named(size: float, effects=effects, shapes=shapes, c=crit[j],
                      steady=name == "stiffness_trend:time_s") -> float:
                return _named_share(parts, c, effects, shapes, size, steady)

            out[name] = _bisect_size(named, power,
                                     0.05 / max(float(np.ptp(z - z.mean())), 1e-12))
    return out


def crossing_step_places(columns: Mapping[str, np.ndarray], *, power: float = 0.95,
                         sessions: Sequence[tuple[np.ndarray, np.ndarray]] | None = None
                         ) -> tuple[tuple[float, float], ...]:
    """The smallest stiffness step along press order the crossing tests name in `power`
    of sessions, at places other than half-way through the presses.

    :func:`crossing_sizes` sizes the step half-way, where the presses on its two sides
    are most even and it is seen best; a step early or late in the session has fewer
    presses on one side and needs to be larger (on a Taxim session of 25 read presses,
    7.7 % half-way, 9.2 % after the 9th, 18.1 % and 20.9 % after the first and the last
    places the scan tests). A "none larger than" that gives the half-way size alone
    would rule out a step it could miss elsewhere.

    Parameters
    ----------
    columns : mapping of str to (N,) array_like
        As for :func:`crossing_sizes` (with ``press``).
    power : float, default 0.95
    sessions : sequence of (keep, sem), optional
        As for :func:`crossing_sizes`.

    Returns
    -------
    places : tuple of (float, float)
        ``(after, s)``: a step just after press number ``after`` (the step falls
        between it and the next press the table has), of relative size ``s``, at the
        first, a quarter of the way, three quarters of the way and the last of the
        places the scan tests a step at (:data:`_MIN_STEP_SIDE` presses on each side);
        ordered by ``after``, each place once. Empty without crossing forces or a
        ``press`` column.

    Notes
    -----
    As :func:`crossing_sizes`: brackets of the table's widths drawn about crossing
    forces with the step at that place (the same draws for every size and place), named
    where its test's gain passes the family-wise threshold; the size by bisection. The
    power is least at the ends of the places (fewest presses on one side), so the
    largest of these is about the largest over every place (on the session above it
    was, over all 22).
    """
    sized = _size_setup(columns, sessions)
    if sized is None:
        return ()
    tests, groups, crit, parts = sized
    out = []
    for j, (col, kind, z) in enumerate(tests):
        if kind != "step" or col != "press":
            continue
        for after, _ in _step_places(z, groups):
            out.append((after, _step_size(parts, j, crit[j], after, power)))
    return tuple(out)


def _size_setup(columns: Mapping[str, np.ndarray],
                sessions: Sequence[tuple[np.ndarray, np.ndarray]] | None = None):
    """What :func:`crossing_sizes` draws its sessions from: ``(tests, groups, thresholds,
    parts)``, the table's tests, indenters and thresholds, and ``parts`` a list of
    ``(setup, tests, (lo, hi))``: the table's own brackets' draws about 1
    (:data:`_SIZE_DRAWS`, seeded), or each of `sessions` with its draws; None without
    crossing forces or tests."""
    prep = _prepared(columns)
    if prep is None:
        return None
    ok, groups, _, w = prep
    tests = _test_columns(columns, ok)
    if not tests:
        return None
    setup = _Brackets.of(columns, ok, groups, w, tests)
    rng = np.random.default_rng(_FAMILY_SEED + 2)
    if sessions is None:
        return tests, groups, setup.thresholds(), [
            (setup, tests, bracket_draws(setup.width, _SIZE_DRAWS, rng))]
    parts = [p for keep, sem in sessions
             if (p := _session_part(columns, keep, sem, tests, rng)) is not None]
    return (tests, groups, setup.thresholds(), parts) if parts else None


def _session_part(columns: Mapping[str, np.ndarray], keep: np.ndarray, sem: np.ndarray,
                  tests: list[tuple[str, str, np.ndarray]], rng: np.random.Generator):
    """One drawn session's ``(setup, tests, (lo, hi))``: the presses it keeps, its brackets
    drawn at each draw's widths; None where its tests are not the table's."""
    keep = np.asarray(keep, bool)
    sem = np.atleast_2d(np.asarray(sem, np.float64))
    cols = {k: np.asarray(v)[keep] for k, v in columns.items()}
    cols["force_w0_sem_n"] = sem[0][keep]
    prep = _prepared(cols)
    if prep is None:
        return None
    ok, groups, _, w = prep
    own = _test_columns(cols, ok)
    if [t[:2] for t in own] != [t[:2] for t in tests]:
        return None
    setup = _Brackets.of(cols, ok, groups, w, own)
    f = np.asarray(cols["force_w0_n"], np.float64)[ok]
    width = np.sqrt(12.0) * sem[:, keep][:, ok] / f
    return setup, own, bracket_draws(width, width.shape[0], rng)


def _step_size(parts: list, j: int, crit: float, after: float, power: float) -> float:
    """The smallest step 1 + s [press > after] that its own test (the `j`-th), at its
    true place only, names in `power` of the parts' draws."""
    effects = [(t[j][2] > after).astype(np.float64) for _, t, _ in parts]
    shapes = [e[None] for e in effects]
    return _bisect_size(lambda size: _named_share(parts, crit, effects, shapes, size),
                        power, 0.05)


def _named_share(parts: list, crit: float, effects: list[np.ndarray],
                 shapes: list[np.ndarray], size: float, steady: bool = False) -> float:
    """The share of the parts' draws in which a test whose largest gain over `shapes`
    passes `crit` names a change of `size` along each part's `effects` (relative, 1 + s x;
    ``exp(s x)`` where `steady`)."""
    hit = total = 0
    for (setup, _, draws), effect, shape in zip(parts, effects, shapes, strict=True):
        true = np.exp(size * effect) if steady else 1.0 + size * effect
        gain, _ = bracket_gains(draws[0] * true, draws[1] * true, setup.groups, shape)
        hit += int(np.sum(gain.max(axis=1) >= crit))
        total += gain.shape[0]
    return hit / total


def _bisect_size(named, power: float, first: float) -> float:
    """The size at which ``named(size)`` (the share of draws named, rising with the size)
    reaches `power`, to 2 % (inf where even a change of half the force is not named)."""
    lo, hi = 0.0, first
    while named(hi) < power:
        lo, hi = hi, 2.0 * hi
        if hi > 64 * first:
            return math.inf
    while hi - lo > 0.02 * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if named(mid) < power else (lo, mid)
    return hi


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

