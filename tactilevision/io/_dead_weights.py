"""A dead-weight session folder: frames of a ball at rest under known masses, no F/T sensor.

::

    <session>/
      session.toml     [sensor] and [indenter] (shape = "sphere"), as a ball's session
      reference.png    a no-contact frame
      frames/          one frame per resting weight
      weights.csv      frame,mass_kg[,mass_std_kg]

``mass_kg`` is the whole mass resting on the gel through the ball (the ball's own
included), kg, > 0; ``mass_std_kg`` its standard uncertainty. The force is
P = m g, g the standard gravity (:data:`STANDARD_GRAVITY`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from PIL import Image

from .._checks import InputError
from ._images import read_image
from ._measurements import STANDARD_GRAVITY
from ._session import SessionConfig, _numbers, _read_config, _read_csv, _unknown_keys

__all__ = ["DeadWeightSession", "read_dead_weights"]


@dataclass(frozen=True)
class DeadWeightSession:
    """A dead-weight session read by :func:`read_dead_weights`.

    Attributes
    ----------
    path : Path
    config : SessionConfig
    reference : (H, W, 3) uint8 ndarray
        BGR.
    frame_paths : tuple of Path
        One per weight, in the order of ``weights.csv``.
    mass_kg, mass_std_kg : (N,) float64 ndarray
        Mass on the gel and its standard uncertainty (0 where not given), kg.
    notes : tuple of str
    """

    path: Path
    config: SessionConfig
    reference: np.ndarray = field(repr=False)
    frame_paths: tuple[Path, ...]
    mass_kg: np.ndarray
    mass_std_kg: np.ndarray
    notes: tuple[str, ...] = ()

    @property
    def force_n(self) -> np.ndarray:
        """(N,) float64 ndarray: P = m g, N."""
        return self.mass_kg * STANDARD_GRAVITY

    @property
    def force_std_n(self) -> np.ndarray:
        """(N,) float64 ndarray: the masses' uncertainty times g, N."""
        return self.mass_std_kg * STANDARD_GRAVITY

    def frames(self) -> np.ndarray:
        """Every frame, (N, H, W, 3) uint8 BGR."""
        return np.stack([read_image(p, colour_only=True) for p in self.frame_paths])


def read_dead_weights(path: str | Path) -> DeadWeightSession:
    """Read and check a dead-weight session folder (module docstring).

    Parameters
    ----------
    path : str or Path
        The folder.

    Returns
    -------
    DeadWeightSession

    Raises
    ------
    InputError
        Naming the file, line and column at fault: no session.toml or a bad key, an
        indenter that is not a ball, no reference.png, no weights.csv or a missing
        column, a frame that is not in frames/ or differs in size from the reference, a
        mass that is not a positive number or an uncertainty that is negative.
    """
    folder = Path(path)
    if not folder.is_dir():
        raise InputError(f"dead-weight session folder {folder} does not exist")
    config = _read_config(folder)
    if config.indenter_shape != "sphere":
        raise InputError(f"{folder / 'session.toml'}: [indenter] shape must be \"sphere\" for "
                         "dead weights (a ball resting on the gel, its depth read from its "
                         "contact circle)")
    ref_path = folder / "reference.png"
    if not ref_path.is_file():
        raise InputError(f"dead-weight session folder {folder} has no reference.png")
    reference = read_image(ref_path, colour_only=True)
    table = folder / "weights.csv"
    header, rows, lines = _read_csv(table, ("frame", "mass_kg"))
    mass = _numbers(table, header, rows, lines, "mass_kg")
    std = (_numbers(table, header, rows, lines, "mass_std_kg") if "mass_std_kg" in header
           else np.zeros_like(mass))
    for i, line in enumerate(lines):
        if mass[i] <= 0:
            raise InputError(f"{table} line {line}, column mass_kg: {mass[i]:g} (a mass must "
                             "be > 0 kg)")
        if std[i] < 0:
            raise InputError(f"{table} line {line}, column mass_std_kg: {std[i]:g} (an "
                             "uncertainty must be >= 0)")
    j = header.index("frame")
    paths = []
    for row, line in zip(rows, lines, strict=True):
        name = row[j].strip()
        p = folder / "frames" / name
        if not name or Path(name).name != name or not p.is_file():
            raise InputError(f"{table} line {line}, column frame: '{name}' is not a file in "
                             f"{folder / 'frames'}")
        try:
            with Image.open(p) as im:
                size = im.size
        except OSError:
            raise InputError(f"frame {p} is not a readable image") from None
        if size[::-1] != reference.shape[:2]:
            raise InputError(f"frame {p} is {size[0]} x {size[1]} px, the reference "
                             f"{reference.shape[1]} x {reference.shape[0]} px")
        paths.append(p)
    notes = _unknown_keys(folder) + [
        f"{table} line 1: column {c} is not read (weights.csv: frame, mass_kg, mass_std_kg)"
        for c in header if c not in ("frame", "mass_kg", "mass_std_kg")]
    return DeadWeightSession(path=folder, config=config, reference=reference,
                             frame_paths=tuple(paths), mass_kg=mass, mass_std_kg=std,
                             notes=tuple(notes))
