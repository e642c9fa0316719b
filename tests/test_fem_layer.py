"""Fourier surface stiffness of a layer bonded to a rigid base (tactilevision.fem._layer).

References used here, all written independently of the module:
- a finite layer method (1D finite elements through the thickness for one
  wavevector, bottom fixed, condensed to the top surface);
- the half-space compliance, the Fourier transform of the Boussinesq and Cerruti
  surface displacements (Johnson, Contact Mechanics, 1985, chapter 3);
- the normal compliance S(k) of a layer on a rigid base with a frictionless top,
  typed from its closed form.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from tactilevision import InputError
from tactilevision.fem import layer_normal_stiffness, layer_surface_stiffness, wavevectors

NUS = (0.0, 0.3, 0.45, 0.49, 0.499)


def _lame(E, nu):
    mu = E / (2.0 * (1.0 + nu))
    return mu, 2.0 * mu * nu / (1.0 - 2.0 * nu)


def _scaled_error(K, ref):
    """max |K - ref|_ij / sqrt(|ref_ii ref_jj|): relative error, fair to every entry."""
    d = np.sqrt(np.abs(np.diagonal(ref, axis1=-2, axis2=-1)))
    return float(np.max(np.abs(K - ref) / (d[..., :, None] * d[..., None, :])))


def _compliance_formula(k, h, E, nu):
    """S(k) = uz_hat / p_hat of a layer on a rigid base, frictionless top (direct form)."""
    x = k * h
    kappa = 3.0 - 4.0 * nu
    return (2.0 * (1.0 - nu**2) / (E * k) * (kappa * np.sinh(2 * x) - 2 * x)
            / (kappa * np.cosh(2 * x) + 2 * x**2 + 5 - 12 * nu + 8 * nu**2))


def _half_space_compliance(kx, ky, E, nu):
    """u_hat = C t_hat for the half-space, from Boussinesq and Cerruti (Johnson 1985).

    Surface displacements (z into the solid) of a point force P (normal) and
    Q (along x) at the origin, rho = |(x, y)|, G = mu:
        P: u_x = -(1 - 2 nu) P x / (4 pi G rho^2),  u_z = (1 - nu) P / (2 pi G rho)
        Q: u_x = Q [(1 - nu) / rho + nu x^2 / rho^3] / (2 pi G),
           u_y = Q nu x y / (2 pi G rho^3),  u_z = (1 - 2 nu) Q x / (4 pi G rho^2).
    Transforms (forward kernel exp(-i k.x)): 1/rho -> 2 pi / k, x/rho^2 -> -2 pi i kx / k^2,
    x^2/rho^3 -> 2 pi (1/k - kx^2/k^3), x y/rho^3 -> -2 pi kx ky / k^3.
    """
    mu = E / (2.0 * (1.0 + nu))
    k = np.hypot(kx, ky)
    kv = (kx, ky)
    C = np.zeros((3, 3), dtype=complex)
    for i in range(2):
        for j in range(2):
            C[i, j] = ((i == j) - nu * kv[i] * kv[j] / k**2) / (mu * k)
        C[i, 2] = 1j * (1.0 - 2.0 * nu) * kv[i] / (2.0 * mu * k**2)   # u_i from p
        C[2, i] = -1j * (1.0 - 2.0 * nu) * kv[i] / (2.0 * mu * k**2)  # u_z from t_i
    C[2, 2] = (1.0 - nu) / (mu * k)
    return C


def _finite_layer_stiffness(kx, ky, h, E, nu, n_el=200):
    """Top-surface 3 x 3 stiffness from quadratic finite elements through the thickness.

    Fields U(zeta) exp(i (kx x + ky y)), zeta = depth (0 top, h bottom), nodal
    (Ux, Uy, Uz) with Uz along +zeta (into the gel). Hermitian weak form
    sum_e int conj(eps(V)) : C eps(U) dzeta = conj(V(0)) . t, with d/dx -> i kx,
    d/dy -> i ky. The lambda (div u)^2 term is projected onto discontinuous
    linear pressures per element (B-bar, no locking up to nu = 0.499). Bottom
    node fixed; the rest condensed onto the top node. Nodes graded towards the
    top (zeta = h s^2) where the fields of large k live.
    """
    mu, lam = _lame(E, nu)
    z = h * np.linspace(0.0, 1.0, n_el + 1) ** 2
    L = np.diff(z)
    xi, w = np.polynomial.legendre.leggauss(3)
    N = np.stack([xi * (xi - 1) / 2, 1 - xi**2, xi * (xi + 1) / 2], axis=1)  # (gauss, node)
    dN = np.stack([xi - 0.5, -2 * xi, xi + 0.5], axis=1)                    # d/dxi
    ikx, iky = 1j * kx, 1j * ky
    B = np.zeros((n_el, 3, 6, 9), dtype=complex)  # strain (Voigt, engineering shear)
    D = np.zeros((n_el, 3, 9), dtype=complex)     # divergence
    for a in range(3):
        na = N[None, :, a]
        dna = dN[None, :, a] * (2.0 / L)[:, None]
        ux, uy, uz = 3 * a, 3 * a + 1, 3 * a + 2
        B[:, :, 0, ux] = ikx * na                                   # eps_xx
        B[:, :, 1, uy] = iky * na                                   # eps_yy
        B[:, :, 2, uz] = dna                                        # eps_zz
        B[:, :, 3, ux], B[:, :, 3, uy] = iky * na, ikx * na         # gamma_xy
        B[:, :, 4, ux], B[:, :, 4, uz] = dna, ikx * na              # gamma_xz
        B[:, :, 5, uy], B[:, :, 5, uz] = dna, iky * na              # gamma_yz
        D[:, :, ux], D[:, :, uy], D[:, :, uz] = ikx * na, iky * na, dna
    jw = w[None, :] * (L / 2.0)[:, None]
    d_mu = mu * np.array([2.0, 2.0, 2.0, 1.0, 1.0, 1.0])
    ke = np.einsum("eg,egia,i,egib->eab", jw, B.conj(), d_mu, B)
    P = np.stack([np.ones_like(xi), xi], axis=1)
    G = np.einsum("eg,gp,ega->epa", jw, P, D)
    M = np.einsum("eg,gp,gq->epq", jw, P, P)
    ke += lam * np.einsum("epa,epq,eqb->eab", G.conj(), np.linalg.inv(M), G)
    nodes = 2 * np.arange(n_el)[:, None] + np.arange(3)[None, :]
    dofs = (3 * nodes[:, :, None] + np.arange(3)).reshape(n_el, 9)
    n_dof = 3 * (2 * n_el + 1) - 3                                  # bottom node fixed
    rows, cols = np.repeat(dofs, 9, axis=1).ravel(), np.tile(dofs, (1, 9)).ravel()
    keep = (rows < n_dof) & (cols < n_dof)
    K = sp.csc_matrix((ke.ravel()[keep], (rows[keep], cols[keep])), shape=(n_dof, n_dof))
    k_tt = K[:3, :3].toarray()
    k_ti = K[:3, 3:].toarray()
    k_it = K[3:, :3].toarray()
    return k_tt - k_ti @ splu(K[3:, 3:].tocsc()).solve(k_it)


# ---------------------------------------------------------------------------- references


@pytest.mark.parametrize("nu", NUS)
def test_matches_finite_layer_method(nu):
    """The key check: signs, coupling and rotation against an independent FE solution."""
    h, E = 2.0, 1.5
    worst = 0.0
    for kh, angle in ((0.05, 0.3), (0.3, 1.1), (1.0, 0.7), (3.0, 2.0), (8.0, -0.4),
                      (20.0, 0.7)):
        k = kh / h
        kx, ky = k * np.cos(angle), k * np.sin(angle)
        ref = _finite_layer_stiffness(kx, ky, h, E, nu)
        K = layer_surface_stiffness(kx, ky, thickness_mm=h, E_mpa=E, nu=nu)
        worst = max(worst, _scaled_error(K, ref))
        # the zero-tangential-traction stiffness of the FE model, too
        fe_normal = (ref[2, 2] - ref[2, :2] @ np.linalg.solve(ref[:2, :2], ref[:2, 2])).real
        normal = layer_normal_stiffness(k, thickness_mm=h, E_mpa=E, nu=nu)
        assert normal == pytest.approx(fe_normal, rel=1e-6)
    assert worst < 1e-6


@pytest.mark.parametrize("nu", NUS)
def test_zero_wavevector_is_diag_mu_mu_lambda_plus_2mu_over_h(nu):
    h, E = 3.0, 0.7
    mu, lam = _lame(E, nu)
    want = np.diag([mu / h, mu / h, (lam + 2 * mu) / h]).astype(complex)
    K0 = layer_surface_stiffness(0.0, 0.0, thickness_mm=h, E_mpa=E, nu=nu)
    np.testing.assert_allclose(K0, want, rtol=1e-14, atol=0)
    # and it is the limit: continuous through k = 0 from any direction
    K_small = layer_surface_stiffness(3e-12, -4e-12, thickness_mm=h, E_mpa=E, nu=nu)
    assert _scaled_error(K_small, want) < 1e-9
    assert layer_normal_stiffness(0.0, thickness_mm=h, E_mpa=E, nu=nu) == pytest.approx(
        (lam + 2 * mu) / h, rel=1e-14)


@pytest.mark.parametrize("nu", NUS)
@pytest.mark.parametrize("kh", [20.0, 50.0, 1e3, 1e4, 1e8])
def test_large_kh_is_the_boussinesq_cerruti_half_space(nu, kh):
    h, E = 4.0, 0.25
    for angle in (0.0, 0.9, 2.5, -1.7):
        k = kh / h
        kx, ky = k * np.cos(angle), k * np.sin(angle)
        want = np.linalg.inv(_half_space_compliance(kx, ky, E, nu))
        K = layer_surface_stiffness(kx, ky, thickness_mm=h, E_mpa=E, nu=nu)
        assert _scaled_error(K, want) < 1e-8
    assert layer_normal_stiffness(k, thickness_mm=h, E_mpa=E, nu=nu) == pytest.approx(
        E * k / (2 * (1 - nu**2)), rel=1e-8)


@pytest.mark.parametrize("nu", NUS)
def test_normal_stiffness_is_schur_complement_and_closed_form(nu):
    h, E = 1.3, 2.0
    k = np.array([1e-4, 1e-3, 0.02, 0.3, 0.77, 1.0, 1.3, 4.0, 15.0, 40.0]) / h
    K = layer_surface_stiffness(k * np.cos(0.4), k * np.sin(0.4), thickness_mm=h, E_mpa=E,
                                nu=nu)
    schur = K[:, 2, 2] - np.einsum("ni,ni->n", K[:, 2, :2],
                                   np.linalg.solve(K[:, :2, :2], K[:, :2, 2:])[..., 0])
    normal = layer_normal_stiffness(k, thickness_mm=h, E_mpa=E, nu=nu)
    assert normal.shape == k.shape and normal.dtype == np.float64
    np.testing.assert_allclose(schur.real, normal, rtol=1e-12)
    np.testing.assert_allclose(schur.imag, 0.0, atol=1e-12 * normal.max())
    np.testing.assert_allclose(normal, 1.0 / _compliance_formula(k, h, E, nu), rtol=1e-10)
    # only |k| matters
    np.testing.assert_array_equal(layer_normal_stiffness(-k, thickness_mm=h, E_mpa=E, nu=nu),
                                  normal)


def test_normal_stiffness_limits_from_the_closed_form():
    h, E, nu = 4.0, 0.3, 0.45
    thin = layer_normal_stiffness(1e-7, thickness_mm=h, E_mpa=E, nu=nu)
    assert thin == pytest.approx(E * (1 - nu) / (h * (1 + nu) * (1 - 2 * nu)), rel=1e-10)
    k = 1e6
    assert layer_normal_stiffness(k, thickness_mm=h, E_mpa=E, nu=nu) == pytest.approx(
        E * k / (2 * (1 - nu**2)), rel=1e-14)


# ---------------------------------------------------------------------------- structure


def test_hermitian_positive_definite_and_finite_over_the_whole_range():
    kh = np.concatenate([[0.0, 1e-300, 1e-12], np.logspace(-6, 4, 161), [1e8, 1e200]])
    angles = np.linspace(-np.pi, np.pi, 7)
    x, a = np.meshgrid(kh, angles)
    for nu in NUS:
        K = layer_surface_stiffness(x * np.cos(a), x * np.sin(a), thickness_mm=1.0, E_mpa=1.0,
                                    nu=nu)
        assert K.shape == (*x.shape, 3, 3) and K.dtype == np.complex128
        assert np.all(np.isfinite(K))
        np.testing.assert_allclose(K, np.conj(np.swapaxes(K, -1, -2)), rtol=0,
                                   atol=1e-15 * np.abs(K).max())
        # positive definite: Cholesky of the diagonally scaled matrix succeeds
        d = np.sqrt(np.diagonal(K, axis1=-2, axis2=-1).real)
        np.linalg.cholesky(K / (d[..., :, None] * d[..., None, :]))
        # real fields stay real: K(-k) = conj(K(k))
        K_minus = layer_surface_stiffness(-x * np.cos(a), -x * np.sin(a), thickness_mm=1.0,
                                          E_mpa=1.0, nu=nu)
        np.testing.assert_allclose(K_minus, np.conj(K), rtol=1e-14, atol=1e-300)
        # tangential block real, coupling imaginary
        assert np.all(K[..., :2, :2].imag == 0) and np.all(K[..., :2, 2].real == 0)


def test_rotation_covariance():
    rng = np.random.default_rng(7)
    for nu in NUS:
        for _ in range(10):
            k = rng.uniform(0.01, 30.0) * np.array([np.cos(t := rng.uniform(0, 2 * np.pi)),
                                                    np.sin(t)])
            theta = rng.uniform(-np.pi, np.pi)
            R = np.eye(3)
            R[:2, :2] = [[np.cos(theta), -np.sin(theta)], [np.sin(theta), np.cos(theta)]]
            rk = R[:2, :2] @ k
            K = layer_surface_stiffness(k[0], k[1], thickness_mm=0.8, E_mpa=1.1, nu=nu)
            K_rot = layer_surface_stiffness(rk[0], rk[1], thickness_mm=0.8, E_mpa=1.1, nu=nu)
            assert _scaled_error(K_rot, R @ K @ R.T) < 1e-13


def test_scaling_with_modulus_and_thickness():
    kx = np.array([0.0, 0.3, -2.0, 7.0, 400.0])
    ky = np.array([0.0, -0.1, 1.5, 0.0, 300.0])
    for nu in (0.0, 0.3, 0.499):
        K1 = layer_surface_stiffness(kx, ky, thickness_mm=1.0, E_mpa=1.0, nu=nu)
        K_e = layer_surface_stiffness(kx, ky, thickness_mm=1.0, E_mpa=3.7, nu=nu)
        np.testing.assert_allclose(K_e, 3.7 * K1, rtol=1e-14, atol=0)
        for h in (0.05, 2.5, 40.0):
            K_h = layer_surface_stiffness(kx, ky, thickness_mm=h, E_mpa=1.0, nu=nu)
            K_ref = layer_surface_stiffness(kx * h, ky * h, thickness_mm=1.0, E_mpa=1.0, nu=nu)
            assert _scaled_error(K_h, K_ref / h) < 1e-14
            n_h = layer_normal_stiffness(np.hypot(kx, ky), thickness_mm=h, E_mpa=1.0, nu=nu)
            n_ref = layer_normal_stiffness(np.hypot(kx, ky) * h, thickness_mm=1.0, E_mpa=1.0,
                                           nu=nu)
            np.testing.assert_allclose(n_h, n_ref / h, rtol=1e-14)


def test_broadcasting_matches_pointwise_evaluation():
    kx = np.linspace(-3.0, 3.0, 4)[None, :]
    ky = np.array([[0.0], [0.5], [-2.0]])
    K = layer_surface_stiffness(kx, ky, thickness_mm=2.0, E_mpa=0.5, nu=0.45)
    assert K.shape == (3, 4, 3, 3)
    for i in range(3):
        for j in range(4):
            one = layer_surface_stiffness(float(kx[0, j]), float(ky[i, 0]), thickness_mm=2.0,
                                          E_mpa=0.5, nu=0.45)
            np.testing.assert_array_equal(K[i, j], one)


# ---------------------------------------------------------------------------- real space


@pytest.mark.parametrize("nu", [0.0, 0.3, 0.499])
@pytest.mark.parametrize("mode", [(3, 0), (2, -5)])
def test_sinusoidal_indentation_through_fft(nu, mode):
    """uz = A cos(k0 . r) on a periodic grid: p = A cos(k0 . r) / S(|k0|), tx = ty = 0."""
    H, W, dx = 48, 64, 0.05
    h, E, A = 1.5, 0.4, 0.01
    kx, ky = wavevectors((H, W), dx)
    y, x = np.mgrid[0:H, 0:W] * dx
    k0 = 2 * np.pi * np.array([mode[0] / (W * dx), mode[1] / (H * dx)])
    phase = k0[0] * x + k0[1] * y
    uz = A * np.cos(phase)
    p_want = uz / _compliance_formula(np.hypot(*k0), h, E, nu)
    # normal-only stiffness
    p = np.fft.ifft2(layer_normal_stiffness(np.hypot(kx, ky), thickness_mm=h, E_mpa=E, nu=nu)
                     * np.fft.fft2(uz))
    np.testing.assert_allclose(p.real, p_want, rtol=0, atol=1e-10 * np.abs(p_want).max())
    np.testing.assert_allclose(p.imag, 0.0, atol=1e-12 * np.abs(p_want).max())
    # full 3 x 3: tangential displacement that zeroes the tangential traction
    K = layer_surface_stiffness(kx, ky, thickness_mm=h, E_mpa=E, nu=nu)
    uz_hat = np.fft.fft2(uz)
    ut_hat = -np.linalg.solve(K[..., :2, :2], K[..., :2, 2:] * uz_hat[..., None, None])[..., 0]
    u_hat = np.concatenate([ut_hat, uz_hat[..., None]], axis=-1)
    t = np.moveaxis(np.fft.ifft2(np.einsum("...ij,...j->...i", K, u_hat), axes=(0, 1)), -1, 0)
    u_t = np.fft.ifft2(ut_hat, axes=(0, 1))
    scale = np.abs(p_want).max()
    np.testing.assert_allclose(np.abs(u_t.imag).max(), 0.0, atol=1e-14)  # real displacement
    np.testing.assert_allclose(np.abs(t.imag).max(), 0.0, atol=1e-12 * scale)
    np.testing.assert_allclose(t[0].real, 0.0, atol=1e-10 * scale)
    np.testing.assert_allclose(t[1].real, 0.0, atol=1e-10 * scale)
    np.testing.assert_allclose(t[2].real, p_want, rtol=0, atol=1e-10 * scale)


def test_wavevectors_follow_numpy_fft2_layout():
    H, W, dx = 6, 10, 0.2
    kx, ky = wavevectors((H, W), dx)
    assert kx.shape == ky.shape == (H, W) and kx.dtype == np.float64
    y, x = np.mgrid[0:H, 0:W] * dx
    k0 = (2 * np.pi * 3 / (W * dx), -2 * np.pi * 2 / (H * dx))
    spectrum = np.fft.fft2(np.exp(1j * (k0[0] * x + k0[1] * y)))
    peak = np.unravel_index(np.argmax(np.abs(spectrum)), spectrum.shape)
    assert kx[peak] == pytest.approx(k0[0]) and ky[peak] == pytest.approx(k0[1])
    np.testing.assert_array_equal(kx[0], 2 * np.pi * np.fft.fftfreq(W, d=dx))
    np.testing.assert_array_equal(ky[:, 0], 2 * np.pi * np.fft.fftfreq(H, d=dx))


# ---------------------------------------------------------------------------- bad inputs

GOOD = {"thickness_mm": 2.0, "E_mpa": 0.5, "nu": 0.4}


@pytest.mark.parametrize(("name", "value"), [
    ("thickness_mm", 0.0), ("thickness_mm", -1.0), ("thickness_mm", np.nan),
    ("thickness_mm", np.inf), ("thickness_mm", "2"), ("thickness_mm", [1.0, 2.0]),
    ("E_mpa", 0.0), ("E_mpa", -3.0), ("E_mpa", np.nan), ("E_mpa", np.inf), ("E_mpa", 1j),
    ("nu", -0.01), ("nu", 0.5), ("nu", 0.7), ("nu", np.nan), ("nu", None),
])
def test_bad_material_raises_naming_the_argument(name, value):
    kwargs = {**GOOD, name: value}
    with pytest.raises(InputError, match=name):
        layer_surface_stiffness(1.0, 0.0, **kwargs)
    with pytest.raises(InputError, match=name):
        layer_normal_stiffness(1.0, **kwargs)
    assert issubclass(InputError, ValueError)


@pytest.mark.parametrize(("kx", "ky", "name"), [
    (np.array([0.0, np.nan]), 0.0, "kx"),
    (np.inf, 0.0, "kx"),
    (0.0, np.array([1.0, -np.inf]), "ky"),
    (np.array([1j]), 0.0, "kx"),
    (0.0, "1", "ky"),
    (np.zeros(3), np.zeros(4), "kx and ky"),
])
def test_bad_wavevectors_raise_naming_the_argument(kx, ky, name):
    with pytest.raises(InputError, match=name):
        layer_surface_stiffness(kx, ky, **GOOD)


def test_bad_normal_k_and_wavevector_grid_arguments():
    with pytest.raises(InputError, match="k must be finite"):
        layer_normal_stiffness(np.array([1.0, np.nan]), **GOOD)
    for shape in ((0, 4), (4,), (2.5, 3), "ab", None):
        with pytest.raises(InputError, match="shape"):
            wavevectors(shape, 0.1)
    for pitch in (0.0, -0.1, np.nan, "x"):
        with pytest.raises(InputError, match="mm_per_px"):
            wavevectors((4, 4), pitch)
