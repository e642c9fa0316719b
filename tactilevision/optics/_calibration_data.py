"""The fields of a photometric calibration, below everything that reads them.

:class:`CalibrationData` holds what the reconstructor (:mod:`._reconstructor`)
and the training (:mod:`._training`) read and write; the public
:class:`~tactilevision.optics.PhotometricCalibration` (:mod:`._calibration`)
adds its constructors (ball presses, gs_sdk's network, a saved file) and its
file format on top of both.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from ._lut import ColourLUT

__all__ = ["CalibrationData", "ModelKind"]

ModelKind = Literal["lut", "mlp"]


@dataclass
class CalibrationData:
    """The fields of a :class:`~tactilevision.optics.PhotometricCalibration` (documented there)."""

    model: ModelKind
    reference: np.ndarray
    mm_per_px: float
    lut: ColourLUT | None = None
    cell_luts: np.ndarray | None = None
    onnx_bytes: bytes | None = None
    use_position: bool = True
    markers: bool = False
    blur_sigma: float = 0.0
    contact_threshold: float = 0.05
    reference_blur: float = 2.0
    normalise_gain: bool = True
    colour_lo: np.ndarray = field(default_factory=lambda: np.full(3, -0.5, np.float32))
    colour_hi: np.ndarray = field(default_factory=lambda: np.full(3, 0.5, np.float32))
    position_cell_px: int = 0
    table_lo: np.ndarray | None = None
    table_hi: np.ndarray | None = None
    table_order: int = 0
    provenance: dict[str, Any] = field(default_factory=dict)

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W) of the frames this calibration applies to."""
        return (int(self.reference.shape[0]), int(self.reference.shape[1]))
