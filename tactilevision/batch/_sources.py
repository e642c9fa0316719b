"""Inputs of a batch: a folder of frames or a video file, read by frame index."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._checks import InputError

__all__ = ["FrameSource", "open_source"]


@dataclass(frozen=True)
class FrameSource:
    """A sequence of tactile frames: a frame folder or a video file.

    Attributes
    ----------
    path : Path
        The folder (or session folder: its ``frames/``) or the video file.
    n_frames : int
    shape : (int, int)
        (H, W) of the frames.
    fps : float
        The video's frame rate; NaN for a folder (its frames carry no times).
    frame_paths : tuple of Path
        A folder's frame files in order; empty for a video.
    reference : Path or None
        The no-contact frame found beside the input (``reference.png``,
        ``ref.jpg``, ... in the folder or its parent; for a video
        ``<stem>_reference.png`` or ``reference.png`` beside it), or None.
    """

    path: Path
    n_frames: int
    shape: tuple[int, int]
    fps: float
    frame_paths: tuple[Path, ...]
    reference: Path | None

    @property
    def is_video(self) -> bool:
        return not self.frame_paths

    def frame_name(self, i: int) -> str:
        """The file name of frame `i` of a folder, or ``'<video>#<i>'``."""
        return self.frame_paths[i].name if self.frame_paths else f"{self.path.name}#{i}"

    def iter(self, start: int, stop: int) -> Iterator[np.ndarray]:
        """Yield frames ``start`` to ``stop - 1``, (H, W, 3) uint8 BGR.

        Raises
        ------
        InputError
            For a frame that cannot be read or has another size than the
            first (named).
        """
        if self.frame_paths:
            from ..io import read_frame

            for i in range(start, stop):
                yield read_frame(self.frame_paths[i], self.shape)
        else:
            from ..io import VideoFrames

            yield from VideoFrames(self.path).iter(start, stop)


def open_source(path: str | Path) -> FrameSource:
    """Open a batch input: a folder of frames (or a session folder) or a video file.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    FrameSource

    Raises
    ------
    InputError
        If the path does not exist, is a file that is not a video
        (:data:`~tactilevision.io.VIDEO_SUFFIXES`), holds no frames, or its
        first frame cannot be read.
    """
    from ..io import (
        VideoFrames,
        find_reference,
        find_video_reference,
        is_video,
        list_frames,
        read_image,
    )

    p = Path(path)
    if not p.exists():
        raise InputError(f"{p}: no such file or folder")
    if p.is_file():
        if not is_video(p):
            raise InputError(f"{p}: not a video file (.mp4, .avi, .mov, .mkv, .m4v) nor a "
                             "folder of frames")
        v = VideoFrames(p)
        return FrameSource(path=p, n_frames=v.n_frames, shape=v.shape, fps=v.fps,
                           frame_paths=(), reference=find_video_reference(p))
    frames = tuple(list_frames(p))
    if not frames:
        raise InputError(f"{p} holds no .png or .jpg frames")
    first = read_image(frames[0])
    if first.ndim != 3 or first.shape[2] != 3:
        raise InputError(f"{frames[0]}: not a colour (H, W, 3) frame")
    return FrameSource(path=p, n_frames=len(frames), shape=(first.shape[0], first.shape[1]),
                       fps=float("nan"), frame_paths=frames, reference=find_reference(p))
