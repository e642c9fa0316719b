"""Frame folders, reference frames and ball-press sets."""

from __future__ import annotations

import csv
import re
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from .._checks import InputError

__all__ = ["MAX_IMAGE_PIXELS", "BallPressSet", "find_reference", "list_frames",
           "read_ball_presses", "read_frame", "read_image", "read_reference", "taxim_datapack"]

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg")
#: Largest image read, in pixels (4096 x 4096): tactile cameras stay far below it
#: (GelSight Mini 3280 x 2464, GelSlim 3.0 427 x 320 after cropping), and an 8000 x 6000
#: frame took minutes and gigabytes per session before anything said why.
MAX_IMAGE_PIXELS = 4096 * 4096
REFERENCE_NAMES = ("reference.png", "reference.jpg", "ref.png", "ref.jpg", "background.png",
                   "background.jpg")


def _natural_key(p: Path) -> list:
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", p.name)]


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


def list_frames(folder: str | Path) -> list[Path]:
    """Frame files of a folder in name order (numbers compared as numbers).

    Parameters
    ----------
    folder : str or Path
        Folder of .png / .jpg frames; reference frames (``reference.*``,
        ``ref.*``) are left out. A folder with no frames of its own but a
        ``frames/`` subfolder (a session folder, formats.md section 1) gives
        the frames of that subfolder.

    Returns
    -------
    paths : list of Path

    Raises
    ------
    InputError
        If the folder does not exist or holds no frames.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError(f"frames folder {folder} does not exist")
    paths = [p for p in folder.iterdir()
             if p.suffix.lower() in IMAGE_SUFFIXES and p.name.lower() not in REFERENCE_NAMES]
    if not paths and (folder / "frames").is_dir():
        return list_frames(folder / "frames")
    if not paths:
        raise InputError(f"frames folder {folder} holds no .png or .jpg frames")
    return sorted(paths, key=_natural_key)


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


def read_reference(path: str | Path, shape: tuple[int, int] | None = None) -> np.ndarray:
    """Read a reference frame and check its size.

    Parameters
    ----------
    path : str or Path
    shape : tuple of int, optional
        Required (H, W).

    Returns
    -------
    reference : (H, W, 3) uint8 ndarray

    Raises
    ------
    InputError
        If unreadable or of the wrong size.
    """
    return read_frame(path, shape, what="reference")


def read_frame(path: str | Path, shape: tuple[int, int] | None = None, *,
               what: str = "frame") -> np.ndarray:
    """Read a tactile frame and check its size against the calibration's.

    Parameters
    ----------
    path : str or Path
    shape : tuple of int, optional
        Required (H, W).
    what : str, default 'frame'
        How the error message names the image.

    Returns
    -------
    frame : (H, W, 3) uint8 ndarray
        BGR.

    Raises
    ------
    InputError
        If unreadable or of the wrong size.
    """
    img = read_image(path, colour_only=True)
    if shape is not None and img.shape[:2] != tuple(shape):
        raise InputError(f"{what} {path} is {img.shape[1]} x {img.shape[0]} px but the "
                         f"calibration expects {shape[1]} x {shape[0]} px")
    return img


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


def read_ball_presses(path: str | Path) -> BallPressSet:
    """Read a ball-press set from an ``.npz`` file or a folder.

    Parameters
    ----------
    path : str or Path
        Either an ``.npz`` with ``reference``, ``frames`` and optionally
        ``centers_px``, ``radii_px`` (or the ``taxim`` layout ``f0``,
        ``imgs``, ``touch_center``, ``touch_radius``), or a folder with a
        reference frame (see :func:`find_reference`), the press frames and
        optionally ``circles.csv`` with columns ``frame,x_px,y_px,radius_px``,
        or a gs_sdk calibration folder (``catalog.csv``, ``background.png``,
        ``<diameter>mm/<i>/gelsight.png``; :func:`read_gs_sdk`), which also
        gives each press's ball radius.

    Returns
    -------
    presses : BallPressSet

    Raises
    ------
    InputError
        Naming the file, key, row or frame at fault.
    """
    path = Path(path)
    if path.suffix == ".npz":
        return _read_npz(path)
    if not path.is_dir():
        raise InputError(f"ball presses {path} is neither an .npz file nor a folder")
    if (path / "catalog.csv").is_file():
        from ._gs_sdk import read_gs_sdk

        return read_gs_sdk(path)
    ref_path = find_reference(path)
    if ref_path is None:
        raise InputError(f"ball-press folder {path} has no reference.png / ref.jpg / "
                         "background.png (the no-contact frame)")
    reference = read_image(ref_path)
    files = list_frames(path)
    frames = []
    for f in files:
        img = read_image(f)
        if img.shape != reference.shape:
            raise InputError(f"frame {f} is {img.shape[1]} x {img.shape[0]} px but the "
                             f"reference is {reference.shape[1]} x {reference.shape[0]} px")
        frames.append(img)
    names = [f.name for f in files]
    centers = radii = None
    circles = path / "circles.csv"
    if not circles.is_file():
        circles = files[0].parent / "circles.csv"      # beside the frames (a frames/ folder)
    if circles.is_file():
        centers, radii = _read_circles(circles, names)
    return BallPressSet(reference, np.stack(frames), centers, radii, names)


def _read_circles(path: Path, names: list[str]) -> tuple[np.ndarray, np.ndarray]:
    rows: dict[str, tuple[float, float, float]] = {}
    with path.open(newline="") as fh:
        reader = csv.DictReader(fh)
        need = {"frame", "x_px", "y_px", "radius_px"}
        if reader.fieldnames is None or not need <= set(reader.fieldnames):
            raise InputError(f"{path} must have the columns frame,x_px,y_px,radius_px")
        for line, row in enumerate(reader, start=2):
            try:
                rows[row["frame"]] = (float(row["x_px"]), float(row["y_px"]),
                                      float(row["radius_px"]))
            except (TypeError, ValueError):
                raise InputError(f"{path} line {line}: non-numeric circle "
                                 f"({row.get('x_px')}, {row.get('y_px')}, "
                                 f"{row.get('radius_px')})") from None
            x, y, r = rows[row["frame"]]
            if not (np.isfinite(x) and np.isfinite(y) and np.isfinite(r) and r > 0):
                raise InputError(f"{path} line {line}: circle ({x:g}, {y:g}, radius {r:g}) "
                                 "needs a finite centre and a positive radius")
    missing = [n for n in names if n not in rows]
    if missing:
        raise InputError(f"{path} has no circle for frame {missing[0]}")
    arr = np.array([rows[n] for n in names], np.float64)
    return arr[:, :2], arr[:, 2]


def _read_npz(path: Path) -> BallPressSet:
    if not path.is_file():
        raise InputError(f"ball presses {path} does not exist")
    try:
        z = np.load(path, allow_pickle=False)
    except (OSError, ValueError) as exc:
        raise InputError(f"ball presses {path} is not a readable .npz ({exc})") from None
    with z:
        keys = set(z.files)
        if {"f0", "imgs"} <= keys:  # the taxim dataPack layout
            ref, frames = z["f0"], z["imgs"]
            centers = z["touch_center"].astype(np.float64) if "touch_center" in keys else None
            radii = z["touch_radius"].astype(np.float64) if "touch_radius" in keys else None
        elif {"reference", "frames"} <= keys:
            ref, frames = z["reference"], z["frames"]
            centers = z["centers_px"].astype(np.float64) if "centers_px" in keys else None
            radii = z["radii_px"].astype(np.float64) if "radii_px" in keys else None
        else:
            raise InputError(f"ball presses {path} needs the keys 'reference' and 'frames' "
                             f"(or taxim's 'f0' and 'imgs'); it has {sorted(keys)}")
    if ref.dtype != np.uint8 or ref.ndim != 3 or frames.ndim != 4 \
            or frames.shape[1:] != ref.shape:
        raise InputError(f"ball presses {path}: frames {frames.shape} {frames.dtype} do not "
                         f"match the reference {ref.shape} {ref.dtype} (uint8 BGR expected)")
    names = [f"press_{i}" for i in range(len(frames))]
    return BallPressSet(ref, frames, centers, radii, names)


def taxim_datapack(sensor: str = "gelsight") -> Path:
    """Path of the ball-press data pack shipped inside the ``taxim`` package.

    Parameters
    ----------
    sensor : {'gelsight', 'gelsight_mini'}
        Which data pack. Only 'gelsight' has a documented ball radius
        (2.0 mm at 0.0295 mm/px, in the taxim package's documentation).

    Returns
    -------
    path : Path
        ``taxim/calib/<sensor>/dataPack.npz`` (MIT licence, CMURoboTouch).

    Raises
    ------
    InputError
        If ``taxim`` is not installed (``pip install tactilevision[test]``).
    """
    import importlib.resources
    import importlib.util

    if importlib.util.find_spec("taxim") is None:
        raise InputError("the taxim package is not installed: pip install 'tactilevision[test]'")
    path = Path(str(importlib.resources.files("taxim") / "calib" / sensor / "dataPack.npz"))
    if not path.is_file():
        raise InputError(f"taxim has no data pack for sensor '{sensor}' ({path})")
    return path
