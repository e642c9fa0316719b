"""Build the sphere table of ``models/`` (``models/sphere_fem.npz``) from our own FEM.

``tactilevision fem tables --what sphere`` runs :func:`sphere_indentation`
on a grid of R/h, nu and w/h for both material models (linear, Neo-Hookean)
and both contact conditions (frictionless, tied), and stores, per entry, the
force over Hertz's and the contact radius over sqrt(R w), both smooth and near
1 for shallow presses on a thick layer. :mod:`tactilevision.mechanics` reads it
with numpy and scipy alone.
"""

from __future__ import annotations

import time
import warnings
from concurrent.futures import ProcessPoolExecutor

import numpy as np
from tqdm.auto import tqdm

from ._sphere import SPHERE_CONTACTS, SPHERE_MODELS, sphere_indentation

__all__ = ["SPHERE_NU_GRID", "SPHERE_RADIUS_GRID", "SPHERE_W_GRID", "build_sphere_table",
           "sphere_reach"]

#: Sphere radius over layer thickness, R/h, of the table.
SPHERE_RADIUS_GRID = np.array([0.5, 1.0, 2.0, 4.0, 8.0, 20.0])
#: Poisson's ratios of the table.
SPHERE_NU_GRID = np.array([0.30, 0.40, 0.45, 0.48, 0.50])
#: Depths w/h of the table (an entry holds those within :func:`sphere_reach`).
SPHERE_W_GRID = np.array([0.01, 0.02, 0.04, 0.06, 0.08, 0.10, 0.13, 0.16, 0.20, 0.25, 0.30,
                          0.35, 0.40, 0.45, 0.50])


def sphere_reach(radius_over_h: float | np.ndarray) -> float | np.ndarray:
    """Deepest w/h of the sphere table at R/h: min(0.5, 0.6 R/h).

    Past 0.6 R the ball is sunk beyond 60 % of its radius and its contact
    circle near its equator (a geometric 0.92 R): no ball press goes there.
    """
    return np.minimum(0.5, 0.6 * np.asarray(radius_over_h, np.float64))


def _sweep(kwargs: dict):
    """One sweep (module level: picklable), warnings recorded as ``complete=False``."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return sphere_indentation(**kwargs)


def build_sphere_table(*, radius_over_h: np.ndarray = SPHERE_RADIUS_GRID,
                       nu: np.ndarray = SPHERE_NU_GRID, w_over_h: np.ndarray = SPHERE_W_GRID,
                       models: tuple[str, ...] = SPHERE_MODELS,
                       contacts: tuple[str, ...] = SPHERE_CONTACTS,
                       pad_radius_over_h: float = 20.0, surface_cell_factor: float = 1.0,
                       jobs: int = 1, progress: bool = True) -> dict:
    """P(w) / P_Hertz and a(w) / sqrt(R w) of a rigid sphere on the bonded layer, on a grid.

    Parameters
    ----------
    radius_over_h : (A,) float ndarray, default :data:`SPHERE_RADIUS_GRID`
    nu : (N,) float ndarray, default :data:`SPHERE_NU_GRID`
    w_over_h : (K,) float ndarray, default :data:`SPHERE_W_GRID`
        Each R/h is swept to :func:`sphere_reach`; deeper entries are NaN.
    models : tuple of str, default ('linear', 'neo_hookean')
    contacts : tuple of str, default ('frictionless', 'tied')
    pad_radius_over_h : float, default 20.0
        The infinite layer (a pad of finite size: :func:`sphere_indentation`).
    surface_cell_factor : float, default 1.0
        Times the default surface cell (1/12 of the first depth's Hertz
        contact radius): 0.5 for a mesh-convergence check.
    jobs : int, default 1
        Worker processes, one sweep each at a time.
    progress : bool, default True

    Returns
    -------
    table : dict
        ``radius_over_h`` (A,), ``nu`` (N,), ``w_over_h`` (K,), ``models`` (M,),
        ``contacts`` (C,), ``force_ratio`` and ``contact_ratio`` (M, C, A, N, K)
        float64 (NaN past an entry's reach or where its sweep stopped),
        ``complete`` (M, C, A, N) bool, ``n_dofs`` (M, C, A, N) int, and
        ``meta``.
    """
    R = np.asarray(radius_over_h, np.float64)
    nu = np.asarray(nu, np.float64)
    wg = np.asarray(w_over_h, np.float64)
    shape = (len(models), len(contacts), R.size, nu.size)
    force = np.full((*shape, wg.size), np.nan)
    radius = np.full_like(force, np.nan)
    complete = np.zeros(shape, bool)
    dofs = np.zeros(shape, np.int64)
    index = [(m, c, i, j) for m in range(shape[0]) for c in range(shape[1])
             for i in range(shape[2]) for j in range(shape[3])]
    tasks = []
    for m, c, i, j in index:
        w = wg[wg <= sphere_reach(R[i]) + 1e-12]
        tasks.append({"radius_over_h": float(R[i]), "nu": float(nu[j]), "w_over_h": w,
                      "model": models[m], "contact": contacts[c],
                      "pad_radius_over_h": pad_radius_over_h,
                      "surface_cell": surface_cell_factor * min(
                          0.0625, float(np.sqrt(R[i] * w[0])) / 12.0)})
    t0 = time.perf_counter()
    pool = ProcessPoolExecutor(max_workers=int(jobs)) if jobs > 1 else None
    results = pool.map(_sweep, tasks) if pool is not None else map(_sweep, tasks)
    seconds = []
    try:
        for (m, c, i, j), res in tqdm(zip(index, results, strict=True), total=len(index),
                                      desc="sphere table", unit="sweep",
                                      disable=not progress):
            k = np.searchsorted(wg, res.w_over_h - 1e-12)
            force[m, c, i, j, k] = res.hertz_ratio
            radius[m, c, i, j, k] = res.contact_radius / np.sqrt(R[i] * res.w_over_h)
            complete[m, c, i, j] = res.complete
            dofs[m, c, i, j] = res.n_dofs
            seconds.append(res.seconds)
    finally:
        if pool is not None:
            pool.shutdown()
    meta = {"quantity": "force_ratio = P / P_Hertz, P_Hertz = 4/3 E / (1 - nu^2) R^(1/2) "
                        "w^(3/2); contact_ratio = a / sqrt(R w); rigid sphere of radius R on a "
                        "layer of thickness h bonded to a rigid base",
            "models": {"linear": "small strain, isotropic linear elastic (mixed u-p), the "
                                 "sphere's exact gap at the reference radii",
                       "neo_hookean": "finite strain, compressible Neo-Hookean (Abaqus form, "
                                      "C10 = E / (4 (1 + nu)), D1 = 6 (1 - 2 nu) / E), total "
                                      "Lagrangian, Newton"},
            "contacts": {"frictionless": "zero shear between sphere and gel",
                         "tied": "no slip: a node that meets the sphere moves with it"},
            "solver": "tactilevision.fem.sphere_indentation (Taylor-Hood P2/P1, axisymmetric)",
            "reach": "w/h <= min(0.5, 0.6 R/h)",
            "mesh": {"pad_radius_over_h": pad_radius_over_h,
                     "surface_cell": "1/12 of sqrt(R w_first) (at most h/16), times "
                                     f"{surface_cell_factor:g}",
                     "dofs_min": int(dofs.min()), "dofs_max": int(dofs.max())},
            "jobs": int(jobs),
            "seconds_per_sweep": {"min": round(min(seconds), 1),
                                  "median": round(float(np.median(seconds)), 1),
                                  "max": round(max(seconds), 1)},
            "sweeps_incomplete": int((~complete).sum()),
            "seconds": round(time.perf_counter() - t0, 1)}
    return {"radius_over_h": R, "nu": nu, "w_over_h": wg, "models": np.array(models),
            "contacts": np.array(contacts), "force_ratio": force, "contact_ratio": radius,
            "complete": complete, "n_dofs": dofs, "meta": meta}
