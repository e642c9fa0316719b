"""Output folders of the sub-commands, checked before any work is done."""

from __future__ import annotations

import os
from pathlib import Path

from .._checks import InputError

__all__ = ["check_output_folder", "output_folder"]


def output_folder(path: Path, what: str = "output folder") -> Path:
    """Create `path` (and its parents) or say in one sentence why it cannot be.

    Parameters
    ----------
    path : Path
        The folder a command writes into.
    what : str
        How the message names it ('output folder', 'report folder').

    Returns
    -------
    path : Path

    Raises
    ------
    InputError
        If `path` is an existing file, cannot be created, or is not writable.
    """
    path = check_output_folder(path, what)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"cannot create the {what} {path}: {exc.strerror}") from None
    if not os.access(path, os.W_OK | os.X_OK):
        raise InputError(f"the {what} {path} is not writable")
    return path


def check_output_folder(path: Path, what: str = "output folder") -> Path:
    """Say at once, creating nothing, whether `path` could be made a writable folder.

    For commands that must not write anything before their input is read and
    checked: this is called first, :func:`output_folder` when writing starts.

    Raises
    ------
    InputError
        If `path`, or the nearest of its parents that exists, is a file, or
        that parent is not writable.
    """
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise InputError(f"the {what} {path} is an existing file, not a folder")
    parent = path
    while not parent.exists():
        if parent.parent == parent:
            break
        parent = parent.parent
    if parent.exists() and not parent.is_dir():
        raise InputError(f"cannot create the {what} {path}: {parent} is a file")
    if parent.exists() and not os.access(parent, os.W_OK | os.X_OK):
        raise InputError(f"cannot create the {what} {path}: {parent} is not writable")
    return path
