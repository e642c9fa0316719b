"""The package's disk cache: its root folder and an atomic ``.npz`` writer.

The root is ``$TACTILEVISION_CACHE`` if that variable is set, else
``~/.cache/tactilevision``; each cache keeps its files in a folder of its own
(``fem/`` for the pad stiffness and the finite-strain sweeps, ``optics/`` for
MLP tabulations; docs/install.md, "The cache").
"""

from __future__ import annotations

import ast
import hashlib
import os
import tempfile
from pathlib import Path

import numpy as np

__all__ = ["ENV_VAR", "cache_root", "code_digest", "savez_atomic"]

#: Environment variable naming the package's cache root.
ENV_VAR = "TACTILEVISION_CACHE"


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
    return True
