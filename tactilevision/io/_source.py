"""One way in for frames: a frame folder, a video, a session folder or a camera.

:func:`open_source` returns a :class:`FrameSource` (the frames with their times,
the reference, ``mm_per_px`` and the sensor name where the source knows them),
which ``reconstruct``, ``forces``, ``view``, ``live`` and ``batch`` all read.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import cv2
import numpy as np

from .._checks import InputError
from ._frames import list_frames, read_frame, read_reference
from ._images import find_reference, read_image
from ._session import Session, read_session
from ._video import VideoFrames, find_video_reference, is_video

__all__ = ["FrameSource", "open_source"]


@dataclass(frozen=True)
class FrameSource:
    """Frames from a folder, a video, a session folder or a camera (:func:`open_source`).

    Attributes
    ----------
    kind : {'folder', 'video', 'session', 'camera'}
    path : Path or None
        The folder or video (None for a camera).
    n_frames : int
        Number of frames (0 for a camera: unknown).
    shape : (int, int) or None
        (H, W) of the frames (None for a camera, or a folder whose first frame
        cannot be read).
    fps : float
        Frames per second of a video (NaN otherwise).
    frame_paths : tuple of Path
        The frame files of a folder or session (empty for a video or camera).
    times_s : (n_frames,) float64 ndarray
        Each frame's time, s: a session's ``frames.csv``, a video's index over
        its frame rate, NaN for a folder of frames.
    reference_path : Path or None
        The no-contact reference found beside the frames (or given).
    session : Session or None
        The session read, for a session folder (``session.toml`` beside
        ``frames/``).
    camera : int or None
        The camera's index.
    """

    kind: str
    path: Path | None
    n_frames: int
    shape: tuple[int, int] | None
    fps: float = float("nan")
    frame_paths: tuple[Path, ...] = ()
    times_s: np.ndarray = field(default_factory=lambda: np.zeros(0))
    reference_path: Path | None = None
    session: Session | None = None
    camera: int | None = None

    @cached_property
    def _video(self) -> VideoFrames:
        """The video's reader, opened once (random access by :meth:`frame`)."""
        return VideoFrames(self.path)

    @property
    def is_video(self) -> bool:
        """True for a video file."""
        return self.kind == "video"

    @property
    def mm_per_px(self) -> float | None:
        """The session's pixel size, mm (None where the source does not say)."""
        return self.session.config.mm_per_px if self.session is not None else None

    @property
    def sensor_name(self) -> str | None:
        """The session's ``[sensor] name`` (None where the source does not say)."""
        return self.session.config.sensor_name if self.session is not None else None

    def frame_name(self, i: int) -> str:
        """The file name of frame `i`, or ``'<video>#<i>'``."""
        if self.frame_paths:
            return self.frame_paths[i].name
        return f"{self.path.name}#{i}" if self.path is not None else f"camera{self.camera}#{i}"

    def frame_stem(self, i: int) -> str:
        """A file stem for frame `i`'s outputs: the frame file's, or ``'<video>_<i:05d>'``."""
        if self.frame_paths:
            return self.frame_paths[i].stem
        return f"{self.path.stem}_{i:05d}" if self.path is not None else f"camera_{i:05d}"

    def iter(self, start: int = 0, stop: int | None = None,
             shape: tuple[int, int] | None = None) -> Iterator[np.ndarray]:
        """Yield frames ``start`` to ``stop - 1`` (a camera: until it stops), in order.

        Parameters
        ----------
        start, stop : int
            Frame indices (`stop` None: to the end).
        shape : (int, int), optional
            Required (H, W), e.g. the calibration's; default the source's own.

        Yields
        ------
        frame : (H, W, 3) uint8 ndarray
            BGR.

        Raises
        ------
        InputError
            A frame that cannot be read or has another size (named).
        """
        shape = shape if shape is not None else self.shape
        if self.kind == "camera":
            yield from _capture(int(self.camera))
            return
        stop = self.n_frames if stop is None else stop
        if self.frame_paths:
            for i in range(start, stop):
                yield read_frame(self.frame_paths[i], shape)
            return
        for i, frame in zip(range(start, stop), VideoFrames(self.path).iter(start, stop),
                            strict=False):
            yield self._checked(frame, shape, i)

    def frames_at(self, picks, shape: tuple[int, int] | None = None
                  ) -> Iterator[tuple[int, np.ndarray | InputError]]:
        """Each picked frame, or why it could not be read, without stopping at a bad one.

        Parameters
        ----------
        picks : iterable of int
            Frame indices in increasing order (a video is decoded once, in order).
        shape : (int, int), optional
            Required (H, W); default the source's own.

        Yields
        ------
        i : int
        frame : (H, W, 3) uint8 ndarray or InputError
            The frame (BGR), or the error naming it (unreadable, another size).
        """
        shape = shape if shape is not None else self.shape
        if self.frame_paths:
            for i in picks:
                try:
                    yield i, read_frame(self.frame_paths[i], shape)
                except InputError as exc:
                    yield i, exc
            return
        decoded = self.iter(0, self.n_frames, shape=None)
        at = 0                          # the next frame the decoder gives
        for i in picks:
            frame = None
            while at <= i:
                frame, at = next(decoded), at + 1
            try:
                yield i, self._checked(frame, shape, i)
            except InputError as exc:
                yield i, exc

    def frame(self, i: int, shape: tuple[int, int] | None = None) -> np.ndarray:
        """Frame `i`, (H, W, 3) uint8 BGR (checked against `shape`, default the source's).

        Raises
        ------
        InputError
            Not readable, another size, or a camera (no random access).
        """
        if self.kind == "camera":
            raise InputError(f"camera {self.camera}: frames come in order, not by index")
        shape = shape if shape is not None else self.shape
        if self.frame_paths:
            return read_frame(self.frame_paths[i], shape)
        return self._checked(self._video.frame(i), shape, i)

    def _checked(self, frame: np.ndarray, shape, i: int) -> np.ndarray:
        if shape is not None and frame.shape[:2] != tuple(shape):
            raise InputError(f"{self.frame_name(i)} is {frame.shape[1]} x {frame.shape[0]} px, "
                             f"expected {shape[1]} x {shape[0]} px (the calibration's)")
        return frame

    def reference(self, shape: tuple[int, int] | None = None) -> np.ndarray | None:
        """The no-contact reference, (H, W, 3) uint8 BGR, or None when there is none.

        A session's own reference, else the file found beside the frames (or
        given to :func:`open_source`), checked against `shape`.

        Raises
        ------
        InputError
            The reference cannot be read or has another size (named).
        """
        if self.reference_path is None:
            return self.session.reference if self.session is not None else None
        return read_reference(self.reference_path, shape)


def open_source(source: str | Path | int, *, reference: str | Path | None = None
                ) -> FrameSource:
    """Open frames from a folder, a video file, a session folder or a camera.

    Parameters
    ----------
    source : str, Path or int
        A folder of .png / .jpg frames (or with a ``frames/`` subfolder); a
        session folder (``session.toml`` beside ``frames/``, formats.md
        section 1: read whole, its frames' times and reference with it); a
        video file (:data:`~tactilevision.io.VIDEO_SUFFIXES`); or a camera
        index.
    reference : str or Path, optional
        A no-contact reference frame to use instead of the one found beside
        the frames (``reference.png``, ``<video stem>_reference.png``, a
        session's own).

    Returns
    -------
    FrameSource

    Raises
    ------
    InputError
        The path does not exist, is a file that is not a video, holds no
        frames or a first frame that is not colour (one that cannot be read
        leaves ``shape`` None); a session folder that
        :func:`~tactilevision.io.read_session` refuses; a `reference` that
        does not exist; a camera that does not open.
    """
    ref = None
    if reference is not None:
        ref = Path(reference)
        if not ref.is_file():
            raise InputError(f"reference {ref} does not exist")
    if isinstance(source, int | np.integer) and not isinstance(source, bool):
        cap = cv2.VideoCapture(int(source))
        opened = cap.isOpened()
        cap.release()
        if not opened:
            raise InputError(f"camera {int(source)} does not open")
        return FrameSource(kind="camera", path=None, n_frames=0, shape=None,
                           camera=int(source), reference_path=ref)
    p = Path(source)
    if not p.exists():
        raise InputError(f"{p} does not exist (no such file or folder)")
    if p.is_file():
        if not is_video(p):
            raise InputError(f"{p}: not a video file (.mp4, .avi, .mov, .mkv, .m4v) nor a "
                             "folder of frames")
        v = VideoFrames(p)
        return FrameSource(kind="video", path=p, n_frames=v.n_frames, shape=tuple(v.shape),
                           fps=float(v.fps), times_s=np.arange(v.n_frames) / v.fps,
                           reference_path=ref or find_video_reference(p))
    if (p / "session.toml").is_file():
        s = read_session(p)
        return FrameSource(kind="session", path=p, n_frames=len(s.frame_paths),
                           shape=tuple(s.reference.shape[:2]), frame_paths=tuple(s.frame_paths),
                           times_s=np.asarray(s.frame_times_s, np.float64), session=s,
                           reference_path=ref or find_reference(p))
    frames = tuple(list_frames(p))
    try:
        first = read_image(frames[0])
    except InputError:
        first = None            # the frames' size unknown: each frame says why when read
    if first is not None and (first.ndim != 3 or first.shape[2] != 3):
        raise InputError(f"{frames[0]}: not a colour (H, W, 3) frame")
    return FrameSource(kind="folder", path=p, n_frames=len(frames),
                       shape=None if first is None else (first.shape[0], first.shape[1]),
                       frame_paths=frames,
                       times_s=np.full(len(frames), np.nan),
                       reference_path=ref or find_reference(p))


def _capture(index: int) -> Iterator[np.ndarray]:
    """A camera's frames until it stops giving them."""
    cap = cv2.VideoCapture(index)
    if not cap.isOpened():
        raise InputError(f"camera {index} does not open")
    try:
        while True:
            ok, frame = cap.read()
            if not ok:
                return
            yield frame
    finally:
        cap.release()
