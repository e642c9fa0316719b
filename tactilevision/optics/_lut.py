"""The classic binned colour lookup table (GelSight; Johnson and Adelson 2009).

Colour change (3 channels) is quantised into ``bins^3`` cells; each cell holds
the mean in-plane normal (n_x, n_y) of the calibration pixels that fell in it.
Empty cells take their nearest filled neighbour, then the table is smoothed
lightly in colour space. Normals rather than gradients are averaged: they are
bounded, so steep, ambiguous cells do not blow up.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import distance_transform_edt, gaussian_filter

from .._checks import InputError, check_array

__all__ = ["ColourLUT", "fit_cell_luts", "fit_colour_lut"]


@dataclass(frozen=True)
class ColourLUT:
    """A fitted colour-to-normal lookup table.

    Attributes
    ----------
    table : (B, B, B, 2) float32 ndarray
        Mean (n_x, n_y) per colour cell.
    lo, hi : (3,) float32 ndarray
        Colour-change range mapped onto the bins, per channel.
    counts : (B, B, B) int64 ndarray
        Calibration pixels per cell (zero for filled-in cells).
    """

    table: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    counts: np.ndarray

    @property
    def bins(self) -> int:
        """Cells per colour channel."""
        return int(self.table.shape[0])

    def index(self, change: np.ndarray) -> np.ndarray:
        """Flat cell index of each colour.

        Parameters
        ----------
        change : (..., 3) float32 ndarray
            Colour change (see :func:`colour_change`).

        Returns
        -------
        idx : (...) int32 ndarray
            ``(q0 * B + q1) * B + q2`` with ``q_c`` the clipped bin of channel c.
        """
        b = self.bins
        scale = (b / (self.hi - self.lo)).astype(np.float32)
        q = ((change - self.lo) * scale).astype(np.int32)
        np.clip(q, 0, b - 1, out=q)
        return (q[..., 0] * b + q[..., 1]) * b + q[..., 2]

    def normals(self, change: np.ndarray) -> np.ndarray:
        """In-plane normal components for colour changes.

        Parameters
        ----------
        change : (..., 3) float32 ndarray
            Colour change.

        Returns
        -------
        nxy : (..., 2) float32 ndarray
            (n_x, n_y) of the unit normal ``(-gx, -gy, 1) / norm``.
        """
        return self.table.reshape(-1, 2)[self.index(change)]


def fit_colour_lut(change: np.ndarray, nxy: np.ndarray, *, bins: int = 32,
                   lo: np.ndarray | None = None, hi: np.ndarray | None = None,
                   smooth_sigma: float = 0.7) -> ColourLUT:
    """Fit a binned colour-to-normal table from labelled pixels.

    Parameters
    ----------
    change : (M, 3) float32 ndarray
        Colour change of the calibration pixels.
    nxy : (M, 2) float32 ndarray
        Their true in-plane normal components.
    bins : int, default 32
        Cells per channel.
    lo, hi : (3,) float ndarray, optional
        Colour range; default the 0.1 and 99.9 percentiles of ``change``.
    smooth_sigma : float, default 0.7
        Gaussian smoothing of the table in cells; 0 for none.

    Returns
    -------
    lut : ColourLUT

    Raises
    ------
    ShapeError
        If ``change`` and ``nxy`` do not match.
    """
    change = check_array(change, "change", [("M", 3)], dtype=np.floating, finite=True)
    nxy = check_array(nxy, "nxy", [(change.shape[0], 2)], dtype=np.floating, finite=True)
    if change.shape[0] < bins:
        raise InputError(f"need at least {bins} labelled pixels, got {change.shape[0]}")
    lo = np.percentile(change, 0.1, axis=0) if lo is None else np.asarray(lo)
    hi = np.percentile(change, 99.9, axis=0) if hi is None else np.asarray(hi)
    hi = np.maximum(hi, lo + 1e-3)
    empty = np.zeros((bins,) * 3 + (2,), np.float32)
    lut = ColourLUT(empty, lo.astype(np.float32), hi.astype(np.float32),
                    np.zeros((bins,) * 3, np.int64))
    idx = lut.index(change.astype(np.float32)).ravel()
    n = bins**3
    counts = np.bincount(idx, minlength=n)
    table = np.stack([np.bincount(idx, nxy[:, k], minlength=n) for k in range(2)], axis=-1)
    table /= np.maximum(counts, 1)[:, None]
    filled = (counts > 0).reshape((bins,) * 3)
    table = table.reshape((bins,) * 3 + (2,))
    _, nearest = distance_transform_edt(~filled, return_indices=True)
    table = table[tuple(nearest)]
    if smooth_sigma > 0:
        table = np.stack([gaussian_filter(table[..., k], smooth_sigma, mode="nearest")
                          for k in range(2)], axis=-1)
    return ColourLUT(table.astype(np.float32), lut.lo, lut.hi, counts.reshape((bins,) * 3))


def fit_cell_luts(x_px: np.ndarray, y_px: np.ndarray, change: np.ndarray, nxy: np.ndarray,
                  shape: tuple[int, int], cells: tuple[int, int], *, lo: np.ndarray,
                  hi: np.ndarray, bins: int = 32, grow: float = 0.5,
                  min_pixels: int = 2000, fallback: ColourLUT | None = None
                  ) -> tuple[np.ndarray, np.ndarray]:
    """One colour table per position cell: a LUT that knows where it is.

    A sensor lit from its edges shades the same normal differently across
    the pad, so a single colour table mixes positions. Here the image is cut
    into ``nx x ny`` cells and each gets its own table, fitted
    (:func:`fit_colour_lut`) on the labelled pixels inside the cell grown by
    `grow` cells on every side (neighbouring cells share data, so tables
    change smoothly and sparse cells still fill), all on one colour range.

    Parameters
    ----------
    x_px, y_px : (M,) ndarray
        Column and row of the labelled pixels.
    change : (M, 3) float32 ndarray
        Their colour change.
    nxy : (M, 2) float32 ndarray
        Their true in-plane normal components.
    shape : (H, W)
        Image size.
    cells : (nx, ny)
        Cells along x (columns) and y (rows).
    lo, hi : (3,) float ndarray
        Colour range of every table (the whole calibration's).
    bins : int, default 32
        Colour cells per channel.
    grow : float, default 0.5
        Training window: the cell grown by this many cell sizes per side.
    min_pixels : int, default 2000
        A cell whose window holds fewer labelled pixels takes `fallback`.
    fallback : ColourLUT, optional
        The table of such cells (the colour-only LUT); without one they
        raise.

    Returns
    -------
    tables : (ny, nx, B, B, B, 2) float32 ndarray
        Mean (n_x, n_y) per position cell and colour cell.
    fell_back : (ny, nx) bool ndarray
        Cells that took `fallback`.

    Raises
    ------
    ValueError
        For fewer than one cell along an axis, or a sparse cell without a
        fallback.
    """
    nx, ny = (int(c) for c in cells)
    if nx < 1 or ny < 1:
        raise InputError(f"cells must be at least (1, 1), got {cells!r}")
    h, w = shape
    cw, ch = w / nx, h / ny
    tables = np.empty((ny, nx) + (bins,) * 3 + (2,), np.float32)
    fell_back = np.zeros((ny, nx), bool)
    for j in range(ny):
        in_y = (y_px >= (j - grow) * ch) & (y_px < (j + 1 + grow) * ch)
        for i in range(nx):
            sel = in_y & (x_px >= (i - grow) * cw) & (x_px < (i + 1 + grow) * cw)
            if np.count_nonzero(sel) < max(min_pixels, bins):
                if fallback is None:
                    raise InputError(f"position cell ({i}, {j}) has {np.count_nonzero(sel)} "
                                     f"labelled pixels, fewer than {min_pixels}")
                tables[j, i] = fallback.table
                fell_back[j, i] = True
                continue
            tables[j, i] = fit_colour_lut(change[sel], nxy[sel], bins=bins, lo=lo, hi=hi).table
    return tables, fell_back
