r"""Contact force distribution from a height map: the layer's spectral Green's
function at full image resolution, or the inverse FEM on a coarser grid.

Two ways of turning the measured top-surface displacement of the gel into the
traction the object applies (Ma, Donlon, Dong, Rodriguez, "Dense Tactile Force
Estimation using GelSlim and Inverse FEM", ICRA 2019, do the second):

``'spectral'``
    The pad is a layer of uniform thickness h bonded to a rigid prism, so away
    from its edges its surface stiffness is translation-invariant: the traction
    is a convolution of the displacement, ``t = IFFT(K(k) FFT(u))`` with
    ``K(k)`` the layer's 3 x 3 Fourier surface stiffness
    (:func:`~tactilevision.fem.layer_surface_stiffness`). The image is
    zero-padded by `pad_mm` on every side before the FFT: the displacement
    outside the sensed area is taken as zero and the periodic images of the
    field are kept `2 pad_mm` apart.
``'fem'``
    The condensed top-surface stiffness of a 3D finite-element model of the
    sensed area (:func:`~tactilevision.fem.pad_surface_stiffness`; sides
    traction-free, bottom bonded) on a grid of surface nodes; the height map
    is averaged over each node's tributary pixels.

Displacement modes: ``'normal'`` (photometric stereo gives the normal
displacement only): the tangential traction is taken as zero and the
tangential displacement is whatever the layer does, so the pressure is the
normal stiffness with tangential traction zero times u_z (the Schur
complement of K). ``'full'``: the lateral displacement is known too (marker
tracking), and all three traction components follow from K.

Contact outside the footprint (``contact``): ``'field'`` trusts the height map
everywhere in the image (the gel's sink-in and bulge around the contact
included); ``'footprint'`` trusts it only where the height exceeds
`threshold_mm` (the contact) and takes the traction as zero elsewhere, solving
the mixed problem ``C t = u`` on the footprint (C = K^-1 the compliance) with
the pressure non-negative and, where it is zero, the model's surface nowhere
shallower than the measured one (the Signorini conditions, whose answer is
unique): sweeps of an active set, each by conjugate gradients preconditioned
with K, that drop pulling pixels and take back lifted ones (in the manner of
Polonsky and Keer, Wear 231, 1999). With ``'fem'`` the footprint problem is
solved on the nodes: a node whose hat function reaches a mask pixel is a
contact node, the others carry no force, and ``(C_mm + S) f_m = u_m`` with
C = K^-1 computed once (a small dense solve per frame). u_m is the hat-weighted
mean height over the mask pixels alone, and S holds springs on the rim nodes: a
node whose hat has the share f of the mask is tied to u_m by a spring of
stiffness ``1.5 sqrt(f) / (1 - f)`` times its own diagonal stiffness (free
at f = 0, prescribed at f = 1; sqrt(f): a punch's stiffness grows as the square
root of its area). On the default grid (0.88 mm nodes at 427 x 320, 0.0806
mm/px, h 3 mm, nu 0.48) a 2.5 mm flat punch reads 0.969 to 0.979 of Hayes (1972) over
three positions, 1.5 mm and 4 mm punches 0.959 to 0.984, rigid spheres 1.009 to
1.039 of the spectral method (``tests/test_fem_forces_grid.py``). The rule
before (every such node prescribed its tributary mean over all pixels, the zero
beyond a rigid profile's edge included) read the 2.5 mm punch 0.80 to 0.81 and
the 1.5 mm one 0.68. The price: on a true gel surface (the sink-in measured off
the contact) it reads 3 to 5 % high where the old rule was within 1 %, and a
mask 1.3 times too wide reads 11 % low (``tests/test_fem_forces_proof.py``).
The 1.5 and the square root were chosen by comparing a few rim laws on these
punches and spheres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np
import scipy.fft as sfft
import scipy.sparse as sp

from .._blocks import AUTO_BIN_MAX, auto_binning, bin_blocks, check_binning, unbin_blocks
from .._checks import InputError, check_poisson, check_positive
from ._layer import layer_normal_stiffness, layer_surface_stiffness
from ._pad import pad_surface_stiffness

__all__ = ["AUTO_BIN_MAX", "ForceEstimator", "ForceMap", "auto_binning"]


@dataclass(frozen=True)
class ForceMap:
    """Contact force distribution of one frame or a batch.

    Attributes
    ----------
    forces_n : (rows, cols, 3) or (N, rows, cols, 3) float64 ndarray
        (float32 for a float32 height map with ``'spectral'``, ``'normal'``, ``'field'``).
        Nodal (per pixel for ``'spectral'``) forces (Fx, Fy, Fz) the object
        applies to the gel, N; Fz positive pressing into the gel.
    pressure_kpa : (rows, cols) or (N, rows, cols) float ndarray
        Normal traction, kPa, compressive positive (Fz over the node's area).
    total_n : (3,) or (N, 3) float64 ndarray
        (Fx, Fy, Fz) summed over the sensed area, N.
    x_mm, y_mm : (cols,), (rows,) float64 ndarray
        Node coordinates from the centre of the image's top-left pixel, mm
        (x along columns, y along rows).
    contact : (rows, cols) or (N, rows, cols) bool ndarray or None
        The footprint used with ``contact='footprint'``.
    """

    forces_n: np.ndarray
    pressure_kpa: np.ndarray
    total_n: np.ndarray
    x_mm: np.ndarray
    y_mm: np.ndarray
    contact: np.ndarray | None = None


#: The settings the operator is built from: changing one rebuilds it.
_OPERATOR_FIELDS = frozenset({"shape_px", "mm_per_px", "thickness_mm", "E_mpa", "nu", "method",
                              "mode", "pad_mm", "grid", "element", "layers", "cache_dir",
                              "binning", "contact"})


@dataclass
class ForceEstimator:
    """Height map to contact force distribution, built once per sensor.

    Parameters
    ----------
    shape_px : (H, W)
        Height-map shape, rows and columns.
    mm_per_px : float
        Pixel size, mm.
    thickness_mm, E_mpa, nu : float
        Gel thickness h (mm), Young's modulus (MPa) and Poisson's ratio, e.g.
        from :func:`~tactilevision.mechanics.fit_indentation`.
    grid : (nx, ny), default (40, 30)
        Surface nodes along x and y for ``method='fem'`` (ignored by
        ``'spectral'``, which works on the full (H, W) grid).
    method : {'spectral', 'fem'}, default 'spectral'
    mode : {'normal', 'full'}, default 'normal'
        Normal displacement only (zero tangential traction), or the full 3D
        displacement (pass `lateral_mm` to the call).
    contact : {'footprint', 'field'}, default 'footprint'
        Trust the height map only where it exceeds `threshold_mm` (zero
        traction elsewhere, non-negative pressure), or everywhere (a
        simulation's height map, right beyond the contact too). The
        default is ``tactilevision forces``' (and ``live``'s, ``batch
        forces``'): on a measured height map every error beyond the
        contact pushes or pulls with ``'field'``. With
        ``method='fem'`` a contact node is tied to the mean height of the
        footprint's pixels under its hat, a partly covered rim node by a spring
        (module docstring: a 2.5 mm flat punch reads 0.97 to 0.98 of Hayes 1972
        on the default grid, true Hertz surfaces with their sink-in 3 to 5 %
        high).
    threshold_mm : float, default 0.02
        Footprint threshold on the height, mm (above the height map's noise;
        ``tactilevision forces --threshold-mm``'s default).
    pad_mm : float, optional
        Zero padding on each side for ``'spectral'``, mm; default 2 h.
    element : {'bbar', 'hex2', 'hex1'}, default 'bbar'
        Element of the FEM model (:func:`~tactilevision.fem.pad_surface_stiffness`).
    layers : int, optional
        FEM elements through the thickness.
    cache_dir : str, optional
        Where the FEM's condensed stiffness is cached.
    beta : float, default 0.0
        Finite-strain stiffening of the calibrated law (``fit.json``'s
        ``beta``; the paper's eq. (2),
        ``kappa_n = kappa (1 + beta w / h)``): forces and pressures are
        scaled by ``1 + beta w / h``, w the depth of the contact (the
        99th percentile of the height over the footprint, or over the
        pixels above `threshold_mm` with ``'field'``). 0: linear
        elasticity, which under-reads a press w/h = 0.17 deep by 12 % (the
        sample session's bonded gauge block, beta = 0.82).
    binning : int or 'auto', default 'auto'
        With ``contact='footprint'``, ``method='spectral'`` and
        ``mode='normal'``: the footprint's contact problem solved on blocks
        of k x k pixels (a block is in the footprint when at least half its
        pixels are, at their mean height), each block's force spread evenly
        over its footprint pixels; the maps keep the image's shape. 'auto':
        per frame, the largest k up to 8 with k pixels at most the
        footprint's width over 20 (:func:`auto_binning`; a disc's width is
        its radius): a flat punch's total within 0.5 % of every pixel's
        (``tests/test_forces_binning.py``), the solve about a twentieth
        of the cost on the sample session's presses (the validation
        report's ``forces_default``). 1: every pixel. Other settings work
        on every pixel ('auto' gives 1; a k above 1 is refused).

    Raises
    ------
    InputError
        For a non-positive size, nu outside [0, 0.5), an unknown method, mode
        or contact, a `binning` other than 'auto' or a positive integer (or
        above 1 where it does not apply), or a grid with fewer than 2 nodes
        along an axis; also when such a value is assigned later (the
        estimator then keeps its old one).

    Notes
    -----
    A setting changed after construction (``est.E_mpa = 0.4``) takes effect at
    once: it is checked, and the operator is rebuilt when it depends on it
    (size, scale, h, E, nu, method, mode, padding, grid; the FEM's from its
    disk cache).

    Examples
    --------
    >>> import numpy as np
    >>> est = ForceEstimator((64, 64), 0.1, thickness_mm=3.0, E_mpa=0.2, nu=0.45)
    >>> u = np.full((64, 64), 0.05)           # the whole sensed area 0.05 mm down
    >>> float(est(u).total_n[2]) > 0
    True
    """

    shape_px: tuple[int, int]
    mm_per_px: float
    thickness_mm: float
    E_mpa: float
    nu: float
    grid: tuple[int, int] = (40, 30)
    method: str = "spectral"
    mode: str = "normal"
    contact: str = "footprint"
    threshold_mm: float = 0.02
    pad_mm: float | None = None
    element: str = "bbar"
    layers: int | None = None
    cache_dir: str | None = None
    beta: float = 0.0
    binning: int | str = "auto"
    _op: object = field(init=False, repr=False, default=None)

    def __post_init__(self) -> None:
        self._validate()
        self._build()
        object.__setattr__(self, "_ready", True)

    def __setattr__(self, name: str, value: object) -> None:
        # a changed setting takes effect at once: checked, and the operator rebuilt when it
        # depends on it; a bad value is refused and the estimator stays as it was
        if name.startswith("_") or not self.__dict__.get("_ready", False):
            object.__setattr__(self, name, value)
            return
        saved = dict(self.__dict__)
        object.__setattr__(self, "_ready", False)
        try:
            object.__setattr__(self, name, value)
            self._validate()
            if name in _OPERATOR_FIELDS:
                self._build()
        except BaseException:
            self.__dict__.clear()
            self.__dict__.update(saved)
            raise
        object.__setattr__(self, "_ready", True)

    def _validate(self) -> None:
        try:
            H, W = (int(s) for s in self.shape_px)
        except (TypeError, ValueError):
            raise InputError(f"shape_px must be (H, W), got {self.shape_px!r}") from None
        if H < 2 or W < 2:
            raise InputError(f"shape_px must be at least (2, 2), got {self.shape_px!r}")
        self.shape_px = (H, W)
        self.mm_per_px = check_positive(self.mm_per_px, "mm_per_px")
        self.thickness_mm = check_positive(self.thickness_mm, "thickness_mm")
        self.E_mpa = check_positive(self.E_mpa, "E_mpa")
        self.nu = check_poisson(self.nu)
        for name, ok in (("method", ("spectral", "fem")), ("mode", ("normal", "full")),
                         ("contact", ("field", "footprint"))):
            if getattr(self, name) not in ok:
                raise InputError(f"{name} must be one of {', '.join(map(repr, ok))}, got "
                                 f"{getattr(self, name)!r}")
        self.threshold_mm = check_positive(self.threshold_mm, "threshold_mm")
        if not (math.isfinite(float(self.beta)) and float(self.beta) >= 0):
            raise InputError(f"beta must be finite and >= 0, got {self.beta!r}")
        self.beta = float(self.beta)
        self.binning = check_binning(self.binning)
        if self.binning not in ("auto", 1) and not self._binnable:
            raise InputError(f"binning = {self.binning} applies to contact='footprint', "
                             "method='spectral', mode='normal' only; use 1 or 'auto'")

    @property
    def _binnable(self) -> bool:
        return (self.contact == "footprint" and self.method == "spectral"
                and self.mode == "normal")

    @property
    def blocks(self) -> int | str:
        """`binning` where it applies (the spectral footprint, normal mode), else 1: what
        a :class:`~tactilevision.optics.DepthReconstructor` with ``boundary='contact'``
        takes for the heights it feeds this estimator (``forces``, ``live``, ``batch``)."""
        return self.binning if self._binnable else 1

    def _build(self) -> None:
        if self.method == "spectral":
            pad = 2.0 * self.thickness_mm if self.pad_mm is None else float(self.pad_mm)
            if not (math.isfinite(pad) and pad >= 0):
                raise InputError(f"pad_mm must be >= 0, got {self.pad_mm!r}")
            self._op = _Spectral(self.shape_px, self.mm_per_px, self.thickness_mm, self.E_mpa,
                                 self.nu, self.mode, pad)
            self._binned = {}        # block side -> its operator, built when first needed
        else:
            self._op = _Fem(self.shape_px, self.mm_per_px, self.thickness_mm, self.E_mpa,
                            self.nu, self.mode, tuple(self.grid), self.element, self.layers,
                            self.cache_dir)

    @property
    def x_mm(self) -> np.ndarray:
        """(cols,) node x coordinates, mm, from the top-left pixel's centre."""
        return self._op.x_mm

    @property
    def y_mm(self) -> np.ndarray:
        """(rows,) node y coordinates, mm."""
        return self._op.y_mm

    def __call__(self, height_mm: np.ndarray, lateral_mm: np.ndarray | None = None, *,
                 contact_mask: np.ndarray | None = None) -> ForceMap:
        """The force map of a height map (or a batch).

        Parameters
        ----------
        height_mm : (H, W) or (N, H, W) array_like
            Normal displacement, mm, positive into the gel (the height maps
            of :class:`~tactilevision.optics.DepthReconstructor`). NaN is
            not allowed: fill masked pixels first. float32 input is
            computed in single precision (the camera-rate path: with
            'spectral', 'normal', 'field' OpenCV's real DFT, about 3.5 times
            the float64 frame rate at 427 x 320, relative error about 1e-6,
            ``tests/test_fem_forces.py``; with 'footprint', the solve on the
            footprint's box), its forces and pressures returned in float32;
            anything else in double.
        lateral_mm : (H, W, 2) or (N, H, W, 2) array_like, optional
            Lateral displacement (ux, uy), mm, along columns and rows; needed
            with ``mode='full'``.
        contact_mask : (H, W) or (N, H, W) bool array_like, optional
            The footprint for ``contact='footprint'`` (e.g.
            :meth:`~tactilevision.optics.DepthReconstructor.contact_mask`,
            the pixels whose colour change exceeds the noise); default
            ``height_mm > threshold_mm``.

        Returns
        -------
        ForceMap

        Raises
        ------
        InputError
            For a shape other than (H, W) / (N, H, W), non-finite values, or
            a missing or misshapen `lateral_mm` in ``'full'`` mode.
        """
        u = np.asarray(height_mm)
        u = u if u.dtype == np.float32 else u.astype(np.float64)
        H, W = self.shape_px
        single = u.ndim == 2
        if u.ndim not in (2, 3) or u.shape[-2:] != (H, W):
            raise InputError(f"height_mm must have shape ({H}, {W}) or (N, {H}, {W}), got "
                             f"{u.shape}")
        if not np.all(np.isfinite(u)):
            raise InputError("height_mm holds NaN or inf: fill masked pixels first")
        u = u[None] if single else u
        if self.mode == "full":
            if lateral_mm is None:
                raise InputError("mode='full' needs lateral_mm, the (ux, uy) displacement")
            lat = np.asarray(lateral_mm, u.dtype)
            lat = lat[None] if lat.ndim == 3 else lat
            if lat.shape != (*u.shape, 2):
                raise InputError(f"lateral_mm must have shape {(*u.shape[1:], 2)} "
                                 f"(or batched), got {np.shape(lateral_mm)}")
            if not np.all(np.isfinite(lat)):
                raise InputError("lateral_mm holds NaN or inf")
            disp = np.concatenate([lat, u[..., None]], axis=-1)
        else:
            disp = u[..., None]
        if self.contact == "footprint":
            if contact_mask is None:
                mask = u > self.threshold_mm
            else:
                mask = np.asarray(contact_mask, bool)
                mask = mask[None] if mask.ndim == 2 else mask
                if mask.shape != u.shape:
                    raise InputError(f"contact_mask must have the height map's shape "
                                     f"{u.shape[1:]}, got {np.shape(contact_mask)}")
            if self._binnable and self.binning != 1:
                forces, mask = self._binned_footprint(u, mask)
            else:
                forces, mask = self._op.footprint(disp, mask)
        else:
            forces, mask = self._op.field(disp), None
        if self.beta > 0:       # in place: the operators' arrays are fresh
            forces *= self._stiffening(u, mask)[:, None, None, None].astype(forces.dtype)
        area = self._op.node_area_mm2
        pressure = forces[..., 2] * (1e3 / area)
        if forces.dtype == np.float32:
            # per component (a float64 reduction over both image axes with a cast
            # took half the camera-rate path's time: 2.1 of 4.5 ms at 427 x 320)
            # (the lateral components of a normal solve are zero: not summed)
            comps = range(3) if self.mode == "full" else (2,)
            total = np.zeros((len(forces), 3))
            for i, fn in enumerate(forces):
                for c in comps:
                    total[i, c] = float(fn[..., c].sum())
        else:
            total = forces.sum(axis=(1, 2))
        if single:
            forces, pressure, total = forces[0], pressure[0], total[0]
            mask = None if mask is None else mask[0]
        return ForceMap(forces_n=forces, pressure_kpa=pressure, total_n=total,
                        x_mm=self.x_mm, y_mm=self.y_mm, contact=mask)

    def _binned_footprint(self, u: np.ndarray, mask: np.ndarray
                          ) -> tuple[np.ndarray, np.ndarray]:
        """The footprint solve on k x k blocks (``binning``), frame by frame: (N, H, W, 3)
        forces, each block's spread evenly over its footprint pixels, and the (N, H, W)
        footprint of the blocks that push."""
        H, W = self.shape_px
        out_f, out_m = [], []
        for ui, mi in zip(u, mask, strict=True):
            k = auto_binning(mi) if self.binning == "auto" else int(self.binning)
            if k == 1:
                f, m = self._op.footprint(ui[None, ..., None], mi[None])
                out_f.append(f[0])
                out_m.append(np.asarray(m[0], bool))
                continue
            op = self._binned.get(k)
            if op is None:
                op = self._binned[k] = _Spectral((-(-H // k), -(-W // k)), self.mm_per_px * k,
                                                 self.thickness_mm, self.E_mpa, self.nu,
                                                 self.mode, self._op.pad_mm)
            f = np.zeros((H, W, 3), u.dtype)
            keep = np.zeros((H, W), bool)
            out_f.append(f)
            out_m.append(keep)
            rows = np.flatnonzero(mi.any(axis=1))
            if rows.size == 0:
                continue
            cols = np.flatnonzero(mi.any(axis=0))
            # the footprint's bounding box in whole blocks: only it is binned and solved
            r0, c0 = int(rows[0]) // k * k, int(cols[0]) // k * k
            r1, c1 = min(H, int(rows[-1]) // k * k + k), min(W, int(cols[-1]) // k * k + k)
            # a block is in the footprint when at least half its pixels are, at their mean
            # height (the indenter's, not the mean with the gel beside it)
            # (a block at the image's edge over the pixels it holds: zeros beyond)
            mf = mi[r0:r1, c0:c1].astype(u.dtype)
            frac = bin_blocks(mf, k, edge="zero")
            uc = np.zeros(op.shape, u.dtype)
            mc = np.zeros(op.shape, bool)
            box = (slice(r0 // k, r0 // k + frac.shape[0]), slice(c0 // k, c0 // k + frac.shape[1]))
            uc[box] = (bin_blocks(ui[r0:r1, c0:c1] * mf, k, edge="zero")
                       / np.maximum(frac, u.dtype.type(1e-6)))
            mc[box] = frac >= 0.5
            fc, kc = op.footprint(uc[None, ..., None], mc[None])
            # each block's force over its footprint pixels (a block in it holds at least one)
            n = frac * u.dtype.type(k * k)
            per = np.where(kc[0][box], fc[0][box][..., 2] / np.maximum(n, 1), 0).astype(u.dtype)
            inside = unbin_blocks(kc[0][box], k, (r1 - r0, c1 - c0)) & mi[r0:r1, c0:c1]
            keep[r0:r1, c0:c1] = inside
            f[r0:r1, c0:c1, 2] = np.where(inside, unbin_blocks(per, k, (r1 - r0, c1 - c0)), 0)
        if len(out_f) == 1:                  # one frame: no copy (7 MB at 640 x 480)
            return out_f[0][None], out_m[0][None]
        return np.stack(out_f), np.stack(out_m)

    def _stiffening(self, u: np.ndarray, mask: np.ndarray | None) -> np.ndarray:
        """(N,) factors 1 + beta w / h, w the contact's depth (99th percentile)."""
        if mask is not None and mask.shape != u.shape:   # FEM nodes: footprint on its grid
            mask = None
        out = np.ones(len(u))
        for i, ui in enumerate(u):
            m = (ui > self.threshold_mm) if mask is None else mask[i]
            if m.any():
                out[i] += self.beta * float(np.percentile(ui[m], 99)) / self.thickness_mm
        return out


class _Spectral:
    """The layer's Fourier surface stiffness on the zero-padded image grid."""

    def __init__(self, shape: tuple[int, int], dx: float, h: float, E: float, nu: float,
                 mode: str, pad_mm: float) -> None:
        H, W = shape
        p = math.ceil(pad_mm / dx)
        self.pad_mm = pad_mm
        self.shape = shape
        self.fshape = (sfft.next_fast_len(H + 2 * p, real=True),
                       sfft.next_fast_len(W + 2 * p, real=True))
        Hf, Wf = self.fshape
        ky = 2 * np.pi * np.fft.fftfreq(Hf, d=dx)[:, None]
        kx = 2 * np.pi * np.fft.rfftfreq(Wf, d=dx)[None, :]
        self.full = mode == "full"
        if self.full:
            K = layer_surface_stiffness(kx, ky, thickness_mm=h, E_mpa=E, nu=nu)
            self.K = K.astype(np.complex128)
            self.C = np.linalg.inv(K)
        else:
            kn = layer_normal_stiffness(np.hypot(kx, ky), thickness_mm=h, E_mpa=E, nu=nu)
            self.K = kn[..., None, None].astype(np.complex128)
            self.C = 1.0 / self.K
            self.K32 = kn.astype(np.complex64)
            self.C32 = (1.0 / kn).astype(np.complex64)
        # the camera-rate path (float32, 'normal'): OpenCV's real DFT, twice as fast
        # as scipy.fft's at these sizes (0.45 against 0.72 ms forward at 480 x 600,
        # one core), with the stiffness times the pixel area as the packed (CCS)
        # spectrum of its real, even kernel
        self.kccs = None
        if not self.full:
            kernel = np.fft.irfft2(kn * (dx * dx), s=self.fshape)
            self.kccs = cv2.dft(kernel.astype(np.float32))
        # 'footprint' in normal mode on the footprint's bounding box (_footprint_box): the
        # compliance's and the stiffness's real, even kernels on the padded grid
        self.box = not self.full
        self._box_cache: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = {}
        self._warm: tuple[np.ndarray, tuple[int, int]] | None = None
        #: a list to which each box solve appends its sweeps (:func:`_mixed_solve`'s `log`)
        self.solve_log: list | None = None
        self._kernels = () if self.full else tuple(
            np.fft.irfft2(spec, s=self.fshape).astype(np.float32) for spec in (1.0 / kn, kn))
        self.node_area_mm2 = dx * dx
        self.x_mm = np.arange(W) * dx
        self.y_mm = np.arange(H) * dx

    def _apply(self, M: np.ndarray, t: np.ndarray) -> np.ndarray:
        """(N, Hf, Wf, c) real field -> (N, Hf, Wf, c): IFFT(M FFT(t)) per component."""
        f = sfft.rfft2(t, s=self.fshape, axes=(1, 2), workers=1)
        g = np.einsum("yxij,nyxj->nyxi", M, f) if M.shape[-1] > 1 else M[..., 0] * f
        return sfft.irfft2(g, s=self.fshape, axes=(1, 2), workers=1)

    def _apply32(self, M: np.ndarray, t: np.ndarray) -> np.ndarray:
        """(Hf, Wf, 1) float32 -> (Hf, Wf, 1) float32: IFFT(M FFT(t)), M scalar per k."""
        f = sfft.rfft2(t[..., 0], s=self.fshape, workers=1)
        return sfft.irfft2(M * f, s=self.fshape, workers=1)[..., None]

    def field(self, disp: np.ndarray) -> np.ndarray:
        H, W = self.shape
        if disp.dtype == np.float32 and self.kccs is not None:
            Hf, Wf = self.fshape
            out = np.zeros((*disp.shape[:3], 3), np.float32)
            for n, d in enumerate(disp[..., 0]):
                u = cv2.copyMakeBorder(d, 0, Hf - H, 0, Wf - W, cv2.BORDER_CONSTANT, value=0)
                f = cv2.dft(u)
                f = cv2.mulSpectrums(f, self.kccs, 0)
                out[n, :, :, 2] = cv2.idft(f, flags=cv2.DFT_REAL_OUTPUT | cv2.DFT_SCALE)[:H, :W]
            return out
        t = self._apply(self.K, disp)[:, :H, :W]
        return self._forces(t)

    def _forces(self, t: np.ndarray) -> np.ndarray:
        """(N, H, W, c) traction, MPa -> (N, H, W, 3) forces, N, in t's dtype (float32 on
        the camera-rate path, whose traction is single precision)."""
        out = np.zeros((*t.shape[:3], 3), t.dtype)
        if t.shape[-1] == 3:
            out[:] = t
        else:
            out[..., 2] = t[..., 0]
        out *= out.dtype.type(self.node_area_mm2)
        return out

    def footprint(self, disp: np.ndarray, contact: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
        H, W = self.shape
        Hf, Wf = self.fshape
        out, masks = [], []
        for d, m in zip(disp, contact, strict=True):
            if not self.full and self.box:
                f, keep = self._footprint_box(d[..., 0], m)
                out.append(f)
                masks.append(keep)
                continue
            mask = np.zeros((Hf, Wf), bool)
            mask[:H, :W] = m
            if self.full:
                u = np.zeros((Hf, Wf, d.shape[-1]))
                u[:H, :W] = d
                t = _mixed_solve(lambda x: self._apply(self.C, x[None])[0],
                                 lambda x: self._apply(self.K, x[None])[0], u, mask)
            else:
                # normal contact: scalar operators in single precision, 2.9 times faster
                # than in double at 640 x 480 with the same total to 1e-6 relative (a
                # 0.3 mm punch: 1.1706174 against 1.1706187 N, timed in one run)
                u = np.zeros((Hf, Wf, 1), np.float32)
                u[:H, :W] = d
                t = _mixed_solve(lambda x: self._apply32(self.C32, x),
                                 lambda x: self._apply32(self.K32, x), u, mask)
            out.append(self._forces(t[None, :H, :W])[0])
            masks.append(mask[:H, :W] & (t[:H, :W, -1] > 0))
        if len(out) == 1:        # one frame: a view, not a copy (7 MB at 640 x 480)
            return out[0][None], masks[0][None]
        return np.stack(out), np.stack(masks)

    def _box_spectra(self, size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
        """The compliance's and the stiffness's kernels on a (Fy, Fx) grid, as OpenCV's
        packed spectra: each offset (dy, dx) with |dy| <= Fy // 2, |dx| <= Fx // 2
        holds the padded grid's periodic kernel at that offset."""
        spectra = self._box_cache.get(size)
        if spectra is None:
            Fy, Fx = size
            Hf, Wf = self.fshape
            iy = np.arange(-(Fy // 2), (Fy + 1) // 2)
            ix = np.arange(-(Fx // 2), (Fx + 1) // 2)
            spectra = []
            for kern in self._kernels:
                k = np.zeros((Fy, Fx), np.float32)
                k[np.ix_(iy % Fy, ix % Fx)] = kern[np.ix_(iy % Hf, ix % Wf)]
                spectra.append(cv2.dft(k))
            if len(self._box_cache) >= 8:
                self._box_cache.pop(next(iter(self._box_cache)))
            spectra = self._box_cache[size] = tuple(spectra)
        return spectra

    def _footprint_box(self, u: np.ndarray, m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """'footprint', normal mode, one frame: the solve of :func:`_mixed_solve` on the
        footprint's bounding box. The traction lies on the footprint and only its values
        there are read, so the padded grid's circular convolutions reduce exactly to
        linear ones over the box's offsets: an FFT grid of twice the box, with the padded
        grid's own kernels. (H, W, 3) forces, N, and the final footprint."""
        H, W = self.shape
        forces = np.zeros((H, W, 3), u.dtype)     # as the padded grid's path gives
        if not m.any():
            self._warm = None
            return forces, np.zeros((H, W), bool)
        rows = np.flatnonzero(m.any(axis=1))
        cols = np.flatnonzero(m.any(axis=0))
        r0, r1, c0, c1 = int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1
        h, w = r1 - r0, c1 - c0
        # at least 2 x 2: OpenCV's dft refuses nonzeroRows on a single column (a footprint
        # one pixel wide)
        Fy = max(2, cv2.getOptimalDFTSize(2 * h - 1))
        Fx = max(2, cv2.getOptimalDFTSize(2 * w - 1))
        if Fy > self.fshape[0] or Fx > self.fshape[1]:       # no smaller than the padded grid
            Fy, Fx = self.fshape
        c_ccs, k_ccs = self._box_spectra((Fy, Fx))

        def conv(spec: np.ndarray, x: np.ndarray) -> np.ndarray:
            # only the first h rows are non-zero going in, and read coming out
            a = cv2.copyMakeBorder(x, 0, Fy - h, 0, Fx - w, cv2.BORDER_CONSTANT, value=0)
            a = cv2.mulSpectrums(cv2.dft(a, nonzeroRows=h), spec, 0)
            return cv2.idft(a, flags=cv2.DFT_REAL_OUTPUT | cv2.DFT_SCALE, nonzeroRows=h)[:h, :w]

        t0 = None
        if self._warm is not None:            # the previous frame's traction where it overlaps
            pt, (p0, q0) = self._warm
            t0 = np.zeros((h, w), np.float32)
            a0, a1 = max(r0, p0), min(r1, p0 + pt.shape[0])
            b0, b1 = max(c0, q0), min(c1, q0 + pt.shape[1])
            if a0 < a1 and b0 < b1:
                t0[a0 - r0:a1 - r0, b0 - c0:b1 - c0] = pt[a0 - p0:a1 - p0, b0 - q0:b1 - q0]
        t = _mixed_solve(lambda x: conv(c_ccs, x[..., 0])[..., None],
                         lambda x: conv(k_ccs, x[..., 0])[..., None],
                         np.ascontiguousarray(u[r0:r1, c0:c1], np.float32)[..., None],
                         m[r0:r1, c0:c1], t0=None if t0 is None else t0[..., None],
                         log=self.solve_log)[..., 0]
        self._warm = (t, (r0, c0))
        forces[r0:r1, c0:c1, 2] = t * self.node_area_mm2
        keep = np.zeros((H, W), bool)
        keep[r0:r1, c0:c1] = m[r0:r1, c0:c1] & (t > 0)
        return forces, keep


def _mixed_solve(compliance, stiffness, u: np.ndarray, mask: np.ndarray, *,
                 tol: float = 1e-5, sweep_tol: float = 1e-3, max_iter: int = 500,
                 max_sweeps: int = 24, t0: np.ndarray | None = None,
                 log: list | None = None) -> np.ndarray:
    """Traction t, zero outside `mask`: the footprint problem's unique answer.

    On the footprint `mask` the traction pushes (normal component t_z >= 0);
    where it pushes, the layer's surface C t equals the measured displacement
    u, and where it is zero the surface lies nowhere shallower than u
    ((C t)_z >= u_z): the Signorini conditions of the strictly convex problem
    min 1/2 t'C t - u't over t_z >= 0 on the mask, whose answer is unique
    (Kalker, Three-dimensional elastic bodies in rolling contact, 1990, ch. 2;
    the rigid indenter's shape read as the measured height on the footprint).
    Solved by sweeps of an active set: preconditioned conjugate gradients on
    the masked compliance operator with the stiffness (its inverse on the
    whole plane) restricted to the set as the preconditioner; after each,
    pixels that pull leave the set and pixels the model's surface lifts above
    the measured height return to it. Every sweep but the last stops at the
    relative residual `sweep_tol`, the last at `tol`: on the sample session's
    frames (``benchmarks/bench_forces_default.py --sweeps``) 14 iterations a
    frame instead of 20 with every sweep at 1e-5, the maps within 0.26 % of
    their peak; the rule before this one (pulling pixels dropped, never taken
    back, every sweep to 1e-5) read within 0.31 % of this answer in 23. With
    `sweep_tol` 1e-3 (the same bench, 60 consecutive frames on every pixel): 10
    iterations a frame (median) against 14 at 1e-4 and 20 with every sweep at
    1e-5; the maps within 0.11 % of their peak of every sweep at 1e-5 (median),
    on one frame of 38 1.7 %, where a single pixel at the contact's edge
    changes sides; the totals within 1.2e-5.
    `tol` 1e-5 moves the totals of the sample session's punch presses by under
    3e-6 N against 1e-8. `t0`, u's shape: the first guess (a previous frame's
    traction), its pushing pixels the first active set, used while its
    residual is below the zero guess's. At most `max_sweeps` sweeps. `log`: a
    list to which the solve appends one list of (conjugate-gradient
    iterations, pixels dropped, pixels taken back) per sweep.
    """
    sweeps: list[tuple[int, int, int]] = []
    if log is not None:
        log.append(sweeps)
    active = mask.copy()
    t = np.zeros_like(u) if t0 is None else t0.astype(u.dtype, copy=False)
    if t0 is not None and (mask & (t0[..., -1] > 0)).any():
        active = mask & (t0[..., -1] > 0)           # the previous frame's contact first
    # a pixel returns where the model's surface lies above the measured height by more
    # than the solve's own tolerance (no sweep undoes the one before over rounding)
    lift = tol * float(np.abs(u[..., -1][mask]).max()) if mask.any() else 0.0
    final = sweep_tol <= tol
    # C t on the whole grid, carried along the iterations (each applies C to the search
    # direction anyway): a sweep that only takes pixels back needs no new product
    Ct = None
    for _ in range(max_sweeps):
        m = active[..., None]
        b = np.where(m, u, 0.0)
        t = np.where(m, t, 0.0)
        if Ct is None:
            Ct = compliance(t) if t.any() else np.zeros_like(u)
        r = b - np.where(m, Ct, 0.0)
        if _norm(r) > _norm(b):                     # a guess further off than zero
            t, r, Ct = np.zeros_like(u), b, np.zeros_like(u)
        stop = (tol if final else sweep_tol) * (_norm(b) or 1.0)
        z = np.where(m, stiffness(r), 0.0)
        p = z.copy()
        rz = _dot(r, z)
        iterations = 0
        while _norm(r) >= stop and iterations < max_iter:
            iterations += 1
            Cp = compliance(p)
            Ap = np.where(m, Cp, 0.0)
            alpha = rz / _dot(p, Ap)
            t = t + alpha * p
            Ct += alpha * Cp                        # a fresh array: compliance's or zeros
            r = r - alpha * Ap
            if _norm(r) < stop:
                break
            z = np.where(m, stiffness(r), 0.0)
            rz_new = _dot(r, z)
            p = z + (rz_new / rz) * p
            rz = rz_new
        tensile = active & (t[..., -1] < 0)
        if tensile.any():
            active &= ~tensile
            Ct = None                               # t changes where it pulled
            sweeps.append((iterations, int(np.count_nonzero(tensile)), 0))
            continue
        lifted = mask & ~active & (Ct[..., -1] < u[..., -1] - lift)
        sweeps.append((iterations, 0, int(np.count_nonzero(lifted))))
        if lifted.any():
            active |= lifted
            continue
        if final:
            break
        final = True
    return t.astype(u.dtype, copy=False)      # the last solve's (zero outside its set)


def _dot(a: np.ndarray, b: np.ndarray) -> float:
    """Sum of the products of two equal-shape arrays, accumulated in their dtype (einsum:
    no BLAS threads, which a busy 2-core machine slows many times)."""
    return float(np.einsum("i,i->", a.ravel(), b.ravel()))


def _norm(a: np.ndarray) -> float:
    return _dot(a, a) ** 0.5


class _Fem:
    """The condensed surface stiffness of the 3D pad on a node grid over the image.

    'field': node values are tributary means of the height map. 'footprint':
    contact nodes (hat reaching the mask) tied to the hat-weighted mean height
    of the mask pixels, the partly covered ones by springs (module docstring,
    issue 21); the mask pixels' heights are the only ones used.
    """

    def __init__(self, shape: tuple[int, int], dx: float, h: float, E: float, nu: float,
                 mode: str, grid: tuple[int, int], element: str, layers: int | None,
                 cache_dir: str | None) -> None:
        H, W = shape
        if len(grid) != 2 or min(int(g) for g in grid) < 2:
            raise InputError(f"grid must be (nx, ny) with at least 2 nodes each, got {grid!r}")
        nx, ny = int(grid[0]), int(grid[1])
        size = ((W - 1) * dx, (H - 1) * dx)
        st = pad_surface_stiffness((nx, ny), size, h, nu, layers=layers, element=element,
                                   cache_dir=cache_dir)
        self.stiffness = st
        self.full = mode == "full"
        self.K = E * (st.K if self.full else st.K_normal)
        self.nx, self.ny = nx, ny
        self.x_mm = st.x_mm - st.x_mm[0]
        self.y_mm = st.y_mm - st.y_mm[0]
        sx, sy = self.x_mm[1] - self.x_mm[0], self.y_mm[1] - self.y_mm[0]
        wx = np.full(nx, sx)
        wx[[0, -1]] /= 2
        wy = np.full(ny, sy)
        wy[[0, -1]] /= 2
        self.node_area_mm2 = wy[:, None] * wx[None, :]
        if nx > W or ny > H:
            raise InputError(f"grid {grid} is finer than the image {shape}: some nodes "
                             "have no pixel")

        # A node's value is the mean of the height map over its tributary
        # rectangle [x_k - s/2, x_k + s/2] x [y_k - s/2, y_k + s/2] (clipped to
        # the image), pixels weighted by their overlap with it: centred on the
        # node, unlike a nearest-node mean, whose pixels sit up to half a pixel
        # off-centre (on a Hertz contact's flanks that read +7.5 % / +12.9 % at
        # nu 0.45 / 0.49 instead of +0.6 / +1.3 %, tests/test_fem_forces_proof.py).
        # (separable: rows, then columns; each pixel meets at most two nodes per axis)
        self.sample_y = sp.csr_matrix(_overlap(self.y_mm, H, dx))
        # (the columns' weights dense: a BLAS product, where scipy's dense @ sparse
        # rebuilds its operand at every call)
        self.sample_xt = np.ascontiguousarray(_overlap(self.x_mm, W, dx).T)
        # 'footprint': the hat functions at the pixel centres (a node is in contact
        # when its hat reaches a mask pixel; the hat's weight of the mask and the
        # mask's mean height under it set the node's constraint, see footprint)
        hy, hx = _hats(self.y_mm, H, dx), _hats(self.x_mm, W, dx)
        self.hat_y = sp.csr_matrix(hy)
        self.hat_xt = sp.csc_matrix(hx.T)
        self.hat_y_dense, self.hat_x_dense = hy, hx     # for a small footprint's box
        self.hat_full = np.outer(hy.sum(axis=1), hx.sum(axis=1)).ravel()
        self._compliance = None
        self._diag = np.diag(self.K).copy()

    def _nodes(self, disp: np.ndarray) -> np.ndarray:
        """(N, H, W, c) -> (N, n * c) node displacements, dof-major per node."""
        N, c = disp.shape[0], disp.shape[-1]
        nodes = np.empty((N, self.ny, self.nx, c))
        for n in range(N):
            for j in range(c):
                nodes[n, :, :, j] = (self.sample_y @ disp[n, :, :, j]) @ self.sample_xt
        return nodes.reshape(N, -1)

    def _shape(self, f: np.ndarray, c: int) -> np.ndarray:
        N = f.shape[0]
        out = np.zeros((N, self.ny, self.nx, 3))
        f = f.reshape(N, self.ny, self.nx, c)
        if c == 3:
            out[:] = f
        else:
            out[..., 2] = f[..., 0]
        return out

    def field(self, disp: np.ndarray) -> np.ndarray:
        c = disp.shape[-1]
        f = self._nodes(disp) @ self.K.T
        return self._shape(f, c)

    @property
    def compliance(self) -> np.ndarray:
        """C = K^-1 (mm/N), computed on first use."""
        if self._compliance is None:
            self._compliance = np.linalg.inv(self.K)
        return self._compliance

    def footprint(self, disp: np.ndarray, contact: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
        c = disp.shape[-1]
        C = self.compliance
        out, masks = [], []
        for d, m in zip(disp, contact, strict=True):
            # the mask's bounding box: a contact a fraction of the image is sampled by
            # dense products on its box alone, a large one by the sparse hats
            rows_on, cols_on = np.flatnonzero(m.any(axis=1)), np.flatnonzero(m.any(axis=0))
            if rows_on.size and (rows_on[-1] + 1 - rows_on[0]) * (cols_on[-1] + 1 - cols_on[0]) \
                    < 0.25 * m.size:
                box = (slice(rows_on[0], rows_on[-1] + 1), slice(cols_on[0], cols_on[-1] + 1))
                hy, hx = self.hat_y_dense[:, box[0]], self.hat_x_dense[:, box[1]]

                def hats(a: np.ndarray, hy=hy, hx=hx) -> np.ndarray:
                    return hy @ a @ hx.T
            else:
                box = (slice(None), slice(None))

                def hats(a: np.ndarray) -> np.ndarray:
                    return (self.hat_y @ a) @ self.hat_xt
            mf, d = m[box].astype(np.float64), d[box]
            weight = hats(mf).ravel()
            on = weight > 0
            # the hat's share of the mask, and the mean height over the mask pixels
            # alone, hat-weighted (the heights off the mask are not trusted)
            frac = np.minimum(weight / self.hat_full, 1.0)
            w = np.where(on, weight, 1.0)
            target = np.empty((frac.size, c))
            for j in range(c):
                target[:, j] = hats(d[..., j] * mf).ravel() / w
            target = target.ravel()
            f = np.zeros(frac.size * c)
            for _ in range(8):
                dof = np.flatnonzero(np.repeat(on, c))
                f[:] = 0.0
                if dof.size:
                    # node forces on the contact nodes alone, the others free:
                    # (C_mm + S) f_m = u_m, S the rim springs' compliances
                    fr = np.repeat(frac, c)[dof]
                    A = C[np.ix_(dof, dof)]
                    A[np.diag_indices_from(A)] += np.where(
                        fr >= 1.0 - 1e-12, 0.0,
                        (1.0 - fr) / (_SPRING * np.sqrt(fr) * self._diag[dof]))
                    f[dof] = np.linalg.solve(A, target[dof])
                fz = f.reshape(-1, c)[:, -1]
                tensile = on & (fz < 0)
                if not tensile.any():
                    break
                on &= ~tensile
            out.append(f.copy())
            masks.append(on.reshape(self.ny, self.nx))
        return self._shape(np.stack(out), c), np.stack(masks)


#: A rim node's spring to the contact ('footprint', method='fem'): stiffness
#: _SPRING sqrt(f) / (1 - f) times the node's own diagonal stiffness, f the
#: node hat's share of the mask (see _Fem).
_SPRING = 1.5


def _overlap(nodes_mm: np.ndarray, npx: int, dx: float) -> np.ndarray:
    """(n, npx) weights: node k's mean over [x_k - s/2, x_k + s/2] of a pixel row.

    Pixel j covers [j dx - dx/2, j dx + dx/2]; each weight is the pixel's
    overlap with the node's tributary strip, rows normalised to 1.
    """
    x = np.arange(npx) * dx
    s = nodes_mm[1] - nodes_mm[0]
    lo = np.maximum(x[None, :] - dx / 2, nodes_mm[:, None] - s / 2)
    hi = np.minimum(x[None, :] + dx / 2, nodes_mm[:, None] + s / 2)
    w = np.clip(hi - lo, 0.0, None)
    return w / w.sum(axis=1, keepdims=True)


def _hats(nodes_mm: np.ndarray, npx: int, dx: float) -> np.ndarray:
    """(n, npx) node k's hat function max(0, 1 - |x - x_k| / s) at the pixel centres."""
    x = np.arange(npx) * dx
    s = nodes_mm[1] - nodes_mm[0]
    return np.maximum(0.0, 1.0 - np.abs(x[None, :] - nodes_mm[:, None]) / s)
