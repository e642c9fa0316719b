r"""Condensed top-surface stiffness of a 3D gel pad, the inverse-FEM reference.

The pad is a box Lx x Ly x h (mm), linear elastic (E, nu), bonded at the
bottom to the sensor's rigid prism (u = 0), traction-free on its four sides,
and loaded on its top by the contact. As in Ma, Donlon, Dong and Rodriguez
[1]_, the measured top-surface displacement is imposed and the nodal
reactions are the contact force distribution. The problem is linear, so one
matrix does it for every frame: with u the top-node displacements and f the
nodal forces, ``f = E K u``, where K (E = 1 MPa) is the Schur complement of
the FEM stiffness on the top nodes (the other nodes unloaded); it scales
linearly with E and is computed once per geometry, mesh and nu, then kept on
disk. K_normal is the further Schur complement on the uz dofs: the normal
forces for a normal displacement field with zero tangential nodal forces
(a frictionless contact, or one whose shear is not sought).

Mesh and elements are described in :mod:`._pad_mesh`, the cache in
:mod:`._pad_cache`.
"""

from __future__ import annotations

import os
import time
import warnings
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from .._checks import InputError, check_poisson, check_positive
from ._pad_cache import (
    CacheError,
    cache_directory,
    cache_key,
    cache_path,
    read_entry,
    write_entry,
)
from ._pad_mesh import ELEMENTS, PadModel, default_layers, single_blas_thread

__all__ = ["PadStiffness", "pad_surface_stiffness"]


@dataclass(frozen=True, eq=False)
class PadStiffness:
    """Condensed top-surface stiffness of the pad, for E = 1 MPa.

    Top-surface node ``k = iy * nx + ix`` sits at ``(x_mm[ix], y_mm[iy])``
    (x along image columns, y along image rows); its dofs are ``3 k + c`` for
    c = 0, 1, 2 = (x, y, z). uz is positive *into* the gel (the indentation
    direction) and Fz is the force the indenter applies to the gel, positive
    pressing into it; x and y components point along +x and +y. The arrays
    are read-only.

    Attributes
    ----------
    K : (3 n, 3 n) float64 ndarray, N/mm per MPa
        Nodal forces (N) ``E * K @ u`` for top displacements u (mm) and
        Young's modulus E (MPa), n = nx * ny. Symmetric positive definite.
    K_normal : (n, n) float64 ndarray, N/mm per MPa
        ``Fz = E * K_normal @ uz`` with zero tangential nodal forces: the
        Schur complement of K on its z dofs. Symmetric positive definite.
    x_mm : (nx,) float64 ndarray
        Node x coordinates, mm, centred on the pad.
    y_mm : (ny,) float64 ndarray
        Node y coordinates, mm, centred on the pad.
    thickness_mm : float
        Pad thickness h, mm.
    nu : float
        Poisson's ratio.
    layers : int
        Elements through the thickness.
    element : str
        'hex1', 'bbar' or 'hex2' (see :func:`pad_surface_stiffness`).
    key : str
        Cache key: SHA-256 hex digest of every input and the cache format version.
    build_s : float
        Seconds the build took (when loaded from the cache: the stored value).
    cached : bool
        Loaded from the disk cache.
    nbytes : int
        Bytes of the cache file (0 when nothing was stored).
    """

    K: np.ndarray
    K_normal: np.ndarray
    x_mm: np.ndarray
    y_mm: np.ndarray
    thickness_mm: float
    nu: float
    layers: int
    element: str
    key: str
    build_s: float
    cached: bool
    nbytes: int

    @property
    def shape(self) -> tuple[int, int]:
        """(ny, nx): the node grid as an image, ``uz.reshape(shape)``."""
        return len(self.y_mm), len(self.x_mm)


def _check_int(value: object, name: str, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < minimum:
        raise InputError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return int(value)


def _check_pair(value: object, name: str) -> tuple[object, object]:
    if isinstance(value, str | bytes) or np.ndim(value) != 1 or len(value) != 2:  # type: ignore[arg-type]
        raise InputError(f"{name} must be a pair (along x, along y), got {value!r}")
    return value[0], value[1]  # type: ignore[index]


def _normal_schur(k: np.ndarray) -> np.ndarray:
    """K_zz - K_zt K_tt^{-1} K_tz (dense Cholesky), symmetrised."""
    n = k.shape[0] // 3
    z = np.arange(n) * 3 + 2
    t = np.setdiff1d(np.arange(3 * n), z)
    factor = sla.cho_factor(k[np.ix_(t, t)], check_finite=False)
    kn = k[np.ix_(z, z)] - k[np.ix_(z, t)] @ sla.cho_solve(factor, k[np.ix_(t, z)],
                                                          check_finite=False)
    kn += kn.T
    kn *= 0.5
    return kn


def pad_surface_stiffness(grid: tuple[int, int] = (40, 30),
                          size_mm: tuple[float, float] = (45.2, 33.8),
                          thickness_mm: float = 4.0, nu: float = 0.49, *,
                          layers: int | None = None, element: str = "bbar",
                          cache: bool = True,
                          cache_dir: str | os.PathLike | None = None) -> PadStiffness:
    """Condensed top-surface stiffness of a bonded gel pad (inverse-FEM matrix).

    Parameters
    ----------
    grid : (int, int), default (40, 30)
        Surface nodes (nx, ny) along x (image columns) and y (image rows),
        each >= 2, equally spaced over `size_mm`; they are the element vertices.
    size_mm : (float, float), default (45.2, 33.8)
        Pad size (Lx, Ly), mm, > 0.
    thickness_mm : float, default 4.0
        Pad thickness h, mm, > 0.
    nu : float, default 0.49
        Poisson's ratio, within [0, 0.5).
    layers : int, optional
        Elements through the thickness, >= 1. Default: the nearest integer
        to h over the mean node spacing, at least 2 (3 for the defaults).
    element : {'bbar', 'hex1', 'hex2'}, default 'bbar'
        'bbar': trilinear hexahedra, 2 x 2 x 2 Gauss points for the shear
        (mu) term and the element centre alone for the volumetric (lambda)
        term: mean-dilatation B-bar, free of volumetric locking.
        'hex1': trilinear, full 2 x 2 x 2 integration; locks as nu -> 0.5
        (62 % too stiff for a 10 mm wavelength on the default mesh at
        nu = 0.49, 3 % at nu = 0.3).
        'hex2': 27-node triquadratic hexahedra (scikit-fem ``ElementHex2``),
        3 x 3 x 3 Gauss points; the top surface's mid-side and face nodes
        follow the bilinear interpolation of the vertex nodes, so K acts on
        the vertices like the other two (the reference; about 100 s on the
        default grid). Left traction-free instead, they would turn the
        vertex forces into point loads, 55 % too soft (see :mod:`._pad_mesh`).
    cache : bool, default True
        Read the result from, and write it to, the disk cache. False builds
        without touching it.
    cache_dir : path-like, optional
        Cache folder. Default ``$TACTILEVISION_CACHE/fem`` if that variable
        is set, else ``~/.cache/tactilevision/fem``.

    Returns
    -------
    PadStiffness
        K (3n x 3n) and K_normal (n x n), float64, N/mm for E = 1 MPa, the
        node coordinates, the resolved inputs, the cache key, the build time,
        whether it came from the cache and the cache file's size.

    Raises
    ------
    InputError
        (a ``ValueError``) naming the argument: `grid` not two integers >= 2,
        `size_mm` or `thickness_mm` not positive and finite, `nu` outside
        [0, 0.5), `layers` not an integer >= 1, unknown `element`.
    numpy.linalg.LinAlgError
        If the stiffness is not positive definite (does not happen for valid
        inputs).

    Warns
    -----
    RuntimeWarning
        If a cache file is corrupt or was written for other inputs (it is
        rebuilt and overwritten), or the cache cannot be written.

    Notes
    -----
    Sign conventions: uz > 0 *into* the gel, Fz > 0 pressing into it (the
    mesh's z axis points out of the gel; its z components are flipped).
    Forces are in N for displacements in mm and E in MPa:
    ``f = E * K @ u``. The problem is linear, so K for E = 1 MPa scales.

    Static condensation: with the FEM stiffness A split into the top-vertex
    dofs t and the others i (bonded base removed),
    ``K = A_tt - A_ti A_ii^{-1} A_it``; A_ii is block tridiagonal in slices
    across the pad's longer axis and is factorised by dense block Cholesky
    (BLAS-3, many right-hand sides at once; SuperLU's multi-right-hand-side
    solve was 30 times slower). ``K_normal = K_zz - K_zt K_tt^{-1} K_tz`` by
    a dense Cholesky of K_tt. Weak form and elements: :mod:`._pad_mesh`.
    The build runs BLAS on one thread (restored afterwards): its hundreds of
    small dense blocks ran 10 to 70 times slower multithreaded on a 2-core
    machine shared with another job. Default mesh: about 2.5 s to build,
    0.15 s to load from the cache.

    A nodal force is the hat-function-weighted integral of the surface
    traction (Galerkin), so ``Fz / (dx dy)`` is a local average of the
    pressure: for a pressure mode cos(k x) it is the pressure times
    ``sinc^2(k dx / 2)`` (0.956 for a 10 mm wavelength on the default
    1.16 mm grid). Against the closed form for a layer on a rigid base
    (Ma et al. [1]_ follow the same inverse FEM), a 10 mm wavelength on the
    default grid at nu = 0.49 comes out 2.5 % soft with 'bbar' and 62 %
    stiff with 'hex1' after this factor (benchmarks/bench_fem_pad.py).

    Size: K holds 72 n^2 bytes (104 MB for the default 1200 nodes), and
    the build needs about as much again; the cache file holds the upper
    triangles of K and K_normal, about 40 n^2 bytes (58 MB). 'hex2' on the
    default grid takes about 100 s.

    References
    ----------
    .. [1] D. Ma, E. Donlon, S. Dong, A. Rodriguez, "Dense Tactile Force
       Estimation using GelSlim and inverse FEM", IEEE ICRA 2019, pp.
       5418-5424. doi:10.1109/ICRA.2019.8794113

    Examples
    --------
    >>> import numpy as np
    >>> from tactilevision.fem import pad_surface_stiffness
    >>> pad = pad_surface_stiffness((9, 7), (16.0, 12.0), 3.0, cache=False)
    >>> pad.K.shape, pad.K_normal.shape, pad.layers
    ((189, 189), (63, 63), 2)
    >>> uz = np.full(pad.shape, 0.1)            # 0.1 mm into the gel everywhere
    >>> fz = 0.5 * pad.K_normal @ uz.ravel()    # E = 0.5 MPa: forces in N
    >>> bool(fz.sum() > 0)
    True
    """
    gx, gy = _check_pair(grid, "grid")
    nx, ny = _check_int(gx, "grid", 2), _check_int(gy, "grid", 2)
    sx, sy = _check_pair(size_mm, "size_mm")
    lx, ly = check_positive(sx, "size_mm"), check_positive(sy, "size_mm")
    h = check_positive(thickness_mm, "thickness_mm")
    nu_f = check_poisson(nu)
    if layers is None:
        n_layers = default_layers((nx, ny), (lx, ly), h)
    else:
        n_layers = _check_int(layers, "layers", 1)
    if element not in ELEMENTS:
        raise InputError(f"element must be one of {ELEMENTS}, got {element!r}")

    inputs = {"grid": [nx, ny], "size_mm": [lx, ly], "thickness_mm": h, "nu": nu_f,
              "layers": n_layers, "element": element}
    key = cache_key(inputs)
    x_mm = np.linspace(-0.5 * lx, 0.5 * lx, nx)
    y_mm = np.linspace(-0.5 * ly, 0.5 * ly, ny)
    path = cache_path(cache_directory(cache_dir), key) if cache else None

    def result(k, kn, build_s, cached, nbytes) -> PadStiffness:
        for a in (k, kn, x_mm, y_mm):
            a.flags.writeable = False
        return PadStiffness(K=k, K_normal=kn, x_mm=x_mm, y_mm=y_mm, thickness_mm=h, nu=nu_f,
                            layers=n_layers, element=element, key=key, build_s=build_s,
                            cached=cached, nbytes=nbytes)

    if path is not None:
        try:
            k, kn, build_s, size = read_entry(path, key, inputs, x_mm, y_mm)
            return result(k, kn, build_s, True, size)
        except FileNotFoundError:
            pass
        except (CacheError, OSError) as exc:
            warnings.warn(f"pad_surface_stiffness: cache file {path} cannot be trusted "
                          f"({exc}); rebuilding it", RuntimeWarning, stacklevel=2)

    t0 = time.perf_counter()
    with single_blas_thread():
        model = PadModel((nx, ny), (lx, ly), h, nu_f, n_layers, element)
        k = model.condense()
        kn = _normal_schur(k)
    build_s = time.perf_counter() - t0

    nbytes = 0
    if path is not None:
        try:
            nbytes = write_entry(path, key, inputs, k, kn, x_mm, y_mm, build_s)
        except OSError as exc:
            warnings.warn(f"pad_surface_stiffness: cannot write the cache file {path} "
                          f"({exc}); continuing without it", RuntimeWarning, stacklevel=2)
    return result(k, kn, build_s, False, nbytes)
