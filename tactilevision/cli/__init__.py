"""The ``tactilevision`` command line.

Each sub-command lives in its own module with ``add_parser(subparsers)`` and
``run(args) -> int``. Bad input raises :class:`tactilevision.InputError`; the
command prints its one-sentence message on standard error and exits with
status 2, deleting nothing already written (``docs/formats.md``).
"""

from __future__ import annotations

import argparse
import sys
import warnings
from collections.abc import Sequence

from .. import InputError, InputWarning, __version__
from . import (
    _batch,
    _calibrate,
    _diagnose,
    _fem,
    _fit,
    _forces,
    _history,
    _live,
    _optics,
    _plan,
    _reconstruct,
    _validate,
    _view,
)

__all__ = ["EXTRAS", "build_parser", "main", "missing_extra"]

_COMMANDS = (_calibrate, _reconstruct, _optics, _fit, _diagnose, _validate, _plan, _fem,
             _forces, _history, _batch, _live, _view)


def build_parser() -> argparse.ArgumentParser:
    """Build the argument parser with every sub-command registered.

    Returns
    -------
    parser : argparse.ArgumentParser
    """
    parser = argparse.ArgumentParser(
        prog="tactilevision",
        description="Vision-based tactile sensors: height maps by photometric stereo, "
        "in-situ elastomer calibration (E, nu), contact forces.",
    )
    parser.add_argument("--version", action="version", version=f"tactilevision {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for mod in _COMMANDS:
        mod.add_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit status.

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments without the program name; ``sys.argv[1:]`` when None.

    Returns
    -------
    status : int
        0 on success, 2 on bad input (message on standard error), 130 when
        interrupted (Ctrl-C: one line, no traceback).
    """
    parser = build_parser()
    argv = list(sys.argv[1:] if argv is None else argv)
    args = parser.parse_args(argv)
    args.argv = argv
    try:
        with warnings.catch_warnings():
            warnings.showwarning = _one_line(args.command, warnings.showwarning)
            return int(args.func(args) or 0)
    except InputError as exc:
        print(f"tactilevision {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"\ntactilevision {args.command}: interrupted", file=sys.stderr)
        return 130
    except ImportError as exc:
        why = missing_extra(exc)
        if why is None:
            raise
        print(f"tactilevision {args.command}: error: {why}", file=sys.stderr)
        return 2


#: The optional extra (pyproject.toml) that installs each package imported on use.
EXTRAS = {"torch": "torch", "kornia": "torch", "onnx": "torch", "dask": "dask",
          "distributed": "dask", "zarr": "dask", "pyarrow": "dask", "plotly": "view"}


def missing_extra(exc: ImportError) -> str | None:
    """One sentence naming the optional extra a failed import needs, or None when the
    import is not one of an extra's (a broken installation: its traceback is kept)."""
    name = (exc.name or "").split(".")[0]
    if name in EXTRAS:
        return (f"this needs {name}, which is not installed: pip install "
                f"'tactilevision[{EXTRAS[name]}]'")
    if "pip install 'tactilevision[" in str(exc):
        return str(exc)
    return None


def _one_line(command: str, default):
    """A ``warnings.showwarning`` that prints an :class:`~tactilevision.InputWarning` as
    one line naming the command (other warnings as Python prints them)."""
    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, InputWarning):
            print(f"tactilevision {command}: warning: {message}", file=sys.stderr)
        else:
            default(message, category, filename, lineno, file, line)
    return show


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
