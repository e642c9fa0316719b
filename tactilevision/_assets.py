"""Locate the default assets (``calibration/``, ``models/``).

In a source checkout or an editable install they are the top-level folders of
the repository; an installed wheel carries them inside the package as
``tactilevision/_assets/{calibration,models}`` (see ``pyproject.toml``).
"""

from __future__ import annotations

from pathlib import Path

from ._errors import InputError

__all__ = ["KNOWN_SENSORS", "asset_dir", "default_calibration_path"]

_PKG = Path(__file__).resolve().parent

#: Sensors with a default photometric calibration shipped in ``calibration/``.
KNOWN_SENSORS = ("gelsight",)


def asset_dir(kind: str) -> Path:
    """Return the folder holding the default assets of one kind.

    Parameters
    ----------
    kind : {'calibration', 'models'}
        Which asset folder.

    Returns
    -------
    path : Path
        The installed copy (``tactilevision/_assets/<kind>``) if present, else
        the repository's top-level folder.

    Raises
    ------
    FileNotFoundError
        If neither exists (a broken install).
    """
    if kind not in ("calibration", "models"):
        raise InputError(f"kind must be 'calibration' or 'models', got {kind!r}")
    for cand in (_PKG / "_assets" / kind, _PKG.parent / kind):
        if cand.is_dir():
            return cand
    raise FileNotFoundError(f"tactilevision asset folder '{kind}' not found next to {_PKG}")


def default_calibration_path(sensor: str) -> Path:
    """Path of the default photometric calibration of a sensor.

    Parameters
    ----------
    sensor : str
        Sensor name, one of :data:`KNOWN_SENSORS`.

    Returns
    -------
    path : Path
        ``calibration/<sensor>.npz``.

    Raises
    ------
    tactilevision.InputError
        For a sensor without a shipped calibration.
    """
    path = asset_dir("calibration") / f"{sensor}.npz"
    if sensor not in KNOWN_SENSORS or not path.is_file():
        raise InputError(
            f"no default calibration for sensor '{sensor}'; shipped: {', '.join(KNOWN_SENSORS)}"
            " (or pass --calibration FILE)"
        )
    return path
