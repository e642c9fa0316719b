"""The layer factor kappa(nu, a/h) of a flat punch on a bonded elastic layer.

One table, with its source, and one interpolation rule. Every value of kappa
the package uses comes from :func:`kappa`.
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import PchipInterpolator

from .._checks import InputError
from ._fem_tables import fem_kappa_table
from ._kappa_table import KappaTable

__all__ = ["HAYES_1972", "KappaTable", "kappa"]


#: Hayes et al. (1972): kappa of a rigid, frictionless, plane-ended cylindrical
#: punch of radius a on an elastic layer of thickness h bonded to a rigid half
#: space (small deformation), as reproduced in the project's ``method.md``.
HAYES_1972 = KappaTable(
    a_over_h=np.array([0.2, 0.4, 0.6, 0.8, 1.0, 1.5, 2.0]),
    nu=np.array([0.30, 0.35, 0.40, 0.45, 0.50]),
    values=np.array([
        # nu = 0.30  0.35   0.40   0.45   0.50
        [1.207, 1.218, 1.232, 1.252, 1.281],  # a/h = 0.2
        [1.472, 1.502, 1.542, 1.599, 1.683],  # 0.4
        [1.784, 1.839, 1.917, 2.031, 2.211],  # 0.6
        [2.124, 2.211, 2.337, 2.532, 2.855],  # 0.8
        [2.480, 2.603, 2.789, 3.085, 3.609],  # 1.0
        [3.400, 3.629, 3.994, 4.645, 6.033],  # 1.5
        [4.336, 4.679, 5.249, 6.332, 8.980],  # 2.0
    ]),
    source=(
        "Hayes, Keer, Herrmann and Mockros 1972, 'A mathematical analysis for "
        "indentation tests of articular cartilage', J. Biomech. 5:541-551, table of "
        "kappa for the plane-ended cylindrical indenter (bonded layer, frictionless "
        "punch, small deformation), values as reproduced in method.md"
    ),
    doi="10.1016/0021-9290(72)90010-3",
)

def _at_nodes(x: np.ndarray, xq: np.ndarray, y: np.ndarray, yq: np.ndarray) -> np.ndarray:
    """Replace interpolated ``yq`` by ``y[i]`` where ``xq`` equals the node ``x[i]``.

    A cubic evaluated at the right end of its interval can be one or two ulps
    off the node value; the table entries must come back exactly.
    """
    i = np.clip(np.searchsorted(x, xq), 0, x.size - 1)
    hit = x[i] == xq
    return np.where(hit, y[i], yq)


def _check_range(x: np.ndarray, name: str, lo: float, hi: float, source: str = "") -> None:
    bad = ~((x >= lo) & (x <= hi))
    if np.any(bad):
        v = float(np.ravel(x)[np.argmax(np.ravel(bad))])
        which = "FEM" if source.startswith("tactilevision FEM") else "Hayes 1972"
        raise InputError(
            f"{name} = {v:g} is outside the {which} kappa table range [{lo:g}, {hi:g}]"
        )


def kappa(nu: float | np.ndarray, a_over_h: float | np.ndarray, *,
          source: str = "hayes", contact: str = "frictionless") -> float | np.ndarray:
    """Layer factor kappa(nu, a/h) of a flat punch on a bonded layer.

    Parameters
    ----------
    nu : float or (...) array_like, dimensionless
        Poisson's ratio, within [0.30, 0.50].
    a_over_h : float or (...) array_like, dimensionless
        Indenter radius a over layer thickness h, within [0.2, 2.0].
        Broadcast against `nu`.
    source : {'hayes', 'fem'}, default 'hayes'
        ``'hayes'``: :data:`HAYES_1972`. ``'fem'``: the project's own FEM
        table ``models/kappa_fem.npz`` (nu 0.30 to 0.499, a/h 0.2 to 2.0;
        ``tactilevision fem tables`` rebuilds it).
    contact : {'frictionless', 'bonded'}, default 'frictionless'
        Punch condition; Hayes is frictionless only.

    Returns
    -------
    kappa : float or (...) float64 ndarray, dimensionless
        A float when both inputs are scalars. Equal to the table entry at
        every table node.

    Raises
    ------
    InputError
        (a ``ValueError``) when `nu` or `a_over_h` is outside the table or
        not finite (the message names the argument and the range), or the
        FEM table file is missing.
    ValueError
        For an unknown `source`, or a bonded punch with ``source='hayes'``.

    Notes
    -----
    kappa enters eq. (1) and (4) of the in-situ calibration paper [1]_:
    ``c = 2 a E kappa(nu, a/h) / (1 - nu^2)``. The table is from [2]_.

    Interpolation rule: piecewise cubic Hermite, shape preserving (PCHIP,
    Fritsch-Carlson slopes as in ``scipy.interpolate.PchipInterpolator``),
    first along nu within each a/h row of the table, then along a/h through
    the seven row values. It passes through every table entry, keeps the
    monotonicity of each row and column, and follows the steep rise of kappa
    towards nu = 0.5 better than bilinear interpolation, which overestimates
    kappa between nodes there (the rows are convex in nu). At a = 2.5 mm,
    h = 3 mm it gives 2.182, 2.620, 2.890, 2.972 at nu = 0.30, 0.45, 0.49,
    0.50 against 2.185, 2.624, 2.888, 2.976 from the project's prototype FEM
    (``method.md``); bilinear gives 2.909 at nu = 0.49.

    References
    ----------
    .. [1] C. Zhao, J. Ren, H. Yu, D. Ma, "In-situ Mechanical Calibration for
       Vision-based Tactile Sensors", IEEE ICRA 2023,
       eq. (1)-(5).
    .. [2] W. C. Hayes, L. M. Keer, G. Herrmann, L. F. Mockros, "A mathematical
       analysis for indentation tests of articular cartilage", J. Biomech.
       5:541-551, 1972. doi:10.1016/0021-9290(72)90010-3

    Examples
    --------
    >>> from tactilevision.mechanics import kappa
    >>> kappa(0.45, 0.8)
    2.532
    """
    table = _table(source, contact)
    n = np.asarray(nu, dtype=np.float64)
    r = np.asarray(a_over_h, dtype=np.float64)
    out = _interpolate(table, n, r)
    if out.ndim == 0:
        return float(out)
    return out


def _table(source: str, contact: str) -> KappaTable:
    if source == "hayes":
        if contact != "frictionless":
            raise InputError("the Hayes 1972 table is for a frictionless punch only")
        return HAYES_1972
    if source == "fem":
        return fem_kappa_table(contact)
    raise InputError(f"source must be 'hayes' or 'fem', got {source!r}")


def _interpolate(t: KappaTable, n: np.ndarray, r: np.ndarray) -> np.ndarray:
    """PCHIP along nu within each a/h row, then along a/h (see :func:`kappa`)."""
    _check_range(n, "nu", float(t.nu[0]), float(t.nu[-1]), t.source)
    _check_range(r, "a_over_h", float(t.a_over_h[0]), float(t.a_over_h[-1]), t.source)
    rows = _rows(t)
    n, r = np.broadcast_arrays(n, r)
    out = np.empty(n.shape)
    flat_n, flat_r, flat_out = n.ravel(), r.ravel(), out.reshape(-1)
    for nv in np.unique(flat_n):  # one a/h interpolant per distinct nu
        sel = flat_n == nv
        if nv in t.nu:  # a table column, exactly
            col = t.values[:, int(np.searchsorted(t.nu, nv))]
        else:
            col = np.array([float(row(nv)) for row in rows])  # (M,) kappa at this nu
        rq = flat_r[sel]
        flat_out[sel] = _at_nodes(t.a_over_h, rq, col, PchipInterpolator(t.a_over_h, col)(rq))
    return out


_ROW_CACHE: dict[int, tuple] = {}


def _rows(t: KappaTable) -> tuple:
    key = id(t)
    if key not in _ROW_CACHE:
        _ROW_CACHE[key] = tuple(PchipInterpolator(t.nu, row) for row in t.values)
    return _ROW_CACHE[key]


def _dkappa_dnu(nu: float, a_over_h: float, *, step: float = 1e-6, source: str = "hayes",
                contact: str = "frictionless") -> float:
    """Derivative of :func:`kappa` along nu by a central difference.

    One-sided at the ends of the nu range. Used by the delta-method intervals
    of :func:`~tactilevision.mechanics.fit_indentation`.
    """
    t = _table(source, contact)
    lo = max(nu - step, float(t.nu[0]))
    hi = min(nu + step, float(t.nu[-1]))
    k = [kappa(v, a_over_h, source=source, contact=contact) for v in (hi, lo)]
    return (k[0] - k[1]) / (hi - lo)
