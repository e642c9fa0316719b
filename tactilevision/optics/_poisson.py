"""Poisson integration of a gradient field into a height map (scipy.fft).

The height map z minimising ``||grad z - g||^2`` satisfies the Poisson
equation ``laplacian(z) = div(g)``. On a rectangular pixel grid the 5-point
Laplacian is diagonalised by the type-II discrete cosine transform (Neumann
boundary, ``dz/dn = 0``) or the type-II discrete sine transform (Dirichlet
boundary, ``z = 0`` half a pixel outside the image), so one forward and one
inverse transform solve it exactly (Simchony, Chellappa and Shao 1990).
"""

from __future__ import annotations

from typing import Literal

import cv2
import numpy as np
from scipy import fft as sfft
from scipy import sparse
from scipy.sparse.linalg import spsolve

from .._checks import InputError, check_array
from ._features import median_last_axis

__all__ = ["PoissonSolver", "divergence", "integrate_poisson", "integrate_poisson_masked"]

Boundary = Literal["neumann", "dirichlet"]


def divergence(gx: np.ndarray, gy: np.ndarray, *, scale: float = 0.5) -> np.ndarray:
    """Divergence of a gradient field by central differences.

    Parameters
    ----------
    gx, gy : ([N, ]H, W) float ndarray
        d(z)/dx along columns and d(z)/dy along rows, in height units per pixel.
    scale : float, default 0.5
        Factor applied to the differences (0.5: the central difference).

    Returns
    -------
    div : ([N, ]H, W) ndarray, dtype of ``gx``
        ``(gx[j+1] - gx[j-1]) / 2 + (gy[i+1] - gy[i-1]) / 2``, zero-flux at the
        image border. With pointwise gradients this is the trapezoid rule
        ``(g[j] + g[j+1]) / 2`` for the forward difference, which the 5-point
        Laplacian of :class:`PoissonSolver` inverts exactly.
    """
    div = np.empty_like(gx)
    np.subtract(gx[..., :, 2:], gx[..., :, :-2], out=div[..., :, 1:-1])
    np.add(gx[..., :, 1], gx[..., :, 0], out=div[..., :, 0])
    np.add(gx[..., :, -1], gx[..., :, -2], out=div[..., :, -1])
    np.negative(div[..., :, -1], out=div[..., :, -1])
    div[..., 1:-1, :] += gy[..., 2:, :]
    div[..., 1:-1, :] -= gy[..., :-2, :]
    div[..., 0, :] += gy[..., 1, :]
    div[..., 0, :] += gy[..., 0, :]
    div[..., -1, :] -= gy[..., -1, :]
    div[..., -1, :] -= gy[..., -2, :]
    if scale != 1.0:
        div *= scale
    return div


class PoissonSolver:
    """Fast Poisson integration on a fixed (H, W) grid; eigenvalues cached.

    Parameters
    ----------
    shape : tuple of int
        (H, W) of the gradient fields it will integrate.
    boundary : {'neumann', 'dirichlet'}, default 'neumann'
        'neumann' (DCT-II): zero normal derivative at the border, height
        defined up to a constant, fixed afterwards (see ``__call__``).
        'dirichlet' (DST-II): zero height half a pixel outside the border;
        use it when the border is known to be flat and untouched.
    dtype : numpy dtype, default float32
        Working precision.
    scale : float, default 1.0
        Factor on every height returned (e.g. mm per pixel, for gradients in
        height per pixel and heights in mm): folded into the cached
        eigenvalues, so it costs nothing per frame.

    Notes
    -----
    With f = div(g), the 5-point Laplacian has the eigenvalues
    ``lambda_kl = 2 cos(pi k / H) + 2 cos(pi l / W) - 4``, with k, l counted
    from 0 in the DCT-II basis (Neumann) and from 1 in the DST-II basis
    (Dirichlet). The solution is ``z = IDCT(DCT(f) / lambda)``: one pair of
    real transforms per frame, about 2 ms at 640 x 480 in float32 on one core.

    References
    ----------
    .. [1] T. Simchony, R. Chellappa, M. Shao, "Direct analytical methods for
       solving Poisson equations in computer vision problems", IEEE TPAMI
       12(5):435-446, 1990. doi:10.1109/34.55103
    """

    def __init__(self, shape: tuple[int, int], *, boundary: Boundary = "neumann",
                 dtype: type = np.float32, scale: float = 1.0) -> None:
        if boundary not in ("neumann", "dirichlet"):
            raise InputError(f"boundary must be 'neumann' or 'dirichlet', got {boundary!r}")
        h, w = (int(s) for s in shape)
        if h < 2 or w < 2:
            raise InputError(f"shape must be at least (2, 2), got {shape}")
        self.shape = (h, w)
        self.boundary = boundary
        shift = 0 if boundary == "neumann" else 1
        ky = 2.0 * np.cos(np.pi * (np.arange(h) + shift) / h) - 2.0
        kx = 2.0 * np.cos(np.pi * (np.arange(w) + shift) / w) - 2.0
        lam = ky[:, None] + kx[None, :]
        if boundary == "neumann":
            lam[0, 0] = 1.0  # the mean is free; fixed afterwards
        inv = (0.5 * float(scale) / lam).astype(dtype)  # 0.5: divergence()'s central difference
        if boundary == "neumann":
            inv[0, 0] = 0.0
        self._inv_lambda = inv

    def __call__(self, gx: np.ndarray, gy: np.ndarray, *,
                 zero_mask: np.ndarray | None = None) -> np.ndarray:
        """Integrate one gradient field or a batch.

        Parameters
        ----------
        gx, gy : ([N, ]H, W) float ndarray
            Gradients along columns (x) and rows (y), height units per pixel.
        zero_mask : ([N, ]H, W) bool ndarray, optional
            Neumann only: pixels whose median height is set to zero (for a
            tactile frame, the no-contact region). Without it the median over
            the image (every 4th pixel along rows and columns) is zero: right
            for a tactile frame whose contact covers under half of it.

        Returns
        -------
        z : ([N, ]H, W) ndarray, dtype of the solver
            Height in the units of ``gx`` times pixels, times ``scale``.
        """
        gx = check_array(gx, "gx", [(*self.shape,), ("N", *self.shape)], dtype=np.floating)
        gy = check_array(gy, "gy", [gx.shape], dtype=np.floating)
        if zero_mask is not None:
            zero_mask = check_array(zero_mask, "zero_mask", [gx.shape], dtype=np.bool_)
        return self.solve_unchecked(gx, gy, zero_mask)

    def solve_unchecked(self, gx: np.ndarray, gy: np.ndarray,
                        zero_mask: np.ndarray | None = None) -> np.ndarray:
        """``__call__`` without its checks of the arguments' shapes and dtypes, for a
        caller that made them (a :class:`DepthReconstructor`'s own gradients)."""
        dt = self._inv_lambda.dtype
        f = divergence(gx.astype(dt, copy=False), gy.astype(dt, copy=False), scale=1.0)
        axes = (-2, -1)
        # in place: the divergence and its transform are this call's own buffers
        if self.boundary == "neumann":
            c = sfft.dctn(f, type=2, axes=axes, workers=1, overwrite_x=True)
            c *= self._inv_lambda
            z = sfft.idctn(c, type=2, axes=axes, workers=1, overwrite_x=True)
            return _fix_offset(z, zero_mask)
        c = sfft.dstn(f, type=2, axes=axes, workers=1, overwrite_x=True)
        c *= self._inv_lambda
        return sfft.idstn(c, type=2, axes=axes, workers=1, overwrite_x=True)


def _fix_offset(z: np.ndarray, zero_mask: np.ndarray | None) -> np.ndarray:
    if z.ndim == 3:
        for i in range(z.shape[0]):
            z[i] = _fix_offset(z[i], None if zero_mask is None else zero_mask[i])
        return z
    if zero_mask is not None and np.count_nonzero(zero_mask) > 0:
        ref = median_last_axis(z[zero_mask])   # a copy: partitioned in place
    else:
        ref = median_last_axis(z[::4, ::4].flatten())
    z -= ref
    return z


def integrate_poisson(gx: np.ndarray, gy: np.ndarray, *, boundary: Boundary = "neumann",
                      zero_mask: np.ndarray | None = None) -> np.ndarray:
    """Height map from a gradient field by Poisson integration.

    Parameters
    ----------
    gx, gy : ([N, ]H, W) float ndarray
        d(z)/dx along columns and d(z)/dy along rows, height units per pixel
        (multiply gradients in mm/mm by nothing and the result by mm/px, or
        pass gradients in mm/px to get mm).
    boundary : {'neumann', 'dirichlet'}, default 'neumann'
        Boundary condition, see :class:`PoissonSolver`.
    zero_mask : ([N, ]H, W) bool ndarray, optional
        Neumann only: region whose median height is zero (default: the
        whole image).

    Returns
    -------
    z : ([N, ]H, W) float32 ndarray
        Height map.

    Raises
    ------
    ShapeError
        If gx and gy differ in shape or are not 2-D or 3-D float arrays.

    Examples
    --------
    >>> import numpy as np
    >>> y, x = np.mgrid[0:64, 0:80].astype(np.float32)
    >>> z = np.exp(-((x - 40) ** 2 + (y - 32) ** 2) / 200.0)
    >>> gy, gx = np.gradient(z)
    >>> zr = integrate_poisson(gx.astype(np.float32), gy.astype(np.float32))
    >>> err = zr - z
    >>> bool(np.abs(err - np.median(err)).max() < 0.01)  # equal up to the free offset
    True
    """
    gx = check_array(gx, "gx", [("H", "W"), ("N", "H", "W")], dtype=np.floating)
    return PoissonSolver(gx.shape[-2:], boundary=boundary)(gx, gy, zero_mask=zero_mask)


def integrate_poisson_masked(gx: np.ndarray, gy: np.ndarray, mask: np.ndarray, *,
                             method: Literal["cg", "direct"] = "cg", tol: float = 1e-6,
                             z0: np.ndarray | None = None) -> np.ndarray:
    """Height map that is zero outside `mask`: Poisson integration on the mask only.

    The 5-point Poisson equation of :class:`PoissonSolver` is solved on the
    pixels of `mask` with ``z = 0`` on the pixels outside it (Dirichlet) and
    zero normal derivative at the image border (Neumann). For a tactile
    frame with `mask` the contact region (colour change above noise, holes
    filled), the untouched gel is pinned at zero, so the slowly varying
    error that a whole-image integration spreads over the frame (gradient
    bias from illumination drift, about 0.05 to 0.1 mm over a GelSight frame)
    cannot enter the height map.

    Parameters
    ----------
    gx, gy : ([N, ]H, W) float ndarray
        Gradients along columns (x) and rows (y), height units per pixel.
    mask : ([N, ]H, W) bool ndarray
        Pixels whose height is solved for; zero height elsewhere. A mask
        covering the whole image has no pinned pixel: the whole-image
        (Neumann, median zero) solution is returned for it.
    method : {'cg', 'direct'}, default 'cg'
        'cg': preconditioned conjugate gradients on the mask's bounding box
        (Notes). 'direct': a sparse LU factorisation of the masked system
        (SuperLU), exact to rounding and 10 to 50 times slower.
    tol : float, default 1e-6
        'cg': the relative residual ``||f - A z|| / ||f||`` at which it stops
        (f the divergence on the mask). 1e-6 leaves the height within about
        1e-6 of its peak of the direct solve's on the sample session's
        contacts.
    z0 : (H, W) float ndarray, optional
        'cg': the first guess, e.g. the previous frame's height of a video in
        the units of the result (values outside `mask` ignored); a guess
        further from the answer than zero is not used. With a batch, each
        frame after the first starts from the one before it.

    Returns
    -------
    z : ([N, ]H, W) float32 ndarray
        Height in the units of ``gx`` times pixels; exactly 0 outside `mask`.

    Raises
    ------
    ShapeError
        If the arrays differ in shape or are not 2-D / 3-D (float gradients,
        bool mask), or `z0` is not (H, W).
    InputError
        For an unknown `method` or a `tol` outside (0, 1).

    Notes
    -----
    Only the pixels of the mask's bounding box take part: every pixel
    outside the mask is pinned at zero, so the box holds the whole problem.
    The 5-point stencil couples only 4-neighbours, so each 4-connected
    region of the mask is a problem of its own, solved on its own box (a
    press and a speck of glare far from it: 25 iterations each instead of 85
    on the box spanning both).
    'cg' solves the masked 5-point system by conjugate gradients with the
    box's own fast Poisson solve as the preconditioner: one pair of real
    trigonometric transforms per iteration, the type on each side of the box
    chosen by whether the mask reaches the image border there (Neumann:
    DCT-II or DCT-IV/DST-IV) or not (Dirichlet half a pixel beyond the box:
    DST-II), the box grown by a few pinned pixels to a fast transform
    length. About 20 to 40 iterations from zero, fewer from a previous
    frame's height. At a `tol` of 1e-5 or looser the iterations run in
    single precision (dot products accumulated in double): at the
    contact-pinned heights' 1e-4 the sample session's heights lie within
    1.6e-5 of their peak of the double-precision solve's (both within 7.5e-5
    of the direct solve's), at about 0.75 of its cost. Should it not converge in
    400 iterations, the direct solve is used. 'direct' (SuperLU through
    :func:`scipy.sparse.linalg.spsolve`) takes about 0.2 to 0.5 s for a
    46 000 px contact at 640 x 480 on one core.

    Examples
    --------
    >>> import numpy as np
    >>> y, x = np.mgrid[0:64, 0:80].astype(np.float32)
    >>> z = 3.0 * np.exp(-((x - 40) ** 2 + (y - 32) ** 2) / 50.0)
    >>> gy, gx = np.gradient(z)
    >>> zr = integrate_poisson_masked(gx, gy, z > 1e-3)
    >>> bool(np.abs(zr - z).max() < 0.05)
    True
    >>> zd = integrate_poisson_masked(gx, gy, z > 1e-3, method="direct")
    >>> bool(np.abs(zr - zd).max() < 1e-5)
    True
    """
    gx = check_array(gx, "gx", [("H", "W"), ("N", "H", "W")], dtype=np.floating)
    gy = check_array(gy, "gy", [gx.shape], dtype=np.floating)
    mask = check_array(mask, "mask", [gx.shape], dtype=np.bool_)
    if method not in ("cg", "direct"):
        raise InputError(f"method must be 'cg' or 'direct', got {method!r}")
    if not 0.0 < float(tol) < 1.0:
        raise InputError(f"tol must lie in (0, 1), got {tol!r}")
    if z0 is not None:
        z0 = check_array(z0, "z0", [gx.shape[-2:]], dtype=np.floating)
    if gx.ndim == 3:
        out = []
        for a, b, m in zip(gx, gy, mask, strict=True):
            out.append(_masked_one(a, b, m, method, float(tol), z0))
            z0 = out[-1]
        return np.stack(out)
    return _masked_one(gx, gy, mask, method, float(tol), z0)


def _masked_one(gx: np.ndarray, gy: np.ndarray, mask: np.ndarray, method: str, tol: float,
                z0: np.ndarray | None) -> np.ndarray:
    """One frame of :func:`integrate_poisson_masked` (arguments checked)."""
    if mask.all():
        return integrate_poisson(gx, gy).astype(np.float32)
    out = np.zeros(gx.shape, np.float32)
    if not mask.any():
        return out
    if method == "cg":
        z = _masked_cg_parts(gx, gy, mask, tol, z0)
        if z is not None:
            return z
    f = divergence(gx.astype(np.float64), gy.astype(np.float64), scale=0.5)
    out[mask] = spsolve(_masked_laplacian(mask), f[mask])
    return out


def _masked_laplacian(mask: np.ndarray) -> sparse.csc_matrix:
    """The 5-point Laplacian on the pixels of `mask` (row-major order), zero height
    outside it and mirrored ghosts at the image border: (n, n) CSC, n pixels."""
    H, W = mask.shape
    n = int(np.count_nonzero(mask))
    idx = np.full(mask.shape, -1, np.int64)
    idx[mask] = np.arange(n)
    r, c = np.nonzero(mask)
    eq = np.arange(n)
    diag = np.full(n, -4.0)
    rows, cols, vals = [eq], [eq], [diag]
    for dr, dc in ((0, 1), (0, -1), (1, 0), (-1, 0)):
        rr, cc = r + dr, c + dc
        inside = (rr >= 0) & (rr < H) & (cc >= 0) & (cc < W)
        diag[~inside] += 1.0                       # mirrored ghost: Neumann border
        j = np.full(n, -1, np.int64)
        j[inside] = idx[rr[inside], cc[inside]]
        nb = j >= 0                                # masked neighbour; else z = 0 there
        rows.append(eq[nb])
        cols.append(j[nb])
        vals.append(np.ones(int(nb.sum())))
    return sparse.csc_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                             shape=(n, n))


#: Conjugate-gradient iterations of the masked integration before it falls back to the
#: direct solve.
_MASKED_MAX_ITER = 400

#: The masked integration's conjugate gradients run in single precision for a tolerance
#: this loose or looser (the contact-pinned heights' 1e-4), in double for tighter ones.
_SINGLE_TOL = 1e-5


def _box_side(lo: int, hi: int, size: int) -> tuple[int, int, str]:
    """A bounding box's extent along one axis grown to a fast transform length, and its
    two sides' conditions: 'N' where the mask reaches the image border, else 'D'."""
    kind = ("N" if lo == 0 else "D") + ("N" if hi == size else "D")
    n = min(sfft.next_fast_len(hi - lo, real=True), size)
    if kind == "DD":
        lo = max(0, min(lo - (n - (hi - lo)) // 2, size - n))
    elif kind == "DN":
        lo = hi - n
    elif kind == "NN":
        return 0, size, kind
    return lo, lo + n, kind


def _box_transforms(kind: str, n: int) -> tuple[str, int, np.ndarray]:
    """The trigonometric transform ('dct' or 'dst', type) that diagonalises the 1-D
    second difference on n pixels with the sides' conditions, and its eigenvalues."""
    k = np.arange(n)
    if kind == "DD":        # zero half a pixel beyond both ends
        return "dst", 2, 2.0 * np.cos(np.pi * (k + 1) / n) - 2.0
    if kind == "NN":        # mirrored at both ends
        return "dct", 2, 2.0 * np.cos(np.pi * k / n) - 2.0
    lam = 2.0 * np.cos(np.pi * (k + 0.5) / n) - 2.0
    return ("dct", 4, lam) if kind == "ND" else ("dst", 4, lam)


def _masked_cg_parts(gx: np.ndarray, gy: np.ndarray, mask: np.ndarray, tol: float,
                     z0: np.ndarray | None) -> np.ndarray | None:
    """:func:`_masked_cg` on each 4-connected region of `mask` alone; None if one did not
    converge. The 5-point system couples only 4-neighbours, so regions that do not touch
    are independent problems: each on its own bounding box, where the box's fast Poisson
    solve is a far better preconditioner than on a box spanning them all (a press and a
    speck of colour change 300 px away: 85 iterations on their common box against 25)."""
    n, labels, stats, _ = cv2.connectedComponentsWithStats(mask.view(np.uint8), connectivity=4)
    if n <= 2:
        return _masked_cg(gx, gy, mask, tol, z0)
    out = np.zeros(mask.shape, np.float32)
    for k in range(1, n):
        x, y, w, h = (int(v) for v in stats[k, :4])
        part = np.zeros(mask.shape, bool)
        part[y:y + h, x:x + w] = labels[y:y + h, x:x + w] == k
        z = _masked_cg(gx, gy, part, tol, z0)
        if z is None:
            return None
        out += z
    return out


def _masked_cg(gx: np.ndarray, gy: np.ndarray, mask: np.ndarray, tol: float,
               z0: np.ndarray | None) -> np.ndarray | None:
    """:func:`integrate_poisson_masked` by conjugate gradients on the mask's bounding box,
    preconditioned by the box's fast Poisson solve; None if it did not converge."""
    H, W = mask.shape
    rows = np.flatnonzero(mask.any(axis=1))
    cols = np.flatnonzero(mask.any(axis=0))
    r0, r1, ky = _box_side(int(rows[0]), int(rows[-1]) + 1, H)
    c0, c1, kx = _box_side(int(cols[0]), int(cols[-1]) + 1, W)
    m = mask[r0:r1, c0:c1]
    h, w = m.shape
    # the divergence on the box: central differences need one pixel beyond it
    a0, a1, b0, b1 = max(r0 - 1, 0), min(r1 + 1, H), max(c0 - 1, 0), min(c1 + 1, W)
    f = divergence(gx[a0:a1, b0:b1].astype(np.float64), gy[a0:a1, b0:b1].astype(np.float64),
                   scale=0.5)[r0 - a0:r0 - a0 + h, c0 - b0:c0 - b0 + w]
    # -A (positive definite): 4 (3, 2 at the image border) minus the masked neighbours
    nb = np.full((h, w), 4.0)
    nb[0] -= r0 == 0
    nb[-1] -= r1 == H
    nb[:, 0] -= c0 == 0
    nb[:, -1] -= c1 == W
    # single precision where the tolerance is loose (float32's rounding, about 1e-7 of
    # the residual a step, stays far below it): its transforms take 0.55 to 0.6 of the
    # time of float64's on 96 to 192 px boxes; double precision for tighter ones
    work = np.float32 if tol >= _SINGLE_TOL else np.float64
    nb = nb.astype(work)
    b = np.where(m, -f, 0.0).astype(work)
    keep = m.astype(work)       # zero off the mask by a product: a boolean index costs more

    def op(z: np.ndarray) -> np.ndarray:
        out = nb * z
        out[1:] -= z[:-1]
        out[:-1] -= z[1:]
        out[:, 1:] -= z[:, :-1]
        out[:, :-1] -= z[:, 1:]
        out *= keep
        return out

    (fy, ty, ly), (fx, tx, lx) = _box_transforms(ky, h), _box_transforms(kx, w)
    lam = -(ly[:, None] + lx[None, :])
    lam[lam <= 0] = 1.0         # both axes mirrored: the free constant, pinned by the mask
    inv = (1.0 / lam).astype(work)
    fwd_y, fwd_x = getattr(sfft, fy), getattr(sfft, fx)
    inv_y, inv_x = getattr(sfft, "i" + fy), getattr(sfft, "i" + fx)

    def precondition(r: np.ndarray) -> np.ndarray:
        c = fwd_x(fwd_y(r, type=ty, axis=0, norm="ortho", workers=1), type=tx, axis=1,
                  norm="ortho", workers=1, overwrite_x=True)
        c *= inv
        z = inv_x(inv_y(c, type=ty, axis=0, norm="ortho", workers=1, overwrite_x=True),
                  type=tx, axis=1, norm="ortho", workers=1, overwrite_x=True)
        z *= keep
        return z

    bn = _norm(b)
    if bn == 0.0:
        return np.zeros((H, W), np.float32)
    x = np.zeros((h, w), work)
    r = b
    if z0 is not None:
        x0 = np.where(m, z0[r0:r1, c0:c1], 0.0).astype(work)
        r_warm = b - op(x0)
        if _norm(r_warm) < bn:      # a guess further off than zero is not used
            x, r = x0, r_warm
    z = precondition(r)
    p = z.copy()
    rz = _dot(r, z)
    for _ in range(_MASKED_MAX_ITER):
        if _norm(r) <= tol * bn:
            out = np.zeros((H, W), np.float32)
            out[r0:r1, c0:c1] = x
            return out
        q = op(p)
        alpha = rz / _dot(p, q)
        x += alpha * p
        r = r - alpha * q
        z = precondition(r)
        rz_new = _dot(r, z)
        p *= rz_new / rz
        p += z
        rz = rz_new
    return None


def _dot(a: np.ndarray, b: np.ndarray) -> float:
    """Sum of the products of two equal-shape arrays, accumulated in double precision
    (einsum: no BLAS threads, which on a shared 2-core machine made a dot product of
    60 000 numbers take milliseconds)."""
    return float(np.einsum("ij,ij->", a, b, dtype=np.float64))


def _norm(a: np.ndarray) -> float:
    return _dot(a, a) ** 0.5
