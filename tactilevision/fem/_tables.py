"""Build the kappa and beta tables of ``models/`` from our own FEM.

``tactilevision fem tables`` runs :func:`build_kappa_table` (small strain,
:class:`LinearIndentationSolver`) and :func:`build_beta_table` (finite strain,
:func:`neo_hookean_indentation`) on a grid of nu and a/h for a frictionless
and a bonded punch, and writes each as an ``.npz`` with a JSON provenance
record (command, mesh, solver versions, date, wall time) inside it.
:mod:`tactilevision.mechanics` reads them with numpy alone.
"""

from __future__ import annotations

import datetime as _dt
import io
import json
import platform
import time
import warnings
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import scipy
import skfem
from tqdm.auto import tqdm

from .._version import __version__
from ._finite import neo_hookean_indentation
from ._linear import LinearIndentationSolver

__all__ = ["A_OVER_H_GRID", "BETA_CONTACTS", "CONTACTS", "KAPPA_NU_GRID", "NU_GRID",
           "build_beta_table", "build_kappa_table", "write_table"]

#: Poisson's ratios of the tables (dense towards 0.5, where kappa and beta rise fastest).
NU_GRID = np.array([0.30, 0.33, 0.36, 0.39, 0.42, 0.44, 0.45, 0.46, 0.47, 0.48, 0.485, 0.49,
                    0.495, 0.499])
#: Poisson's ratios of the kappa table: :data:`NU_GRID` and the incompressible 0.5,
#: which the mixed small-strain solver reaches exactly (Hayes' last column).
KAPPA_NU_GRID = np.append(NU_GRID, 0.5)
#: a/h of the tables (the Hayes range).
A_OVER_H_GRID = np.array([0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.2, 1.4, 1.6, 1.8, 2.0])
#: Punch conditions, in table order.
CONTACTS = ("frictionless", "bonded")
#: Coarsest edge mesh the beta sweeps fall back to (see ``_beta_sweep``).
_MIN_EDGE_REFINEMENTS = 4
#: Punch conditions of the finite-strain beta table: bonded only, because a
#: frictionless sharp-edged punch folds the edge elements before w/h = 0.2
#: (see :func:`~tactilevision.fem.neo_hookean_indentation`, Limits).
BETA_CONTACTS = ("bonded",)


def _versions() -> dict:
    return {"tactilevision": __version__, "scikit-fem": skfem.__version__,
            "scipy": scipy.__version__, "numpy": np.__version__,
            "python": platform.python_version()}


def build_kappa_table(*, nu: np.ndarray = KAPPA_NU_GRID, a_over_h: np.ndarray = A_OVER_H_GRID,
                      contacts: tuple[str, ...] = CONTACTS, pad_radius_over_h: float = 20.0,
                      cell: float = 0.125, edge_refinements: int = 10, jobs: int = 1,
                      progress: bool = True) -> dict:
    """kappa(nu, a/h) of the small-strain problem on a grid.

    Parameters
    ----------
    nu : (N,) float ndarray, default :data:`KAPPA_NU_GRID`
    a_over_h : (A,) float ndarray, default :data:`A_OVER_H_GRID`
    contacts : tuple of str, default ('frictionless', 'bonded')
    pad_radius_over_h : float, default 20.0
        R_pad / h: 20 is the infinite layer to < 0.001% (pad study of
        ``benchmarks/bench_fem_linear.py``).
    cell, edge_refinements : float, int
        Mesh of :func:`~tactilevision.fem.indentation_mesh`; the defaults are
        within 0.01% of a 500k-dof mesh at a/h = 0.8.
    jobs : int, default 1
        Worker processes, one (contact, a/h) column each (the same table as
        with one).
    progress : bool, default True

    Returns
    -------
    table : dict
        ``nu`` (N,), ``a_over_h`` (A,), ``contacts`` (C,) str, ``kappa``
        (C, A, N) float64 and ``meta`` (dict: mesh, dofs, versions, seconds).
    """

    nu = np.asarray(nu, np.float64)
    a_over_h = np.asarray(a_over_h, np.float64)
    kap = np.empty((len(contacts), a_over_h.size, nu.size))
    dofs = np.empty((len(contacts), a_over_h.size), np.int64)
    t0 = time.perf_counter()
    index = [(c, i) for c in range(len(contacts)) for i in range(a_over_h.size)]
    tasks = [{"a_over_h": float(a_over_h[i]), "contact": contacts[c], "nu": nu,
              "pad_radius_over_h": pad_radius_over_h, "cell": cell,
              "edge_refinements": edge_refinements} for c, i in index]
    pool = ProcessPoolExecutor(max_workers=int(jobs)) if jobs > 1 else None
    results = pool.map(_kappa_column, tasks) if pool is not None else map(_kappa_column, tasks)
    try:
        for (c, i), (column, n_dofs) in tqdm(zip(index, results, strict=True),
                                             total=len(index), desc="kappa table", unit="a/h",
                                             disable=not progress):
            kap[c, i] = column
            dofs[c, i] = n_dofs
    finally:
        if pool is not None:
            pool.shutdown()
    meta = {"quantity": "kappa = P (1 - nu^2) / (2 a E w), small strain, linear elastic",
            "solver": "tactilevision.fem.LinearIndentationSolver (Taylor-Hood P2/P1, "
                      "axisymmetric, bonded base, punch by prescribed u_z)",
            "mesh": {"cell": cell, "edge_refinements": edge_refinements,
                     "pad_radius_over_h": pad_radius_over_h,
                     "dofs_min": int(dofs.min()), "dofs_max": int(dofs.max())},
            "jobs": int(jobs), "seconds": round(time.perf_counter() - t0, 1)}
    return {"nu": nu, "a_over_h": a_over_h, "contacts": np.array(contacts), "kappa": kap,
            "meta": meta}


def _kappa_column(kwargs: dict) -> tuple[np.ndarray, int]:
    """kappa over nu at one (contact, a/h), and the mesh's dofs, for :func:`build_kappa_table`
    (a module-level function: picklable)."""
    kwargs = dict(kwargs)
    nu = kwargs.pop("nu")
    a_over_h = kwargs.pop("a_over_h")
    solver = LinearIndentationSolver(a_over_h, **kwargs)
    return solver.kappa(nu), solver.n_dofs


def _beta_sweep(kwargs: dict):
    """One sweep for :func:`build_beta_table` (a module-level function: picklable).

    When Newton fails before the last depth the sweep is repeated with one
    edge refinement fewer, down to 4: the bonded punch edge is a stress
    singularity, and at small nu (compressible) the finest edge cells fold
    first. Returns the result and the refinements it used.
    """
    kwargs = dict(kwargs)
    while True:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)   # recorded as complete=False
            res = neo_hookean_indentation(**kwargs)
        if res.complete or kwargs["edge_refinements"] <= _MIN_EDGE_REFINEMENTS:
            return res, kwargs["edge_refinements"]
        kwargs["edge_refinements"] -= 1


def build_beta_table(*, nu: np.ndarray = NU_GRID, a_over_h: np.ndarray = A_OVER_H_GRID,
                     contacts: tuple[str, ...] = BETA_CONTACTS, w_over_h_max: float = 0.2,
                     steps: int = 10, pad_radius_over_h: float = 20.0, cell: float = 0.25,
                     edge_refinements: int = 7, jobs: int = 1, progress: bool = True) -> dict:
    """kappa_n(nu, a/h, w/h) and beta(nu, a/h) of the finite-strain problem on a grid.

    Parameters
    ----------
    nu, a_over_h, pad_radius_over_h
        As :func:`build_kappa_table`.
    contacts : tuple of str, default ('bonded',)
        :data:`BETA_CONTACTS`. A frictionless sharp-edged punch is accepted
        but its sweeps rarely reach w/h = 0.2 (see
        :func:`~tactilevision.fem.neo_hookean_indentation`, Limits); they are
        stored with ``complete = False`` and NaN beyond the depth reached.
    w_over_h_max : float, default 0.2
        Deepest press (the paper keeps w/h within 20%).
    steps : int, default 10
        Depth increments; kappa_n is stored at ``w/h = (1..steps) w_max / steps``.
    cell, edge_refinements : float, int
        Mesh (coarser than the kappa table: a sweep costs many solves). At
        a/h = 0.8, nu = 0.49 (bonded) the secant beta is 0.7863, 0.7706,
        0.7629 with 4, 6, 8 edge refinements at cell 0.25 and 0.7601 at
        cell 0.125 with 8 (34k dofs): the default is within 1% of the finest.
        A sweep that fails is repeated with one edge refinement fewer, down to
        4 (``edge_refinements`` of the result says which mesh each entry used;
        at a/h = 1.0, nu = 0.3, 6 and 5 refinements give 0.6836 and 0.6798).
    jobs : int, default 1
        Worker processes (one sweep each at a time).
    progress : bool, default True

    Returns
    -------
    table : dict
        ``nu`` (N,), ``a_over_h`` (A,), ``contacts`` (C,), ``w_over_h`` (K,),
        ``kappa_n`` (C, A, N, K) (NaN where a sweep stopped early),
        ``beta_secant``, ``beta_tangent``, ``kappa0``, ``linearity_r2``
        (C, A, N), ``complete`` (C, A, N) bool, ``edge_refinements`` (C, A, N)
        int (the mesh each sweep used), and ``meta``.
    """

    nu = np.asarray(nu, np.float64)
    a_over_h = np.asarray(a_over_h, np.float64)
    shape = (len(contacts), a_over_h.size, nu.size)
    w_grid = w_over_h_max * np.arange(1, steps + 1) / steps
    kn = np.full((*shape, steps), np.nan)
    out = {k: np.full(shape, np.nan) for k in ("beta_secant", "beta_tangent", "kappa0",
                                                 "linearity_r2")}
    complete = np.zeros(shape, bool)
    t0 = time.perf_counter()
    index = [(c, i, j) for c in range(shape[0]) for i in range(shape[1])
             for j in range(shape[2])]
    tasks = [{"a_over_h": float(a_over_h[i]), "nu": float(nu[j]), "contact": contacts[c],
              "w_over_h_max": w_over_h_max, "steps": steps,
              "pad_radius_over_h": pad_radius_over_h, "cell": cell,
              "edge_refinements": edge_refinements} for c, i, j in index]
    if jobs > 1:
        pool = ProcessPoolExecutor(max_workers=int(jobs))
        results = pool.map(_beta_sweep, tasks)
    else:
        pool, results = None, map(_beta_sweep, tasks)
    seconds = []
    refinements = np.zeros(shape, np.int64)
    for (c, i, j), (res, er) in tqdm(zip(index, results, strict=True), total=len(index),
                               desc="beta table", unit="sweep", disable=not progress):
        seconds.append(res.seconds)
        refinements[c, i, j] = er
        kn[c, i, j] = np.interp(w_grid, res.w_over_h, res.kappa_n, right=np.nan)
        for k in out:
            out[k][c, i, j] = getattr(res, k)
        complete[c, i, j] = res.complete
    if pool is not None:
        pool.shutdown()
    meta = {"quantity": "kappa_n = P (1 - nu^2) / (2 a E w) at finite strain; beta from "
                        "P/w = c (1 + beta w/h) fitted over the depths (secant, eq. 5) and "
                        "from the tangent stiffness",
            "material": "compressible Neo-Hookean, Abaqus form, C10 = E / (4 (1 + nu)), "
                        "D1 = 6 (1 - 2 nu) / E",
            "solver": "tactilevision.fem.neo_hookean_indentation (total Lagrangian, mixed "
                      "u-p Taylor-Hood, Newton)",
            "mesh": {"cell": cell, "edge_refinements": edge_refinements,
                     "pad_radius_over_h": pad_radius_over_h},
            "w_over_h_max": w_over_h_max, "steps": steps, "jobs": int(jobs),
            "seconds_per_sweep": {"min": round(min(seconds), 2), "median":
                                  round(float(np.median(seconds)), 2),
                                  "max": round(max(seconds), 2)},
            "sweeps_incomplete": int((~complete).sum()),
            "sweeps_on_coarser_edge_mesh": int((refinements < edge_refinements).sum()),
            "seconds": round(time.perf_counter() - t0, 1)}
    return {"nu": nu, "a_over_h": a_over_h, "contacts": np.array(contacts), "w_over_h": w_grid,
            "kappa_n": kn, **out, "complete": complete, "edge_refinements": refinements,
            "meta": meta}


def write_table(path: str | Path, table: dict, *, command: str) -> Path:
    """Write a table as ``.npz`` with its provenance (JSON under the key ``meta``).

    Parameters
    ----------
    path : str or Path
        Destination ``.npz``.
    table : dict
        From :func:`build_kappa_table` or :func:`build_beta_table`.
    command : str
        The command line that built it (recorded).

    Returns
    -------
    path : Path
    """
    meta = dict(table["meta"])
    meta.update(command=command, versions=_versions(),
                created=_dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"))
    arrays = {k: v for k, v in table.items() if k != "meta"}
    arrays["meta"] = np.frombuffer(json.dumps(meta).encode(), np.uint8)
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(buf.getvalue())
    return path
