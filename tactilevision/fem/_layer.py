r"""Fourier-domain surface stiffness of an elastic layer bonded to a rigid base.

An isotropic linear elastic layer (Young's modulus E, Poisson's ratio nu,
thickness h) is bonded (u = 0) to a rigid base at its bottom and loaded on its
top surface. The layer is invariant under translations in x, y, so the
top-surface traction is a convolution of the top-surface displacement:
``t_hat(k) = K(k) u_hat(k)`` with one 3 x 3 matrix per wavevector k.

Conventions (the public contract of this module)
------------------------------------------------
- ``u = (ux, uy, uz)``: top-surface displacement in mm. ux, uy along the image
  x (columns) and y (rows) axes; **uz positive into the gel** (downwards, the
  indentation direction).
- ``t = (tx, ty, p)``: traction the indenter applies to the gel's top surface in
  MPa (N/mm^2); tx, ty along +x, +y; **p positive compressive** (pushing into
  the gel).
- Hats follow numpy's FFT: the forward transform uses exp(-i (kx x + ky y)),
  so a field is a sum of exp(+i k.x) and d/dx -> +i kx;
  ``kx = 2 pi numpy.fft.fftfreq(n, d=dx_mm)`` in rad/mm (see :func:`wavevectors`).
- K in MPa/mm (N/mm^3); ``K(0) = diag(mu/h, mu/h, (lambda + 2 mu)/h)``, with
  mu = E / (2 (1 + nu)) and lambda = 2 mu nu / (1 - 2 nu).

Derivation (done here; checked against an independent finite-layer solution in
``tests/test_fem_layer.py``)
-----------------------------------------------------------------------------
Let zeta be the depth below the top surface (0 <= zeta <= h, pointing into the
gel, so uz is the zeta component). Isotropic elasticity does not care about the
handedness of the frame (x, y, zeta). Rotate x, y so that k = (k, 0), k = |k|,
and write u = U(zeta) exp(i k x'). The tangential displacement across k (the
anti-plane, SH part) decouples: ``mu (U_s'' - k^2 U_s) = 0`` with U_s(h) = 0
gives ``t_s = -sigma_s,zeta(0) = mu k coth(k h) U_s(0)``. The plane-strain part
(U_t along k, W = uz) obeys the Navier equations

    mu (U_t'' - k^2 U_t) + (lambda + mu) i k (i k U_t + W') = 0,
    mu (W'' - k^2 W) + (lambda + mu) (i k U_t' + W'') = 0,

whose general solution, with kappa = 3 - 4 nu, is

    U_t = (a0 + a1 zeta) e^{k zeta} + (a2 + a3 zeta) e^{-k zeta},
    W = i [(kappa a1 - k a0) / k - a1 zeta] e^{k zeta}
        + i [(kappa a3 + k a2) / k + a3 zeta] e^{-k zeta}.

Fixing a0..a3 with U_t(0), W(0) given and U_t(h) = W(h) = 0, the top
traction is ``t_t = -mu (U_t' + i k W)``
and ``p = -(lambda (i k U_t + W') + 2 mu W')`` at zeta = 0 (outward normal
-zeta). Solved with sympy and simplified by hand; with x = k h and

    Delta = kappa^2 (cosh 2x - 1) - 2 x^2   (> 0 for x > 0),

the rotated-frame stiffness, ordered (t, s, z), is K' = (mu / h) times

    [[ 4 (1-nu) x (kappa sinh 2x - 2x) / Delta,   0,          C ],
     [ 0,                                          x coth x,   0 ],
     [ conj(C),   0,   4 (1-nu) x (kappa sinh 2x + 2x) / Delta  ]],

    C = -2 i x [(1 - 2 nu) kappa (cosh 2x - 1) - 2 x^2] / Delta.

The off-diagonal term is purely imaginary and odd in k, so real fields map to
real fields. Back in (x, y) with c = kx / k, s = ky / k (c = 1, s = 0 at k = 0):
``K = Q K' Q^T`` with Q = [[c, -s, 0], [s, c, 0], [0, 0, 1]].

Limits. x -> 0: K' -> diag(1, 1, 2 (1 - nu) / (1 - 2 nu)) mu / h, i.e.
diag(mu, mu, lambda + 2 mu) / h. x -> infinity: the half-space,
K' = (mu k / kappa) [[4 (1-nu), 0, -2i (1-2nu)], [0, kappa, 0], [2i (1-2nu),
0, 4 (1-nu)]], whose inverse is the Fourier transform of the Boussinesq and
Cerruti surface displacements (Johnson 1985, chapter 3); e.g. uz_hat
= -i (1 - 2 nu) kx / (2 mu k^2) tx_hat: a tangential load in +x pushes the
surface into the gel ahead of it. Eliminating the tangential dofs at zero
tangential traction (Schur complement) gives the normal stiffness
``p_hat / uz_hat = 1 / S(k)`` with

    S(k) = 2 (1 - nu^2) / (E k) [kappa sinh 2x - 2x]
           / [kappa cosh 2x + 2 x^2 + 5 - 12 nu + 8 nu^2],

the normal compliance of a layer on a rigid base with a frictionless top (the
expression implemented for finite thickness in ContactMechanics' periodic FFT
half-space, and in the contact-mechanics literature on thin layers).

Numerics. Every term above is divided by e^{2x} (and by x or x^2) and written
with q = e^{-2x}, expm1 and, for x < 1, power series of (sinh 2x - 2x) / x and
(cosh 2x - 1 - 2x^2) / x^2. This removes the overflow of cosh 2x at large k h
and the cancellations at small k h and at nu -> 1/2: with a = 1 - 2 nu,
b = 1 - nu, the numerators and denominators become sums of non-negative terms
(``kappa = 1 + 2a``, ``kappa^2 - 1 = 8ab``). For x > 40 the half-space forms
are used (the layer's corrections, ~x^2 e^{-2x}, are below 1e-31 there), so
nothing overflows or underflows for any finite k. The result agrees with the
symbolic solution evaluated in 60-digit arithmetic to ~3e-16 for x from 1e-6 to
300 and nu up to 0.499.
"""

from __future__ import annotations

import math

import numpy as np

from .._checks import InputError, check_poisson, check_positive

__all__ = ["layer_normal_stiffness", "layer_surface_stiffness", "wavevectors"]

# Taylor coefficients in t^2 (t = 2x) of (sinh t - t) / x = 2 sum_{n>=1} t^{2n} / (2n+1)!
# and (cosh t - 1 - t^2/2) / x^2 = 4 sum_{n>=2} t^{2n-2} / (2n)!, highest power first
# (Horner). 14 terms: the first omitted one is below 1e-19 relative at x = 1 (t = 2).
_N_SERIES = 14
_SINH_COEFFS = tuple(2.0 / math.factorial(2 * n + 1) for n in range(_N_SERIES, 0, -1))
_COSH_COEFFS = tuple(4.0 / math.factorial(2 * n) for n in range(_N_SERIES + 1, 1, -1))
_X_SWITCH = 1.0  # below: power series; above: expm1 forms (< 1 digit of cancellation)
# Above: the half-space forms, exact in double (the layer's corrections are ~x^2 e^{-2x} <
# 1e-31 relative there); keeps x^2 and 1/x^2 away from overflow and underflow.
_X_HALF_SPACE = 40.0


def _check_material(thickness_mm: float, E_mpa: float, nu: float) -> tuple[float, float, float]:
    """Validate the layer's scalars; return them as floats."""
    return (check_positive(thickness_mm, "thickness_mm"), check_positive(E_mpa, "E_mpa"),
            check_poisson(nu))


def _check_k(k: object, name: str) -> np.ndarray:
    """A real, finite float64 array (any shape) from `k`."""
    arr = np.asarray(k)
    if arr.dtype == object or not (np.issubdtype(arr.dtype, np.integer)
                                   or np.issubdtype(arr.dtype, np.floating)):
        raise InputError(f"{name} must be a real numeric array (rad/mm), got dtype {arr.dtype}")
    arr = arr.astype(np.float64, copy=False)
    if not np.all(np.isfinite(arr)):
        bad = int(arr.size - np.count_nonzero(np.isfinite(arr)))
        raise InputError(f"{name} must be finite, found {bad} NaN or infinite value(s)")
    return arr


def _horner(coeffs: tuple[float, ...], t2: np.ndarray) -> np.ndarray:
    out = np.full_like(t2, coeffs[0])
    for c in coeffs[1:]:
        out *= t2
        out += c
    return out


def _scaled_hyperbolics(x: np.ndarray) -> tuple[np.ndarray, ...]:
    """Overflow-free building blocks for x = |k| h >= 0 (float64 arrays of x's shape).

    Returns ``q = e^{-2x}`` and, all multiplied by e^{-2x}:
    ``sig = sinh(2x) / x``, ``sig3 = (sinh 2x - 2x) / x``,
    ``gam = (cosh 2x - 1) / x^2``, ``gam4 = (cosh 2x - 1 - 2x^2) / x^2``.
    """
    q = np.exp(-2.0 * x)
    small = x < _X_SWITCH
    # Small x: power series (no cancellation), times q.
    xs = np.where(small, x, 0.0)
    t2 = 4.0 * xs * xs
    sinh_part = t2 * _horner(_SINH_COEFFS, t2)      # (sinh 2x - 2x) / x
    cosh_part = t2 * _horner(_COSH_COEFFS, t2)      # (cosh 2x - 1 - 2x^2) / x^2
    # Large x: sinh(2x) e^{-2x} = -expm1(-4x) / 2, (cosh 2x - 1) e^{-2x} = expm1(-2x)^2 / 2.
    xl = np.where(small, 1.0, x)
    sig_l = -np.expm1(-4.0 * xl) / (2.0 * xl)
    gam_l = np.expm1(-2.0 * xl) ** 2 / (2.0 * xl * xl)
    sig = np.where(small, q * (2.0 + sinh_part), sig_l)
    gam = np.where(small, q * (2.0 + cosh_part), gam_l)
    sig3 = np.where(small, q * sinh_part, sig_l - 2.0 * q)
    gam4 = np.where(small, q * cosh_part, gam_l - 2.0 * q)
    return q, sig, sig3, gam, gam4


def _x_coth_x(x: np.ndarray) -> np.ndarray:
    """x coth x for x >= 0 (1 at x = 0), overflow-free."""
    xs = np.where(x > 0, x, 1.0)
    out = xs * (1.0 + np.exp(-2.0 * xs)) / -np.expm1(-2.0 * xs)
    return np.where(x > 0, out, 1.0)


def _rotated_blocks(x: np.ndarray, nu: float) -> tuple[np.ndarray, ...]:
    """Dimensionless (times h / mu) K_tt, K_ss, K_zz and Im K_tz in the frame k = (|k|, 0)."""
    a, b = 1.0 - 2.0 * nu, 1.0 - nu
    kappa = 3.0 - 4.0 * nu
    far = x > _X_HALF_SPACE
    xc = np.where(far, _X_HALF_SPACE, x)
    q, sig, sig3, gam, gam4 = _scaled_hyperbolics(xc)
    delta = 8.0 * a * b * gam + gam4                    # Delta e^{-2x} / x^2
    k_tt = 4.0 * b * (2.0 * a * sig + sig3) / delta
    k_zz = 4.0 * b * (kappa * sig + 2.0 * q) / delta
    k_tz_imag = -2.0 * xc * (a * kappa * gam - 2.0 * q) / delta
    k_ss = _x_coth_x(xc)
    # Half-space: K' = (mu k / kappa) [[4b, -2i a], [2i a, 4b]], K'_ss = mu k.
    k_tt = np.where(far, 4.0 * b / kappa * x, k_tt)
    k_zz = np.where(far, 4.0 * b / kappa * x, k_zz)
    k_tz_imag = np.where(far, -2.0 * a / kappa * x, k_tz_imag)
    k_ss = np.where(far, x, k_ss)
    return k_tt, k_ss, k_zz, k_tz_imag


def layer_surface_stiffness(kx: np.ndarray | float, ky: np.ndarray | float, *,
                            thickness_mm: float, E_mpa: float, nu: float) -> np.ndarray:
    """3 x 3 Fourier surface stiffness K(k) of a layer bonded to a rigid base.

    ``t_hat(k) = K(k) @ u_hat(k)`` relates the FFTs of the top-surface
    displacement u = (ux, uy, uz) (uz positive into the gel) and of the
    traction t = (tx, ty, p) the indenter applies (p positive compressive).
    Conventions and derivation are in the module docstring.

    Parameters
    ----------
    kx, ky : array_like of float
        Wavevector components in rad/mm (``2 pi numpy.fft.fftfreq(n, d=mm)``,
        e.g. from :func:`wavevectors`), mutually broadcastable, finite.
    thickness_mm : float
        Layer thickness h in mm, > 0.
    E_mpa : float
        Young's modulus in MPa, > 0.
    nu : float
        Poisson's ratio, within [0, 0.5) (0.499 is fine).

    Returns
    -------
    K : (..., 3, 3) complex128 ndarray
        ``...`` is the broadcast shape of `kx` and `ky`; units MPa/mm. Rows and
        columns ordered (x, y, z). Hermitian and positive definite; the
        tangential block is real, the tangential-normal coupling imaginary and
        odd in k. ``K(0) = diag(mu, mu, lambda + 2 mu) / h``; for |k| h >> 1 it
        tends to the half-space stiffness (the inverse of the Fourier-transformed
        Boussinesq-Cerruti surface displacements), reached to double precision
        for |k| h > ~20.

    Raises
    ------
    InputError
        (a ``ValueError``) naming `thickness_mm` or `E_mpa` (not positive and
        finite), `nu` (outside [0, 0.5)), `kx` or `ky` (not real, not finite,
        or not broadcastable).

    Notes
    -----
    In the frame rotated so that k lies along x', with x = |k| h,
    kappa = 3 - 4 nu and Delta = kappa^2 (cosh 2x - 1) - 2 x^2::

        K'_tt = (mu/h) 4 (1-nu) x (kappa sinh 2x - 2x) / Delta
        K'_zz = (mu/h) 4 (1-nu) x (kappa sinh 2x + 2x) / Delta
        K'_tz = -(mu/h) 2i x [(1-2nu) kappa (cosh 2x - 1) - 2x^2] / Delta = conj(K'_zt)
        K'_ss = (mu/h) x coth x                     (anti-plane, decoupled)

    and ``K = Q K' Q^T`` with Q the rotation by the angle of k. The formulas are
    derived here from the Navier equations (module docstring), evaluated in an
    overflow- and cancellation-free form, and checked in the tests against an
    independent finite-element (finite layer method) solution and the
    half-space limit. The 2 x 2 in-plane part is the zero-frequency limit of
    the layer stiffness matrix of the stiffness-matrix method for layered
    media [2]_ with its bottom fixed (not compared with that paper's printed
    form); its Schur complement is the normal compliance of [3]_ (see
    :func:`layer_normal_stiffness`). A 640 x 480 grid takes ~0.1 s.

    References
    ----------
    .. [1] K. L. Johnson, "Contact Mechanics", Cambridge University Press, 1985,
       chapter 3 (Boussinesq and Cerruti: the half-space limit).
       doi:10.1017/CBO9781139171731
    .. [2] E. Kausel, J. M. Roesset, "Stiffness matrices for layered soils",
       Bull. Seismol. Soc. Am. 71(6):1743-1761, 1981.
    .. [3] ContactEngineering/ContactMechanics, ``FFTElasticHalfSpace.py``:
       ``PeriodicFFTElasticHalfSpace(..., thickness=h, poisson=nu)``, the
       finite-thickness correction of the normal surface stiffness.

    Examples
    --------
    >>> import numpy as np
    >>> from tactilevision.fem._layer import layer_surface_stiffness
    >>> K = layer_surface_stiffness(0.0, 0.0, thickness_mm=2.0, E_mpa=3.0, nu=0.25)
    >>> K.shape, K.dtype
    ((3, 3), dtype('complex128'))
    >>> np.round(K.real, 4)  # mu / h = 0.6, (lambda + 2 mu) / h = 1.8
    array([[0.6, 0. , 0. ],
           [0. , 0.6, 0. ],
           [0. , 0. , 1.8]])
    >>> K = layer_surface_stiffness(np.array([1.0, -1.0]), 0.0, thickness_mm=2.0,
    ...                             E_mpa=3.0, nu=0.25)
    >>> np.round(K[:, 0, 2], 4)  # odd, imaginary tangential-normal coupling
    array([0.-0.4519j, 0.+0.4519j])
    """
    h, e, n = _check_material(thickness_mm, E_mpa, nu)
    kx_arr, ky_arr = _check_k(kx, "kx"), _check_k(ky, "ky")
    try:
        kx_arr, ky_arr = np.broadcast_arrays(kx_arr, ky_arr)
    except ValueError:
        raise InputError(f"kx and ky must be broadcastable, got shapes {np.shape(kx_arr)} "
                         f"and {np.shape(ky_arr)}") from None
    k = np.hypot(kx_arr, ky_arr)
    k_tt, k_ss, k_zz, k_tz_imag = _rotated_blocks(k * h, n)
    scale = e / (2.0 * (1.0 + n)) / h                    # mu / h
    nonzero = k > 0
    k_safe = np.where(nonzero, k, 1.0)
    c = np.where(nonzero, kx_arr / k_safe, 1.0)
    s = np.where(nonzero, ky_arr / k_safe, 0.0)
    out = np.zeros((*k.shape, 3, 3), dtype=np.complex128)
    re, im = out.real, out.imag                           # views
    re[..., 0, 0] = scale * (k_tt * c * c + k_ss * s * s)
    re[..., 1, 1] = scale * (k_tt * s * s + k_ss * c * c)
    re[..., 0, 1] = re[..., 1, 0] = scale * (k_tt - k_ss) * c * s
    re[..., 2, 2] = scale * k_zz
    coupling = scale * k_tz_imag                          # K_tz = i * coupling
    im[..., 0, 2] = coupling * c
    im[..., 1, 2] = coupling * s
    im[..., 2, 0] = -im[..., 0, 2]
    im[..., 2, 1] = -im[..., 1, 2]
    return out


def layer_normal_stiffness(k: np.ndarray | float, *, thickness_mm: float, E_mpa: float,
                           nu: float) -> np.ndarray:
    """Normal surface stiffness p_hat / uz_hat at zero tangential traction.

    The Schur complement of :func:`layer_surface_stiffness` eliminating the
    tangential dofs: the response of a layer bonded to a rigid base under a
    frictionless indenter (tx = ty = 0).

    Parameters
    ----------
    k : array_like of float
        Wavenumber in rad/mm; only |k| is used. Finite.
    thickness_mm : float
        Layer thickness h in mm, > 0.
    E_mpa : float
        Young's modulus in MPa, > 0.
    nu : float
        Poisson's ratio, within [0, 0.5).

    Returns
    -------
    stiffness : float64 ndarray, shape of `k`
        ``1 / S(|k|)`` in MPa/mm (p positive compressive, uz positive into the
        gel); ``(lambda + 2 mu) / h`` at k = 0, ``E |k| / (2 (1 - nu^2))`` (the
        half-space) for |k| h >> 1.

    Raises
    ------
    InputError
        (a ``ValueError``) naming `thickness_mm`, `E_mpa`, `nu` or `k`, as in
        :func:`layer_surface_stiffness`.

    Notes
    -----
    With x = |k| h and kappa = 3 - 4 nu, the normal compliance is [1]_ [2]_::

        S(k) = 2 (1 - nu^2) / (E k) [kappa sinh 2x - 2x]
               / [kappa cosh 2x + 2 x^2 + 5 - 12 nu + 8 nu^2],

    evaluated here (scaled by e^{-2x}, a = 1 - 2 nu, b = 1 - nu) as
    ``(mu / h) [kappa G + (2 x^2 + 8 b^2) q] / (b (2 a Sg + Sg3))`` with
    q = e^{-2x}, G = (cosh 2x - 1) q, Sg = sinh(2x) q / x and
    Sg3 = (sinh 2x - 2x) q / x, which neither overflows nor cancels. It equals
    ``K_zz - |K_tz|^2 / K_tt`` of the 3 x 3 (the anti-plane part is decoupled);
    that identity is checked in the tests.

    References
    ----------
    .. [1] ContactEngineering/ContactMechanics, ``FFTElasticHalfSpace.py``:
       ``PeriodicFFTElasticHalfSpace(..., thickness=h, poisson=nu)`` implements
       this finite-thickness stiffness (with overflowing values replaced by the
       half-space).
    .. [2] K. L. Johnson, "Contact Mechanics", Cambridge University Press,
       1985, chapter 3: the half-space limit 2 (1 - nu^2) / (E k).

    Examples
    --------
    >>> from tactilevision.fem._layer import layer_normal_stiffness
    >>> layer_normal_stiffness(0.0, thickness_mm=1.0, E_mpa=1.0, nu=0.0)
    array(1.)
    >>> float(layer_normal_stiffness(1e3, thickness_mm=1.0, E_mpa=1.0, nu=0.0))  # E k / 2
    500.0
    """
    h, e, n = _check_material(thickness_mm, E_mpa, nu)
    x = np.abs(_check_k(k, "k")) * h
    a, b = 1.0 - 2.0 * n, 1.0 - n
    kappa = 3.0 - 4.0 * n
    far = x > _X_HALF_SPACE
    xc = np.where(far, _X_HALF_SPACE, x)
    q, sig, sig3, gam, _ = _scaled_hyperbolics(xc)
    num = kappa * gam * xc * xc + (2.0 * xc * xc + 8.0 * b * b) * q
    den = b * (2.0 * a * sig + sig3)
    dimensionless = np.where(far, x / b, num / den)      # half-space: mu k / (1 - nu)
    return np.asarray(e / (2.0 * (1.0 + n)) / h * dimensionless, dtype=np.float64)


def wavevectors(shape: tuple[int, int], mm_per_px: float) -> tuple[np.ndarray, np.ndarray]:
    """Angular wavevector grids (kx, ky) for an (H, W) image, in numpy FFT order.

    Parameters
    ----------
    shape : tuple of int
        (H, W): rows run along y, columns along x. Both >= 1.
    mm_per_px : float
        Pixel pitch in mm, > 0.

    Returns
    -------
    kx, ky : (H, W) float64 ndarrays
        ``kx[i, j] = 2 pi fftfreq(W, mm_per_px)[j]``,
        ``ky[i, j] = 2 pi fftfreq(H, mm_per_px)[i]``, in rad/mm, matching
        ``numpy.fft.fft2`` of an (H, W) image.

    Raises
    ------
    InputError
        (a ``ValueError``) naming `shape` (not two positive integers) or
        `mm_per_px` (not positive and finite).

    Examples
    --------
    >>> from tactilevision.fem._layer import wavevectors
    >>> kx, ky = wavevectors((2, 4), 0.25)
    >>> kx.shape, float(kx[0, 1]), float(ky[1, 0])  # 2 pi / (4 * 0.25), -2 pi / (2 * 0.25)
    ((2, 4), 6.283185307179586, -12.566370614359172)
    """
    try:
        dims = tuple(shape)
        ok = len(dims) == 2 and all(int(d) == d and int(d) >= 1 for d in dims)
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise InputError(f"shape must be two positive integers (H, W), got {shape!r}")
    pitch = check_positive(mm_per_px, "mm_per_px")
    height, width = int(dims[0]), int(dims[1])
    kx = 2.0 * np.pi * np.fft.fftfreq(width, d=pitch)
    ky = 2.0 * np.pi * np.fft.fftfreq(height, d=pitch)
    kx_grid, ky_grid = np.meshgrid(kx, ky)
    return kx_grid, ky_grid
