"""Contact force maps (``ForceEstimator``) against models other than their own:
the axisymmetric P2/P1 FEM flat punch (total force, force profile, its surface
field), Hertz on a thick pad, and the spectral and FEM methods against each
other; the footprint assumption's effect; batches, modes and bad input."""

from __future__ import annotations

import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.fem import ForceEstimator, LinearIndentationSolver

A, H, NU, E, W = 2.5, 3.0, 0.45, 0.2, 0.05     # mm, mm, -, MPa, mm


@pytest.fixture(scope="module")
def punch():
    """The axisymmetric FEM's frictionless punch (a = 2.5, h = 3): force, reactions, surface."""
    s = LinearIndentationSolver(A / H, contact="frictionless")
    x, res = s.solve(NU)
    dofs_p = s.ubasis.get_dofs("punch").all("u^2")
    dofs_f = s.ubasis.get_dofs("free").all("u^2")
    r_p = s.ubasis.doflocs[0, dofs_p] * H
    f_p = -res[dofs_p] * E * H * W                 # N, the punch's nodal reactions
    dofs = np.concatenate([dofs_p, dofs_f])
    r = s.ubasis.doflocs[0, dofs] * H
    order = np.argsort(r)
    depth = -x[dofs][order] * W                    # mm, positive into the gel
    return {"P": float(f_p.sum()), "r_p": r_p, "f_p": f_p, "r": r[order], "depth": depth}


def _disc(shape, dx, centre, radius):
    yy, xx = np.indices(shape, dtype=np.float64)
    return np.hypot((xx - centre[0]) * dx, (yy - centre[1]) * dx)


def test_flat_punch_total_force_and_profile_against_the_axisymmetric_fem(punch):
    dx, n = 0.05, 360                               # a = 50 px, 18 mm square
    r = _disc((n, n), dx, ((n - 1) / 2, (n - 1) / 2), A)
    u = np.where(r <= A, W, 0.0)
    est = ForceEstimator((n, n), dx, thickness_mm=H, E_mpa=E, nu=NU, contact="footprint",
                         threshold_mm=W / 2)
    fm = est(u)
    P = punch["P"]
    assert fm.total_n[2] == pytest.approx(P, rel=0.02)
    assert abs(fm.total_n[0]) < 1e-9 and abs(fm.total_n[1]) < 1e-9
    # force profile: the fraction of P inside radius rho, against the FEM's reactions
    fz = fm.forces_n[..., 2]
    for rho in (0.5, 0.8, 0.9):
        ours = fz[r <= rho * A].sum() / fz.sum()
        fem = punch["f_p"][punch["r_p"] <= rho * A].sum() / P
        assert ours == pytest.approx(fem, abs=0.02), rho
    assert fm.pressure_kpa.min() >= 0.0
    assert np.all(fz[r > A + dx] == 0)              # zero traction off the footprint


def test_flat_punch_from_its_whole_surface_field(punch):
    """'field' mode fed the FEM's own surface (footprint, sink-in, outside)."""
    dx, n = 0.06, 480                               # 28.8 mm square: the field has decayed
    r = _disc((n, n), dx, ((n - 1) / 2, (n - 1) / 2), A)
    u = np.interp(r, punch["r"], punch["depth"])
    fm = ForceEstimator((n, n), dx, thickness_mm=H, E_mpa=E, nu=NU, contact="field")(u)
    assert fm.total_n[2] == pytest.approx(punch["P"], rel=0.03)
    # the pressure off the footprint is small against the mean contact pressure
    p_mean = punch["P"] / (np.pi * A**2) * 1e3
    outside = fm.pressure_kpa[r > A + 0.5]
    assert np.abs(outside).max() < 0.1 * p_mean


def test_hertz_sphere_on_a_thick_pad():
    R, delta, h, nu = 5.0, 0.08, 10.0, 0.45
    a = np.sqrt(R * delta)                          # 0.632 mm, a/h = 0.063
    Es = E / (1 - nu**2)
    P = 4 / 3 * Es * np.sqrt(R) * delta**1.5
    p0 = 3 * P / (2 * np.pi * a**2)
    dx, n = 0.04, 64
    r = _disc((n, n), dx, ((n - 1) / 2, (n - 1) / 2), a)
    u = np.maximum(delta - r**2 / (2 * R), 0.0)
    est = ForceEstimator((n, n), dx, thickness_mm=h, E_mpa=E, nu=nu, contact="footprint",
                         threshold_mm=1e-6, pad_mm=h)
    fm = est(u)
    # the bonded layer is stiffer than Hertz's half-space: by 7.8 % here (2.8 % at
    # h = 40 mm and 1.3 % at 100 mm, converging on Hertz; dx = 0.02 mm gives the same)
    ratio = fm.total_n[2] / P
    assert 1.0 < ratio < 1.10
    inside = r < 0.9 * a
    p_hertz = p0 * np.sqrt(1 - (r[inside] / a) ** 2) * 1e3
    # the shape of the pressure: Hertz's ellipse within 4 % of p0 (rms, r < 0.9 a)
    err = fm.pressure_kpa[inside] - ratio * p_hertz
    assert np.sqrt(np.mean(err**2)) < 0.04 * p0 * 1e3
    assert np.all(fm.pressure_kpa >= 0) and np.all(fm.forces_n[r > a + 2 * dx] == 0)


def test_batches_equal_single_frames_and_modes_agree():
    dx, n = 0.1, 96
    r = _disc((n, n), dx, (40.0, 50.0), 1.0)
    u1 = 0.03 * np.exp(-(r / 1.5) ** 2)
    u2 = 0.5 * u1
    est = ForceEstimator((n, n), dx, thickness_mm=H, E_mpa=E, nu=NU, contact="field")
    b = est(np.stack([u1, u2]))
    assert b.forces_n.shape == (2, n, n, 3) and b.total_n.shape == (2, 3)
    np.testing.assert_allclose(b.forces_n[0], est(u1).forces_n, atol=1e-15)
    np.testing.assert_allclose(b.total_n[1], 0.5 * b.total_n[0], rtol=1e-10)
    # full mode with the lateral displacement the layer takes under zero tangential
    # traction gives the same normal force and zero tangential traction
    from tactilevision.fem import layer_surface_stiffness

    ky = 2 * np.pi * np.fft.fftfreq(n, dx)[:, None]
    kx = 2 * np.pi * np.fft.fftfreq(n, dx)[None, :]
    K = layer_surface_stiffness(kx, ky, thickness_mm=H, E_mpa=E, nu=NU)
    uz = np.fft.fft2(u1)
    ut = -np.linalg.solve(K[..., :2, :2], (K[..., :2, 2] * uz[..., None])[..., None])[..., 0]
    lat = np.real(np.fft.ifft2(ut, axes=(0, 1)))
    full = ForceEstimator((n, n), dx, thickness_mm=H, E_mpa=E, nu=NU, mode="full",
                          pad_mm=0.0, contact="field")
    normal = ForceEstimator((n, n), dx, thickness_mm=H, E_mpa=E, nu=NU, pad_mm=0.0, contact="field")
    f_full, f_norm = full(u1, lat), normal(u1)
    # (to 1e-4: the lateral field's Nyquist terms are not real on an even grid)
    np.testing.assert_allclose(f_full.forces_n[..., 2], f_norm.forces_n[..., 2],
                               atol=1e-4 * np.abs(f_norm.forces_n).max())
    assert np.abs(f_full.forces_n[..., :2]).max() < 1e-4 * np.abs(f_norm.forces_n).max()


def test_full_mode_shear_gives_tangential_force():
    dx, n = 0.1, 96
    r = _disc((n, n), dx, (48.0, 48.0), 1.0)
    bump = np.exp(-(r / 1.5) ** 2)
    lat = np.stack([0.02 * bump, np.zeros_like(bump)], axis=-1)   # pulled along +x
    # periodic (no padding): the sum over the image is the k = 0 term, mu / h times the
    # displaced area (the bump's integral), exactly
    est = ForceEstimator((n, n), dx, thickness_mm=H, E_mpa=E, nu=NU, mode="full", pad_mm=0.0,
                         contact="field")
    fm = est(np.zeros((n, n)), lat)
    assert fm.total_n[0] > 0 and abs(fm.total_n[1]) < 1e-9 * fm.total_n[0]
    mu = E / (2 * (1 + NU))
    assert fm.total_n[0] == pytest.approx(mu / H * 0.02 * bump.sum() * dx * dx, rel=1e-9)


def test_bad_input():
    with pytest.raises(InputError, match="nu"):
        ForceEstimator((10, 10), 0.1, thickness_mm=3, E_mpa=0.2, nu=0.5, contact="field")
    with pytest.raises(InputError, match="method"):
        ForceEstimator((10, 10), 0.1, thickness_mm=3, E_mpa=0.2, nu=0.4, method="bem",
                       contact="field")
    with pytest.raises(InputError, match="thickness_mm"):
        ForceEstimator((10, 10), 0.1, thickness_mm=0, E_mpa=0.2, nu=0.4, contact="field")
    est = ForceEstimator((10, 12), 0.1, thickness_mm=3, E_mpa=0.2, nu=0.4, contact="field")
    with pytest.raises(InputError, match=r"\(10, 12\)"):
        est(np.zeros((12, 10)))
    bad = np.zeros((10, 12))
    bad[3, 3] = np.nan
    with pytest.raises(InputError, match="NaN"):
        est(bad)
    full = ForceEstimator((10, 12), 0.1, thickness_mm=3, E_mpa=0.2, nu=0.4, mode="full",
                          contact="field")
    with pytest.raises(InputError, match="lateral_mm"):
        full(np.zeros((10, 12)))


def test_fem_and_spectral_agree_on_a_sphere_press():
    """Two different models of the pad (40 x 30 B-bar hexahedra with free sides; the
    infinite layer's Green's function at 0.2 mm pixels) on one press."""
    Hpx, Wpx, dx, h = 150, 200, 0.2, 4.0
    r = _disc((Hpx, Wpx), dx, ((Wpx - 1) / 2, (Hpx - 1) / 2), 0)
    u = np.maximum(0.3 - r**2 / 20.0, 0.0)          # R = 10 mm, 0.3 mm deep: a = 2.45 mm
    kw = dict(thickness_mm=h, E_mpa=0.2, nu=0.49, contact="footprint", threshold_mm=1e-6)
    sp = ForceEstimator((Hpx, Wpx), dx, **kw)(u)
    fe = ForceEstimator((Hpx, Wpx), dx, method="fem", grid=(40, 30), **kw)(u)
    assert fe.forces_n.shape == (30, 40, 3) and fe.pressure_kpa.shape == (30, 40)
    # 0.6 % apart (measured; the rim nodes' springs of the footprint rule, see
    # tests/test_fem_forces_grid.py): the FEM's free sides and 1 mm nodes against the
    # infinite layer at 0.2 mm; the rule's spread over press positions is about 2 %
    assert fe.total_n[2] == pytest.approx(sp.total_n[2], rel=0.03)
    assert fe.pressure_kpa.min() >= 0
    # its peak is at the centre node
    iy, ix = np.unravel_index(np.argmax(fe.pressure_kpa), fe.pressure_kpa.shape)
    assert abs(fe.x_mm[ix] - (Wpx - 1) / 2 * dx) < 1.1
    assert abs(fe.y_mm[iy] - (Hpx - 1) / 2 * dx) < 1.1


def test_single_precision_path_matches_double():
    """float32 height maps take OpenCV's real DFT with the stiffness as a packed
    spectrum; it must give the float64 scipy.fft answer to single precision, single
    frames and batches alike, and the same totals with the periodic k = 0 check."""
    n, dx = 96, 0.1
    r = _disc((n, n + 4), dx, ((n + 3) / 2, (n - 1) / 2), 0)
    u = np.maximum(0.2 - r**2 / 8.0, 0.0)                  # R = 4 mm, 0.2 mm deep
    est = ForceEstimator((n, n + 4), dx, thickness_mm=H, E_mpa=E, nu=NU, contact="field")
    ref = est(u)
    one = est(u.astype(np.float32))
    assert one.forces_n.dtype == np.float32 and one.total_n.dtype == np.float64
    scale = np.abs(ref.forces_n).max()
    assert np.abs(one.forces_n - ref.forces_n).max() < 1e-5 * scale
    assert one.total_n == pytest.approx(ref.total_n, rel=1e-5, abs=1e-9)
    batch = est(np.stack([u, u[::-1]]).astype(np.float32))
    np.testing.assert_array_equal(batch.forces_n[0], one.forces_n)
    assert batch.total_n[1] == pytest.approx(ref.total_n, rel=1e-5, abs=1e-9)
    # no padding (96 x 100: fast FFT lengths, so no zeros are added): a uniform
    # 0.01 mm everywhere is the k = 0 stiffness times the area
    periodic = ForceEstimator((n, n + 4), dx, thickness_mm=H, E_mpa=E, nu=NU, pad_mm=0.0,
                              contact="field")
    k0 = E * (1 - NU) / ((1 + NU) * (1 - 2 * NU)) / H
    flat = periodic(np.full((n, n + 4), 0.01, np.float32)).total_n[2]
    assert flat == pytest.approx(k0 * 0.01 * n * (n + 4) * dx * dx, rel=1e-5)


@pytest.mark.parametrize("method", ["spectral", "fem"])
def test_footprint_of_a_flat_gel_carries_no_force(method):
    # a contact mask (from the colour change) over a gel that did not move: zero traction,
    # not a division by zero in the conjugate gradients (a no-contact frame in `forces`)
    est = ForceEstimator((48, 64), 0.1, thickness_mm=3, E_mpa=0.2, nu=0.48,
                         contact="footprint", method=method, grid=(16, 12), threshold_mm=0.01)
    mask = np.zeros((48, 64), bool)
    mask[20:25, 30:35] = True
    fm = est(np.zeros((48, 64), np.float32), contact_mask=mask)
    np.testing.assert_array_equal(fm.total_n, 0.0)
    # and a real press inside the same mask still pushes
    u = np.where(mask, 0.05, 0.0).astype(np.float32)
    assert est(u, contact_mask=mask).total_n[2] > 0


def test_a_changed_setting_takes_effect_and_a_bad_one_changes_nothing():
    """ForceEstimator's settings are live: E doubled doubles the force (linear elasticity,
    the operator rebuilt), the same as an estimator built with it; h changed matches a new
    estimator too; a bad value is refused naming it and leaves the estimator as it was."""
    from tactilevision import InputError
    from tactilevision.fem import ForceEstimator

    u = np.zeros((48, 64))
    yy, xx = np.mgrid[:48, :64]
    u[np.hypot(xx - 32, yy - 24) < 10] = 0.05
    est = ForceEstimator((48, 64), 0.1, thickness_mm=3.0, E_mpa=0.2, nu=0.45, contact="field")
    f0 = float(est(u).total_n[2])
    est.E_mpa = 0.4
    assert est.E_mpa == 0.4
    assert float(est(u).total_n[2]) == pytest.approx(2 * f0, rel=1e-9)
    est.thickness_mm = 4.0
    fresh = ForceEstimator((48, 64), 0.1, thickness_mm=4.0, E_mpa=0.4, nu=0.45, contact="field")
    assert float(est(u).total_n[2]) == pytest.approx(float(fresh(u).total_n[2]), rel=1e-12)
    before = float(est(u).total_n[2])
    with pytest.raises(InputError, match="nu"):
        est.nu = 0.7
    with pytest.raises(InputError, match="E_mpa"):
        est.E_mpa = -1.0
    assert (est.nu, est.E_mpa) == (0.45, 0.4)
    assert float(est(u).total_n[2]) == pytest.approx(before, rel=1e-12)
    est.beta = 0.8                         # not the operator's: checked, not rebuilt
    assert est.beta == 0.8
