"""Poisson integration: analytic height fields, boundaries, batches, dtypes, errors."""

from __future__ import annotations

import numpy as np
import pytest

from tactilevision import ShapeError
from tactilevision.optics import PoissonSolver, divergence, integrate_poisson
from tactilevision.optics._features import median_last_axis

H, W = 64, 80
Y, X = np.mgrid[0:H, 0:W].astype(np.float64)


def gaussian(amp: float = 5.0, s: float = 6.0, cx: float = 40.3, cy: float = 31.6):
    """z = A exp(-r^2 / 2 s^2) and its exact pointwise gradients (px units)."""
    z = amp * np.exp(-((X - cx) ** 2 + (Y - cy) ** 2) / (2 * s * s))
    return z, -(X - cx) / s**2 * z, -(Y - cy) / s**2 * z


def gaussian_tolerance(amp: float = 5.0, s: float = 6.0, h: float = 1.0) -> float:
    # Central differences of pointwise gradients approximate z'' with error
    # (h^2/6) z'''' where the 5-point Laplacian the solver inverts has
    # (h^2/12) z''''; the height error is therefore about (h^2/12) |lap z|
    # (lap z = Laplacian of z) and |lap z| <= 2 A / s^2 at the top of a
    # Gaussian. Two times that:
    return 2 * (h * h / 12) * (2 * amp / s**2)


def sphere_cap(radius: float = 40.0, contact: float = 25.0, cx: float = 40.3, cy: float = 31.7):
    """Ball press: sqrt(R^2-r^2) - sqrt(R^2-a^2) inside r < a, 0 outside; exact gradients."""
    r2 = (X - cx) ** 2 + (Y - cy) ** 2
    inside = r2 < contact**2
    s = np.sqrt(np.maximum(radius**2 - r2, 1e-9))
    z = np.where(inside, s - np.sqrt(radius**2 - contact**2), 0.0)
    return z, np.where(inside, -(X - cx) / s, 0.0), np.where(inside, -(Y - cy) / s, 0.0)


@pytest.mark.parametrize("boundary", ["neumann", "dirichlet"])
def test_gaussian_bump_recovered(boundary):
    # the bump is ~0 at the border (30 px = 5 s away), so both boundary
    # conditions hold; Neumann fixes the offset on the flat majority of the
    # image, Dirichlet needs no offset at all
    z, gx, gy = gaussian()
    zr = integrate_poisson(gx, gy, boundary=boundary)
    assert np.abs(zr - z).max() < gaussian_tolerance()


@pytest.mark.parametrize("boundary", ["neumann", "dirichlet"])
def test_sphere_cap_recovered(boundary):
    # The gradient jumps by g_rim = a / sqrt(R^2 - a^2) = 0.80 at the contact
    # rim; where inside a pixel the kink lies is not resolved, and shifting it
    # by half a pixel changes the integrated height by g_rim * h / 2 = 0.4 px
    # (4.6 % of the 8.8 px cap depth): the tolerance.
    radius, contact = 40.0, 25.0
    z, gx, gy = sphere_cap(radius, contact)
    g_rim = contact / np.sqrt(radius**2 - contact**2)
    zr = integrate_poisson(gx, gy, boundary=boundary)
    assert np.abs(zr - z).max() < g_rim * 0.5
    # depth at the centre: R - sqrt(R^2 - a^2)
    assert zr[32, 40] == pytest.approx(radius - np.sqrt(radius**2 - contact**2), abs=g_rim * 0.5)


def test_plane_ramp_exact_with_neumann():
    # A plane's forward differences equal the trapezoid average of its
    # constant gradient, so it solves the discrete Neumann system exactly:
    # only float32 rounding remains (tolerance 64 eps32 * max|z|).
    z = 0.3 * X - 0.2 * Y + 2.0
    zr = integrate_poisson(np.full((H, W), 0.3), np.full((H, W), -0.2))
    d = zr - z
    assert np.ptp(d) < 64 * np.finfo(np.float32).eps * np.abs(z).max()


def test_dirichlet_pins_border_not_neumann():
    # Dirichlet forces z = 0 half a pixel outside the image, so a plane cannot
    # be represented: the result must differ from the ramp by far more than
    # float rounding (guards against the boundary argument being ignored)
    gx, gy = np.full((H, W), 0.3), np.full((H, W), -0.2)
    zr = integrate_poisson(gx, gy, boundary="dirichlet")
    z = 0.3 * X - 0.2 * Y
    assert np.ptp(zr - z) > 1.0
    assert np.abs(zr[[0, -1], :]).max() < np.abs(zr).max()


def test_zero_mask_sets_region_median_to_zero():
    z, gx, gy = gaussian()
    mask = np.zeros((H, W), bool)
    mask[40:60, 5:30] = True  # arbitrary region, partly on the bump's flank
    zr = integrate_poisson(gx, gy, zero_mask=mask)
    assert abs(float(np.median(zr[mask]))) < 1e-5
    # the shape is unchanged: only a constant moves
    assert np.ptp(zr - z) < 2 * gaussian_tolerance()


def test_batch_equals_per_frame():
    _, gx1, gy1 = gaussian(amp=5.0, s=6.0)
    _, gx2, gy2 = sphere_cap()
    _, gx3, gy3 = gaussian(amp=-2.0, s=9.0, cx=30.0, cy=20.0)
    gx = np.stack([gx1, gx2, gx3])
    gy = np.stack([gy1, gy2, gy3])
    mask = np.zeros((3, H, W), bool)
    mask[:, :10, :] = True
    mask[1, :, :10] = True
    for boundary in ("neumann", "dirichlet"):
        zb = integrate_poisson(gx, gy, boundary=boundary)
        assert zb.shape == (3, H, W)
        for i in range(3):
            zi = integrate_poisson(gx[i], gy[i], boundary=boundary)
            np.testing.assert_allclose(zb[i], zi, atol=1e-5)
    zb = integrate_poisson(gx, gy, zero_mask=mask)
    for i in range(3):
        np.testing.assert_allclose(zb[i], integrate_poisson(gx[i], gy[i], zero_mask=mask[i]),
                                   atol=1e-5)
        assert abs(float(np.median(zb[i][mask[i]]))) < 1e-5


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_output_float32(dtype):
    _, gx, gy = gaussian()
    zr = integrate_poisson(gx.astype(dtype), gy.astype(dtype))
    assert zr.dtype == np.float32
    assert zr.shape == (H, W)


def test_solver_dtype_and_function_agree():
    _, gx, gy = gaussian()
    solver = PoissonSolver((H, W), dtype=np.float64)
    z64 = solver(gx, gy)
    assert z64.dtype == np.float64
    np.testing.assert_allclose(z64, integrate_poisson(gx, gy), atol=1e-4)
    # the same solver object is reusable on a new field (cached eigenvalues)
    z2, gx2, gy2 = sphere_cap()
    assert np.abs(solver(gx2, gy2) - z2).max() < 0.5 * 25 / np.sqrt(40**2 - 25**2)


def test_divergence_known_values():
    # gx = x (z = x^2 / 2): central difference of gx is exactly 1 inside
    div = divergence(X.copy(), np.zeros_like(X))
    np.testing.assert_allclose(div[:, 1:-1], 1.0)
    # zero flux: border column is the trapezoid (g0 + g1) / 2 and -(g[-1] + g[-2]) / 2
    np.testing.assert_allclose(div[:, 0], 0.5)
    np.testing.assert_allclose(div[:, -1], -(W - 1 + W - 2) / 2)


def test_divergence_total_flux_zero():
    # Neumann compatibility: zero flux through the border, so the divergence
    # sums to zero for any field (discrete Gauss theorem)
    rng = np.random.default_rng(3)
    gx, gy = rng.normal(size=(2, H, W))
    assert abs(divergence(gx, gy).sum()) < 1e-9 * np.abs(gx).sum()


def test_bad_shapes_raise_shape_error_naming_argument():
    g = np.zeros((H, W))
    with pytest.raises(ShapeError, match="gx"):
        integrate_poisson(np.zeros(W), np.zeros(W))
    with pytest.raises(ShapeError, match="gx"):
        integrate_poisson(np.zeros((2, 2, H, W)), np.zeros((2, 2, H, W)))
    with pytest.raises(ShapeError, match="gy"):
        integrate_poisson(g, np.zeros((H, W + 1)))
    with pytest.raises(ShapeError, match="gy"):
        integrate_poisson(np.zeros((2, H, W)), g)
    with pytest.raises(ShapeError, match=r"gx.*dtype float"):
        integrate_poisson(np.zeros((H, W), np.int64), g)
    with pytest.raises(ValueError, match="gx"):  # ShapeError is a ValueError
        PoissonSolver((H, W))(np.zeros((H + 1, W)), np.zeros((H + 1, W)))


def test_bad_solver_settings():
    with pytest.raises(ValueError, match="boundary"):
        PoissonSolver((H, W), boundary="periodic")
    with pytest.raises(ValueError, match="shape"):
        PoissonSolver((1, W))


@pytest.mark.parametrize("batch", [False, True])
def test_zero_mask_shape_checked(batch):
    _, gx, gy = gaussian()
    if batch:  # a single (H, W) mask for a batch: zero_mask[i] would be row i
        gx, gy, mask = np.stack([gx, gx]), np.stack([gy, gy]), np.ones((H, W), bool)
    else:
        mask = np.ones((H, W + 1), bool)
    with pytest.raises(ShapeError, match="zero_mask"):
        integrate_poisson(gx, gy, zero_mask=mask)


# --------------------------------------------------------------- masked integration
def _bump(shape=(96, 120), sigma=6.0):
    y, x = np.mgrid[0:shape[0], 0:shape[1]].astype(np.float64)
    return 4.0 * np.exp(-((x - 60) ** 2 + (y - 48) ** 2) / (2 * sigma**2))


def test_masked_integration_pins_the_untouched_gel():
    """A gradient bias everywhere (the illumination drift of a real frame)
    spreads over the whole image with whole-image integration; pinned to zero
    outside the contact it stays a small error inside it."""
    from tactilevision.optics import integrate_poisson_masked

    z = _bump()
    gy, gx = np.gradient(z)
    rng = np.random.default_rng(0)
    bias = 0.02 + 0.01 * rng.standard_normal(z.shape)       # px per px
    gxb, gyb = (gx + bias).astype(np.float32), (gy - 0.5 * bias).astype(np.float32)
    mask = z > 1e-3
    zm = integrate_poisson_masked(gxb, gyb, mask)
    zw = integrate_poisson(gxb, gyb)
    assert zm.dtype == np.float32
    assert np.all(zm[~mask] == 0)
    err_masked = np.abs(zm - z).max()
    err_whole = np.abs(zw - z).max()
    # bias 0.02 px/px across the 25 px wide contact: at most ~0.5; whole image ~0.02 x 120
    assert err_masked < 0.45
    assert err_whole > 2 * err_masked
    # exact gradients: the bump itself, to the discretisation's accuracy
    exact = integrate_poisson_masked(gx.astype(np.float32), gy.astype(np.float32), mask)
    assert np.abs(exact - z).max() < 0.05 * z.max()


def test_masked_integration_limits_and_batches():
    from tactilevision.optics import integrate_poisson_masked

    z = _bump()
    gy, gx = (g.astype(np.float32) for g in np.gradient(z))
    full = integrate_poisson_masked(gx, gy, np.ones(z.shape, bool))
    np.testing.assert_allclose(full, integrate_poisson(gx, gy), atol=1e-5)
    assert not integrate_poisson_masked(gx, gy, np.zeros(z.shape, bool)).any()
    m = z > 1e-3
    batch = integrate_poisson_masked(np.stack([gx, 2 * gx]), np.stack([gy, 2 * gy]),
                                     np.stack([m, m]))
    np.testing.assert_allclose(batch[1], 2 * batch[0], rtol=1e-4, atol=1e-5)
    with pytest.raises(ShapeError, match="mask"):
        integrate_poisson_masked(gx, gy, m[:-1])
    with pytest.raises(ShapeError, match="mask"):
        integrate_poisson_masked(gx, gy, m.astype(np.float32))


@pytest.mark.parametrize("boundary", ["neumann", "dirichlet"])
def test_scale_is_folded_into_the_solve(boundary):
    """PoissonSolver(scale=s) returns s times the unscaled heights (mm per px folded into
    the eigenvalues)."""
    rng = np.random.default_rng(0)
    gx, gy = rng.normal(size=(2, 48, 64)).astype(np.float32)
    plain = PoissonSolver((48, 64), boundary=boundary)(gx, gy)
    scaled = PoissonSolver((48, 64), boundary=boundary, scale=0.0295)(gx, gy)
    np.testing.assert_allclose(scaled, 0.0295 * plain, rtol=1e-5, atol=1e-7)


@pytest.mark.parametrize("n", [4799, 4800])
def test_the_offset_median_is_numpys(n):
    """The partitioned median that fixes the Neumann offset equals np.median for odd and
    even counts, and the unchecked solve equals the checked one."""
    x = np.random.default_rng(n).standard_normal(n).astype(np.float32)
    assert median_last_axis(x.copy()) == np.median(x)
    gx, gy = (np.random.default_rng(k).standard_normal((24, 32)).astype(np.float32)
              for k in (1, 2))
    solver = PoissonSolver((24, 32))
    np.testing.assert_array_equal(solver.solve_unchecked(gx.copy(), gy.copy()), solver(gx, gy))


@pytest.mark.parametrize("tol", [1e-4, 1e-5, 1e-6])
def test_masked_conjugate_gradients_meet_the_direct_solve(tol):
    """At a tolerance of 1e-5 or looser the masked integration's conjugate gradients run in
    single precision (the contact-pinned heights' 1e-4), tighter in double: either way
    the answer is the direct (SuperLU) solve's to within the tolerance's reach, on a bump
    cut by the image's left and right sides (two regions, the boxes' mixed transforms)."""
    from tactilevision.optics import integrate_poisson_masked

    z = _bump()
    z = np.roll(z, 8 - int(np.argmax(z.max(axis=0))), axis=1)     # wrapped round the sides
    rng = np.random.default_rng(3)
    gy, gx = (g + 0.01 * rng.standard_normal(z.shape) for g in np.gradient(z))
    gx, gy = gx.astype(np.float32), gy.astype(np.float32)
    mask = z > 1e-3
    assert mask[:, 0].any() and mask[:, -1].any()
    direct = integrate_poisson_masked(gx, gy, mask, method="direct")
    cg = integrate_poisson_masked(gx, gy, mask, tol=tol)
    assert cg.dtype == np.float32 and np.all(cg[~mask] == 0)
    err = np.abs(cg - direct).max() / np.abs(direct).max()
    assert err < tol            # 0.04 to 0.07 times tol at 1e-3 to 1e-6 when written


@pytest.mark.parametrize("n", [1, 2, 7, 34240])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_the_partitioned_median_is_numpys_with_ties_and_batches(n, dtype):
    """median_last_axis (one partition, then the lower middle as the largest value before
    the upper) gives np.median's values along the last axis, ties (a quantised colour
    change) and all."""
    rng = np.random.default_rng(n)
    x = rng.standard_normal((3, n)).astype(dtype)
    x[1] = np.round(x[1] * 4) / 4               # many equal values
    x[2] = 0.5                                  # all equal
    np.testing.assert_array_equal(median_last_axis(x.copy()), np.median(x, axis=-1))
