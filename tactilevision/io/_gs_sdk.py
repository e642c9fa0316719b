"""Ball presses in the layout of gs_sdk, the SDK GelSight users calibrate with.

gs_sdk's ``calibration/collect_data.py`` (GelSight and the Robotics and Perception
Lab, CMU; GPL-3.0, none of its code is used here) writes one calibration folder::

    CALIB_DIR/
      background.png                 the no-contact frame
      catalog.csv                    experiment_reldir,diameter(mm)
      <diameter>mm/<i>/gelsight.png  one press of a ball of that diameter
      <diameter>mm/<i>/label.npz     optional: center (x, y) and radius, px, drawn
                                     on the frame by its label_data.py

so one folder holds presses of several ball sizes. :func:`read_gs_sdk` reads it into
a :class:`~tactilevision.io.BallPressSet` with each press's ball radius.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from .._checks import InputError
from ._images import BallPressSet, find_reference, read_image

__all__ = ["CATALOG", "read_gs_sdk"]

#: gs_sdk's press catalogue, in the calibration folder.
CATALOG = "catalog.csv"


def read_gs_sdk(folder: str | Path) -> BallPressSet:
    """Read a gs_sdk calibration folder.

    Parameters
    ----------
    folder : str or Path
        The folder holding ``catalog.csv`` (columns ``experiment_reldir`` and
        ``diameter(mm)``), ``background.png`` and one sub-folder per press
        with its ``gelsight.png`` and, optionally, ``label.npz`` (``center``
        (x, y) and ``radius``, px).

    Returns
    -------
    presses : BallPressSet
        In the catalogue's order, named by their ``experiment_reldir``;
        ``ball_radius_mm`` (N,) float64, half of each row's diameter; the
        circles when every press has a ``label.npz``, else None (detected
        when calibrating).

    Raises
    ------
    InputError
        Naming the file, row or press at fault: no catalogue or no
        background, a missing column, a diameter that is not a positive
        number, a press folder without ``gelsight.png``, a frame of another
        size than the background, a ``label.npz`` without ``center`` and
        ``radius``, or labels on some presses but not all.
    """
    folder = Path(folder)
    catalog = folder / CATALOG
    if not catalog.is_file():
        raise InputError(f"{folder} has no {CATALOG} (gs_sdk's calibration layout)")
    ref_path = find_reference(folder)
    if ref_path is None or ref_path.parent != folder:
        raise InputError(f"gs_sdk calibration folder {folder} has no background.png (the "
                         "no-contact frame)")
    reference = read_image(ref_path)
    rows = _catalog_rows(catalog)
    frames, names, diameters, labels = [], [], [], []
    for line, reldir, diameter in rows:
        press = folder / reldir
        image = press / "gelsight.png"
        if not image.is_file():
            raise InputError(f"{catalog} line {line}: {image} does not exist")
        img = read_image(image)
        if img.shape != reference.shape:
            raise InputError(f"{image} is {img.shape[1]} x {img.shape[0]} px but "
                             f"{ref_path.name} is {reference.shape[1]} x "
                             f"{reference.shape[0]} px")
        frames.append(img)
        names.append(reldir)
        diameters.append(diameter)
        labels.append(_label(press / "label.npz"))
    have = [lab is not None for lab in labels]
    centers = radii = None
    if all(have):
        centers = np.array([lab[0] for lab in labels], np.float64)
        radii = np.array([lab[1] for lab in labels], np.float64)
    elif any(have):
        first = names[have.index(False)]
        raise InputError(f"{folder}: press {first} has no label.npz while others have one; "
                         "label every press, or none (the circles are then detected)")
    return BallPressSet(reference, np.stack(frames), centers, radii, names,
                        ball_radius_mm=np.array(diameters, np.float64) / 2.0)


def _catalog_rows(catalog: Path) -> list[tuple[int, str, float]]:
    """(line, experiment_reldir, diameter in mm) of every row of gs_sdk's catalogue."""
    with catalog.open(newline="") as fh:
        reader = csv.DictReader(fh)
        fields = [f.strip() for f in reader.fieldnames or []]
        need = ("experiment_reldir", "diameter(mm)")
        if not set(need) <= set(fields):
            raise InputError(f"{catalog} must have the columns {','.join(need)}; it has "
                             f"{','.join(fields) or 'none'}")
        rows = []
        for line, row in enumerate(reader, start=2):
            row = {k.strip(): (v or "").strip() for k, v in row.items() if k is not None}
            reldir, text = row["experiment_reldir"], row["diameter(mm)"]
            try:
                diameter = float(text)
            except ValueError:
                diameter = float("nan")
            if not (np.isfinite(diameter) and diameter > 0):
                raise InputError(f"{catalog} line {line}: diameter(mm) {text!r} is not a "
                                 "positive number")
            if not reldir or Path(reldir).is_absolute() or ".." in Path(reldir).parts:
                raise InputError(f"{catalog} line {line}: experiment_reldir {reldir!r} must "
                                 "be a folder inside the calibration folder")
            rows.append((line, reldir, diameter))
    if len(rows) < 2:
        raise InputError(f"{catalog} lists {len(rows)} press(es); calibrating needs 2 or more")
    return rows


def _label(path: Path) -> tuple[np.ndarray, float] | None:
    """The circle of a gs_sdk ``label.npz`` (centre (x, y), radius, px), or None."""
    if not path.is_file():
        return None
    try:
        with np.load(path, allow_pickle=False) as z:
            centre = np.asarray(z["center"], np.float64).reshape(-1)
            radius = float(np.asarray(z["radius"], np.float64).reshape(-1)[0])
    except (OSError, ValueError, KeyError, IndexError) as exc:
        raise InputError(f"{path} is not a gs_sdk label (center and radius, px): "
                         f"{exc}") from None
    if centre.size != 2 or not (np.all(np.isfinite(centre)) and np.isfinite(radius)
                                and radius > 0):
        raise InputError(f"{path}: circle centre {centre.tolist()} radius {radius:g} needs "
                         "two finite coordinates and a positive radius")
    return centre, radius
