"""Gradient tables: the fast per-frame path shared by the LUT and the tabulated MLP.

A table maps a quantised colour change (``bins^3`` cells) and, optionally, a
coarse pixel-position cell to the depth gradient (gx, gy). A frame is
looked up with a handful of whole-image operations; nothing is allocated
per frame that construction could prepare. Two sources fill it:

- a :class:`ColourLUT` (one position cell: the classic colour-only table);
- a position-aware network, evaluated once per (position cell, colour cell)
  at construction (:func:`tabulate_mlp`): the network's accuracy at the
  table's speed, up to the quantisation of colour and position.

A network's table may also be of first order (``order=1``): each colour cell
then holds the plane through the network's value at its centre with the
network's derivatives along the three colour axes (stored as the plane's value
at the colour origin and its slopes), and a pixel reads
``g0 + sum_c dg/dq_c q_c`` at its colour coordinates q: a piecewise-linear
table, which on gs_sdk's
GelSight Mini network removes most of what 32 colour cells cost (16 cells of
first order: 0.41 to 0.85 degrees median from the network inside the contacts
against 1.00 to 1.54 for 32 of order 0), at 0.03 to 0.15 ms more per 320 x 240
frame (one thread, ``benchmarks/bench_table_order.py``, 2-core x86_64, 2026-11-27).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from .._checks import InputError
from ._ball import gradients_from_normals
from ._features import channel_medians
from ._lut import ColourLUT
from ._mlp import MLPGradientModel, cell_position_inputs, mlp_inputs
from ._table_kernel import check_kernel, first_order_kernel

__all__ = ["GradientTable", "table_from_cell_luts", "table_from_lut", "tabulate_mlp"]


@dataclass
class GradientTable:
    """Quantised colour (and position cell) -> depth gradient.

    Attributes
    ----------
    gx_table, gy_table : (C * B^3,) float16 or float32 ndarray
        gx and gy per position cell and colour cell (row
        ``cell * B^3 + (q_0 B + q_1) B + q_2``).
    cell_offset : (H, W) int32 ndarray
        ``cell * B^3`` for each pixel.
    bins : int
        B, colour cells per channel.
    lo, hi : (3,) float32 ndarray
        Colour-change range over the bins.
    ref_inv : (H, W, 3) float32 ndarray
        Inverse reference (:func:`reference_inverse`).
    slopes : (C * B^3, 8) float32 ndarray or None
        A first-order table: per row the plane of its colour cell, (gx, gy)
        where the plane meets the colour origin (q = 0), then (dgx/dq_c,
        dgy/dq_c) for c = 0, 1, 2, derivatives per colour cell, so that a
        pixel of colour coordinates q in the row's cell reads
        ``g = row_0 + sum_c row_c q_c`` (nothing about its place inside the
        cell is computed per frame); ``gx_table, gy_table`` then hold the
        cells' centre values. None: order 0 (the centre value for the whole
        cell).
    """

    gx_table: np.ndarray
    gy_table: np.ndarray
    cell_offset: np.ndarray
    bins: int
    lo: np.ndarray
    hi: np.ndarray
    ref_inv: np.ndarray
    slopes: np.ndarray | None = None

    def __post_init__(self) -> None:
        k = (self.bins / (self.hi - self.lo)).astype(np.float32)
        self._scale_map = np.ascontiguousarray(self.ref_inv * k, dtype=np.float32)  # HxWx3
        self._offset = (-(1.0 + self.lo) * k).astype(np.float32)  # 3
        self._sub_ref_inv = np.ascontiguousarray(self.ref_inv[::8, ::8]).reshape(-1, 3)
        self._affine = np.zeros((3, 4), np.float32)
        self._top = float(self.bins) - 1e-3
        b = self.bins
        self._weights = np.array([[b * b, b, 1]], np.float32)
        self._single_cell = not np.any(self.cell_offset)
        self._rows = None
        self._kernel_in: tuple = ()
        if self.slopes is not None:
            # one gather of 32 bytes a pixel: the eight values of its row at once
            rows = np.ascontiguousarray(self.slopes, dtype=np.float32)
            self._rows = rows.view(np.dtype((np.void, 32))).ravel()
            # the compiled kernel's inputs: read-only C-order views, made once
            self._kernel_in = tuple(_read_only(a) for a in (
                self._scale_map, np.ascontiguousarray(self.cell_offset, dtype=np.int32), rows))

    @property
    def order(self) -> int:
        """0 for a table of cell values, 1 for one of values and slopes."""
        return 0 if self.slopes is None else 1

    def gradients(self, blurred: np.ndarray, *, normalise_gain: bool = True,
                  kernel: str = "numpy", window: tuple[int, int, int, int] | None = None
                  ) -> tuple[np.ndarray, np.ndarray]:
        """Look up one (already blurred) frame.

        Parameters
        ----------
        blurred : (H, W, 3) uint8 ndarray
            Frame, BGR, blurred as in calibration.
        normalise_gain : bool, default True
            Divide by the frame's per-channel gain (else g = 1: the
            calibration's ``normalise_gain``).
        kernel : {'numpy', 'auto', 'numba'}, default 'numpy'
            How a first-order table is read: 'numpy', whole-image OpenCV and
            numpy operations; 'numba', one compiled pass over the pixels with
            the same arithmetic (:func:`first_order_kernel`, the ``fast``
            extra; uint8 frames); 'auto', numba where installed. A table of
            order 0 is one gather either way.

        Returns
        -------
        gx, gy : (H, W) float32 ndarray
            Depth gradients.

        Raises
        ------
        InputError
            For an unknown `kernel`, or 'numba' without numba installed (a first-order
            table only).

        Notes
        -----
        With ratio = frame / reference and the per-channel gain g (median
        ratio over every 8th pixel), the colour cell of channel c is
        ``q_c = floor((ratio_c / g_c - 1 - lo_c) * k_c)``, ``k = B / (hi - lo)``,
        clipped to [0, B - 1], and the table row is ``(q_0 B + q_1) B + q_2``
        plus the pixel's position-cell offset. Computed as ``frame * (k /
        reference)`` (per-pixel factor prepared once), then one affine map per
        channel (``1 / g`` and the offset), clipping and flooring, all in
        OpenCV and numpy whole-image operations: about 2 ms at 640 x 480 on
        one core.
        """
        if normalise_gain:
            gain = channel_medians(blurred[::8, ::8].reshape(-1, 3) * self._sub_ref_inv)
        else:
            gain = np.ones(3, np.float32)
        scale_map, cell_offset, kernel_in = self._scale_map, self.cell_offset, self._kernel_in
        if window is not None:
            r0, r1, c0, c1 = (int(v) for v in window)
            blurred = blurred[r0:r1, c0:c1]
            scale_map, cell_offset = scale_map[r0:r1, c0:c1], cell_offset[r0:r1, c0:c1]
            if self._rows is not None:
                kernel_in = (_read_only(scale_map), _read_only(cell_offset.astype(np.int32)),
                             kernel_in[2])
        # only a first-order table has a compiled pass: an order-0 one never loads numba
        compiled = first_order_kernel(kernel) if self._rows is not None else check_kernel(kernel)
        if compiled is not None and blurred.dtype == np.uint8:
            gx = np.empty(blurred.shape[:2], np.float32)
            gy = np.empty_like(gx)
            coef = np.concatenate([np.float32(1.0) / gain, self._offset]).astype(np.float32)
            compiled(_read_only(blurred), kernel_in[0], _read_only(coef),
                     np.float32(self._top), int(self.bins), *kernel_in[1:], gx, gy)
            return gx, gy
        a = self._affine
        a[0, 0], a[1, 1], a[2, 2] = 1.0 / gain
        a[:, 3] = self._offset
        q = cv2.multiply(blurred, scale_map, dtype=cv2.CV_32F)  # HxWx3
        q = cv2.transform(q, a)
        cv2.threshold(q, self._top, self._top, cv2.THRESH_TRUNC, dst=q)
        cv2.threshold(q, 0.0, 0.0, cv2.THRESH_TOZERO, dst=q)
        if self._rows is not None:
            return self._first_order(q, cell_offset)
        np.floor(q, out=q)
        idx = cv2.transform(q, self._weights).astype(np.int32)  # HxW
        if not self._single_cell:
            idx += cell_offset
        # two 1-D tables: two lookups give contiguous gx, gy, which the Poisson
        # solver's differences read faster than strided views of one (H, W, 2)
        gx, gy = self.gx_table.take(idx, mode="wrap"), self.gy_table.take(idx, mode="wrap")
        if gx.dtype == np.float16:
            # OpenCV widens half floats exactly, five times faster than numpy's astype
            # (0.08 against 0.4 ms a component at 640 x 480, one thread)
            gx = cv2.add(gx, 0.0, dtype=cv2.CV_32F)
            gy = cv2.add(gy, 0.0, dtype=cv2.CV_32F)
        elif gx.dtype != np.float32:
            gx, gy = gx.astype(np.float32), gy.astype(np.float32)
        return gx, gy

    def _first_order(self, q: np.ndarray, cell_offset: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray]:
        """(gx, gy) of a first-order table from the colour coordinates q (h, w, 3) and the
        pixels' position-cell offsets (h, w)."""
        h, w = q.shape[:2]
        idx = cv2.transform(np.floor(q), self._weights).astype(np.int32)
        if not self._single_cell:
            idx += cell_offset
        # planes by transposing (N, 8) and (N, 3) pixel-major blocks: OpenCV's blocked
        # transpose takes a third of the time of cv2.split on eight channels
        # mode 'wrap': the rows are in range by construction, and numpy's wrapping gather
        # runs a quarter faster than its bounds-checked one (0.047 against 0.062 ms here)
        rows = self._rows.take(idx, mode="wrap").view(np.float32).reshape(h * w, 8)
        rows = cv2.transpose(rows)
        rows = rows.reshape(8, h, w)
        qc = cv2.transpose(q.reshape(h * w, 3)).reshape(3, h, w)
        gx, gy = rows[0], rows[1]
        for c in range(3):                            # fused multiply-adds, in place
            cv2.accumulateProduct(rows[2 + 2 * c], qc[c], gx)
            cv2.accumulateProduct(rows[3 + 2 * c], qc[c], gy)
        return gx, gy


def _read_only(a: np.ndarray) -> np.ndarray:
    """A read-only C-order view of `a` (a copy only where `a` is not C-ordered)."""
    v = np.ascontiguousarray(a).view()
    v.setflags(write=False)
    return v


def table_from_lut(lut: ColourLUT, ref_inv: np.ndarray) -> GradientTable:
    """Gradient table of a colour-only LUT (one position cell).

    Parameters
    ----------
    lut : ColourLUT
    ref_inv : (H, W, 3) float32 ndarray

    Returns
    -------
    table : GradientTable
    """
    nxy = lut.table.reshape(-1, 2)
    gx, gy = gradients_from_normals(nxy[:, 0], nxy[:, 1])
    return GradientTable(gx, gy, np.zeros(ref_inv.shape[:2], np.int32), lut.bins, lut.lo, lut.hi,
                         ref_inv)


def table_from_cell_luts(tables: np.ndarray, ref_inv: np.ndarray, *, lo: np.ndarray,
                         hi: np.ndarray) -> GradientTable:
    """Gradient table of per-position-cell LUTs (:func:`fit_cell_luts`).

    Parameters
    ----------
    tables : (ny, nx, B, B, B, 2) float ndarray
        (n_x, n_y) per position cell and colour cell; cell (i, j) covers
        columns ``[i W / nx, (i + 1) W / nx)`` and rows likewise.
    ref_inv : (H, W, 3) float32 ndarray
    lo, hi : (3,) float ndarray
        The tables' colour range.

    Returns
    -------
    table : GradientTable
        float32, ``nx ny B^3`` entries per component.
    """
    ny, nx, b = tables.shape[0], tables.shape[1], tables.shape[2]
    nxy = np.asarray(tables, np.float32).reshape(-1, 2)
    gx, gy = gradients_from_normals(nxy[:, 0], nxy[:, 1])
    h, w = ref_inv.shape[:2]
    rows = np.minimum((np.arange(h) * ny) // h, ny - 1)
    cols = np.minimum((np.arange(w) * nx) // w, nx - 1)
    cell = (rows[:, None] * nx + cols[None, :]).astype(np.int32) * np.int32(b**3)
    return GradientTable(gx.astype(np.float32), gy.astype(np.float32), cell, b,
                         np.asarray(lo, np.float32), np.asarray(hi, np.float32), ref_inv)


def tabulate_mlp(model: MLPGradientModel, ref_inv: np.ndarray, *, lo: np.ndarray,
                 hi: np.ndarray, bins: int = 32, cell_px: int = 40,
                 use_position: bool = True, order: int = 0) -> GradientTable:
    """Evaluate a position-aware network on a grid of position and colour cells.

    Parameters
    ----------
    model : MLPGradientModel
    ref_inv : (H, W, 3) float32 ndarray
        Inverse reference; the network's reference-colour input is the mean
        reference colour of each position cell and its position input the
        cell's centre (:func:`cell_position_inputs`): exactly what a network
        calibrated with ``position_cell_px = cell_px`` sees, so its table
        differs from it by the colour quantisation alone.
    lo, hi : (3,) float ndarray
        Colour-change range (the calibration data's).
    bins : int, default 32
        Colour cells per channel.
    cell_px : int, default 40
        Size of the square position cells, px (480 x 640 -> 12 x 16 cells).
        For a network of every pixel's own position and reference
        (``position_cell_px = 0``) the cells cost accuracy: on taxim's held-out
        real GelSight presses its table read 1.53 degrees median from it
        inside the contacts (``benchmarks/bench_table_engine.py``).
    use_position : bool, default True
        Whether the network takes the position (else one cell).
    order : {0, 1}, default 0
        0: the network's value at each colour cell's centre. 1: also its
        slopes along the three colour axes, central differences across the
        cell (half a cell either side of the centre: the chord), so that a
        pixel is read by the plane through them (:class:`GradientTable`);
        seven network evaluations per cell.

    Returns
    -------
    table : GradientTable
        ``C * bins^3`` entries per component, float16 (gradients to about
        0.1%); at 192 cells and 32 bins 25 MB. Of order 1, also ``slopes``
        (float32, 32 bytes a cell: at 192 cells and 16 bins 25 MB).

    Raises
    ------
    InputError
        For an order other than 0 or 1.
    """
    if order not in (0, 1):
        raise InputError(f"table order must be 0 or 1, got {order!r}")
    h, w = ref_inv.shape[:2]
    if not use_position:
        cell_px = max(h, w)
    ny, nx = -(-h // cell_px), -(-w // cell_px)
    lo = np.asarray(lo, np.float32)
    hi = np.asarray(hi, np.float32)
    centres = [lo[c] + (np.arange(bins) + 0.5) * (hi[c] - lo[c]) / bins for c in range(3)]
    grid = np.stack(np.meshgrid(*centres, indexing="ij"), axis=-1).reshape(-1, 3)
    # the cells' mean reference colour and centre, as a cell-snapped network sees them
    ref_cell, x_cell, y_cell = cell_position_inputs(1.0 / ref_inv, cell_px)
    step = (hi - lo) / bins                                   # one colour cell
    # the centres, then (order 1) half a cell below and above along each channel
    shifts = [np.zeros(3, np.float32)]
    if order == 1:
        for c in range(3):
            shifts += [-0.5 * step * np.eye(3, dtype=np.float32)[c],
                       0.5 * step * np.eye(3, dtype=np.float32)[c]]
    points = np.concatenate([grid + s for s in shifts]).astype(np.float32)
    n = len(grid)
    tables, slopes = [], []
    for cy in range(ny):
        for cx in range(nx):
            y0, x0 = cy * cell_px, cx * cell_px
            ref_colour = np.broadcast_to(ref_cell[y0, x0], points.shape)
            px = np.full(len(points), x_cell[y0, x0], np.float32)
            py = np.full(len(points), y_cell[y0, x0], np.float32)
            nxy = model.normals(mlp_inputs(points, ref_colour, px, py, (h, w),
                                           use_position=use_position))
            gx, gy = gradients_from_normals(nxy[:, 0], nxy[:, 1])
            tables.append((gx[:n].astype(np.float16), gy[:n].astype(np.float16)))
            if order == 1:
                slopes.append(_cell_slopes(gx.reshape(7, n), gy.reshape(7, n), bins))
    rows = np.minimum(np.arange(h) // cell_px, ny - 1)
    cols = np.minimum(np.arange(w) // cell_px, nx - 1)
    cell = (rows[:, None] * nx + cols[None, :]).astype(np.int32) * np.int32(bins**3)
    return GradientTable(np.concatenate([t[0] for t in tables]),
                         np.concatenate([t[1] for t in tables]), cell, bins, lo, hi, ref_inv,
                         slopes=np.concatenate(slopes) if order == 1 else None)


def _cell_slopes(gx: np.ndarray, gy: np.ndarray, bins: int) -> np.ndarray:
    """Rows of a first-order table from the network at the cells' centres and half a cell
    either side along each channel ((7, n) each, n = bins^3 in row order: centre, then
    -c0, +c0, -c1, +c1, -c2, +c2): (gx, gy) of each cell's plane at the colour origin,
    then (dgx/dq_c, dgy/dq_c) per cell (:class:`GradientTable`)."""
    out = np.empty((gx.shape[1], 8), np.float32)
    out[:, 0], out[:, 1] = gx[0], gy[0]
    r = np.arange(gx.shape[1])
    cells = (r // (bins * bins), (r // bins) % bins, r % bins)
    for c in range(3):
        dx, dy = gx[2 + 2 * c] - gx[1 + 2 * c], gy[2 + 2 * c] - gy[1 + 2 * c]
        out[:, 2 + 2 * c], out[:, 3 + 2 * c] = dx, dy
        centre = cells[c] + 0.5                      # the centre's colour coordinate
        out[:, 0] -= dx * centre                     # from the centre to the origin
        out[:, 1] -= dy * centre
    return out
