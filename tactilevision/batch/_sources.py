"""Inputs of a batch: a folder of frames, a session folder or a video file, read by frame
index through :func:`tactilevision.io.open_source`."""

from __future__ import annotations

from pathlib import Path

from .._checks import InputError
from ..io import FrameSource, read_frame
from ..io import open_source as _open

__all__ = ["FrameSource", "open_source"]


def open_source(path: str | Path) -> FrameSource:
    """Open a batch input: a folder of frames, a session folder or a video file.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    FrameSource
        With its frames' shape known.

    Raises
    ------
    InputError
        What :func:`~tactilevision.io.open_source` refuses, or a folder whose
        first frame cannot be read (its reader's message).
    """
    src = _open(Path(path))
    if src.shape is None:
        read_frame(src.frame_paths[0])        # says why the first frame cannot be read
        raise InputError(f"{src.frame_paths[0]}: cannot be read")
    return src
