"""The CNC gauge block of the paper and the gel surface under one of its indenters.

The block (paper, Fig. 5; method.md) carries five flat-ended cylindrical
indenters of radius a protruding w0 = 0.15 ... 0.60 mm beyond the block's
reference plane (the "land"), each with a bevel beside it. Pressed to depth
w, the gel surface follows the finite-strain FEM
(:class:`~tactilevision.sim.PressProfile`): the flat footprint, the sink-in,
and the bulge that rises around the indenter.

The bevel as it is machined (``bevel_angle_deg`` theta > 0, the default): a
V-shaped ridge whose straight crest, of length ``bevel_length_mm``, lies in
the reference plane (w0 behind the indenter face) at ``bevel_offset_mm``
from the indenter axis in the direction ``bevel_direction_deg``, across that
direction; its two flanks fall away from the gel at theta on both sides of
the crest, and the rest of the block is relieved out of the gel's reach.
Pressed to w = w0 + delta, the crest lies delta into the gel and the gel
meets the flanks over the band ``|u| <= L``, ``|v| <= bevel_length_mm / 2``
(u along the direction from the crest, v along the crest) where the flank
reaches the gel surface: on a flat gel ``L = delta / tan(theta)``, the
vernier that :func:`tactilevision.contact.read_bevel` reads. Here the gel
surface is the FEM's, bulge included, so ``L tan(theta) = delta + b`` with
b the bulge height at the crest (:func:`tactilevision.contact.bulge_at`).
The gel is taken to conform to the rigid flanks where they reach it (the
clip ``max(gel, block)``): the elastic sink-in beside the band and the
band's own force are neglected (docs/guide/calibrate.md, "The bevel as a vernier").

The legacy drawn mark (``bevel_angle_deg = 0``, the sample session of
earlier versions): no vernier; a thin V-shaped line impression (depth
``bevel_depth_mm``, half-width ``bevel_width_mm / 2``) is drawn from the
moment the land meets the gel, decided by :attr:`GaugeBlock.land`:

- ``'ideal'``: the paper's premise, "the gel touches the block land:
  depth = w0 exactly".
- ``'bulge'``: a flat land that flattens the bulge where the gel would rise
  above it (a rigid clip); it first touches the bulge crest, at the depth
  w_c < w0 of :func:`~tactilevision.contact.land_contact_depth`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._checks import InputError
from ..contact import bulge_height
from ..fem import PressProfile

__all__ = ["GaugeBlock", "press_surface"]


@dataclass(frozen=True)
class GaugeBlock:
    """Geometry of the gauge block (lengths in mm, angles in degrees).

    Attributes
    ----------
    depths_mm : tuple of float
        w0 of each indenter (protrusion beyond the land); default the paper's.
    radius_mm : float
        Indenter radius a.
    bevel_offset_mm : float, default 9.0
        Distance from the indenter axis to the bevel's crest line (3 h for
        a 3 mm gel, where the bulge has fallen to about 2 % of w).
    bevel_direction_deg : float, default 0.0
        Direction from the indenter axis to the bevel in the image (0 = +x,
        along the columns; 90 = +y, down the rows).
    bevel_angle_deg : float, default 5.0
        Flank angle theta of the bevel ridge to the land; 0 for the legacy
        drawn mark (no vernier).
    bevel_length_mm : float, default 3.0
        Length of the crest line.
    bevel_width_mm, bevel_depth_mm : float
        Size of the legacy drawn mark (``bevel_angle_deg = 0`` only).
    land : {'ideal', 'bulge'}
        When the legacy mark shows (module docstring).
    """

    depths_mm: tuple[float, ...] = (0.15, 0.30, 0.40, 0.50, 0.60)
    radius_mm: float = 2.5
    bevel_offset_mm: float = 9.0
    bevel_direction_deg: float = 0.0
    bevel_angle_deg: float = 5.0
    bevel_length_mm: float = 3.0
    bevel_width_mm: float = 0.15
    bevel_depth_mm: float = 0.050
    land: str = "ideal"

    def __post_init__(self) -> None:
        if not 0.0 <= self.bevel_angle_deg < 45.0:
            raise InputError(f"bevel_angle_deg must be in [0, 45) degrees, got "
                             f"{self.bevel_angle_deg!r}")

    @property
    def vernier(self) -> bool:
        """Whether the bevel is a machined ridge (theta > 0) that reads the overshoot."""
        return self.bevel_angle_deg > 0

    def bevel_centre_mm(self) -> np.ndarray:
        """(x, y) of the bevel crest's middle relative to the indenter axis, mm."""
        t = np.deg2rad(self.bevel_direction_deg)
        return self.bevel_offset_mm * np.array([np.cos(t), np.sin(t)])


def press_surface(profile: PressProfile, block: GaugeBlock, *, indenter: int, depth_mm: float,
                  centre_px: tuple[float, float], shape: tuple[int, int], mm_per_px: float,
                  thickness_mm: float) -> tuple[np.ndarray, bool]:
    """Gel surface under one indenter of the block pressed to `depth_mm`.

    Parameters
    ----------
    profile : PressProfile
        FEM surface profiles for the gel's nu and a/h.
    block : GaugeBlock
    indenter : int
        Index into ``block.depths_mm``.
    depth_mm : float
        Indentation depth w of the indenter face, mm (0 = no contact).
    centre_px : (x, y)
        Indenter axis in the image (column, row), px.
    shape : (H, W)
    mm_per_px, thickness_mm : float

    Returns
    -------
    height_mm : (H, W) float32 ndarray
        Depth of the gel surface, mm, positive into the gel.
    land_contact : bool
        Whether the bevel touches the gel (the ridge's flanks meet it, or
        the legacy mark is drawn).

    Raises
    ------
    InputError
        For an unknown indenter.
    """
    if not 0 <= indenter < len(block.depths_mm):
        raise InputError(f"indenter {indenter} is not on the block (0 to "
                         f"{len(block.depths_mm) - 1})")
    h = float(thickness_mm)
    if depth_mm <= 0:
        return np.zeros(shape, np.float32), False
    z = profile.height_map(shape, mm_per_px, h, centre_px, depth_mm).astype(np.float64)
    land = depth_mm - block.depths_mm[indenter]          # land level, into the gel
    rows, cols = np.indices(shape, dtype=np.float64)
    dx = (cols - centre_px[0]) * mm_per_px
    dy = (rows - centre_px[1]) * mm_per_px
    t = np.deg2rad(block.bevel_direction_deg)
    u = dx * np.cos(t) + dy * np.sin(t) - block.bevel_offset_mm
    v = -dx * np.sin(t) + dy * np.cos(t)
    if block.vernier:
        # the ridge: crest `land` into the gel, flanks falling away at theta
        ridge = np.where(np.abs(v) <= 0.5 * block.bevel_length_mm,
                         land - np.abs(u) * np.tan(np.deg2rad(block.bevel_angle_deg)), -np.inf)
        touching = bool(np.any(ridge > z))
        return np.maximum(z, ridge).astype(np.float32), touching
    if block.land == "bulge":
        touching = land >= -bulge_height(profile, depth_mm / h)[0] * h
    elif block.land == "ideal":
        touching = land >= -1e-9
    else:
        raise InputError(f"land must be 'ideal' or 'bulge', got {block.land!r}")
    outside = np.hypot(dx, dy) > block.radius_mm
    if touching:
        if block.land == "bulge":
            z = np.where(outside, np.maximum(z, land), z)
        hw = 0.5 * block.bevel_width_mm
        on = (np.abs(u) < hw) & (np.abs(v) <= 0.5 * block.bevel_length_mm)
        z = z + np.where(on, block.bevel_depth_mm * (1.0 - np.abs(u) / hw), 0.0)
    return z.astype(np.float32), bool(touching)
