"""``DepthReconstructor``: tactile frame -> gradients -> height map.

Built once from a :class:`PhotometricCalibration`; everything that does not
depend on the frame (reference inverse, the gradient table, the Poisson
eigenvalues, the network session) is prepared at construction, so a call
does only per-frame work.
"""

from __future__ import annotations

import functools
import hashlib
from collections import OrderedDict
from pathlib import Path
from typing import Literal

import cv2
import numpy as np
import onnxruntime

from .._blocks import (
    HEIGHT_BIN_PER_WIDTH,
    auto_binning,
    bin_blocks,
    check_binning,
    unbin_blocks,
)
from .._cache import cache_root, code_digest, savez_atomic, touch
from .._checks import InputError, check_array
from .._morphology import fill_holes as _fill_holes
from ._ball import gradients_from_normals
from ._calibration_data import CalibrationData
from ._features import (
    blur_frames,
    channel_magnitude,
    colour_change,
    median_last_axis,
    reference_inverse,
)
from ._markers import fill_masked_fields, marker_mask
from ._mlp import (
    MLPGradientModel,
    cell_position_inputs,
    default_position_cell_px,
    mlp_inputs,
)
from ._poisson import PoissonSolver, integrate_poisson_masked
from ._table import GradientTable, table_from_cell_luts, table_from_lut, tabulate_mlp
from ._table_kernel import check_kernel, first_order_kernel

__all__ = ["DepthReconstructor"]

Engine = Literal["table", "onnx"]
Boundary = Literal["neumann", "dirichlet", "contact"]
Kernel = Literal["auto", "numba", "numpy"]


class DepthReconstructor:
    """Height maps from tactile frames by photometric stereo.

    Parameters
    ----------
    calibration : PhotometricCalibration
        The sensor's colour-to-normal model.
    reference : (H, W, 3) uint8 ndarray or 'calibration', default 'calibration'
        Today's no-contact frame (BGR), of the calibration's size; by default
        (``'calibration'``) the calibration's own. A fresh reference absorbs
        slow changes of the lights and the gel. ``None`` is refused, never
        replaced: it is what ``cv2.imread`` returns for a missing file.
    engine : {'table', 'onnx'}, default 'table'
        How the colour-to-gradient model runs per frame. 'table': one
        lookup per pixel in a gradient table (a LUT calibration's own
        table, or an MLP tabulated over colour cells and position cells at
        construction, 2 to 3 s at 640 x 480 on 2 cores: the calibration's
        ``position_cell_px`` cells over its ``table_lo, table_hi`` range,
        where the network differs from its table by the colour cells alone;
        ``max(H, W) // 16`` px cells, at least 20, over ``colour_lo,
        colour_hi`` for a network of every pixel's own position). 'onnx':
        the MLP evaluated per pixel by onnxruntime (exact, about 60 times
        slower: 305 against 4.7 ms at 640 x 480, one thread,
        ``benchmarks/bench_speed.py``, 2-core x86_64, 2026-11-25).
    boundary : {'neumann', 'dirichlet', 'contact'}, default 'neumann'
        Poisson boundary condition. 'neumann' and 'dirichlet': the
        whole-image transform (:class:`PoissonSolver`), camera rate.
        'contact': zero height outside the frame's contact region
        (:meth:`contact_mask` with ``threshold='frame'`` and
        ``fill_holes=True``), integrated on that region only
        (:func:`integrate_poisson_masked`, conjugate gradients on its bounding
        box started from the previous frame's height; with the contact mask 5
        to 11 bare 'neumann' frames on the sample session):
        removes the slowly varying error of the whole-image integration
        (on the sample session's flat-punch frames the area above 0.02 mm
        falls from 111-125 mm^2 to 23-34 mm^2, the punch face being
        20 mm^2).
    table_bins : int, optional
        Colour cells per channel when tabulating an MLP: by default 32 for a
        table of order 0 and 16 for one of order 1.
    table_order : {0, 1}, optional
        Order of an MLP's table (:func:`tabulate_mlp`): 0, the network's
        value per colour cell; 1, its value and slopes along the colour
        axes, read as a plane inside the cell. Default: the calibration's
        ``table_order`` (1 for gs_sdk's networks, whose table of order 0
        read 1.00 to 1.54 degrees median from the network inside the
        contacts of a real GelSight Mini and of order 1 0.41 to 0.85, at
        about 1.3 times the per-frame cost: ``benchmarks/bench_table_order.py``).
    threads : int, default 1
        onnxruntime threads (1: one core, as embedded users run it).
    level : {'median', 'far_field'}, default 'median'
        Neumann only: how the height's zero is set. 'median': the frame's
        median is zero (the contact covering under half of it).
        'far_field': a Legendre surface of degree `level_degree` in x and
        y, fitted by least squares to the heights outside the frame's
        contact region (colour change above the frame's median plus 8
        robust sd, on a quarter-resolution copy, grown 12 px, holes filled),
        is subtracted: the undeformed gel is zero where it is seen, the
        integration's tilts and bowls removed (5 ms per 640 x 480 frame on
        one core on top of 12 ms; ``docs/absolute_depth.md``). When the
        contact covers over three quarters of the frame the median is kept.
    level_degree : int, default 4
        Degree of that surface.
    flat_reference : bool, default False
        Subtract, at every pixel, the gradient the model gives for the
        reference itself (zero colour change): the reference is the flat,
        undeformed gel by definition, so whatever the model reads there is
        its own bias (a position-aware network's offsets, a LUT's cell
        centre). Without it that bias integrates to a bowl of about 0.1 mm
        rms over the shipped GelSight calibration's frames.
    zero_background : bool, default False
        Before integrating, set the gradients outside the frame's contact
        region to zero, so the flat gel's noise does not integrate into the
        height map. The region: colour change above the frame's median plus
        8 robust sd on a quarter-resolution copy, grown 12 px (as for
        ``level='far_field'``), each region filled to its convex hull (a
        ball's ring, above the noise only where steep, is often open on its
        gentle side). Right while the contact covers under half of the
        frame (the median measures the noise); kept off when the region
        covers over three quarters of it. :meth:`gradients` is left as
        read; no effect with ``boundary='contact'``, which zeroes the height
        there. Meant for calibrations with fewer flat samples
        (``PhotometricCalibration.from_ball_presses(flat_fraction=0.003)``),
        which read gentle slopes in full but also read the flat gel's noise
        (``docs/guide/optics.md``, "Flat samples"). About 3 ms per
        640 x 480 frame on one core (14.1 against 11.3 ms without it in the
        same run, shipped GelSight network, ``benchmarks/bench_speed.py``,
        2-core AMD EPYC, 2026-11-23).
    kernel : {'auto', 'numba', 'numpy'}, default 'auto'
        How a first-order table (gs_sdk's networks) is read per frame: one
        compiled pass over the pixels where numba is installed (``pip install
        'tactilevision[fast]'``; :func:`~tactilevision.optics.first_order_kernel`),
        else whole-image OpenCV and numpy operations, with the same
        arithmetic. numba costs about 0.4 times the import of
        ``tactilevision.optics`` once per process (its import and the kernel
        read back from its disk cache; about as much again the first time
        it is compiled; see ``first_order_kernel``), paid here;
        'numpy' skips it for a few frames. 'numba' requires it for a
        first-order table. Other tables are one gather either way.
    binning : int or 'auto', default 1
        ``boundary='contact'`` only: the integration on k x k blocks of
        pixels (each block's mean gradient; a block is in the contact
        region when all its pixels are), the height returned on the
        frame's grid, constant over each block. 'auto': per frame, the
        largest k up to 8 with k pixels at most the contact region's width
        over 40 (:func:`~tactilevision.fem.auto_binning`; the region holds
        the footprint and the sink-in round it), as
        ``tactilevision forces`` (``--binning``), ``live`` and ``batch
        forces`` integrate by default before the force solve. 1: every
        pixel.

    Raises
    ------
    InputError
        For an unknown `engine`, `boundary`, `level`, `kernel` (or 'numba'
        without numba), a bad `level_degree`, `table_order`, `table_bins` or
        `binning` (or a `binning` other than 1 without ``boundary='contact'``), or a
        calibration without its model; :class:`~tactilevision.ShapeError` (an
        InputError) for a reference that is not uint8 BGR of the calibration's size.

    Notes
    -----
    Per frame: blur (uint8), colour change against the reference divided by
    the frame's per-channel gain, gradient lookup, marker fill (gels with
    markers), Poisson integration (:class:`PoissonSolver`), and the height
    zero set to the median of the frame (contact covering under half of it).

    Examples
    --------
    >>> recon = DepthReconstructor(PhotometricCalibration.load(path))  # doctest: +SKIP
    >>> height_mm = recon(frame)                                        # doctest: +SKIP
    >>> gx, gy = recon.gradients(frame)                                 # doctest: +SKIP
    """

    def __init__(self, calibration: CalibrationData, *,
                 reference: np.ndarray | str = "calibration", engine: Engine = "table",
                 boundary: Boundary = "neumann", table_bins: int | None = None,
                 table_order: int | None = None, threads: int = 1, flat_reference: bool = False,
                 level: Literal["median", "far_field"] = "median",
                 level_degree: int = 4, zero_background: bool = False,
                 kernel: Kernel = "auto", binning: int | str = 1) -> None:
        _check_options(engine, boundary, level, level_degree, kernel)
        self.binning = _check_binning(binning, boundary)
        self.kernel = kernel
        self.boundary = boundary
        self.level, self.level_degree = level, int(level_degree)
        self.zero_background = bool(zero_background)
        self._ref_inv_small: np.ndarray | None = None
        self._level_basis: tuple | None = None
        self.calibration = calibration
        self.shape = calibration.shape
        if reference is None:
            raise InputError("reference is None (cv2.imread returns None for a missing or "
                             "unreadable file); pass the no-contact frame as an (H, W, 3) uint8 "
                             "array, or reference='calibration' for the calibration's own")
        if isinstance(reference, str):
            if reference != "calibration":
                raise InputError(f"reference must be an (H, W, 3) uint8 array or "
                                 f"'calibration', got the string {reference!r}")
            reference = calibration.reference
        ref = check_array(reference, "reference", [(*self.shape, 3)], dtype=np.uint8)
        ref_mask = marker_mask(ref) if calibration.markers else None
        self._ref_inv = reference_inverse(ref, marker_mask=ref_mask,
                                          blur_sigma=calibration.reference_blur)
        # a quarter-resolution copy for level='far_field', on the grid of z[::4, ::4]
        self._small_size = ((self.shape[1] + 3) // 4, (self.shape[0] + 3) // 4)   # (w, h)
        small = cv2.resize(ref, self._small_size, interpolation=cv2.INTER_AREA)
        self._ref_inv_small = 1.0 / np.maximum(small.astype(np.float32), 1.0)
        self._mm = np.float32(calibration.mm_per_px)
        # heights in mm straight from the solve (mm per px folded into its eigenvalues)
        self._solver = PoissonSolver(self.shape,
                                     boundary="dirichlet" if boundary == "dirichlet" else "neumann",
                                     scale=float(self._mm))
        self._mlp = None
        self._table = None
        if calibration.model == "lut":
            if calibration.lut is None:
                raise InputError("LUT calibration without a table")
            if engine != "table":
                raise InputError("a LUT calibration runs only with engine='table'")
            if calibration.cell_luts is not None:
                self._table = table_from_cell_luts(calibration.cell_luts, self._ref_inv,
                                                   lo=calibration.lut.lo, hi=calibration.lut.hi)
            else:
                self._table = table_from_lut(calibration.lut, self._ref_inv)
        else:
            if calibration.onnx_bytes is None:
                raise InputError("MLP calibration without a network")
            self._mlp = MLPGradientModel(calibration.onnx_bytes, threads=threads)
            if engine == "table":  # tabulated once on all cores, and kept for the next
                order = calibration.table_order if table_order is None else table_order
                if order not in (0, 1):
                    raise InputError(f"table_order must be 0 or 1, got {table_order!r}")
                bins = (32 if order == 0 else 16) if table_bins is None else table_bins
                if isinstance(bins, bool) or not isinstance(bins, int | np.integer) or bins < 2:
                    raise InputError(f"table_bins must be an integer of at least 2, got "
                                     f"{table_bins!r}")
                if order == 1:   # compiled now (once per process), not on a frame
                    first_order_kernel(kernel)
                self._table = _tabulated(calibration, self._ref_inv, int(bins), int(order))
        self.engine = engine
        if engine == "onnx":
            h, w = self.shape
            if calibration.position_cell_px:   # the network sees each pixel's cell
                ref_in, x_in, y_in = cell_position_inputs(1.0 / self._ref_inv,
                                                          calibration.position_cell_px)
                self._xx, self._yy = x_in.ravel(), y_in.ravel()
                self._ref_colour = ref_in.reshape(-1, 3)
            else:
                self._yy, self._xx = (a.ravel() for a in np.mgrid[0:h, 0:w].astype(np.float32))
                self._ref_colour = (1.0 / self._ref_inv).reshape(-1, 3)
        self.flat_reference = bool(flat_reference)
        self._g0: tuple[np.ndarray, np.ndarray] | None = None
        self._last_contact_z: np.ndarray | None = None    # boundary='contact': warm start
        if self.flat_reference:
            self._g0 = self._one(ref)
        k = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (13, 13))
        self._dilate = k
        self._open = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))
        self._grow = cv2.getStructuringElement(cv2.MORPH_CROSS, (3, 3))
        # closes gaps under BRIDGED_GAP_PX on the quarter-resolution grid (a disc of radius
        # BRIDGED_GAP_PX / 8 quarter-resolution pixels closes gaps under twice its radius)
        r = BRIDGED_GAP_PX // 8
        self._bridge = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1))

    # ---------------------------------------------------------------- pieces
    def _one(self, frame: np.ndarray, window: tuple[int, int, int, int] | None = None
             ) -> tuple[np.ndarray, np.ndarray]:
        """(gx, gy) of one frame, or of its rows ``r0:r1`` and columns ``c0:c1`` for a
        `window` (a table only, without markers: :meth:`_gradient_window`)."""
        cal = self.calibration
        blurred = blur_frames(frame, cal.blur_sigma) if cal.blur_sigma > 0 else frame
        if self._table is not None:
            gx, gy = self._table.gradients(blurred, normalise_gain=cal.normalise_gain,
                                           kernel=self.kernel, window=window)
        else:
            change = colour_change(blurred, self._ref_inv,
                                   normalise_gain=cal.normalise_gain).reshape(-1, 3)
            inputs = mlp_inputs(change, self._ref_colour, self._xx, self._yy, self.shape,
                                use_position=cal.use_position)
            nxy = self._mlp.normals(inputs)
            gx, gy = gradients_from_normals(nxy[:, 0], nxy[:, 1])
            gx, gy = gx.reshape(self.shape), gy.reshape(self.shape)
        if self._g0 is not None:
            g0x, g0y = self._g0
            if window is not None:
                r0, r1, c0, c1 = window
                g0x, g0y = g0x[r0:r1, c0:c1], g0y[r0:r1, c0:c1]
            gx, gy = gx - g0x, gy - g0y
        if cal.markers:
            gx, gy = fill_masked_fields([gx, gy], marker_mask(frame))
        return gx, gy

    def _height(self, frame: np.ndarray) -> np.ndarray:
        """One frame's height map, mm."""
        if self.boundary == "contact":
            return self._contact_height(frame)
        return self._integrate(*self._one(frame), frame)

    def _contact_height(self, frame: np.ndarray) -> np.ndarray:
        """``boundary='contact'``: the height solved on the frame's contact region, zero
        outside it, its gradients looked up only where the solve reads them
        (:meth:`_gradient_window`)."""
        mask = self.contact_mask(frame, threshold="frame", fill_holes=True)
        k = (auto_binning(mask, HEIGHT_BIN_PER_WIDTH) if self.binning == "auto"
             else self.binning)
        window = self._gradient_window(mask, k)
        if window is None:
            gx, gy = self._one(frame)
        else:
            # zero outside the window: the solve reads no gradient there
            r0, r1, c0, c1 = window
            wx, wy = self._one(frame, window) if r1 > r0 else (None, None)
            if k > 1:
                grid = (-(-self.shape[0] // k), -(-self.shape[1] // k))
                gx, gy = np.zeros(grid, np.float32), np.zeros(grid, np.float32)
                if wx is not None:
                    # the window's edges lie on the blocks' (or the image's): its blocks
                    # are the whole image's
                    rows = slice(r0 // k, -(-r1 // k))
                    cols = slice(c0 // k, -(-c1 // k))
                    gx[rows, cols], gy[rows, cols] = bin_blocks(wx, k), bin_blocks(wy, k)
            else:
                gx, gy = np.zeros(self.shape, np.float32), np.zeros(self.shape, np.float32)
                if wx is not None:
                    gx[r0:r1, c0:c1], gy[r0:r1, c0:c1] = wx, wy
        return self._contact_solve(gx, gy, mask, k, binned=window is not None)

    def _gradient_window(self, mask: np.ndarray, k: int
                         ) -> tuple[int, int, int, int] | None:
        """The rows and columns ``(r0, r1, c0, c1)`` whose gradients the contact's solve
        reads: the k x k blocks of the contact region `mask` and one block round them (the
        divergence's central differences), on the blocks' grid; ``(0, 0, 0, 0)`` for no
        contact; None where the whole frame is looked up (a network without its table,
        or markers, which are filled from the whole frame)."""
        if self._table is None or self.calibration.markers:
            return None
        rows = np.flatnonzero(mask.any(axis=1))
        if rows.size == 0:
            return (0, 0, 0, 0)
        cols = np.flatnonzero(mask.any(axis=0))
        H, W = self.shape
        r0, r1 = max(0, (int(rows[0]) // k - 1) * k), min(H, (int(rows[-1]) // k + 2) * k)
        c0, c1 = max(0, (int(cols[0]) // k - 1) * k), min(W, (int(cols[-1]) // k + 2) * k)
        return r0, r1, c0, c1

    def _contact_solve(self, gx: np.ndarray, gy: np.ndarray, mask: np.ndarray, k: int, *,
                       binned: bool) -> np.ndarray:
        """The contact-pinned integration of (gx, gy) on the region `mask` (pixels) on k x k
        blocks; `binned`: the gradients are on the blocks' grid already (block means)."""
        # warm-started from the previous frame's height (pixel units): a video's next
        # frame is close to it, and a guess further off than zero is not used
        if k > 1:
            # on k x k blocks: each block's mean slope times k is the height step from
            # one block to the next; a block is in the region when all its pixels are,
            # so that the zero beyond it lies, on average, where every pixel's does
            # (the first block not wholly in the region: its centre (k - 1) / 2 px
            # beyond the first pixel outside, less r for r from 0 to k - 1)
            if not binned:
                gx, gy = bin_blocks(gx, k), bin_blocks(gy, k)
            gx, gy = gx * np.float32(k), gy * np.float32(k)
            mask = bin_blocks(mask.view(np.uint8).astype(np.float32), k,
                              edge="zero") > np.float32(1 - 1e-3)
        z0 = self._last_contact_z
        z = integrate_poisson_masked(gx, gy, mask, tol=_CONTACT_TOL,
                                     z0=z0 if z0 is not None and z0.shape == mask.shape
                                     else None)
        self._last_contact_z = z.copy()
        z *= self._mm
        if k > 1:
            z = np.ascontiguousarray(unbin_blocks(z, k, self.shape))
        return z

    def _integrate(self, gx: np.ndarray, gy: np.ndarray, frame: np.ndarray) -> np.ndarray:
        """The whole frame's height ('neumann' or 'dirichlet'), mm."""
        far_field = self.level == "far_field" and self.boundary == "neumann"
        grown = self._contact_small(frame) if far_field or self.zero_background else None
        if self.zero_background:
            keep = self._hull(grown)
            if keep.mean() <= 0.75:        # else the contact covers the frame: keep all
                h, w = self.shape
                keep = cv2.resize(keep, (w, h), interpolation=cv2.INTER_NEAREST).view(bool)
                gx, gy = gx * keep, gy * keep
        z = self._solver.solve_unchecked(gx, gy)    # mm; the gradients are its own
        if far_field:
            z = self._level_far_field(z, grown)
        return z

    def _contact_small(self, frame: np.ndarray) -> np.ndarray:
        """The frame's contact region on the quarter-resolution grid of z[::4, ::4]: colour
        change above the frame's median + 8 robust sd, grown by 3 samples (12 px); uint8."""
        # every 4th pixel: the full-resolution contact_mask costs 10 times the Poisson solve
        small = cv2.resize(frame, self._small_size, interpolation=cv2.INTER_AREA)
        mag = channel_magnitude(small.astype(np.float32) * self._ref_inv_small - 1.0)
        med = float(np.median(mag))
        thr = med + 8.0 * 1.4826 * float(np.median(np.abs(mag - med))) + 1e-3
        return cv2.dilate((mag > thr).view(np.uint8), self._grow, iterations=3)

    @staticmethod
    def _hull(grown: np.ndarray) -> np.ndarray:
        """Each region of `grown` filled to its convex hull (uint8): a ball's contact ring,
        seen above the noise only where steep and so often open on its gentle side, is
        closed over its middle, which ``binary_fill_holes`` leaves out."""
        contours, _ = cv2.findContours(grown, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
        out = np.zeros_like(grown)
        for c in contours:
            cv2.fillPoly(out, [cv2.convexHull(c)], 1)
        return out

    def _level_far_field(self, z: np.ndarray, grown: np.ndarray) -> np.ndarray:
        """Subtract the polynomial surface fitted to z outside the contact region `grown`,
        its holes filled (a flat face changes no colour)."""
        step = 4
        d = self.level_degree
        free = ~_fill_holes(grown)
        if free.mean() < 0.25:                 # the contact covers the frame: keep the median
            return z
        if self._level_basis is None:
            h, w = z.shape
            vy = np.polynomial.legendre.legvander(np.linspace(-1.0, 1.0, h), d)   # (H, d+1)
            vx = np.polynomial.legendre.legvander(np.linspace(-1.0, 1.0, w), d)   # (W, d+1)
            terms = [(i, j) for i in range(d + 1) for j in range(d + 1 - i)]      # P_i(y) P_j(x)
            sy, sx = vy[::step][:, None, :], vx[::step][None, :, :]
            design = np.stack([sy[..., i] * sx[..., j] for i, j in terms], axis=-1)
            self._level_basis = (vy.astype(np.float32), vx.astype(np.float32), terms,
                                 design.astype(np.float32))
        vy, vx, terms, design = self._level_basis
        A = design[free]
        b = z[::step, ::step][free]
        coef = np.linalg.solve((A.T @ A).astype(np.float64), (A.T @ b).astype(np.float64))
        C = np.zeros((d + 1, d + 1), np.float32)
        for (i, j), c in zip(terms, coef, strict=True):
            C[i, j] = c
        return z - (vy @ C @ vx.T).astype(z.dtype)

    def _check(self, frames: np.ndarray) -> np.ndarray:
        return check_array(frames, "frame", [(*self.shape, 3), ("N", *self.shape, 3)],
                           dtype=np.uint8)

    # ---------------------------------------------------------------- public
    def gradients(self, frames: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Surface gradients of one frame or a batch.

        Parameters
        ----------
        frames : (H, W, 3) or (N, H, W, 3) uint8 ndarray
            Tactile frames, BGR, the calibration's size.

        Returns
        -------
        gx, gy : ([N, ]H, W) float32 ndarray
            d(depth)/dx along columns and d(depth)/dy along rows, mm per mm,
            depth positive into the gel.

        Raises
        ------
        ShapeError
            If the frame is not uint8 BGR of the calibration's size.
        """
        frames = self._check(frames)
        if frames.ndim == 3:
            return self._one(frames)
        out = [self._one(f) for f in frames]
        return np.stack([o[0] for o in out]), np.stack([o[1] for o in out])

    def __call__(self, frames: np.ndarray) -> np.ndarray:
        """Height map of one frame or a batch.

        Parameters
        ----------
        frames : (H, W, 3) or (N, H, W, 3) uint8 ndarray
            Tactile frames, BGR, the calibration's size.

        Returns
        -------
        height : ([N, ]H, W) float32 ndarray
            Depth into the gel, mm (positive where pressed in); zero median
            over the frame ('neumann'), zero at the border ('dirichlet') or
            zero outside the contact region ('contact').

        Raises
        ------
        ShapeError
            If the frame is not uint8 BGR of the calibration's size.
        """
        frames = self._check(frames)
        if frames.ndim == 3:
            return self._height(frames)
        return np.stack([self._height(f) for f in frames])

    def out_of_range(self, frames: np.ndarray) -> np.ndarray:
        """Pixels whose colour lies outside what the calibration saw.

        The colour change, read as the model reads it (after the calibration's
        blur), outside the calibration's range ``[colour_lo, colour_hi]`` (the
        0.1 and 99.9 percentiles of its labelled pixels) in any channel: the
        table clips such colours to its edge and the network was not trained
        on them, so their slopes are extrapolated, typically too shallow (a
        rim steeper than the calibration's steepest, a shadow, a foreign
        object).

        Parameters
        ----------
        frames : (H, W, 3) or (N, H, W, 3) uint8 ndarray
            Tactile frames, BGR.

        Returns
        -------
        mask : ([N, ]H, W) bool ndarray
            Marker pixels excluded.

        Raises
        ------
        ShapeError
            If the frame is not uint8 BGR of the calibration's size.
        """
        frames = self._check(frames)
        cal = self.calibration
        one = frames[None] if frames.ndim == 3 else frames
        masks = []
        for f in one:
            m = self._out_of_range(colour_change(f, self._ref_inv, blur_sigma=cal.blur_sigma))
            if cal.markers:
                m &= ~marker_mask(f)
            masks.append(m)
        return masks[0] if frames.ndim == 3 else np.stack(masks)

    def _out_of_range(self, change: np.ndarray) -> np.ndarray:
        """Pixels of a colour change (H, W, 3) outside the calibration's range in any
        channel (bool): the complement of OpenCV's inRange over all three at once."""
        cal = self.calibration
        inside = cv2.inRange(change, tuple(float(v) for v in np.float32(cal.colour_lo)),
                             tuple(float(v) for v in np.float32(cal.colour_hi)))
        return inside == 0

    def contact_and_out_of_range(self, frame: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`contact_mask` (at the calibration's threshold) and :meth:`out_of_range`
        of one frame, from one colour change: what ``reconstruct`` and ``batch`` summarise
        per frame.

        Parameters
        ----------
        frame : (H, W, 3) uint8 ndarray
            Tactile frame, BGR.

        Returns
        -------
        contact, out_of_range : (H, W) bool ndarray
            Equal to ``contact_mask(frame)`` and ``out_of_range(frame)``.

        Raises
        ------
        ShapeError
            If the frame is not one uint8 BGR frame of the calibration's size.
        """
        frame = check_array(frame, "frame", [(*self.shape, 3)], dtype=np.uint8)
        cal = self.calibration
        change = colour_change(frame, self._ref_inv, blur_sigma=cal.blur_sigma)
        outside = self._out_of_range(change)
        markers = marker_mask(frame) if cal.markers else None
        if markers is not None:
            outside &= ~markers
        return self._grown(channel_magnitude(change) > cal.contact_threshold, markers), outside

    def _grown(self, above: np.ndarray, markers: np.ndarray | None) -> np.ndarray:
        """A contact mask from the pixels above the threshold (bool, (H, W)): marker pixels
        out, opened (5 px) against specks and grown by 6 px."""
        m = above.astype(np.uint8)
        if markers is not None:
            m[markers] = 0
        m = cv2.morphologyEx(m, cv2.MORPH_OPEN, self._open)
        return cv2.dilate(m, self._dilate).astype(bool)

    def contact_mask(self, frames: np.ndarray, *,
                     threshold: float | Literal["calibration", "frame"] = "calibration",
                     fill_holes: bool = False) -> np.ndarray:
        """Pixels whose colour change exceeds the noise level.

        Parameters
        ----------
        frames : (H, W, 3) or (N, H, W, 3) uint8 ndarray
            Tactile frames, BGR.
        threshold : float or {'calibration', 'frame'}, default 'calibration'
            Colour-change level (max over channels, relative to the
            reference). 'calibration': the calibration's
            ``contact_threshold`` (99.9th percentile of its frames'
            no-contact change). 'frame': from the frame itself, its median
            change plus 8 robust standard deviations (1.4826 x the median
            absolute deviation) over every 3rd row and column, after a
            1.5 px blur; right while the
            contact covers under half of the frame, and the better choice
            when today's frames are cleaner or noisier than the
            calibration's.
        fill_holes : bool, default False
            Also take in regions enclosed by the mask: a flat indenter's
            face has no slope and so no colour change, but is ringed by its
            edge (:func:`scipy.ndimage.binary_fill_holes`); a ring whose gaps
            are under :data:`BRIDGED_GAP_PX` (24 px) counts as closed (a side
            of the ring faint under the light's direction), its gaps left out.

        Returns
        -------
        mask : ([N, ]H, W) bool ndarray
            Colour change above the threshold, opened (5 px) against specks
            and grown by 6 px; marker pixels excluded.

        Raises
        ------
        ShapeError
            If the frame is not uint8 BGR of the calibration's size.
        ValueError
            For an unknown `threshold` string or a non-positive number.
        """
        if isinstance(threshold, str):
            if threshold not in ("calibration", "frame"):
                raise InputError("threshold must be 'calibration', 'frame' or a number, got "
                                 f"{threshold!r}")
        elif not float(threshold) > 0:
            raise InputError(f"threshold must be positive, got {threshold}")
        frames = self._check(frames)
        cal = self.calibration
        one = frames[None] if frames.ndim == 3 else frames
        masks = []
        for f in one:
            if threshold == "frame":
                mag = channel_magnitude(colour_change(f, self._ref_inv,
                                                      blur_sigma=max(cal.blur_sigma, 1.5)))
                # the median and its deviation over every 3rd row and column (a ninth of
                # the pixels, every position of JPEG's 8 x 8 blocks): within 0.7 % of the
                # whole frame's threshold on the sample session's presses, a seventh of
                # the cost (every 4th: 1 to 4 % low, the same place in every block)
                sample = np.ascontiguousarray(mag[::3, ::3]).ravel()    # a copy
                med = float(median_last_axis(sample))                   # partitions it
                thr = med + 8.0 * 1.4826 * float(median_last_axis(np.abs(sample - med)))
            else:
                mag = channel_magnitude(colour_change(f, self._ref_inv,
                                                      blur_sigma=cal.blur_sigma))
                thr = cal.contact_threshold if threshold == "calibration" else float(threshold)
            m = self._grown(mag > thr, marker_mask(f) if cal.markers else None)
            masks.append(self._filled(m) if fill_holes else m)
        return masks[0] if frames.ndim == 3 else np.stack(masks)

    def _filled(self, mask: np.ndarray) -> np.ndarray:
        """`mask` (bool, (H, W)) with its holes filled, and those of a ring whose gaps are
        under :data:`BRIDGED_GAP_PX` wide: a flat face's ring of colour change faint on one
        side (a light from the other) misses closure by a few pixels, and its face (no
        change of its own) would be left out of the contact, its heights pinned at zero.
        The gaps are bridged on the quarter-resolution grid (a closing), only the region
        they enclose is taken in; the gap itself stays out."""
        if not mask.any():                # a frame without contact: nothing to fill
            return mask.copy()
        h, w = self.shape
        # a quarter-resolution pixel is in when any of its pixels is (255 / 16 rounds up)
        small = cv2.resize(np.multiply(mask.view(np.uint8), np.uint8(255)), self._small_size,
                           interpolation=cv2.INTER_AREA) > 0
        closed = cv2.morphologyEx(small.view(np.uint8), cv2.MORPH_CLOSE, self._bridge)
        enclosed = _fill_holes(closed) & ~closed.view(bool)
        if not enclosed.any():
            return _fill_holes(mask)
        # the enclosed region grown by one quarter-resolution pixel (to meet the ring's
        # inner edge), back on the image's grid, then the holes filled as ever
        grown = cv2.dilate(enclosed.view(np.uint8), self._grow)
        up = cv2.resize(grown, (w, h), interpolation=cv2.INTER_NEAREST)
        return _fill_holes(mask | up.view(bool))


#: contact_mask(fill_holes=True): a ring of the mask whose gaps are narrower than this
#: (px) counts as closed, its inside taken into the contact (twice the mask's own growth,
#: 6 px a side, which closes gaps of 12 px by itself).
BRIDGED_GAP_PX = 24

#: boundary='contact': the masked integration's relative residual. On the sample session's
#: 60 frames of presses (``python benchmarks/bench_forces_default.py --rate``'s) 1e-4 moved
#: the footprint force maps by under 3e-4 of their peak and the totals by under 2e-6
#: against 1e-6, in about half the iterations.
_CONTACT_TOL = 1e-4

#: The last few MLP tabulations (about 25 MB each at 640 x 480), by network, reference and
#: bins: a second reconstructor of the same sensor (a pipeline's, a CLI command's after
#: another) reuses the table instead of evaluating the network again (2 to 3 s).
_TABLES: OrderedDict[tuple, object] = OrderedDict()
_TABLES_KEPT = 2

#: Bump when the stored tabulation or its meaning changes: old files then miss.
_TABLE_FORMAT = 3       # 3: first-order rows hold their plane at the colour origin

#: The modules whose code decides a network's tabulation: the tabulation itself and the
#: network's inputs and the gradients from its normals (their syntax trees enter the disk
#: cache's key).
TABLE_SOURCES = ("_table.py", "_mlp.py", "_ball.py")


@functools.lru_cache(maxsize=1)
def _table_source_digest() -> str:
    """SHA-256 of :data:`TABLE_SOURCES`' code, docstrings and comments left out."""
    here = Path(__file__).resolve().parent
    return code_digest(*(here / name for name in TABLE_SOURCES))


def _table_cache_path(key: tuple):
    """``<cache root>/optics/mlp_table_<sha256>.npz``: the root is ``$TACTILEVISION_CACHE``
    if set, else ``~/.cache/tactilevision`` (the FEM cache's); the digest covers the
    network, the reference, the colour range, the bins, the position input, the format,
    the code that tabulates (:data:`TABLE_SOURCES`) and the onnxruntime version that
    evaluated the network."""
    h = hashlib.sha256(repr((_TABLE_FORMAT, _table_source_digest(), onnxruntime.__version__,
                             key)).encode())
    return cache_root() / "optics" / f"mlp_table_{h.hexdigest()}.npz"


def _check_binning(binning: object, boundary: str) -> int | str:
    """`binning` checked (:func:`~tactilevision._blocks.check_binning`), above 1 only with
    'contact'."""
    binning = check_binning(binning)
    if binning != 1 and boundary != "contact":
        raise InputError(f"binning = {binning!r} applies to boundary='contact' only; use 1")
    return binning


def _check_options(engine: str, boundary: str, level: str, level_degree: int,
                   kernel: str) -> None:
    """:class:`DepthReconstructor`'s choices, each one of its own (InputError naming it)."""
    if engine not in ("table", "onnx"):
        raise InputError(f"engine must be 'table' or 'onnx', got {engine!r}")
    if boundary not in ("neumann", "dirichlet", "contact"):
        raise InputError("boundary must be 'neumann', 'dirichlet' or 'contact', got "
                         f"{boundary!r}")
    if level not in ("median", "far_field"):
        raise InputError(f"level must be 'median' or 'far_field', got {level!r}")
    if not 0 <= int(level_degree) <= 8:
        raise InputError(f"level_degree must be 0 to 8, got {level_degree!r}")
    check_kernel(kernel)


def _read_table(path, ref_inv: np.ndarray, bins: int, order: int = 0):
    """The tabulation stored at `path`, or None (a miss, or a file that cannot be trusted)."""
    try:
        with np.load(path, allow_pickle=False) as data:
            gx, gy, cell = data["gx_table"], data["gy_table"], data["cell_offset"]
            lo, hi, b = data["lo"], data["hi"], int(data["bins"])
            slopes = data["slopes"] if order == 1 else None
    except Exception:          # missing, truncated, damaged or of another layout
        return None
    if (b != bins or cell.shape != ref_inv.shape[:2] or gx.shape != gy.shape
            or not (np.all(np.isfinite(gx)) and np.all(np.isfinite(gy)))):
        return None
    if slopes is not None and (slopes.shape != (gx.size, 8)
                               or not np.all(np.isfinite(slopes))):
        return None
    touch(path)                          # used: evicted last (tactilevision._cache)
    return GradientTable(gx, gy, cell, b, lo, hi, ref_inv, slopes=slopes)


def _write_table(path, table) -> None:
    """Store a tabulation atomically; a folder that cannot be written is skipped."""
    extra = {} if table.slopes is None else {"slopes": table.slopes}
    savez_atomic(path, gx_table=table.gx_table, gy_table=table.gy_table,
                 cell_offset=table.cell_offset, lo=np.asarray(table.lo),
                 hi=np.asarray(table.hi), bins=np.int64(table.bins), **extra)


def table_domain(calibration) -> tuple[np.ndarray, np.ndarray, int]:
    """The colour range (lo, hi: (3,) float32) and the position cell (px) of a network's
    table: the calibration's table range and position cells where it has them, else its
    colour range and :func:`default_position_cell_px` cells (a network of every pixel's
    own position: 20 px at 320 x 240, where 40 px cells read gs_sdk's GelSight Mini network
    1.17 to 1.97 degrees median from its own gradients inside the contacts and 20 px cells
    1.00 to 1.54, tables of order 0; 40 px at 640 x 480 as before)."""
    if calibration.table_lo is not None and calibration.table_hi is not None:
        lo, hi = calibration.table_lo, calibration.table_hi
    else:
        lo, hi = calibration.colour_lo, calibration.colour_hi
    cell_px = int(calibration.position_cell_px) or default_position_cell_px(
        calibration.shape)
    return np.asarray(lo, np.float32), np.asarray(hi, np.float32), cell_px


def _tabulated(calibration, ref_inv: np.ndarray, bins: int, order: int = 0):
    """The network's gradient table (of `order`) for `ref_inv`: from memory, else from the
    disk cache, else tabulated (and kept in both)."""
    lo, hi, cell_px = table_domain(calibration)
    key = (hashlib.blake2b(calibration.onnx_bytes, digest_size=16).digest(),
           hashlib.blake2b(np.ascontiguousarray(ref_inv).tobytes(), digest_size=16).digest(),
           ref_inv.shape, tuple(lo.tolist()), tuple(hi.tolist()), int(bins),
           bool(calibration.use_position), cell_px, int(order))
    if key in _TABLES:
        _TABLES.move_to_end(key)
        return _TABLES[key]
    # then the disk cache (a CLI command or a worker process starts without the table in
    # memory), else the network over every colour cell
    path = _table_cache_path(key)
    table = _read_table(path, ref_inv, bins, order)
    if table is None:
        table = tabulate_mlp(MLPGradientModel(calibration.onnx_bytes, threads=0), ref_inv,
                             lo=lo, hi=hi, bins=bins, cell_px=cell_px,
                             use_position=calibration.use_position, order=order)
        _write_table(path, table)
    for arr in (table.gx_table, table.gy_table, table.cell_offset, table.slopes):
        if arr is not None:
            arr.setflags(write=False)             # shared between reconstructors: read only
    _TABLES[key] = table
    while len(_TABLES) > _TABLES_KEPT:
        _TABLES.popitem(last=False)
    return table
