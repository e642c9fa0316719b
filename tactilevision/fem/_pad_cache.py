"""Disk cache of the condensed pad stiffness (see :mod:`._pad`).

One uncompressed ``.npz`` per key, ``pad_<key>.npz``, holding the row-packed
upper triangles of K and K_normal (symmetric: half the bytes), the node
coordinates and a JSON record (format version, key, inputs, build time,
library versions). Written to a temporary file in the same folder, then
``os.replace``-d into place, so readers never see a partial file. On reading,
the zip CRC of every member, the format version, the key, the inputs, the
array sizes, finiteness and a positive diagonal are checked; any failure is
reported as :class:`CacheError` and the caller rebuilds.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import platform
import tempfile
from pathlib import Path

import numpy as np
import scipy
import skfem

from .._cache import ENV_VAR, cache_root, code_digest, prune_cache, touch

__all__ = ["ENV_VAR", "FORMAT_VERSION", "PAD_SOURCES", "CacheError", "cache_directory",
           "cache_key", "cache_path", "pack_upper", "read_entry", "unpack_upper", "write_entry"]

#: Bump when the stored arrays or their meaning change: old files then miss.
FORMAT_VERSION = 1

#: The modules whose code decides a pad's stiffness: the mesh and its condensation, and the
#: normal Schur complement (their syntax trees enter the key, docstrings and comments not).
PAD_SOURCES = ("_pad.py", "_pad_mesh.py")


@functools.lru_cache(maxsize=1)
def _source_digest() -> str:
    """SHA-256 of :data:`PAD_SOURCES`' code: a cached pad misses when either changes."""
    here = Path(__file__).resolve().parent
    return code_digest(*(here / name for name in PAD_SOURCES))


class CacheError(Exception):
    """A cache file that cannot be trusted (unreadable, corrupt or mismatched)."""


def cache_directory(cache_dir: str | os.PathLike | None) -> Path:
    """Folder of the cache files: `cache_dir`, else ``$TACTILEVISION_CACHE/fem``,
    else ``~/.cache/tactilevision/fem``."""
    if cache_dir is not None:
        return Path(cache_dir).expanduser()
    return cache_root() / "fem"


def cache_key(inputs: dict) -> str:
    """SHA-256 hex digest of the inputs (JSON, sorted keys), :data:`FORMAT_VERSION` and the
    code of :data:`PAD_SOURCES` (a change to the mesh or the condensation misses the
    matrices the old code built)."""
    text = json.dumps({"format": FORMAT_VERSION, "code": _source_digest(), **inputs},
                      sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def cache_path(directory: Path, key: str) -> Path:
    """The file of `key` in `directory`."""
    return directory / f"pad_{key}.npz"


def pack_upper(a: np.ndarray) -> np.ndarray:
    """Rows of the upper triangle of a square matrix, concatenated: (n (n + 1) / 2,)."""
    return np.concatenate([a[i, i:] for i in range(a.shape[0])])


def unpack_upper(packed: np.ndarray, n: int) -> np.ndarray:
    """The symmetric (n, n) matrix of :func:`pack_upper`'s output."""
    if packed.shape != (n * (n + 1) // 2,):
        raise CacheError(f"packed triangle of {packed.size} values, expected {n * (n + 1) // 2}")
    upper = np.zeros((n, n), dtype=np.float64)
    start = 0
    for i in range(n):
        upper[i, i:] = packed[start:start + n - i]
        start += n - i
    full = upper + upper.T
    full[np.diag_indices(n)] *= 0.5
    return full


def _versions() -> dict:
    return {"scikit-fem": skfem.__version__, "scipy": scipy.__version__,
            "numpy": np.__version__, "python": platform.python_version()}


def write_entry(path: Path, key: str, inputs: dict, k: np.ndarray, k_normal: np.ndarray,
                x_mm: np.ndarray, y_mm: np.ndarray, build_s: float) -> int:
    """Write one entry atomically; returns the file size in bytes.

    Raises
    ------
    OSError
        If the folder cannot be created or written.
    """
    path.parent.mkdir(parents=True, exist_ok=True)
    meta = {"format": FORMAT_VERSION, "key": key, "inputs": inputs, "build_s": float(build_s),
            "versions": _versions()}
    fd, tmp = tempfile.mkstemp(prefix=path.name + ".", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            np.savez(f, meta=np.array(json.dumps(meta, sort_keys=True)),
                     K_upper=pack_upper(k), K_normal_upper=pack_upper(k_normal),
                     x_mm=x_mm, y_mm=y_mm)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, 0o644)  # mkstemp's 0600 would hide a shared cache from other users
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    if path.parent.parent == cache_root():
        prune_cache(keep=path)           # the cache's bound (tactilevision._cache)
    return path.stat().st_size


def read_entry(path: Path, key: str, inputs: dict, x_mm: np.ndarray,
               y_mm: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, int]:
    """Read and check one entry: (K, K_normal, build_s, file size).

    Raises
    ------
    FileNotFoundError
        If there is no file (a plain miss).
    CacheError
        If the file is unreadable, corrupt or was written for other inputs.
    """
    n = len(x_mm) * len(y_mm)
    if not path.is_file():
        raise FileNotFoundError(path)
    try:
        size = path.stat().st_size
        with np.load(path, allow_pickle=False) as data:
            arrays = {name: data[name] for name in
                      ("meta", "K_upper", "K_normal_upper", "x_mm", "y_mm")}
        touch(path)                      # used: evicted last
        meta = json.loads(str(arrays["meta"]))
    except Exception as exc:  # zip CRC, truncation, missing member, bad JSON, ...
        raise CacheError(f"unreadable ({type(exc).__name__}: {exc})") from exc
    if not isinstance(meta, dict) or meta.get("format") != FORMAT_VERSION:
        raise CacheError(f"format {meta.get('format') if isinstance(meta, dict) else None!r},"
                         f" expected {FORMAT_VERSION}")
    if meta.get("key") != key or meta.get("inputs") != json.loads(json.dumps(inputs)):
        raise CacheError("written for other inputs")
    if not (np.array_equal(arrays["x_mm"], x_mm) and np.array_equal(arrays["y_mm"], y_mm)):
        raise CacheError("node coordinates differ")
    for name in ("K_upper", "K_normal_upper"):
        if arrays[name].dtype != np.float64 or not np.all(np.isfinite(arrays[name])):
            raise CacheError(f"{name} is not finite float64")
    k = unpack_upper(arrays["K_upper"], 3 * n)
    k_normal = unpack_upper(arrays["K_normal_upper"], n)
    if not (np.all(np.diag(k) > 0) and np.all(np.diag(k_normal) > 0)):
        raise CacheError("non-positive diagonal")
    build_s = meta.get("build_s")
    if not isinstance(build_s, int | float):
        raise CacheError("no build time")
    return k, k_normal, float(build_s), size
