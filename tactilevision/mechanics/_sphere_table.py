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

Below the table's smallest R/h (0.5: a thick gel, down to Hertz's half-space)
the ratios are the closed forms carried on from that seam at the same w/R
(:func:`_below_seam`): Hertz's half-space made a sphere's (Sneddon 1965) times
Dimitriadis' bonded-layer correction (2002) in chi = sqrt(R w)/h, scaled by
what the table adds to that closed form at the seam (exactly continuous
there). The reach, w/h <= min(0.5, 0.6 R/h), is one rule at every R/h
(w <= 0.6 R below R/h 5/6); the finite-strain law below the seam stops at
w/R = :data:`NEO_HOOKEAN_REACH_BELOW_SEAM`.
"""

from __future__ import annotations

import json
from functools import lru_cache

import numpy as np
from scipy.interpolate import RegularGridInterpolator

from .._assets import asset_dir
from .._checks import InputError
from ._sphere_closed import dimitriadis_force_ratio, sneddon_sphere_ratios

__all__ = ["NEO_HOOKEAN_REACH_BELOW_SEAM", "SPHERE_TABLE", "hertz_force_n",
           "sphere_contact_ratio", "sphere_force_ratio", "sphere_reach", "sphere_table_meta",
           "table_reach"]

#: File name of the sphere table in the package's ``models`` folder.
SPHERE_TABLE = "sphere_fem.npz"
#: Deepest w/R the finite-strain law is read to below the table's smallest R/h. Its
#: departure from the small-strain law is carried from the seam at the same w/R; carried
#: from R/h = 1 to the table's own R/h = 0.5 that transfer is within 1.3 % up to w/R = 0.08
#: (nu 0.3 to 0.5, both contacts) and 2 to 21 % past w/R = 0.12 (the finite strain and the
#: layer do not separate), so it is not trusted further. The small-strain law keeps the
#: table's w/R <= 0.6.
NEO_HOOKEAN_REACH_BELOW_SEAM = 0.08


def sphere_reach(radius_over_h: float) -> float:
    """Deepest w/h a ball is read to at R/h: min(0.5, 0.6 R/h), for every R/h > 0.

    The one rule of the table (built to it), of the closed forms below its
    smallest R/h (w <= 0.6 R), of a ball on a finite pad (FEM sweeps to it)
    and of the inverse :meth:`~tactilevision.mechanics.Sphere.depth_from_contact_radius`;
    :func:`table_reach` lowers it where a sweep stopped early or the law is
    the finite-strain one below the seam.
    """
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

    Below the table's smallest R/h (the seam), the seam's reach in w/R, and
    for ``'neo_hookean'`` at most :data:`NEO_HOOKEAN_REACH_BELOW_SEAM` in w/R.

    Raises
    ------
    InputError
        If the table is missing, or for an unknown model or contact.
    """
    data = _load()
    rg = data["radius_over_h"].astype(np.float64)
    reached = _reached(model, contact)
    ratio = float(radius_over_h)
    if ratio < rg[0] * (1 - 1e-9):     # below the seam: the seam's reach in w/R
        w_over_r = min(sphere_reach(rg[0]), float(reached[0])) / rg[0]
        if model == "neo_hookean":
            w_over_r = min(w_over_r, NEO_HOOKEAN_REACH_BELOW_SEAM)
        return float(min(sphere_reach(ratio), w_over_r * ratio))
    node = np.flatnonzero(np.abs(rg / ratio - 1.0) <= 1e-9)
    if node.size:                      # on a node the interpolant is that node's values
        return float(min(sphere_reach(ratio), reached[node[0]]))
    i = int(np.clip(np.searchsorted(rg, ratio) - 1, 0, rg.size - 2))
    return float(min(sphere_reach(ratio), reached[i], reached[i + 1]))


def _closed(radius_over_h: float, nu: float, w_over_h: np.ndarray) -> np.ndarray:
    """Hertz's sphere (Sneddon) times Dimitriadis' bonded layer: P / P_Hertz at (R/h, w/h)."""
    chi = np.sqrt(radius_over_h * w_over_h)
    return dimitriadis_force_ratio(chi, nu, "bonded") * sneddon_sphere_ratios(
        w_over_h / radius_over_h)[0]


def _below_seam(kind: str, model: str, contact: str, radius_over_h: float, nu: float,
                w_over_h: np.ndarray, seam: float) -> np.ndarray:
    """P / P_Hertz or a / sqrt(R w) below the table's smallest R/h (`seam`), at the same w/R.

    Force: the closed form :func:`_closed` (Sneddon's sphere on the half-space times
    Dimitriadis' bonded-layer series, frictionless, small strain) times two factors read
    at the seam at the same w/R, so continuous there:

    - the small-strain frictionless table's ratio to the closed form (the series'
      truncation and its coupling with the sphere's shape: 0.25 % up to w/R 0.26, 2.8 %
      at 0.6, nu 0.3 to 0.5), scaled by (R/h) / seam, as chi at a given w/R: it vanishes
      in the Hertz limit, where Sneddon's sphere is exact. Carried whole, it put the
      force 1.8 % under direct FEM solves at R/h 0.1 and w/R 0.6;
    - the model's and contact's ratio to that small-strain frictionless table (finite
      strain, a tied contact's stiffening), carried whole: both grow with the strain,
      w/R, and stay on a half-space.

    Contact radius: Sneddon's a / sqrt(R w) on the half-space, with the table's excess over
    it at the seam (the layer's bulge, 2 to 14 %) scaled by (R/h) / seam, as chi at a given
    w/R (no closed form for a on a layer; the excess grows about as chi).
    """
    x = np.asarray(w_over_h, np.float64)
    s = x / radius_over_h                                  # w/R
    x0 = s * seam                                          # the seam's depth at that w/R
    look = _interpolant(kind, model, contact)
    data = _load()
    ng = data["nu"]
    pts = np.column_stack([np.full(x.size, np.log(seam)),
                           np.full(x.size, np.clip(float(nu), ng[0], ng[-1])),
                           np.sqrt(x0.ravel())])
    table = look(pts).reshape(x.shape)
    if kind == "force":
        small = table
        if (model, contact) != ("linear", "frictionless"):
            small = _interpolant(kind, "linear", "frictionless")(pts).reshape(x.shape)
        layer = small / _closed(seam, nu, x0)
        return (_closed(radius_over_h, nu, x) * (1.0 + (layer - 1.0) * radius_over_h / seam)
                * table / small)
    sned = sneddon_sphere_ratios(s)[1]
    return sned * (1.0 + (table / sned - 1.0) * radius_over_h / seam)


def _lookup(kind: str, model: str, contact: str, radius_over_h: float, nu: float,
            w_over_h: np.ndarray) -> np.ndarray:
    data = _load()
    rg, ng = data["radius_over_h"], data["nu"]
    ratio = float(radius_over_h)
    if not (np.isfinite(ratio) and 0.0 < ratio <= float(rg[-1]) * (1 + 1e-9)):
        raise InputError(f"R/h = {ratio:.4g} is past the sphere table's largest, "
                         f"{float(rg[-1]):g} ({SPHERE_TABLE}; below its smallest, "
                         f"{float(rg[0]):g}, the closed forms of Hertz and Dimitriadis "
                         "answer): a ball this large on a gel this thin is not modelled")
    if not float(ng[0]) - 1e-9 <= float(nu) <= float(ng[-1]) + 1e-9:
        raise InputError(f"nu = {float(nu):.4g} is outside the sphere table's {float(ng[0]):g} "
                         f"to {float(ng[-1]):g} ({SPHERE_TABLE})")
    x = np.asarray(w_over_h, np.float64)
    reach = table_reach(ratio, model, contact)
    if np.any(x < 0) or np.any(x > reach * (1 + 1e-9)):
        worst = float(x.max()) if np.any(x > reach) else float(x.min())
        below = ratio < float(rg[0]) * (1 - 1e-9)
        why = ((f"below the table's R/h {float(rg[0]):g}: w <= 0.6 R"
                + (f", w/R <= {NEO_HOOKEAN_REACH_BELOW_SEAM:g} for the finite-strain law"
                   if model == "neo_hookean" else "")) if below else
               "w/h <= min(0.5, 0.6 R/h), less where a sweep stopped early")
        raise InputError(f"w/h = {worst:.4g} is outside the sphere's 0 to {reach:.4g} "
                         f"at R/h = {ratio:.4g} ({model}, {contact}; {why})")
    if ratio < float(rg[0]) * (1 - 1e-9):
        return _below_seam(kind, model, contact, ratio, float(nu),
                           np.minimum(x, reach), float(rg[0]))
    pts = np.column_stack([np.full(x.size, np.log(np.clip(ratio, rg[0], rg[-1]))),
                           np.full(x.size, np.clip(float(nu), ng[0], ng[-1])),
                           np.sqrt(np.minimum(x.ravel(), reach))])
    return _interpolant(kind, model, contact)(pts).reshape(x.shape)


def sphere_force_ratio(radius_over_h: float, nu: float, w_over_h: np.ndarray, *,
                       model: str = "neo_hookean", contact: str = "frictionless") -> np.ndarray:
    """P / P_Hertz of a rigid sphere on the bonded layer, from the FEM table.

    Below the table's smallest R/h (0.5) down to the half-space, the closed
    forms carried on from that seam (module docstring, :func:`_below_seam`).

    Parameters
    ----------
    radius_over_h : float
        R/h, > 0 and at most the table's largest, 20.
    nu : float
        Within the table's 0.30 to 0.50.
    w_over_h : array_like of float
        Depths w/h, from 0 to :func:`table_reach`.
    model : {'neo_hookean', 'linear'}, default 'neo_hookean'
    contact : {'frictionless', 'tied'}, default 'frictionless'

    Returns
    -------
    float64 ndarray, shape of `w_over_h`

    Raises
    ------
    InputError
        For R/h past 20 (or not positive), nu outside the table, a depth past
        :func:`table_reach`, an unknown model or contact, or a missing table;
        the message names the table's file for R/h and nu.
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
