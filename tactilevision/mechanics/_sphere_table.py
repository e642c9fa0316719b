"""Read the sphere table (``models/sphere_fem.npz``): P(w) and a(w) of a ball on the layer.

Built by ``tactilevision fem tables --what sphere``
(:func:`tactilevision.fem.build_sphere_table`); read here with numpy and
scipy alone, once per process. The table holds, for a rigid sphere of radius
R pressed to depth w into a layer of thickness h bonded to a rigid base,

    force_ratio   = P / P_Hertz,  P_Hertz = 4/3 E / (1 - nu^2) R^(1/2) w^(3/2)
    contact_ratio = a / sqrt(R w)

for two material models (``'linear'``, ``'neo_hookean'``) and two contact
conditions (``'frictionless'``, ``'tied'``). Both ratios tend to 1 as the
contact shrinks against the layer (Hertz's half-space), and grow smoothly
with sqrt(R w) / h: they are interpolated cubically in (ln R/h, nu,
sqrt(w/h)), with the Hertz limit (1 at w = 0) as the first node in w.
"""

from __future__ import annotations

import json
from functools import lru_cache

import numpy as np
from scipy.interpolate import RegularGridInterpolator

from .._assets import asset_dir
from .._checks import InputError

__all__ = ["SPHERE_TABLE", "hertz_force_n", "sphere_contact_ratio", "sphere_force_ratio",
           "sphere_reach", "sphere_table_meta", "table_reach"]

#: File name of the sphere table in the package's ``models`` folder.
SPHERE_TABLE = "sphere_fem.npz"


def sphere_reach(radius_over_h: float) -> float:
    """Deepest w/h the sphere table holds at R/h: min(0.5, 0.6 R/h)."""
    return float(min(0.5, 0.6 * float(radius_over_h)))


def hertz_force_n(depth_mm: np.ndarray, *, E_mpa: float, nu: float,
                  radius_mm: float) -> np.ndarray:
    """Hertz's force of a rigid sphere on an elastic half-space, N.

    P = 4/3 E / (1 - nu^2) R^(1/2) w^(3/2) (H. Hertz, J. reine angew. Math.
    92:156, 1882; K. L. Johnson, Contact Mechanics, 1985, eq. 4.23 with a
    rigid sphere); its contact radius is a = sqrt(R w).

    Parameters
    ----------
    depth_mm : (N,) array_like of float
        Depths w, mm, >= 0.
    E_mpa, nu : float
    radius_mm : float
        R, mm.

    Returns
    -------
    (N,) float64 ndarray, N
    """
    w = np.maximum(np.asarray(depth_mm, np.float64), 0.0)
    return 4.0 / 3.0 * E_mpa / (1.0 - nu**2) * np.sqrt(radius_mm) * w**1.5


@lru_cache(maxsize=1)
def _load() -> dict:
    path = asset_dir("models") / SPHERE_TABLE
    if not path.is_file():
        raise InputError(f"the sphere table {path} is missing: rebuild it with "
                         "'tactilevision fem tables --what sphere'")
    with np.load(path, allow_pickle=False) as z:
        data = {k: z[k] for k in z.files}
    data["meta"] = json.loads(data["meta"].tobytes().decode())
    data["path"] = str(path)
    return data


def sphere_table_meta() -> dict:
    """Provenance record of the stored sphere table (a copy).

    Raises
    ------
    InputError
        If the table is missing (naming the path and the command that builds it).
    """
    return dict(_load()["meta"])


def _index(data: dict, key: str, value: str) -> int:
    names = [str(v) for v in data[key]]
    if value not in names:
        raise InputError(f"{key[:-1]} must be one of {names}, got {value!r}")
    return names.index(value)


def _filled(values: np.ndarray, s: np.ndarray) -> np.ndarray:
    """NaN past an entry's reach filled by linear extrapolation in sqrt(w/h) from its last
    two nodes (the cubic interpolant needs a full grid; a query past the reach is refused
    before it gets here)."""
    out = values.copy()
    for idx in np.ndindex(out.shape[:-1]):
        row = out[idx]
        ok = np.isfinite(row)
        if ok.all():
            continue
        k = np.flatnonzero(ok)
        if k.size < 2:
            raise InputError("the sphere table has an entry with fewer than two depths")
        i, j = k[-2], k[-1]
        slope = (row[j] - row[i]) / (s[j] - s[i])
        row[~ok] = row[j] + slope * (s[~ok] - s[j])
    return out


@lru_cache(maxsize=8)
def _interpolant(kind: str, model: str, contact: str) -> RegularGridInterpolator:
    data = _load()
    m, c = _index(data, "models", model), _index(data, "contacts", contact)
    s = np.concatenate([[0.0], np.sqrt(data["w_over_h"].astype(np.float64))])
    vals = data["force_ratio" if kind == "force" else "contact_ratio"][m, c].astype(np.float64)
    vals = np.concatenate([np.ones((*vals.shape[:-1], 1)), vals], axis=-1)   # Hertz at w = 0
    vals = _filled(vals, s)
    grid = (np.log(data["radius_over_h"].astype(np.float64)), data["nu"].astype(np.float64), s)
    return RegularGridInterpolator(grid, vals, method="cubic", bounds_error=True)


@lru_cache(maxsize=8)
def _reached(model: str, contact: str) -> np.ndarray:
    """(A,) deepest w/h every nu of the table's sweeps reached at each R/h (a sweep whose
    Newton failed stops early; the table holds NaN past it)."""
    data = _load()
    m, c = _index(data, "models", model), _index(data, "contacts", contact)
    vals = data["force_ratio"][m, c]                      # (A, N, K)
    w = data["w_over_h"].astype(np.float64)
    last = np.where(np.isfinite(vals), w, 0.0).max(axis=-1)   # (A, N)
    return last.min(axis=-1)


def table_reach(radius_over_h: float, model: str = "neo_hookean",
                contact: str = "frictionless") -> float:
    """Deepest w/h the table answers at R/h: :func:`sphere_reach`, or less where a sweep of
    a neighbouring R/h stopped early (between two nodes both bound it; on a node, its own).

    Raises
    ------
    InputError
        If the table is missing, or for an unknown model or contact.
    """
    data = _load()
    rg = data["radius_over_h"].astype(np.float64)
    reached = _reached(model, contact)
    ratio = float(radius_over_h)
    node = np.flatnonzero(np.abs(rg / ratio - 1.0) <= 1e-9)
    if node.size:                      # on a node the interpolant is that node's values
        return float(min(sphere_reach(ratio), reached[node[0]]))
    i = int(np.clip(np.searchsorted(rg, ratio) - 1, 0, rg.size - 2))
    return float(min(sphere_reach(ratio), reached[i], reached[i + 1]))


def _lookup(kind: str, model: str, contact: str, radius_over_h: float, nu: float,
            w_over_h: np.ndarray) -> np.ndarray:
    data = _load()
    rg, ng = data["radius_over_h"], data["nu"]
    ratio = float(radius_over_h)
    if not float(rg[0]) * (1 - 1e-9) <= ratio <= float(rg[-1]) * (1 + 1e-9):
        raise InputError(f"R/h = {ratio:.4g} is outside the sphere table's {float(rg[0]):g} to "
                         f"{float(rg[-1]):g}")
    if not float(ng[0]) - 1e-9 <= float(nu) <= float(ng[-1]) + 1e-9:
        raise InputError(f"nu = {float(nu):.4g} is outside the sphere table's {float(ng[0]):g} "
                         f"to {float(ng[-1]):g}")
    x = np.asarray(w_over_h, np.float64)
    reach = table_reach(ratio, model, contact)
    if np.any(x < 0) or np.any(x > reach * (1 + 1e-9)):
        worst = float(x.max()) if np.any(x > reach) else float(x.min())
        raise InputError(f"w/h = {worst:.4g} is outside the sphere table's 0 to {reach:.4g} "
                         f"at R/h = {ratio:.4g} ({model}, {contact}; w/h <= min(0.5, "
                         "0.6 R/h), less where a sweep stopped early)")
    pts = np.column_stack([np.full(x.size, np.log(np.clip(ratio, rg[0], rg[-1]))),
                           np.full(x.size, np.clip(float(nu), ng[0], ng[-1])),
                           np.sqrt(np.minimum(x.ravel(), reach))])
    return _interpolant(kind, model, contact)(pts).reshape(x.shape)


def sphere_force_ratio(radius_over_h: float, nu: float, w_over_h: np.ndarray, *,
                       model: str = "neo_hookean", contact: str = "frictionless") -> np.ndarray:
    """P / P_Hertz of a rigid sphere on the bonded layer, from the FEM table.

    Parameters
    ----------
    radius_over_h : float
        R/h, within the table's 0.5 to 20.
    nu : float
        Within the table's 0.30 to 0.50.
    w_over_h : array_like of float
        Depths w/h, from 0 to :func:`sphere_reach`.
    model : {'neo_hookean', 'linear'}, default 'neo_hookean'
    contact : {'frictionless', 'tied'}, default 'frictionless'

    Returns
    -------
    float64 ndarray, shape of `w_over_h`

    Raises
    ------
    InputError
        For R/h, nu or a depth outside the table, an unknown model or
        contact, or a missing table.
    """
    return _lookup("force", model, contact, radius_over_h, nu, w_over_h)


def sphere_contact_ratio(radius_over_h: float, nu: float, w_over_h: np.ndarray, *,
                         model: str = "neo_hookean",
                         contact: str = "frictionless") -> np.ndarray:
    """a / sqrt(R w) of a rigid sphere on the bonded layer, from the FEM table.

    Parameters and errors as :func:`sphere_force_ratio`. The contact radius
    is the current one (where the gel leaves the ball) for ``'neo_hookean'``,
    the reference one for ``'linear'``.
    """
    return _lookup("contact", model, contact, radius_over_h, nu, w_over_h)
