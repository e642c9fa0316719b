"""Output folders of the library and its commands: checked before any work is done, written whole or
not at all (:class:`StagedOutput`), never replacing files tactilevision did not write
without ``--overwrite``."""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from pathlib import Path

from .._checks import InputError

__all__ = ["MANIFEST", "STAGING", "StagedOutput", "check_output_file", "check_output_folder",
           "check_overwrite", "output_folder", "record_output", "remove_staging",
           "write_output_file"]


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


#: The file in an output folder that lists what tactilevision wrote there (so that a rerun
#: may replace those, and nothing else, without --overwrite).
MANIFEST = ".tactilevision-outputs.json"


def _ours(out: Path) -> set[str]:

    try:
        return set(json.loads((out / MANIFEST).read_text(encoding="utf-8")).get("files", []))
    except (OSError, ValueError, AttributeError):
        return set()


def check_overwrite(out: Path, names, *, overwrite: bool = False) -> None:
    """Refuse, before any work, to replace files in `out` that tactilevision did not write.

    Parameters
    ----------
    out : Path
        The output folder.
    names : iterable of str
        Files (relative to `out`) the command will write.
    overwrite : bool, default False
        ``--overwrite``: replace them whatever wrote them.

    Raises
    ------
    InputError
        Naming the files in the way, when `out` holds some of `names` that
        its manifest (:data:`MANIFEST`) does not list and `overwrite` is off.
    """
    out = Path(out)
    if overwrite or not out.is_dir():
        return
    ours = _ours(out)
    blocking = sorted(n for n in set(names) if (out / n).exists() and n not in ours)
    if blocking:
        shown = ", ".join(blocking[:6]) + (f" and {len(blocking) - 6} more"
                                            if len(blocking) > 6 else "")
        raise InputError(f"{out} already holds {shown}, not written by tactilevision: give "
                         "--overwrite to replace them, or another output folder")


def check_output_file(path: str | Path, *, overwrite: bool = False) -> Path:
    """Refuse, before any work, to replace a single file tactilevision did not write.

    The one rule for every output (a folder's, :func:`check_overwrite`, and a single
    file's): a file in the way is replaced only when the folder's manifest
    (:data:`MANIFEST`) lists it (a tactilevision output of an earlier run) or with
    `overwrite`.

    Parameters
    ----------
    path : str or Path
        The file a command will write.
    overwrite : bool, default False
        ``--overwrite``: replace it whatever wrote it.

    Returns
    -------
    Path

    Raises
    ------
    InputError
        Naming the file, when it is a folder, its folder cannot be created, or it
        exists, was not written by tactilevision and `overwrite` is off.
    """
    path = Path(path)
    if path.is_dir():
        raise InputError(f"{path} is a folder, not a file")
    parent = path.parent
    while not parent.exists() and parent.parent != parent:
        parent = parent.parent
    if not parent.is_dir():
        raise InputError(f"cannot write {path}: {parent} is a file")
    if path.exists() and not overwrite and path.name not in _ours(path.parent):
        raise InputError(f"{path} already exists and was not written by tactilevision: give "
                         "--overwrite to replace it, or another file name")
    return path


def write_output_file(path: str | Path, data: str | bytes, *,
                      overwrite: bool = False) -> Path:
    """Write one output file whole (a temporary file moved into place) under the rule
    of :func:`check_output_file`, and list it in its folder's manifest so that a rerun
    may replace it.

    Parameters
    ----------
    path : str or Path
    data : str or bytes
        UTF-8 text, or bytes.
    overwrite : bool, default False

    Returns
    -------
    Path

    Raises
    ------
    InputError
        As :func:`check_output_file`, or when the file cannot be written (nothing of
        the failed write is left behind, the old file stays whole).
    """
    path = check_output_file(path, overwrite=overwrite)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tactilevision-tmp")
    try:
        if isinstance(data, bytes):
            tmp.write_bytes(data)
        else:
            tmp.write_text(data, encoding="utf-8")
        os.replace(tmp, path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise InputError(f"cannot write {path}: {exc.strerror}") from None
    record_output(path)
    return path


def record_output(path: str | Path) -> None:
    """List a file tactilevision wrote in its folder's manifest (:data:`MANIFEST`); an
    unwritable manifest is skipped (the file then needs ``--overwrite`` next time)."""
    path = Path(path)
    try:
        _add_to_manifest(path.parent, [path.name])
    except OSError:
        pass


def _add_to_manifest(out: Path, names) -> None:
    """List `names` (relative to `out`) in `out`'s manifest beside what it lists already."""
    ours = _ours(out) | set(names)
    (out / MANIFEST).write_text(json.dumps({"files": sorted(ours)}, indent=1) + "\n",
                                encoding="utf-8")


#: The hidden staging folders of the :class:`StagedOutput` blocks open now: what an
#: interrupt that cannot unwind (the command line's watchdog) removes before it exits.
STAGING: set[Path] = set()

#: The folders the open :class:`StagedOutput` blocks created (an output folder and the
#: parents it lacked), removed with their staging folders when nothing was moved into them.
_CREATED: set[Path] = set()


def remove_staging() -> None:
    """Remove every open staging folder (:data:`STAGING`), and the output folders their
    blocks created, when empty: nothing half-written is left, nor an empty folder."""
    for path in list(STAGING):
        shutil.rmtree(path, ignore_errors=True)
        STAGING.discard(path)
    _remove_empty(list(_CREATED))


def _missing(path: Path) -> list[Path]:
    """`path` and those of its parents that do not exist, deepest first."""
    path = Path(path).absolute()
    return [p for p in (path, *path.parents) if not p.exists()]


def _remove_empty(folders: list[Path]) -> None:
    """Remove each of `folders` that is empty, deepest first (a parent after its child);
    one that holds anything stays, and none is remembered afterwards."""
    for folder in sorted(folders, key=lambda p: len(p.parts), reverse=True):
        try:
            folder.rmdir()
        except OSError:
            pass
        _CREATED.discard(folder)


class StagedOutput:
    """A command's files written into a hidden folder in `out`, moved into place at the end.

    A run either replaces a complete result or changes nothing: the files are
    written into ``out/.tactilevision-tmp-*`` (the same file system), and
    :meth:`commit` moves each into `out` (``os.replace``) only when the
    command has written them all. Leaving the ``with`` block without a
    commit (an error, Ctrl-C) removes the hidden folder and leaves `out` as
    it was (a folder the block created, `out` or a parent, is removed again
    when empty). The files moved are listed in `out`'s manifest (:data:`MANIFEST`):
    a rerun may replace them without ``--overwrite``; anything else in the
    way stops the commit (and the run's files are dropped) unless
    `overwrite`.

    Parameters
    ----------
    out : Path
        The output folder (created if needed).
    overwrite : bool, default False
    what : str
        How messages name the folder.

    Examples
    --------
    >>> with StagedOutput(out) as stage:          # doctest: +SKIP
    ...     (stage.path / "fit.json").write_text("{}")
    ...     stage.commit()
    """

    def __init__(self, out: Path, *, overwrite: bool = False,
                 what: str = "output folder") -> None:
        self.out = Path(out)
        self.overwrite = bool(overwrite)
        self.what = what
        self.path: Path = self.out
        self.committed = False
        self.created: list[Path] = []

    def __enter__(self) -> StagedOutput:

        # noted before they exist: an interrupt at any moment finds them (remove_staging)
        self.created = _missing(self.out)
        _CREATED.update(self.created)
        try:
            output_folder(self.out, self.what)
            self.path = Path(tempfile.mkdtemp(prefix=".tactilevision-tmp-", dir=self.out))
            STAGING.add(self.path)
        except OSError as exc:
            _remove_empty(self.created)
            raise InputError(f"cannot write into the {self.what} {self.out}: "
                             f"{exc.strerror}") from None
        except BaseException:
            _remove_empty(self.created)
            raise
        return self

    def commit(self) -> list[str]:
        """Move every file written into place; returns their names relative to `out`.

        Raises
        ------
        InputError
            When files the command did not write before are in the way and
            `overwrite` is off (nothing is moved then), or a move fails.
        """
        files = sorted(str(p.relative_to(self.path)) for p in self.path.rglob("*")
                       if p.is_file())
        check_overwrite(self.out, files, overwrite=self.overwrite)
        try:
            for name in files:
                target = self.out / name
                target.parent.mkdir(parents=True, exist_ok=True)
                os.replace(self.path / name, target)
            _add_to_manifest(self.out, files)
        except OSError as exc:
            raise InputError(f"cannot move the results into the {self.what} {self.out}: "
                             f"{exc.strerror}") from None
        finally:
            shutil.rmtree(self.path, ignore_errors=True)
            STAGING.discard(self.path)
        self.committed = True
        return files

    def __exit__(self, exc_type, exc, tb) -> bool:

        if not self.committed:
            shutil.rmtree(self.path, ignore_errors=True)
            STAGING.discard(self.path)
            _remove_empty(self.created)
        else:
            _CREATED.difference_update(self.created)
        return False
