"""The package's error and warning classes, apart from the array checks
(:mod:`tactilevision._checks`, which uses NumPy) so that ``import tactilevision``, the
command line's start and its ``--help`` load no NumPy."""

from __future__ import annotations

__all__ = ["InputError", "InputWarning", "ShapeError"]


class InputError(ValueError):
    """Bad user input: a file, row, key or argument the user can fix.

    The message is one sentence naming the file, row or key at fault.
    """


class ShapeError(InputError):
    """An array argument has the wrong shape, dtype or non-finite values."""


class InputWarning(UserWarning):
    """Input that is read but likely not what the user meant: a key this version does
    not read (a typo falls back to the default), with the nearest known key. The command
    line prints it as one line, ``tactilevision COMMAND: warning: ...``."""
