"""The holds: each press's force while the stage stands still, tested for relaxation.

A measurements table has one force per press, taken in a window at one time of the hold
(``hold_s``). Where every press is read at the same time of its hold (most sessions), a
gel that relaxes only scales that force alike, and the table cannot show it
(``viscoelastic_relaxation`` is untestable on a constant ``hold_s``). But ``calibrate``
also writes the force over each whole hold (``holds.csv``), at a depth the stage keeps:
there a relaxing gel's force falls while nothing else moves. This module reads that
(:func:`~tactilevision.mechanics.fit_relaxation`: an F test of the decay against a
constant force per press at p < ``RELAX_ALPHA``, tau identified or not, and a decay that
only follows a stiffness falling between presses told apart as softening), and says
whether the holds name the relaxation: ``diagnose`` then takes it as the missing effect
where the table named nothing.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy import optimize, stats

from .._checks import InputError
from ..mechanics import RELAX_ALPHA, RelaxationFit, fit_relaxation

__all__ = ["HOLDS_POWER", "HoldsFinding", "holds_finding", "holds_relaxation"]

#: The power at which the holds' smallest named decay is stated (as the table's rules-out).
HOLDS_POWER = 0.95


@lru_cache(maxsize=8)
def _power_factor(alpha: float = RELAX_ALPHA, power: float = HOLDS_POWER) -> float:
    """sqrt(lambda) of the noncentral chi2 on 2 degrees of freedom (g and tau: the holds' F
    test) that exceeds its level-`alpha` quantile with probability `power`: 5.25 at 0.001
    and 0.95. The smallest decay rate named is that many standard errors of the rate."""
    crit = float(stats.chi2.ppf(1.0 - alpha, 2))
    lam = optimize.brentq(lambda x: float(stats.ncx2.sf(crit, 2, x)) - power, 1e-6, 1e3)
    return math.sqrt(lam)


def holds_relaxation(holds: Mapping[str, np.ndarray], columns: Mapping[str, np.ndarray],
                     labels: Mapping[str, Sequence] | None = None) -> RelaxationFit:
    """The relaxation fitted to a table's holds, with the table's presses' times and indenters.

    Parameters
    ----------
    holds : mapping of str to (K,) ndarray
        ``holds.csv``'s columns (:func:`~tactilevision.io.read_holds`): ``press``,
        ``t_s`` (s since the hold's start), ``fz_n`` (N) and, optionally, ``ramp_s``.
    columns : mapping of str to (N,) ndarray
        The measurements table's numeric columns: ``press`` and ``time_s`` (each
        press's time in the session, s) and ``indenter``, where present, tell a gel that
        softens over the session from one that relaxes (a relaxing gel recovers between
        presses).
    labels : mapping of str to sequence, optional
        The table's text columns (an ``indenter`` given by name).

    Returns
    -------
    RelaxationFit
        :func:`~tactilevision.mechanics.fit_relaxation`'s result.

    Raises
    ------
    InputError
        From :func:`~tactilevision.mechanics.fit_relaxation` (fewer than 3 presses, a
        hold of fewer than 5 samples, non-positive forces).
    """
    press, t = columns.get("press"), columns.get("time_s")
    times = groups = None
    if press is not None and t is not None:
        press, t = np.asarray(press, np.float64), np.asarray(t, np.float64)
        ok = np.isfinite(press) & np.isfinite(t)
        times = {int(p): float(v) for p, v in zip(press[ok], t[ok], strict=True)}
        ind = columns.get("indenter")
        if ind is None and labels is not None and "indenter" in labels:
            ind = np.array(labels["indenter"], dtype=object)
        if ind is not None:
            groups = {int(p): g for p, g, k in zip(press, ind, ok, strict=True) if k}
    return fit_relaxation(holds["press"], holds["t_s"], holds["fz_n"], holds.get("ramp_s"),
                          press_time_s=times, press_group=groups)


@dataclass(frozen=True)
class HoldsFinding:
    """What the holds say about a relaxing gel (:func:`holds_finding`).

    Attributes
    ----------
    relaxation : RelaxationFit
        The fit to the holds.
    source : str
        Where the holds were read (a file name; empty when given as arrays).
    named : bool
        Whether the holds name ``viscoelastic_relaxation``: they fall (the F test
        against a constant force per press, p < ``RELAX_ALPHA``), the fall is not the
        stiffness falling between presses (verdict not ``'softening'``), and the
        force decreases. Its size: ``relaxation.decay_rate_per_s`` (the initial
        relative rate, ``-g phi / tau`` for a slow relaxation) always; g and tau only
        where they are identified (``relaxation.identified``).
    """

    relaxation: RelaxationFit
    source: str = ""
    named: bool = False

    @property
    def smallest_rate_per_s(self) -> float:
        """The smallest initial decay rate these holds name in :data:`HOLDS_POWER` of
        sessions, 1/s (> 0; NaN without a rate's standard error): the F test's
        noncentrality at that power (2 degrees of freedom, level ``RELAX_ALPHA``) in
        standard errors of the measured rate, ``5.25 se``. A slow relaxation's initial
        rate is ``g phi(T / tau) / tau``."""
        se = self.relaxation.decay_rate_se_per_s
        return _power_factor() * se if math.isfinite(se) and se > 0 else math.nan

    def sentence(self) -> str:
        """One paragraph for ``diagnose``'s message: what the holds show."""
        r = self.relaxation
        where = f" ({self.source})" if self.source else ""
        rate = (f"{100 * r.decay_rate_per_s:+.3g} %/s of their force (se "
                f"{100 * r.decay_rate_se_per_s:.2g})"
                if math.isfinite(r.decay_rate_per_s) else "a rate not measured")
        head = (f"The holds{where}, {r.n_presses} presses' force while the stage keeps their "
                f"depth, change at {rate} from the hold's start")
        if not self.named:
            return f"{head}: {r.verdict} ({r.why})."
        p = f"p = {r.p_value:.2g}" if r.p_value > 1e-16 else "p < 1e-16"
        between = (f"; between presses the forces at one depth move by "
                   f"{100 * r.trend_per_s:+.3g} %/s (se {100 * r.trend_se_per_s:.2g}), where "
                   "a gel that softens over the session would fall as the holds do"
                   if math.isfinite(r.trend_per_s) else "")
        if r.identified:
            size = (f"g = {r.g:.3g}, tau = {r.tau_s:.3g} s (95 % intervals "
                    f"[{r.g_ci[0]:.3g}, {r.g_ci[1]:.3g}] and [{r.tau_ci_s[0]:.3g}, "
                    f"{r.tau_ci_s[1]:.3g}] s)")
        else:
            size = (f"g and tau are not identified, only the initial rate g phi / tau = "
                    f"{-r.decay_rate_per_s:.3g} 1/s (the decay's curvature, which would "
                    f"separate them, is not resolved by holds of {r.longest_hold_s:.3g} s at "
                    "most; longer holds, or holds of different lengths, would tell)")
        return (f"{head}: they fall ({p} against a constant force per press){between}. "
                f"The gel relaxes: viscoelastic_relaxation, named from the holds; {size}. "
                "Fit it from the holds (fit --holds), not as a column effect of this table.")

    def to_json_dict(self) -> dict:
        """The finding as plain JSON types (NaN as None)."""
        r = self.relaxation

        def num(v: float) -> float | None:
            return float(v) if math.isfinite(v) else None

        return {"source": self.source or None, "named": self.named, "verdict": r.verdict,
                "p_value": num(r.p_value), "decay_rate_per_s": num(r.decay_rate_per_s),
                "decay_rate_se_per_s": num(r.decay_rate_se_per_s),
                "identified": r.identified,
                "g": num(r.g) if r.identified else None,
                "tau_s": num(r.tau_s) if r.identified else None,
                "smallest_rate_per_s": num(self.smallest_rate_per_s),
                "n_presses": r.n_presses, "why": r.why}


def holds_finding(holds: Mapping[str, np.ndarray], columns: Mapping[str, np.ndarray], *,
                  labels: Mapping[str, Sequence] | None = None, source: str = ""
                  ) -> HoldsFinding:
    """Whether a table's holds name a relaxing gel (module docstring).

    Parameters
    ----------
    holds, columns, labels
        As for :func:`holds_relaxation`.
    source : str, optional
        The holds' file, for the sentence and the errors.

    Returns
    -------
    HoldsFinding

    Raises
    ------
    InputError
        Holds that cannot be fitted, naming `source` where given.
    """
    try:
        relax = holds_relaxation(holds, columns, labels)
    except InputError as exc:
        raise InputError(f"{source}: {exc}" if source else str(exc)) from None
    named = bool(relax.verdict in ("relaxing", "decay not identified")
                 and relax.decay_rate_per_s < 0)
    return HoldsFinding(relaxation=relax, source=source, named=named)
