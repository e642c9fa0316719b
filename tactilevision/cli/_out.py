"""The sub-commands' ``--overwrite`` flag; the output folders themselves are
:mod:`tactilevision.io`'s (:class:`~tactilevision.io.StagedOutput`)."""

from __future__ import annotations

__all__ = ["add_overwrite_argument"]


def add_overwrite_argument(parser, what: str = "output folder") -> None:
    """Give a sub-command its ``--overwrite`` flag (:func:`~tactilevision.io.check_overwrite`)."""
    parser.add_argument("--overwrite", action="store_true",
                        help=f"replace files in the {what} that tactilevision did not write "
                             "(without it such files stop the run before any work)")
