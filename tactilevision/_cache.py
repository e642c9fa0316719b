"""The package's disk cache: its root folder and an atomic ``.npz`` writer.

The root is ``$TACTILEVISION_CACHE`` if that variable is set, else
``~/.cache/tactilevision``; each cache keeps its files in a folder of its own
(``fem/`` for the pad stiffness and the finite-strain sweeps, ``optics/`` for
MLP tabulations; docs/install.md, "The cache").

The cache is bounded: after every write the least recently used files are removed
until the cache (its ``tests/`` folder, the suite's own renders, left out) holds at most
``$TACTILEVISION_CACHE_MB`` MiB (default :data:`DEFAULT_MAX_MB`); a read marks a file
used (:func:`touch`). :func:`cache_info` and :func:`clear_cache` back
``tactilevision cache info|clear``.
"""

from __future__ import annotations

import ast
import hashlib
import math
import os
import tempfile
import warnings
from pathlib import Path

import numpy as np

from ._checks import InputWarning

__all__ = ["DEFAULT_MAX_MB", "ENV_VAR", "MAX_ENV_VAR", "UNBOUNDED", "cache_info",
           "cache_limit_bytes", "cache_root", "clear_cache", "code_digest", "prune_cache",
           "savez_atomic", "touch"]

#: Environment variable naming the package's cache root.
ENV_VAR = "TACTILEVISION_CACHE"
#: Environment variable bounding the cache, MiB.
MAX_ENV_VAR = "TACTILEVISION_CACHE_MB"
#: The cache's default bound, MiB: the FEM sweeps of a busy week and some 20 optics tables
#: (25 MiB each at 640 x 480).
DEFAULT_MAX_MB = 1024
#: Folders of the cache root left out of the bound (the test suite's own renders).
UNBOUNDED = ("tests",)


def cache_root() -> Path:
    """``$TACTILEVISION_CACHE``, else ``~/.cache/tactilevision``."""
    root = os.environ.get(ENV_VAR)
    return Path(root).expanduser() if root else Path.home() / ".cache" / "tactilevision"


def _strip_docstrings(tree: ast.AST) -> ast.AST:
    """`tree` without the docstrings of its module, classes and functions."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) \
                    and isinstance(body[0].value.value, str):
                node.body = body[1:] or [ast.Pass()]
    return tree


def code_digest(*paths: Path) -> str:
    """SHA-256 of the code of Python source files, docstrings and comments left out.

    A cache keyed on it misses when a statement changes, not when the text that
    explains it does (the syntax tree, ``ast.dump`` without positions, is hashed).

    Parameters
    ----------
    *paths : Path
        Source files, hashed in the order given (each one's name enters the hash).

    Returns
    -------
    str
        64 hex digits.
    """
    h = hashlib.sha256()
    for path in paths:
        tree = _strip_docstrings(ast.parse(Path(path).read_text(encoding="utf-8")))
        h.update(Path(path).name.encode())
        h.update(ast.dump(tree, include_attributes=False).encode())
    return h.hexdigest()


def savez_atomic(path: Path, **arrays: np.ndarray) -> bool:
    """Write ``np.savez(path, **arrays)`` through a temporary file in the same folder,
    then ``os.replace`` it into place (readers never see a partial file), readable by
    other users. Returns False, leaving nothing behind, when the folder cannot be
    created or written: a cache only saves time."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=path.name + ".", suffix=".tmp", dir=path.parent)
    except OSError:
        return False
    try:
        with os.fdopen(fd, "wb") as f:
            np.savez(f, **arrays)
        os.chmod(tmp, 0o644)  # mkstemp's 0600 would hide a shared cache from other users
        os.replace(tmp, path)
    except OSError:
        Path(tmp).unlink(missing_ok=True)
        return False
    prune_cache(keep=path)
    return True


def cache_limit_bytes() -> int:
    """The cache's bound: ``$TACTILEVISION_CACHE_MB`` MiB, else :data:`DEFAULT_MAX_MB`
    (a value that is not a positive number is warned, InputWarning, and the default
    used)."""
    raw = os.environ.get(MAX_ENV_VAR)
    if raw is None:
        return DEFAULT_MAX_MB * 2**20
    try:
        mb = float(raw)
    except ValueError:
        mb = math.nan
    if not (math.isfinite(mb) and mb > 0):
        warnings.warn(f"${MAX_ENV_VAR} = {raw!r} is not a positive number of MiB: the "
                      f"cache's bound is the default {DEFAULT_MAX_MB} MiB",
                      InputWarning, stacklevel=2)
        return DEFAULT_MAX_MB * 2**20
    return int(mb * 2**20)


def touch(path: Path) -> None:
    """Mark a cache file used (its modification time: the key, not the time, names its
    content), so that eviction takes the least recently used first."""
    try:
        os.utime(path)
    except OSError:
        pass


def _entries(root: Path) -> list[tuple[float, int, Path]]:
    """(last use, size, path) of every bounded file under `root`."""
    out = []
    for p in root.rglob("*"):
        rel = p.relative_to(root).parts
        if not rel or rel[0] in UNBOUNDED:
            continue
        try:
            st = p.stat()
        except OSError:
            continue
        if p.is_file():
            out.append((st.st_mtime, st.st_size, p))
    return out


def prune_cache(*, root: Path | None = None, limit: int | None = None,
                keep: Path | None = None) -> int:
    """Remove the least recently used files until the bounded part of the cache holds at
    most `limit` bytes (default :func:`cache_limit_bytes`), `keep` last.

    Returns
    -------
    removed : int
        Bytes removed.
    """
    root = cache_root() if root is None else Path(root)
    if not root.is_dir():
        return 0
    limit = cache_limit_bytes() if limit is None else int(limit)
    entries = sorted(_entries(root), key=lambda e: (e[2] == keep, e[0]))
    total = sum(e[1] for e in entries)
    removed = 0
    for _, size, path in entries:
        if total <= limit:
            break
        try:
            path.unlink()
        except OSError:
            continue
        total -= size
        removed += size
    return removed


def cache_info(root: Path | None = None) -> dict[str, tuple[int, int]]:
    """Files and bytes in each folder of the cache.

    Returns
    -------
    dict of str to (int, int)
        Folder name (``'fem'``, ``'optics'``, ``'tests'``, ...) to (files, bytes).
    """
    root = cache_root() if root is None else Path(root)
    out: dict[str, tuple[int, int]] = {}
    if not root.is_dir():
        return out
    for p in root.rglob("*"):
        if p.is_file():
            folder = p.relative_to(root).parts[0] if len(p.relative_to(root).parts) > 1 \
                else "."
            n, b = out.get(folder, (0, 0))
            out[folder] = (n + 1, b + p.stat().st_size)
    return dict(sorted(out.items()))


def clear_cache(folder: str | None = None, root: Path | None = None) -> tuple[int, int]:
    """Delete the cache's files (always safe: they are computed again when needed).

    Parameters
    ----------
    folder : str, optional
        One folder of the cache (``'fem'``, ``'optics'``, ``'tests'``); default all.
    root : Path, optional

    Returns
    -------
    (files, bytes) removed
    """
    root = cache_root() if root is None else Path(root)
    base = root if folder is None else root / folder
    files = bytes_ = 0
    if not base.is_dir():
        return 0, 0
    for p in sorted(base.rglob("*"), reverse=True):
        try:
            if p.is_file() or p.is_symlink():
                size = p.stat().st_size
                p.unlink()
                files, bytes_ = files + 1, bytes_ + size
            elif p.is_dir():
                p.rmdir()
        except OSError:
            continue
    return files, bytes_
