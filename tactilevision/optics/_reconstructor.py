"""``DepthReconstructor``: tactile frame -> gradients -> height map.

Built once from a :class:`PhotometricCalibration`; everything that does not
depend on the frame (reference inverse, pixel grids, the Poisson
eigenvalues, the model session) is prepared at construction, so a call does
only per-frame work.
"""

from __future__ import annotations

import cv2
import numpy as np

from .._checks import check_array
from ._ball import gradients_from_normals
from ._calibration import PhotometricCalibration
from ._features import colour_change, reference_inverse
from ._markers import fill_masked, marker_mask
from ._mlp import MLPGradientModel, mlp_inputs
from ._poisson import Boundary, PoissonSolver

__all__ = ["DepthReconstructor"]


class DepthReconstructor:
    """Height maps from tactile frames by photometric stereo.

    Parameters
    ----------
    calibration : PhotometricCalibration
        The sensor's colour-to-normal model.
    reference : (H, W, 3) uint8 ndarray, optional
        Today's no-contact frame (BGR); default the calibration's. A fresh
        reference absorbs slow changes of the lights and the gel.
    boundary : {'neumann', 'dirichlet'}, default 'neumann'
        Poisson boundary condition (:class:`PoissonSolver`). With 'neumann'
        the median height of the no-contact region is zero.
    mask_contact : bool, default True
        Set the gradient to zero where the colour change is below the
        calibration's noise threshold (no contact), so camera noise is not
        integrated into the height map.
    contact_dilate_px : int, default 6
        Grow the contact mask by this many pixels (the soft edge of the
        colour change).
    threads : int, default 1
        onnxruntime threads for the MLP model.

    Examples
    --------
    >>> recon = DepthReconstructor(PhotometricCalibration.load(path))  # doctest: +SKIP
    >>> height_mm = recon(frame)                                        # doctest: +SKIP
    """

    def __init__(self, calibration: PhotometricCalibration, *,
                 reference: np.ndarray | None = None, boundary: Boundary = "neumann",
                 mask_contact: bool = True, contact_dilate_px: int = 6,
                 threads: int = 1) -> None:
        self.calibration = calibration
        ref = calibration.reference if reference is None else reference
        ref = check_array(ref, "reference", [(*calibration.shape, 3)], dtype=np.uint8)
        self.shape = calibration.shape
        ref_mask = marker_mask(ref) if calibration.markers else None
        self._ref_inv = reference_inverse(ref, marker_mask=ref_mask)
        self._ref_colour = (1.0 / self._ref_inv).astype(np.float32)
        self._solver = PoissonSolver(self.shape, boundary=boundary)
        self.mask_contact = mask_contact
        k = 2 * int(contact_dilate_px) + 1
        self._dilate = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k))
        self._open = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))
        if calibration.model == "lut":
            if calibration.lut is None:
                raise ValueError("LUT calibration without a table")
            self._lut_flat = calibration.lut.table.reshape(-1, 2)
            self._mlp = None
        else:
            if calibration.onnx_bytes is None:
                raise ValueError("MLP calibration without a network")
            self._mlp = MLPGradientModel(calibration.onnx_bytes, threads=threads)

    # ---------------------------------------------------------------- pieces
    def _contact(self, change: np.ndarray, markers: np.ndarray | None) -> np.ndarray:
        mag = np.abs(change).max(axis=-1)
        m = (mag > self.calibration.contact_threshold).astype(np.uint8)
        if markers is not None:
            m[markers] = 0
        m = cv2.morphologyEx(m, cv2.MORPH_OPEN, self._open)
        return cv2.dilate(m, self._dilate).astype(bool)

    def _one(self, frame: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        cal = self.calibration
        change = colour_change(frame, self._ref_inv, blur_sigma=cal.blur_sigma)
        markers = marker_mask(frame) if cal.markers else None
        contact = (self._contact(change, markers) if self.mask_contact
                   else np.ones(self.shape, bool))
        h, w = self.shape
        gx = np.zeros((h, w), np.float32)
        gy = np.zeros((h, w), np.float32)
        if cal.model == "lut":
            nxy = self._lut_flat[cal.lut.index(change)]
            ngx, ngy = gradients_from_normals(nxy[..., 0], nxy[..., 1])
            gx = np.where(contact, ngx, 0).astype(np.float32)
            gy = np.where(contact, ngy, 0).astype(np.float32)
        else:
            yy, xx = np.nonzero(contact)
            inputs = mlp_inputs(change[yy, xx], self._ref_colour[yy, xx], xx, yy, self.shape,
                                use_position=cal.use_position)
            nxy = self._mlp.normals(inputs)
            gx[yy, xx], gy[yy, xx] = gradients_from_normals(nxy[:, 0], nxy[:, 1])
        if markers is not None:
            gx = fill_masked(gx, markers)
            gy = fill_masked(gy, markers)
        return gx, gy, contact

    # ---------------------------------------------------------------- public
    def _check(self, frames: np.ndarray) -> np.ndarray:
        return check_array(frames, "frame", [(*self.shape, 3), ("N", *self.shape, 3)],
                           dtype=np.uint8)

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
            gx, gy, _ = self._one(frames)
            return gx, gy
        out = [self._one(f)[:2] for f in frames]
        return np.stack([o[0] for o in out]), np.stack([o[1] for o in out])

    def contact_mask(self, frames: np.ndarray) -> np.ndarray:
        """Pixels whose colour change exceeds the calibration's noise level.

        Parameters
        ----------
        frames : (H, W, 3) or (N, H, W, 3) uint8 ndarray
            Tactile frames, BGR.

        Returns
        -------
        mask : ([N, ]H, W) bool ndarray
        """
        frames = self._check(frames)
        cal = self.calibration
        one = frames[None] if frames.ndim == 3 else frames
        masks = np.stack([
            self._contact(colour_change(f, self._ref_inv, blur_sigma=cal.blur_sigma),
                          marker_mask(f) if cal.markers else None) for f in one])
        return masks[0] if frames.ndim == 3 else masks

    def __call__(self, frames: np.ndarray) -> np.ndarray:
        """Height map of one frame or a batch.

        Parameters
        ----------
        frames : (H, W, 3) or (N, H, W, 3) uint8 ndarray
            Tactile frames, BGR, the calibration's size.

        Returns
        -------
        height : ([N, ]H, W) float32 ndarray
            Depth into the gel, mm (positive where pressed in), zero median
            over the no-contact region.

        Raises
        ------
        ShapeError
            If the frame is not uint8 BGR of the calibration's size.
        """
        frames = self._check(frames)
        one = frames[None] if frames.ndim == 3 else frames
        heights = np.empty((len(one), *self.shape), np.float32)
        for i, f in enumerate(one):
            gx, gy, contact = self._one(f)
            z = self._solver(gx, gy, zero_mask=~contact if contact.any() else None)
            heights[i] = z * np.float32(self.calibration.mm_per_px)
        return heights[0] if frames.ndim == 3 else heights
