"""Tactile video files (``.mp4``, ``.avi``, ...) read through OpenCV, by frame index."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from .._checks import InputError

__all__ = ["VIDEO_SUFFIXES", "VideoFrames", "find_video_reference", "is_video"]

#: File suffixes read as videos (OpenCV's FFmpeg backend decodes them).
VIDEO_SUFFIXES = (".mp4", ".avi", ".mov", ".mkv", ".m4v")


def is_video(path: str | Path) -> bool:
    """Whether `path` names a video file (by its suffix, :data:`VIDEO_SUFFIXES`)."""
    return Path(path).suffix.lower() in VIDEO_SUFFIXES


def find_video_reference(video: str | Path) -> Path | None:
    """The no-contact frame beside a video: ``<stem>_reference.png``, else ``reference.png``
    in its folder, else None (the convention of ``batch``, ``reconstruct``, ``forces`` and
    ``view``)."""
    video = Path(video)
    for cand in (video.with_name(f"{video.stem}_reference.png"),
                 video.parent / "reference.png"):
        if cand.is_file():
            return cand
    return None


class VideoFrames:
    """The frames of a video file, read by index range (a sequence of frames).

    Parameters
    ----------
    path : str or Path
        Video file; every frame is decoded by OpenCV (``cv2.VideoCapture``) as
        an (H, W, 3) uint8 BGR array, the channel order of
        :func:`~tactilevision.io.read_frame`.

    Attributes
    ----------
    path : Path
    n_frames : int
        Frames in the file (counted by decoding when the container's count is
        missing).
    fps : float
        The container's frame rate (NaN when it states none).
    shape : (int, int)
        (H, W) of every frame.

    Raises
    ------
    InputError
        If the file does not exist, OpenCV cannot open it, or it holds no frame.

    Notes
    -----
    :meth:`read` seeks to the first frame asked for and checks that the
    decoder landed there (``CAP_PROP_POS_FRAMES``); where a codec cannot seek
    exactly it decodes forward from the start instead, so a chunk of frames is
    the same whether it is read alone or in a sequential pass
    (``tests/test_batch.py`` checks this for MJPG ``.avi`` and ``mp4v`` ``.mp4``).

    Examples
    --------
    >>> video = VideoFrames("press.mp4")            # doctest: +SKIP
    >>> chunk = video.read(0, 64)                   # doctest: +SKIP
    >>> chunk.shape                                 # doctest: +SKIP
    (64, 480, 640, 3)
    """

    def __init__(self, path: str | Path) -> None:

        self.path = Path(path)
        if not self.path.is_file():
            raise InputError(f"{self.path}: no such video file")
        cap = cv2.VideoCapture(str(self.path))
        try:
            if not cap.isOpened():
                raise InputError(f"{self.path}: OpenCV cannot open this video (codec or "
                                 "container not supported, or not a video)")
            ok, first = cap.read()
            if not ok or first is None:
                raise InputError(f"{self.path}: the video holds no readable frame")
            fps = float(cap.get(cv2.CAP_PROP_FPS))
            n = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
            if n <= 0:                               # no count in the container: decode
                n = 1
                while cap.grab():
                    n += 1
        finally:
            cap.release()
        self.n_frames = n
        self.fps = fps if fps > 0 else float("nan")
        self.shape = (int(first.shape[0]), int(first.shape[1]))

    def __len__(self) -> int:
        return self.n_frames

    def __repr__(self) -> str:
        return (f"VideoFrames({str(self.path)!r}, n_frames={self.n_frames}, "
                f"shape={self.shape}, fps={self.fps:g})")

    def iter(self, start: int, stop: int):
        """Yield frames ``start`` to ``stop - 1`` one at a time, (H, W, 3) uint8 BGR.

        Raises
        ------
        InputError
            For a range outside the video, or a frame that does not decode
            (a truncated file), naming the frame.
        """

        if not (0 <= start < stop <= self.n_frames):
            raise InputError(f"{self.path}: frames {start} to {stop - 1} lie outside the "
                             f"video's {self.n_frames} frames")
        cap = cv2.VideoCapture(str(self.path))
        try:
            if start > 0:
                cap.set(cv2.CAP_PROP_POS_FRAMES, start)
                if round(cap.get(cv2.CAP_PROP_POS_FRAMES)) != start:
                    cap.release()                    # inexact seek: decode from the start
                    cap = cv2.VideoCapture(str(self.path))
                    for i in range(start):
                        if not cap.grab():
                            raise InputError(f"{self.path}: frame {i} does not decode")
            for k in range(stop - start):
                ok, frame = cap.read()
                if not ok or frame is None:
                    raise InputError(f"{self.path}: frame {start + k} does not decode "
                                     "(truncated or damaged file?)")
                if frame.shape[:2] != self.shape:
                    raise InputError(f"{self.path}: frame {start + k} is "
                                     f"{frame.shape[1]} x {frame.shape[0]}, the first is "
                                     f"{self.shape[1]} x {self.shape[0]}")
                yield frame
        finally:
            cap.release()

    def read(self, start: int, stop: int) -> np.ndarray:
        """Frames ``start`` to ``stop - 1``, stacked.

        Parameters
        ----------
        start, stop : int
            Frame indices, ``0 <= start < stop <= n_frames``.

        Returns
        -------
        frames : (stop - start, H, W, 3) uint8 ndarray
            BGR.

        Raises
        ------
        InputError
            As :meth:`iter`.
        """
        return np.stack(list(self.iter(start, stop)))

    def frame(self, i: int) -> np.ndarray:
        """Frame `i`, (H, W, 3) uint8 BGR."""
        return self.read(int(i), int(i) + 1)[0]
