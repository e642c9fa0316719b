"""Single image files, the no-contact reference's names and the ball-press set: the
bottom of the frame readers (:mod:`._frames`, :mod:`._gs_sdk`, :mod:`._session`)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from .._checks import InputError

__all__ = ["MAX_IMAGE_PIXELS", "REFERENCE_NAMES", "BallPressSet", "find_reference", "read_image"]

#: Largest image read, in pixels (4096 x 4096): tactile cameras stay far below it
#: (GelSight Mini 3280 x 2464, GelSlim 3.0 427 x 320 after cropping), and an 8000 x 6000
#: frame took minutes and gigabytes per session before anything said why.
MAX_IMAGE_PIXELS = 4096 * 4096
REFERENCE_NAMES = ("reference.png", "reference.jpg", "ref.png", "ref.jpg", "background.png",
                   "background.jpg")


def read_image(path: str | Path, *, colour_only: bool = False) -> np.ndarray:
    """Read a colour image as BGR uint8 (as ``cv2.imread`` gives).

    Parameters
    ----------
    path : str or Path
        A .png or .jpg file.
    colour_only : bool, default False
        Refuse a grey-level file instead of repeating its one channel three
        times (session frames and references: a grey frame among colour
        ones is a fault, not a frame).

    Returns
    -------
    image : (H, W, 3) uint8 ndarray
        BGR.

    Raises
    ------
    InputError
        If the file is missing, truncated (a JPEG without its end-of-image
        marker, a PNG without its IEND chunk: libjpeg would fill the rest
        with grey and only print a warning naming no file), not a readable
        image, deeper than 8 bits, or grey-level with `colour_only`. A
        fourth (alpha) channel is dropped.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"image {path} does not exist")
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InputError(f"image {path} cannot be read: {exc.strerror}") from None
    if not data:
        raise InputError(f"image {path} is empty (0 bytes)")
    _check_complete(path, data)
    size = _header_size(data)
    if size is not None and size[0] * size[1] > MAX_IMAGE_PIXELS:
        raise InputError(f"image {path} is {size[0]} x {size[1]} px "
                         f"({size[0] * size[1] / 1e6:.1f} megapixels), above the "
                         f"{MAX_IMAGE_PIXELS / 1e6:.1f} megapixel bound for tactile frames "
                         "(tactilevision.io.MAX_IMAGE_PIXELS): crop or downscale it first")
    try:
        img = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)
    except cv2.error:                       # the decoder's own assertion on broken data
        img = None
    if img is None:
        raise InputError(f"image {path} is not a readable image")
    if img.dtype != np.uint8:
        raise InputError(f"image {path} has {8 * img.dtype.itemsize}-bit values; tactile frames "
                         "and references are 8-bit colour images")
    if img.ndim == 2 or img.shape[2] == 1:
        if colour_only:
            raise InputError(f"image {path} is grey-level (one channel); tactile frames and "
                             "references are colour (BGR) images")
        img = cv2.cvtColor(img.reshape(img.shape[:2]), cv2.COLOR_GRAY2BGR)
    if img.shape[2] == 4:
        img = np.ascontiguousarray(img[:, :, :3])
    return img


def _header_size(data: bytes) -> tuple[int, int] | None:
    """(width, height) from a PNG's IHDR or a JPEG's start-of-frame, without decoding;
    None when the header cannot be read (the decoder then decides)."""
    if data[:8] == b"\x89PNG\r\n\x1a\n" and data[12:16] == b"IHDR" and len(data) >= 24:
        return int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")
    if data[:2] != b"\xff\xd8":
        return None
    i = 2
    while i + 4 <= len(data):
        if data[i] != 0xFF:
            return None
        marker = data[i + 1]
        if marker == 0xFF:                       # fill byte
            i += 1
            continue
        if marker in (0x01, *range(0xD0, 0xD8)):  # stand-alone markers: no length
            i += 2
            continue
        length = int.from_bytes(data[i + 2:i + 4], "big")
        if 0xC0 <= marker <= 0xCF and marker not in (0xC4, 0xC8, 0xCC) and i + 9 <= len(data):
            return (int.from_bytes(data[i + 7:i + 9], "big"),
                    int.from_bytes(data[i + 5:i + 7], "big"))
        if marker == 0xDA or length < 2:         # scan data before any frame header
            return None
        i += 2 + length
    return None


def _check_complete(path: Path, data: bytes) -> None:
    """Refuse a JPEG or PNG file cut short (a partial copy or write)."""
    if data[:2] == b"\xff\xd8":
        if b"\xff\xd9" not in data[-64:].rstrip(b"\x00\r\n "):
            raise InputError(f"image {path} is a truncated JPEG (no end-of-image marker): "
                             "a partial copy or write?")
    elif data[:8] == b"\x89PNG\r\n\x1a\n":
        if b"IEND" not in data[-16:]:
            raise InputError(f"image {path} is a truncated PNG (no IEND chunk): a partial copy "
                             "or write?")


def find_reference(frames_dir: str | Path) -> Path | None:
    """Find the no-contact reference frame of a frame folder.

    Looks for ``reference.png``, ``reference.jpg``, ``ref.png``, ``ref.jpg``,
    ``background.png`` or ``background.jpg`` (gs_sdk's name), in that order,
    in the folder, then in its parent (the session-folder layout of
    ``formats.md``: ``<session>/reference.png`` beside ``<session>/frames/``).

    Parameters
    ----------
    frames_dir : str or Path

    Returns
    -------
    path : Path or None
    """
    frames_dir = Path(frames_dir)
    for folder in (frames_dir, frames_dir.parent):
        for name in REFERENCE_NAMES:
            if (folder / name).is_file():
                return folder / name
    return None


@dataclass
class BallPressSet:
    """Ball-press calibration frames.

    Attributes
    ----------
    reference : (H, W, 3) uint8 ndarray
        No-contact frame, BGR.
    frames : (N, H, W, 3) uint8 ndarray
        Presses, BGR.
    centers_px : (N, 2) float64 ndarray or None
        Annotated circle centres (x, y), px, when known.
    radii_px : (N,) float64 ndarray or None
        Annotated circle radii, px, when known.
    names : list of str
        Frame names.
    ball_radius_mm : (N,) float64 ndarray or None
        Each press's ball radius, mm, where the set says it (gs_sdk's
        ``catalog.csv``); None where the caller gives one radius for all.
    """

    reference: np.ndarray
    frames: np.ndarray
    centers_px: np.ndarray | None
    radii_px: np.ndarray | None
    names: list[str]
    ball_radius_mm: np.ndarray | None = None
