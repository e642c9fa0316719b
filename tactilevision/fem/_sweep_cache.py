"""Disk cache of finite-strain depth sweeps (see :func:`._finite.neo_hookean_indentation`).

One ``.npz`` per key, ``sweep_<key>.npz``, in the folder of the pad cache
(:func:`._pad_cache.cache_directory`). The key is the SHA-256 of the sweep's
resolved inputs, :data:`FORMAT_VERSION`, the library versions (numpy, scipy,
scikit-fem, Python) and a digest of the code of the solver's own modules
(:data:`SOURCES`; docstrings and comments left out): a change to the solver, the
mesh or the material forms misses every old entry, so a cached sweep is always the
one this code computes. Only complete sweeps are stored. Written to a temporary file, then
``os.replace``-d into place; on reading, the format, the key, the inputs and
the finiteness of every array are checked, and any failure is a plain miss
(the sweep is run again and the entry rewritten).
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import os
import platform
from pathlib import Path

import numpy as np
import scipy
import skfem

from .._cache import code_digest, savez_atomic, touch
from ._pad_cache import cache_directory

__all__ = ["FORMAT_VERSION", "SOURCES", "read_sweep", "sweep_key", "write_sweep"]

#: Bump when the stored fields or their meaning change: old files then miss.
FORMAT_VERSION = 1

#: The modules whose code decides a sweep's numbers (their syntax trees, docstrings and
#: comments left out, enter the key: :func:`tactilevision._cache.code_digest`).
SOURCES = ("_finite.py", "_finite_solver.py", "_mesh.py", "_neohookean_forms.py")


@functools.lru_cache(maxsize=1)
def _source_digest() -> str:
    here = Path(__file__).resolve().parent
    return code_digest(*(here / name for name in SOURCES))


@functools.lru_cache(maxsize=1)
def _versions() -> dict:
    return {"scikit-fem": skfem.__version__, "scipy": scipy.__version__,
            "numpy": np.__version__, "python": platform.python_version()}


def sweep_key(inputs: dict) -> str:
    """SHA-256 hex digest of the inputs, the format, the library versions and the source."""
    text = json.dumps({"format": FORMAT_VERSION, "inputs": inputs, "versions": _versions(),
                       "source": _source_digest()}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def _path(cache_dir: str | os.PathLike | None, key: str) -> Path:
    return cache_directory(cache_dir) / f"sweep_{key}.npz"


def read_sweep(inputs: dict, cls: type, cache_dir: str | os.PathLike | None = None):
    """The cached sweep of `inputs` as a `cls` instance, or None (a miss or a bad file)."""
    key = sweep_key(inputs)
    path = _path(cache_dir, key)
    if not path.is_file():
        return None
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {name: data[name] for name in data.files}
        meta = json.loads(str(arrays.pop("meta")))
        if meta.get("format") != FORMAT_VERSION or meta.get("key") != key or \
                meta.get("inputs") != json.loads(json.dumps(inputs)):
            return None
        values = dict(meta["scalars"])
        for name, a in arrays.items():
            if a.dtype.kind == "f" and not np.all(np.isfinite(a) | np.isnan(a)):
                return None
            values[name] = a
        touch(path)                      # used: evicted last
        return cls(**values, from_cache=True)
    except Exception:  # truncated zip, missing member, bad JSON, changed fields: a miss
        return None


def write_sweep(inputs: dict, result, cache_dir: str | os.PathLike | None = None) -> None:
    """Store one complete sweep atomically; an unwritable folder is silently skipped
    (the cache only saves time)."""
    key = sweep_key(inputs)
    path = _path(cache_dir, key)
    scalars, arrays = {}, {}
    for f in dataclasses.fields(result):
        if f.name == "from_cache":
            continue
        v = getattr(result, f.name)
        if isinstance(v, np.ndarray):
            arrays[f.name] = v
        elif v is not None:
            scalars[f.name] = v.item() if isinstance(v, np.generic) else v
    meta = {"format": FORMAT_VERSION, "key": key, "inputs": inputs, "scalars": scalars,
            "versions": _versions()}
    savez_atomic(path, meta=np.array(json.dumps(meta, sort_keys=True)), **arrays)
