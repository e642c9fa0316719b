"""The CNC gauge block of the paper and the gel surface under one of its indenters.

The block (paper, Fig. 5; method.md) carries five flat-ended cylindrical
indenters of radius a protruding w0 = 0.15 ... 0.60 mm above the block land,
each with a bevel incision beside it. Pressed to depth w, the gel surface
follows the finite-strain FEM (:class:`~tactilevision.sim.PressProfile`):
the flat footprint, the sink-in, and the bulge that rises around the
indenter. The land lies ``w - w0`` into the gel.

Two land models (:attr:`GaugeBlock.land`):

- ``'ideal'`` (default): the paper's premise, "the gel touches the block
  land: depth = w0 exactly". The bevel shows when the indenter is w0 deep;
  the land is taken as relieved around the indenter, out of the bulge's
  reach.
- ``'bulge'``: a flat land. Where the gel would rise above it, the land
  flattens it (a rigid clip: its elastic spread and its force are neglected,
  which holds while it is only just touching); it first touches the bulge
  crest, at the depth w_c < w0 of :func:`~tactilevision.contact.land_contact_depth`
  (7 to 13% short of w0 for nu = 0.45 to 0.49 at a/h = 0.83).

What the camera shows when the land first touches is *drawn*: the bevel edge
appears as a thin V-shaped line impression beside the indenter (depth
``bevel_depth_mm``, half-width ``bevel_width_mm / 2``), present from the
first contact of the land on. The line is a visual marker of the land
contact, with no force; its onset, not its shape, is what certification
reads.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._checks import InputError
from ..contact._land import bulge_height
from ._press import PressProfile

__all__ = ["GaugeBlock", "press_surface"]


@dataclass(frozen=True)
class GaugeBlock:
    """Geometry of the gauge block (lengths in mm).

    Attributes
    ----------
    depths_mm : tuple of float
        w0 of each indenter (protrusion over the land); default the paper's.
    radius_mm : float
        Indenter radius a.
    bevel_offset_mm : float
        Distance from the indenter axis to the bevel edge (near the bulge
        crest of a 3 mm layer, 1.5 h).
    bevel_angle_deg : float
        Direction of the bevel from the indenter axis in the image (0 = +x,
        along the columns; 90 = +y, down the rows).
    bevel_length_mm, bevel_width_mm, bevel_depth_mm : float
        Size of the drawn bevel-edge line.
    land : {'ideal', 'bulge'}
        When the land meets the gel (module docstring).
    """

    depths_mm: tuple[float, ...] = (0.15, 0.30, 0.40, 0.50, 0.60)
    radius_mm: float = 2.5
    bevel_offset_mm: float = 4.5
    bevel_angle_deg: float = 0.0
    bevel_length_mm: float = 2.4
    bevel_width_mm: float = 0.15
    bevel_depth_mm: float = 0.050
    land: str = "ideal"

    def bevel_centre_mm(self) -> np.ndarray:
        """(x, y) of the bevel line's middle relative to the indenter axis, mm."""
        t = np.deg2rad(self.bevel_angle_deg)
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
        Whether the land touches the gel (the bevel line is drawn).

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
    if block.land == "bulge":
        touching = land >= -bulge_height(profile, depth_mm / h)[0] * h
    elif block.land == "ideal":
        touching = land >= -1e-9
    else:
        raise InputError(f"land must be 'ideal' or 'bulge', got {block.land!r}")
    rows, cols = np.indices(shape, dtype=np.float64)
    dx = (cols - centre_px[0]) * mm_per_px
    dy = (rows - centre_px[1]) * mm_per_px
    outside = np.hypot(dx, dy) > block.radius_mm
    if touching:
        if block.land == "bulge":
            z = np.where(outside, np.maximum(z, land), z)
        t = np.deg2rad(block.bevel_angle_deg)
        u = dx * np.cos(t) + dy * np.sin(t) - block.bevel_offset_mm
        v = -dx * np.sin(t) + dy * np.cos(t)
        hw = 0.5 * block.bevel_width_mm
        on = (np.abs(u) < hw) & (np.abs(v) <= 0.5 * block.bevel_length_mm)
        z = z + np.where(on, block.bevel_depth_mm * (1.0 - np.abs(u) / hw), 0.0)
    return z.astype(np.float32), bool(touching)
