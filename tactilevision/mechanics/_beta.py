"""The large-deformation factor beta(nu) and its inverse nu(beta).

eq. (2) of the paper: ``kappa_n = kappa (1 + beta w/h)``. Two tables: the
paper's fitted relation (7) at a/h = 0.8 (``'paper'``) and the project's
finite-strain FEM table (``'fem'``, :mod:`._fem_tables`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._checks import InputError
from ._fem_tables import fem_beta_relation

__all__ = ["PAPER_BETA_RELATION", "BetaRelation", "beta", "beta_from_nu", "beta_relation",
           "nu_from_beta"]


@dataclass(frozen=True)
class BetaRelation:
    """A logarithmic relation ``nu = slope ln(beta) + intercept`` with its range.

    Attributes
    ----------
    slope : float, dimensionless
    intercept : float, dimensionless
    a_over_h : float, dimensionless
        The aspect ratio the relation was built for.
    nu_min, nu_max : float, dimensionless
        The relation is used for ``nu_min <= nu < nu_max``.
    source : str
        Where the relation comes from.
    range_reason : str
        Why the range is what it is.
    """

    slope: float
    intercept: float
    a_over_h: float
    nu_min: float
    nu_max: float
    source: str
    range_reason: str

    @property
    def beta_min(self) -> float:
        """Smallest beta in range, ``exp((nu_min - intercept) / slope)``."""
        return math.exp((self.nu_min - self.intercept) / self.slope)

    @property
    def beta_max(self) -> float:
        """Supremum of beta in range (excluded), ``exp((nu_max - intercept) / slope)``."""
        return math.exp((self.nu_max - self.intercept) / self.slope)

    def dnu_dbeta(self, beta: float) -> float:
        """Slope of the relation, ``slope / beta``, 1 per unit beta."""
        return self.slope / beta

    def nu(self, beta: float | np.ndarray) -> float | np.ndarray:
        """``slope ln(beta) + intercept`` (no range check)."""
        return _out(self.slope * np.log(np.asarray(beta, np.float64)) + self.intercept)

    def beta(self, nu: float | np.ndarray) -> float | np.ndarray:
        """``exp((nu - intercept) / slope)`` (no range check)."""
        return _out(np.exp((np.asarray(nu, np.float64) - self.intercept) / self.slope))

    def range_text(self) -> str:
        """The range as one phrase, for messages."""
        return (f"beta in [{self.beta_min:.4f}, {self.beta_max:.4f}), "
                f"i.e. nu in [{self.nu_min:.2f}, {self.nu_max:.2f})")


#: The paper's relation (7) at a/h = 0.8, nu = 0.0813 ln(beta) + 0.4464
#: (R^2 = 0.9842), fitted to beta values derived from Zhang et al. 1997.
PAPER_BETA_RELATION = BetaRelation(
    slope=0.0813,
    intercept=0.4464,
    a_over_h=0.8,
    nu_min=0.30,
    nu_max=0.50,
    source=(
        "'In-situ Mechanical Calibration for Vision-based Tactile Sensors', eq. (7), "
        "nu = 0.0813 ln(beta) + 0.4464 at a/h = 0.8 (R^2 = 0.9842), from the "
        "finite-element data of Zhang, Zheng and Mak 1997, Med. Eng. Phys. 19:512-517"
    ),
    range_reason=(
        "nu < 0.30 is below the Hayes kappa table that E needs; nu >= 0.5 is "
        "not a compressible solid (the logarithm does not saturate there)"
    ),
)

def _relation(table: str, a_over_h: float | None = None, contact: str = "bonded",
              definition: str = "secant", w_over_h: tuple[float, ...] | None = None,
              weights: tuple[float, ...] | None = None):
    if table == "paper":
        return PAPER_BETA_RELATION
    if table == "fem":
        if a_over_h is None:
            raise InputError("table='fem' needs a_over_h (the FEM beta depends on it)")
        return fem_beta_relation(float(a_over_h), contact=contact, definition=definition,
                                 w_over_h=w_over_h, weights=weights)
    raise InputError(f"table must be 'paper' or 'fem', got {table!r}")


def _out(x: np.ndarray | float) -> float | np.ndarray:
    arr = np.asarray(x, dtype=np.float64)
    return float(arr) if arr.ndim == 0 else arr


def nu_from_beta(beta: float | np.ndarray, *, table: str = "paper",
                 a_over_h: float | None = None, contact: str = "bonded",
                 definition: str = "secant") -> float | np.ndarray:
    """Poisson's ratio from the large-deformation factor beta.

    Parameters
    ----------
    beta : float or (...) array_like, dimensionless
        Stiffening factor of eq. (2), the slope over the intercept of eq. (5).
    table : {'paper', 'fem'}, default 'paper'
        ``'paper'``: :data:`PAPER_BETA_RELATION`, eq. (7), built for
        a/h = 0.8. ``'fem'``: the project's FEM table ``models/beta_fem.npz``
        at `a_over_h` (:func:`~tactilevision.mechanics._fem_tables.fem_beta_relation`).
    a_over_h : float, optional
        Needed for ``table='fem'``.
    contact : str, default 'bonded'
        FEM table only: the punch condition ('bonded', the only one the
        finite-strain table holds).
    definition : {'secant', 'tangent'}, default 'secant'
        FEM table only: beta of eq. (5)'s straight line (the paper's
        procedure) or of the tangent stiffness.

    Returns
    -------
    nu : float or (...) float64 ndarray, dimensionless
        A float for a scalar `beta`.

    Raises
    ------
    InputError
        (a ``ValueError``) when a `beta` is not finite or outside the
        relation's range (see :attr:`BetaRelation.range_text`); it is never
        clamped.
    ValueError
        For an unknown `table`, or ``table='fem'`` without `a_over_h`.

    Notes
    -----
    ``nu = 0.0813 ln(beta) + 0.4464``, eq. (7) of [1]_, valid at a/h = 0.8.
    Range: nu in [0.30, 0.50), i.e. beta in [0.1652, 1.9334). The lower end is
    where the Hayes kappa table starts (E cannot be computed below it); the
    upper end is incompressibility, which the logarithm crosses without
    noticing. The range of nu over which the paper fitted (7) is not stated.

    References
    ----------
    .. [1] C. Zhao, J. Ren, H. Yu, D. Ma, "In-situ Mechanical Calibration for
       Vision-based Tactile Sensors", IEEE ICRA 2023,
       eq. (7).
    .. [2] M. Zhang, Y. P. Zheng, A. F. T. Mak, "Estimating the effective
       Young's modulus of soft tissues from indentation tests - nonlinear finite
       element analysis of effects of friction and large deformation",
       Med. Eng. Phys. 19:512-517, 1997.

    Examples
    --------
    >>> from tactilevision.mechanics import nu_from_beta
    >>> round(nu_from_beta(5.2662 / 3.4943), 4)
    0.4797
    """
    rel = _relation(table, a_over_h, contact, definition)
    b = np.asarray(beta, dtype=np.float64)
    bad = ~((b >= rel.beta_min) & (b < rel.beta_max))
    if np.any(bad):
        v = float(np.ravel(b)[np.argmax(np.ravel(bad))])
        raise InputError(
            f"beta = {v:g} is outside the range of the {table} beta table ({rel.range_text()})"
        )
    return rel.nu(b)


def beta_from_nu(nu: float | np.ndarray, *, table: str = "paper",
                 a_over_h: float | None = None, contact: str = "bonded",
                 definition: str = "secant") -> float | np.ndarray:
    """Large-deformation factor beta from Poisson's ratio; inverse of :func:`nu_from_beta`.

    Parameters
    ----------
    nu : float or (...) array_like, dimensionless
        Poisson's ratio, within [0.30, 0.50) for ``table='paper'``.
    table, a_over_h, contact, definition
        As in :func:`nu_from_beta`.

    Returns
    -------
    beta : float or (...) float64 ndarray, dimensionless
        ``exp((nu - 0.4464) / 0.0813)``, eq. (7) inverted. A float for a
        scalar `nu`.

    Raises
    ------
    InputError
        (a ``ValueError``) when a `nu` is not finite or outside the range.
    ValueError
        For an unknown `table`, or ``table='fem'`` without `a_over_h`.

    References
    ----------
    .. [1] C. Zhao, J. Ren, H. Yu, D. Ma, "In-situ Mechanical Calibration for
       Vision-based Tactile Sensors", IEEE ICRA 2023,
       eq. (7).
    """
    rel = _relation(table, a_over_h, contact, definition)
    n = np.asarray(nu, dtype=np.float64)
    lo = getattr(rel, "nu_forward_min", rel.nu_min)  # a FEM table: its whole nu range
    hi = getattr(rel, "nu_forward_max", rel.nu_max)
    bad = ~((n >= lo) & (n < hi))
    if np.any(bad):
        v = float(np.ravel(n)[np.argmax(np.ravel(bad))])
        raise InputError(
            f"nu = {v:g} is outside the range of the {table} beta table ("
            + (f"nu in [{lo:.3f}, {float(np.nextafter(hi, 0.0)):.3f}]"
               if hasattr(rel, "nu_forward_min") else rel.range_text()) + ")"
        )
    return rel.beta(n)


def beta_relation(table: str = "paper", *, a_over_h: float | None = None,
                  contact: str = "bonded", definition: str = "secant",
                  w_over_h: tuple[float, ...] | None = None,
                  weights: tuple[float, ...] | None = None):
    """The beta relation named `table` (at `a_over_h` for the FEM table).

    Parameters
    ----------
    table : {'paper', 'fem'}, default 'paper'
    a_over_h, contact, definition
        As in :func:`nu_from_beta`.
    w_over_h : tuple of float, optional
        FEM table only: read the secant beta at these press depths (see
        :func:`~tactilevision.mechanics._fem_tables.fem_beta_relation`).
    weights : tuple of float, optional
        With `w_over_h`: each press's weight in the line of eq. (5).

    Returns
    -------
    relation : BetaRelation or TabulatedBetaRelation
        Both have ``nu(beta)``, ``beta(nu)``, ``dnu_dbeta``, ``beta_min``,
        ``beta_max``, ``nu_min``, ``nu_max``, ``range_text()``, ``a_over_h``
        and ``source``.

    Raises
    ------
    InputError
        For a missing FEM table or `a_over_h` outside it.
    ValueError
        For an unknown `table`, or ``table='fem'`` without `a_over_h`.
    """
    return _relation(table, a_over_h, contact, definition, w_over_h, weights)


def beta(nu: float | np.ndarray, a_over_h: float | np.ndarray, *, source: str = "fem",
         contact: str = "bonded", definition: str = "secant") -> float | np.ndarray:
    """Large-deformation factor beta(nu, a/h) of eq. (2), vectorised.

    Parameters
    ----------
    nu : float or (...) array_like
        Poisson's ratio, within the source's range.
    a_over_h : float or (...) array_like
        Indenter radius over thickness; broadcast against `nu`. The paper's
        relation (7) was fitted at a/h = 0.8 and is accepted within 0.75 to
        0.85 only (the paper's 2.5 / 3.0 = 0.833 included).
    source : {'fem', 'paper'}, default 'fem'
        The project's finite-strain FEM table or the paper's relation (7).
    contact, definition
        FEM only, as in :func:`nu_from_beta`.

    Returns
    -------
    beta : float or (...) float64 ndarray

    Raises
    ------
    InputError
        (a ``ValueError``) outside the tabulated range of nu or a/h.
    ValueError
        For an unknown `source`.

    Notes
    -----
    ``'fem'``: the secant beta of ``models/beta_fem.npz`` (the straight line
    P/w = c (1 + beta w/h) fitted over w/h = 0.02 ... 0.2 of a finite-strain
    compressible Neo-Hookean sweep, bonded punch), PCHIP in a/h then nu,
    exact at the nodes; :func:`fit_indentation` reads it at the measured
    depths instead. ``'paper'``: relation (7), nu = 0.0813 ln(beta) + 0.4464.

    References
    ----------
    .. [1] C. Zhao, J. Ren, H. Yu, D. Ma, "In-situ Mechanical Calibration for
       Vision-based Tactile Sensors", IEEE ICRA 2023,
       eq. (2), (5), (7).

    Examples
    --------
    >>> from tactilevision.mechanics import beta
    >>> round(beta(0.45, 0.8, source="paper"), 4)
    1.0453
    >>> bool(beta(0.49, 1.2) > beta(0.45, 1.2) > beta(0.30, 1.2))
    True
    """
    if source not in ("fem", "paper"):
        raise InputError(f"source must be 'fem' or 'paper', got {source!r}")
    n, r = np.broadcast_arrays(np.asarray(nu, np.float64), np.asarray(a_over_h, np.float64))
    if source == "paper" and np.any(np.abs(r - PAPER_BETA_RELATION.a_over_h) > 0.05):
        bad = float(r[np.abs(r - PAPER_BETA_RELATION.a_over_h) > 0.05].ravel()[0])
        raise InputError("a_over_h must lie within 0.75 to 0.85 for the paper's relation (7), "
                         f"fitted at a/h = 0.8; got {bad:g}")
    out = np.empty(n.shape)
    for rv in np.unique(r):
        sel = r == rv
        out[sel] = beta_from_nu(n[sel], table=source, a_over_h=float(rv), contact=contact,
                                definition=definition)
    return float(out) if out.ndim == 0 else out
