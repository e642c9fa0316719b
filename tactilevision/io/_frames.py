"""Frame folders, reference frames and ball-press sets.

Single images, the reference's names and :class:`BallPressSet` live in
:mod:`._images` (below :mod:`._gs_sdk`, which this module dispatches to) and are
re-exported here.
"""

from __future__ import annotations

import csv
import importlib.resources
import importlib.util
import re
from pathlib import Path

import numpy as np

from .._checks import InputError
from ._gs_sdk import read_gs_sdk
from ._images import (
    MAX_IMAGE_PIXELS,
    REFERENCE_NAMES,
    BallPressSet,
    _header_size,  # noqa: F401 - re-exported: the header parser's tests read it here
    find_reference,
    read_image,
)

__all__ = ["MAX_IMAGE_PIXELS", "BallPressSet", "find_reference", "list_frames",
           "read_ball_presses", "read_frame", "read_image", "read_reference", "taxim_datapack"]

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg")


def _natural_key(p: Path) -> list:
    """Sort key of a file name with its digit runs compared as numbers."""
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", p.name)]


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
    """Centres (N, 2) and radii (N,), px, of the frames `names` from a ``circles.csv``."""
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
    """A ball-press set from an ``.npz`` (this library's keys or taxim's data pack)."""
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
    if importlib.util.find_spec("taxim") is None:
        raise InputError("the taxim package is not installed: pip install 'tactilevision[test]'")
    path = Path(str(importlib.resources.files("taxim") / "calib" / sensor / "dataPack.npz"))
    if not path.is_file():
        raise InputError(f"taxim has no data pack for sensor '{sensor}' ({path})")
    return path
