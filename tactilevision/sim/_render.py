"""Frames from height maps: the forward photometric model of Taxim.

Taxim (Si and Yuan, "Taxim: An Example-based Simulation Model for GelSight
Tactile Sensors", IEEE RA-L 7(2), 2022, Sec. III-B) renders the colour change
of a pixel as a polynomial in its image position whose coefficients are looked
up by the surface normal:

``dI_c(x, y) = [x^2, y^2, x y, x, y, 1] . C_c(bin(theta), bin(phi))``

with theta = arctan |grad z| in ``num_bins`` bins over [0, pi/2], phi the
gradient direction in ``num_bins`` bins over [-pi, pi], and (x, y) the pixel
position on the full-resolution grid. The table ``C`` of the GelSight sensor
was fitted by the Taxim authors to real ball presses and ships with the
``taxim`` package (``taxim/calib/gelsight/polycalib.npz``, MIT).

This module is the *renderer* of the simulated sessions; it is deliberately a
different model from the reconstructor of :mod:`tactilevision.optics` (an
inverse colour -> gradient table fitted by us), so that the pipeline is never
tested against its own inverse. What we take from Taxim is its published
shading model and its fitted table; we render only the change relative to the
flat gel, ``T(grad z) - T(0)`` (slope bin 0 of the same direction), on top of
the real reference frame, and leave out Taxim's own gel-deformation
approximation (our deformations come from the FEM) and its shadows.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from functools import cached_property
from importlib.resources import files
from pathlib import Path

import numpy as np

from .._checks import InputError
from ..optics import ball_gradients

__all__ = ["ShadingTable", "fit_shading_table", "taxim_shading"]


@dataclass(frozen=True)
class ShadingTable:
    """Taxim's polynomial shading table of one sensor.

    Attributes
    ----------
    coeffs : (B, B, 6, 3) float64 ndarray
        Polynomial coefficients per (slope bin, direction bin), for the
        features ``[x^2, y^2, x y, x, y, 1]`` (x = column, y = row, px) and the
        three channels in the order of the sensor's frames (BGR as
        ``cv2.imread`` gives), in grey levels (0-255).
    shape : (H, W)
        Image size the positions refer to.
    mm_per_px : float
        Image scale on the gel, mm per pixel.
    """

    coeffs: np.ndarray
    shape: tuple[int, int]
    mm_per_px: float

    @property
    def num_bins(self) -> int:
        """Number of bins along the slope angle and along the direction."""
        return int(self.coeffs.shape[0])

    @cached_property
    def _features(self) -> np.ndarray:
        """(H, W, 6) position features, built once per table (the renderer's hot path)."""
        h, w = self.shape
        y, x = np.meshgrid(np.arange(h, dtype=np.float64), np.arange(w, dtype=np.float64),
                           indexing="ij")
        return np.stack([x * x, y * y, x * y, x, y, np.ones_like(x)], axis=-1)

    def shading(self, height_mm: np.ndarray) -> np.ndarray:
        """Colour change of the gel against its flat state.

        Parameters
        ----------
        height_mm : (H, W) float ndarray
            Depth of the gel surface into the gel, mm (positive into the gel,
            the convention of :class:`~tactilevision.optics.DepthReconstructor`).

        Returns
        -------
        change : (H, W, 3) float64 ndarray
            Grey levels to add to the reference frame.

        Raises
        ------
        InputError
            If the height map is not (H, W) of the table or not finite.
        """
        z = np.asarray(height_mm, np.float64)
        out = np.zeros((*z.shape, 3))
        tilted, change = self._tilted_change(z)
        if change is not None:
            out[tilted] = change
        return out

    def _tilted_change(self, z: np.ndarray) -> tuple[tuple, np.ndarray | None]:
        """The tilted pixels (row-major ``np.nonzero`` indices) and their (n, 3) change.

        The flat gel: slope bin 0 of the same direction (the table's bin-0 rows
        differ slightly between directions; subtracting the same direction's keeps a
        flat gel exactly at the reference, with no sector pattern). A pixel in bin 0
        changes by exactly nothing, so only the tilted pixels are evaluated, and the
        slope angle and direction only where the gradient's magnitude can reach bin 1
        (tan of the bin width, less a margin): a no-contact frame costs nothing, a
        press its contact's neighbourhood.
        """
        if z.shape != tuple(self.shape):
            raise InputError(f"height map of shape {z.shape} does not match the shading "
                             f"table's {tuple(self.shape)}")
        if not np.all(np.isfinite(z)):
            raise InputError("height map contains NaN or inf")
        if not z.any():                 # the flat gel: no change at all
            return (), None
        zp = z / self.mm_per_px
        d_row, d_col = np.gradient(zp)
        g = np.hypot(d_row, d_col)
        b = self.num_bins
        width = 0.5 * np.pi / (b - 1)
        near = np.nonzero(g >= np.tan(width) * (1.0 - 1e-6))
        slope = np.arctan(g[near])
        i_mag = np.clip(np.floor(slope / width).astype(np.int64), 0, b - 1)
        keep = i_mag > 0
        tilted = tuple(ix[keep] for ix in near)
        if not tilted[0].size:
            return (), None
        i_mag = i_mag[keep]
        direction = np.arctan2(d_row[tilted], d_col[tilted])  # Taxim: atan2(d/drow, d/dcol)
        d = np.clip(np.floor((direction + np.pi) / (2 * np.pi / (b - 1))).astype(np.int64),
                    0, b - 1)
        feats = self._features[tilted]                                      # (n, 6)
        lit = np.einsum("nf,nfc->nc", feats, self.coeffs[i_mag, d])
        flat = np.einsum("nf,nfc->nc", feats, self.coeffs[0, d])
        return tilted, lit - flat

    def render(self, height_mm: np.ndarray, reference: np.ndarray, *, noise_dn: float = 0.0,
               rng: np.random.Generator | None = None) -> np.ndarray:
        """A tactile frame: reference + shading change + camera noise, as uint8.

        Parameters
        ----------
        height_mm : (H, W) float ndarray
            Gel surface depth, mm, positive into the gel.
        reference : (H, W, 3) uint8 ndarray
            The no-contact frame of the sensor (channel order of ``coeffs``).
        noise_dn : float, default 0.0
            Standard deviation of additive Gaussian camera noise, grey levels.
        rng : numpy.random.Generator, optional
            Source of the noise (required when ``noise_dn > 0``).

        Returns
        -------
        frame : (H, W, 3) uint8 ndarray

        Raises
        ------
        InputError
            If the reference does not match the table's shape.
        """
        ref = np.asarray(reference)
        if ref.shape != (*self.shape, 3):
            raise InputError(f"reference of shape {ref.shape} does not match the shading "
                             f"table's {(*self.shape, 3)}")
        if noise_dn > 0 and rng is None:
            raise InputError("rng is required when noise_dn > 0")
        img = ref.astype(np.float64)
        tilted, change = self._tilted_change(np.asarray(height_mm, np.float64))
        if change is not None:
            img[tilted] += change            # reference + change (0 elsewhere: unchanged)
        if noise_dn > 0:
            img += rng.normal(0.0, noise_dn, img.shape)
        np.rint(img, out=img)
        np.clip(img, 0, 255, out=img)        # the same as clipping first: 255.5 rounds to 256
        return img.astype(np.uint8)


def _taxim_folder(sensor: str) -> Path:
    try:
        root = Path(str(files("taxim")))
    except ModuleNotFoundError as exc:  # pragma: no cover - depends on the install
        raise InputError("the Taxim shading table needs the 'taxim' package: "
                         "pip install 'tactilevision[test]'") from exc
    folder = root / "calib" / sensor
    if not (folder / "polycalib.npz").is_file():
        raise InputError(f"taxim ships no polynomial table for sensor {sensor!r} "
                         f"(looked for {folder / 'polycalib.npz'})")
    return folder


def taxim_shading(sensor: str = "gelsight") -> tuple[ShadingTable, np.ndarray]:
    """Taxim's fitted shading table and reference frame of a sensor.

    Parameters
    ----------
    sensor : str, default 'gelsight'
        Folder under ``taxim/calib`` (``'gelsight'``; ``'gelsight_mini'``
        exists but its table does not reproduce its own frames).

    Returns
    -------
    table : ShadingTable
        Coefficients in the channel order of the frames (BGR).
    reference : (H, W, 3) uint8 ndarray
        The sensor's real no-contact frame (``f0`` of ``dataPack.npz``, BGR).

    Raises
    ------
    InputError
        If ``taxim`` is not installed or has no table for `sensor`.

    Notes
    -----
    The table's ``grad_r`` and ``grad_b`` arrays are swapped with respect to
    their names (the Taxim sources say so); stacked as (grad_r, grad_g,
    grad_b) they follow the BGR order of ``f0``. The test suite checks the
    order against the real ball presses of the same package.
    """
    folder = _taxim_folder(sensor)
    with np.load(folder / "polycalib.npz") as d:
        coeffs = np.stack([d["grad_r"], d["grad_g"], d["grad_b"]], axis=-1).astype(np.float64)
    with np.load(folder / "dataPack.npz", allow_pickle=False) as d:
        reference = np.asarray(d["f0"], np.uint8)
    params = json.loads((folder / "params.json").read_text())["sensor"]
    table = ShadingTable(coeffs=coeffs, shape=(int(params["h"]), int(params["w"])),
                         mm_per_px=float(params["pixmm"]))
    return table, reference


def fit_shading_table(reference: np.ndarray, frames: np.ndarray, centres_px: np.ndarray,
                      radii_px: np.ndarray, *, ball_radius_mm: float, mm_per_px: float,
                      num_bins: int = 48, min_samples: int = 40) -> ShadingTable:
    """Fit a shading table of Taxim's form to ball presses of a sensor.

    For every (slope, direction) bin the colour change ``frame - reference``
    of the pixels inside the contact circles whose ball normal falls in the
    bin is fitted, per channel, by least squares in ``[x^2, y^2, x y, x, y,
    1]`` (Taxim, Sec. III-B). A forward model (normal -> colour), unlike the
    reconstructor's inverse one, and fitted to the real frames.

    Parameters
    ----------
    reference : (H, W, 3) uint8 ndarray
        No-contact frame.
    frames : (N, H, W, 3) uint8 ndarray
        Ball presses.
    centres_px : (N, 2) float ndarray
        Contact-circle centres (x = column, y = row), px.
    radii_px : (N,) float ndarray
        Contact-circle radii, px.
    ball_radius_mm, mm_per_px : float
    num_bins : int, default 48
        Bins along the slope angle (over [0, pi/2]) and along the direction.
    min_samples : int, default 40
        Bins with fewer pixels copy the nearest fitted bin of the same
        direction (steeper slopes than the ball shows) or direction.

    Returns
    -------
    ShadingTable
        Slope bin 0 is the flat gel (zero change).

    Raises
    ------
    InputError
        For mismatched shapes or no usable pixels.
    """
    ref = np.asarray(reference, np.float64)
    fr = np.asarray(frames)
    if fr.ndim != 4 or fr.shape[1:] != ref.shape or ref.ndim != 3 or ref.shape[2] != 3:
        raise InputError(f"frames {fr.shape} and reference {ref.shape} must be (N, H, W, 3) and "
                         "(H, W, 3)")
    c = np.asarray(centres_px, np.float64).reshape(-1, 2)
    r = np.asarray(radii_px, np.float64).ravel()
    if c.shape[0] != fr.shape[0] or r.shape[0] != fr.shape[0]:
        raise InputError(f"{fr.shape[0]} frames but {c.shape[0]} centres and {r.shape[0]} radii")
    h, w = ref.shape[:2]
    b = int(num_bins)
    ball_px = ball_radius_mm / mm_per_px
    rows, cols = np.indices((h, w), dtype=np.float64)
    keys, feats, targets = [], [], []
    for k in range(fr.shape[0]):
        gx, gy, inside = ball_gradients((h, w), tuple(c[k]), 0.95 * r[k], ball_px)
        gx, gy = gx[inside].astype(np.float64), gy[inside].astype(np.float64)
        slope = np.arctan(np.hypot(gx, gy))
        direction = np.arctan2(gy, gx)
        i_mag = np.clip(np.floor(slope / (0.5 * np.pi / (b - 1))).astype(np.int64), 0, b - 1)
        i_dir = np.clip(np.floor((direction + np.pi) / (2 * np.pi / (b - 1))).astype(np.int64),
                        0, b - 1)
        x, y = cols[inside] / w, rows[inside] / h
        keys.append(i_mag * b + i_dir)
        feats.append(np.stack([x * x, y * y, x * y, x, y, np.ones_like(x)], axis=1))
        targets.append(fr[k][inside].astype(np.float64) - ref[inside])
    if not keys:
        raise InputError("no ball press to fit the shading table to")
    key = np.concatenate(keys)
    a = np.concatenate(feats)
    t = np.concatenate(targets)
    coeffs = np.zeros((b, b, 6, 3))
    fitted = np.zeros((b, b), bool)
    order = np.argsort(key, kind="stable")
    key, a, t = key[order], a[order], t[order]
    bounds = np.flatnonzero(np.diff(key)) + 1
    for lo, hi in zip(np.r_[0, bounds], np.r_[bounds, key.size], strict=True):
        if hi - lo < min_samples:
            continue
        im, idr = divmod(int(key[lo]), b)
        if im == 0:
            continue
        sol, *_ = np.linalg.lstsq(a[lo:hi], t[lo:hi], rcond=None)
        coeffs[im, idr] = sol
        fitted[im, idr] = True
    if not fitted.any():
        raise InputError("no (slope, direction) bin has enough pixels: more or larger presses")
    for idr in range(b):                      # steeper than seen: the steepest fitted
        col = np.flatnonzero(fitted[:, idr])
        if col.size == 0:
            continue
        for im in range(1, b):
            if not fitted[im, idr]:
                near = col[np.argmin(np.abs(col - im))]
                coeffs[im, idr] = coeffs[near, idr]
    have = np.flatnonzero(fitted.any(axis=0))
    for idr in range(b):                      # directions never seen: the nearest
        if idr not in have:
            d = np.abs((have - idr + b // 2) % b - b // 2)
            coeffs[1:, idr] = coeffs[1:, have[np.argmin(d)]]
    scale = np.array([w * w, h * h, w * h, w, h, 1.0])[:, None]
    return ShadingTable(coeffs=coeffs / scale, shape=(h, w), mm_per_px=float(mm_per_px))
