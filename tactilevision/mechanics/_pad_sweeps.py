"""Shipped FEM sweeps of a ball on a pad of finite size (``models/sphere_pad_sweeps.npz``).

A ball on a pad whose lateral size matters (``[sensor] gel_radius_mm``), on a domed top
or with Coulomb friction is one FEM sweep per (nu, law, contact): minutes each at
finite strain, then kept in the disk cache. The sweeps the bundled samples need (the
FEATS gel, ``sample_frames/feats``) ship in this table, so a first ``fit`` or
``diagnose`` of them reads numbers instead of solving; any other geometry is computed
as before. The table holds each sweep's force and contact ratios against w/h, keyed by
its physical inputs alone (R/h, nu, pad radius / h, law, contact, first depth,
friction, dome radius / h), and is rebuilt by ``tactilevision fem tables --what pad``
(:data:`SHIPPED_PAD_SWEEPS` says which).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Iterable
from functools import lru_cache

import numpy as np

from .._assets import asset_dir

__all__ = ["PAD_SWEEPS_FILE", "SHIPPED_PAD_SWEEPS", "build_pad_sweeps", "pad_sweep_key",
           "shipped_pad_sweep"]

#: The shipped table's file name in ``models/``.
PAD_SWEEPS_FILE = "sphere_pad_sweeps.npz"

#: The sweeps shipped: the FEATS gel of ``sample_frames/feats`` (R 7.5 mm, h 4 mm, pad
#: equal-area radius 12.92 mm: R/h 1.875, pad / h 3.23) at nu 0.5, each law and contact
#: that ``fit`` and ``diagnose`` read, from the first depth the presses need (0.04 h).
SHIPPED_PAD_SWEEPS: tuple[tuple, ...] = tuple(
    (1.875, 0.5, 3.23, law, contact, 0.04, None, None)
    for law in ("linear", "neo_hookean") for contact in ("tied", "frictionless"))


def pad_sweep_key(radius_over_h: float, nu: float, pad_over_h: float, law: str, contact: str,
                  start: float, friction: float | None = None,
                  dome_over_h: float | None = None) -> str:
    """A sweep's inputs as the table's key: JSON of the values rounded to 9 digits."""
    def r(v: float | None) -> float | None:
        return None if v is None else round(float(v), 9)

    return json.dumps([r(radius_over_h), r(nu), r(pad_over_h), str(law), str(contact),
                       r(start), r(friction), r(dome_over_h)])


@lru_cache(maxsize=1)
def _table() -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    path = asset_dir("models") / PAD_SWEEPS_FILE
    if not path.is_file():
        return {}
    with np.load(path, allow_pickle=False) as z:
        keys = json.loads(z["keys"].tobytes().decode())
        return {k: (z["w_over_h"][i], z["force_ratio"][i], z["contact_ratio"][i])
                for i, k in enumerate(keys)}


def shipped_pad_sweep(*key) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """The shipped sweep of these inputs (:func:`pad_sweep_key`'s arguments), or None.

    Returns
    -------
    (w_over_h, force_ratio, contact_ratio) : three (K,) float64 ndarrays, or None
        The sweep's depths over h, P / P_Hertz and a / sqrt(R w) at each (NaN entries
        dropped).
    """
    hit = _table().get(pad_sweep_key(*key))
    if hit is None:
        return None
    w, f, a = hit
    ok = np.isfinite(w) & np.isfinite(f) & np.isfinite(a)
    return w[ok], f[ok], a[ok]


def build_pad_sweeps(keys: Iterable[tuple], compute: Callable, *,
                     progress: Callable[[str], None] | None = None) -> dict:
    """The table of the sweeps `keys`, each computed by `compute(*key)`.

    Parameters
    ----------
    keys : iterable of tuple
        :func:`pad_sweep_key`'s arguments, one tuple per sweep.
    compute : callable
        ``compute(*key)`` -> an object with ``w_over_h``, ``hertz_ratio`` and
        ``contact_radius`` (over h) arrays: :func:`~tactilevision.mechanics.
        pad_sweep_result`.
    progress : callable, optional
        Called with each key's text before it is computed.

    Returns
    -------
    table : dict
        ``keys`` (uint8 JSON of the key texts), ``w_over_h``, ``force_ratio``,
        ``contact_ratio`` (S, K) float64 (NaN-padded), and ``meta``.
    """
    keys = list(keys)
    rows = []
    for key in keys:
        if progress is not None:
            progress(pad_sweep_key(*key))
        res = compute(*key)
        w = np.asarray(res.w_over_h, np.float64)
        rows.append((w, np.asarray(res.hertz_ratio, np.float64),
                     np.asarray(res.contact_radius, np.float64) / np.sqrt(key[0] * w)))
    k = max((r[0].size for r in rows), default=0)
    out = {name: np.full((len(rows), k), math.nan) for name in
           ("w_over_h", "force_ratio", "contact_ratio")}
    for i, row in enumerate(rows):
        for name, v in zip(("w_over_h", "force_ratio", "contact_ratio"), row, strict=True):
            out[name][i, :v.size] = v
    out["keys"] = np.frombuffer(json.dumps([pad_sweep_key(*key) for key in keys]).encode(),
                                np.uint8)
    out["meta"] = {"what": "a rigid sphere on a bonded pad of finite radius: force_ratio = "
                           "P / P_Hertz and contact_ratio = a / sqrt(R w) against w/h, one "
                           "row per sweep (key: R/h, nu, pad/h, law, contact, first w/h, "
                           "friction, dome/h)",
                   "solver": "tactilevision.mechanics.pad_sweep_result "
                             "(tactilevision.fem.sphere_indentation)"}
    return out
