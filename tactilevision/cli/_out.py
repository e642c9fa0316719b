"""The sub-commands' ``--overwrite`` flag; the output folders themselves are
:mod:`tactilevision.io`'s (:class:`~tactilevision.io.StagedOutput`)."""

from __future__ import annotations

from ..io import (
    MANIFEST,
    StagedOutput,
    check_output_file,
    check_output_folder,
    check_overwrite,
    output_folder,
    write_output_file,
)

__all__ = ["MANIFEST", "StagedOutput", "add_overwrite_argument", "check_output_file",
           "check_output_folder", "check_overwrite", "output_folder", "write_output_file"]


def add_overwrite_argument(parser, what: str = "output folder") -> None:
    """Give a sub-command its ``--overwrite`` flag (:func:`check_overwrite`)."""
    parser.add_argument("--overwrite", action="store_true",
                        help=f"replace files in the {what} that tactilevision did not write "
                             "(without it such files stop the run before any work)")
