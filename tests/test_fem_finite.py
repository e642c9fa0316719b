"""Finite-strain Neo-Hookean indentation: material law, homogeneous stretch, limits, beta."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq
from skfem import MeshTri

from tactilevision.fem import FiniteIndentation, linear_indentation, neo_hookean_indentation
from tactilevision.fem._finite_solver import ConstrainedNewton
from tactilevision.fem._neohookean_forms import (
    AxisymmetricNeoHookean,
    cauchy_stress,
    iso_energy,
    iso_stress,
    iso_tangent,
)

COARSE = {"cell": 0.25, "edge_refinements": 3}
NU_C10_D1 = [(nu, 1 / (4 * (1 + nu)), 6 * (1 - 2 * nu)) for nu in (0.3, 0.45, 0.499)]


def _f(stretch_r: float, stretch_z: float, shear: float = 0.0) -> np.ndarray:
    """(F_rr, F_rz, F_zr, F_zz, F_tt) of a homogeneous axisymmetric stretch."""
    return np.array([stretch_r, shear, 0.0, stretch_z, stretch_r])


# ------------------------------------------------------------- material law


@pytest.mark.parametrize(("nu", "c10", "d1"), NU_C10_D1)
def test_cauchy_stress_is_the_abaqus_closed_form(nu, c10, d1):
    # sigma = 2 C10 / J dev(Bbar) + 2 (J - 1) / D1 I, with Bbar = J^(-2/3) F F^T
    rng = np.random.default_rng(3)
    for _ in range(5):
        f = _f(*rng.uniform(0.7, 1.4, 2), rng.uniform(-0.5, 0.5))
        f[2], f[4] = rng.uniform(-0.3, 0.3), rng.uniform(0.7, 1.4)
        F = np.array([[f[0], f[1], 0], [f[2], f[3], 0], [0, 0, f[4]]])
        J = np.linalg.det(F)
        Bbar = J ** (-2 / 3) * F @ F.T
        want = 2 * c10 / J * (Bbar - np.trace(Bbar) / 3 * np.eye(3)) + 2 * (J - 1) / d1 * np.eye(3)
        np.testing.assert_allclose(cauchy_stress(f, c10, d1), want, atol=1e-12)
        np.testing.assert_allclose(cauchy_stress(f, c10, d1), cauchy_stress(f, c10, d1).T,
                                   atol=1e-12)


def test_stress_and_tangent_are_derivatives_of_the_energy():
    rng = np.random.default_rng(0)
    f = np.array([1.0, 0, 0, 1, 1])[:, None] + 0.2 * rng.standard_normal((5, 6))
    eps = 1e-6
    for k in range(5):
        d = np.zeros((5, 1))
        d[k] = eps
        np.testing.assert_allclose((iso_energy(f + d, 0.3) - iso_energy(f - d, 0.3)) / (2 * eps),
                                   iso_stress(f, 0.3)[k], atol=1e-8)
        np.testing.assert_allclose((iso_stress(f + d, 0.3) - iso_stress(f - d, 0.3)) / (2 * eps),
                                   iso_tangent(f, 0.3)[:, k], atol=1e-7)


def test_undeformed_tangent_is_isotropic_elasticity():
    # shear modulus mu = 2 C10; a rigid rotation stores nothing
    A = iso_tangent(_f(1.0, 1.0)[:, None], 0.25)[..., 0]
    shear = np.array([0, 1.0, 0, 0, 0])
    rotation = np.array([0, 1.0, -1.0, 0, 0])
    assert shear @ A @ shear == pytest.approx(0.5)
    assert rotation @ A @ rotation == pytest.approx(0.0, abs=1e-14)


@pytest.mark.parametrize("stretch", [1.3, 0.8])
def test_homogeneous_uniaxial_stretch_of_a_cylinder(stretch):
    # a cylinder of radius 1, height 2, ends free to slide: exact homogeneous
    # solution, lateral stretch from sigma_rr = 0, end force sigma_zz pi r^2
    nu = 0.45
    c10, bulk = 1 / (4 * (1 + nu)), 1 / (3 * (1 - 2 * nu))
    mesh = MeshTri.init_tensor(np.linspace(0, 1, 4), np.linspace(0, 2, 5)).with_boundaries({
        "bottom": lambda x: np.isclose(x[1], 0), "top": lambda x: np.isclose(x[1], 2),
        "axis": lambda x: np.isclose(x[0], 0)})
    solid = AxisymmetricNeoHookean(mesh, c10, bulk)
    ub = solid.ubasis
    top_z = ub.get_dofs("top").all("u^2")
    newton = ConstrainedNewton(solid, np.concatenate([
        ub.get_dofs("bottom").all("u^2"), top_z, ub.get_dofs("axis").all("u^1")]))
    target = np.where(np.isin(newton.fixed, top_z), 2 * (stretch - 1), 0.0)
    x, _, ok = newton.solve(np.zeros(solid.n_dofs), target)
    assert ok
    lam = brentq(lambda s: cauchy_stress(_f(s, stretch), c10, 2 / bulk)[0, 0], 0.3, 2.0)
    sigma_zz = cauchy_stress(_f(lam, stretch), c10, 2 / bulk)[1, 1]
    force = 2 * np.pi * solid.residual(x)[top_z].sum()
    assert force == pytest.approx(sigma_zz * np.pi * lam**2, rel=1e-10)
    ur = ub.get_dofs("top").all("u^1")
    np.testing.assert_allclose(x[ur], (lam - 1) * ub.doflocs[0, ur], atol=1e-10)
    assert solid.min_jacobian(x) == pytest.approx(lam**2 * stretch, rel=1e-10)


@pytest.mark.parametrize("c20", [0.0, 0.3])
def test_tangent_is_the_derivative_of_the_residual(c20):
    # the consistent tangent (Neo-Hookean, and with Yeoh's C20) against central
    # differences of the residual at a random deformed state (of a ring, R in
    # [0.5, 1.5], so that u_r / R stays small)
    mesh = MeshTri.init_tensor(np.linspace(0.5, 1.5, 3), np.linspace(0, 1, 3))
    solid = AxisymmetricNeoHookean(mesh, 0.2, 5.0, c20=c20)
    rng = np.random.default_rng(1)
    x = 0.01 * rng.standard_normal(solid.n_dofs)
    assert 0.5 < solid.min_jacobian(x) < 0.99
    k = solid.tangent(x).toarray()
    eps = 1e-6
    for j in rng.choice(solid.n_dofs, 8, replace=False):
        d = np.zeros(solid.n_dofs)
        d[j] = eps
        fd = (solid.residual(x + d) - solid.residual(x - d)) / (2 * eps)
        np.testing.assert_allclose(k[:, j], fd, atol=1e-6)
    np.testing.assert_allclose(k, k.T, atol=1e-12)


def test_yeoh_stiffening_raises_beta_not_kappa0():
    # C20 adds stiffening at finite strain only: kappa0 (small strain) is the
    # Neo-Hookean one, beta grows with C20 (benchmarks/bench_material_law.py)
    kw = {"contact": "bonded", "w_over_h_max": 0.1, "steps": 4, **COARSE}
    nh = neo_hookean_indentation(0.8, 0.45, **kw)
    ye = neo_hookean_indentation(0.8, 0.45, c20_over_c10=0.3, **kw)
    assert ye.kappa0 == pytest.approx(nh.kappa0, rel=1e-9)
    assert ye.beta_secant > nh.beta_secant + 0.2
    assert np.all(ye.kappa_n > nh.kappa_n)


# ---------------------------------------------------------- indentation


def test_result_fields_and_force_balance():
    res = neo_hookean_indentation(0.8, 0.45, contact="bonded", w_over_h_max=0.1, steps=2,
                                  **COARSE)
    assert isinstance(res, FiniteIndentation)
    assert res.complete
    np.testing.assert_allclose(res.w_over_h, [0.05, 0.1])
    for name in ("force", "kappa_n", "newton_iterations", "min_jacobian",
                 "tangent_stiffness", "penetration", "contact_radius"):
        assert getattr(res, name).shape == (2,), name
    np.testing.assert_allclose(res.kappa_n,
                               res.force * (1 - 0.45**2) / (2 * 0.8 * res.w_over_h))
    assert np.all(res.force > 0) and np.all(np.diff(res.force) > 0)
    assert np.all((res.min_jacobian > 0) & (res.min_jacobian < 1))
    assert np.all(res.penetration < 1e-4)
    assert res.n_dofs > 0 and res.seconds > 0


@pytest.mark.parametrize(("nu", "contact"), [(0.3, "frictionless"), (0.45, "bonded"),
                                             (0.499, "frictionless")])
def test_small_strain_limit_is_the_linear_solver(nu, contact):
    # the linear problem holds the nodes initially under the punch on its face:
    # contact_search=False is the same contact (with the search, a frictionless
    # edge node that slides past r = a leaves the face, an O(element) change)
    lin = linear_indentation(0.8, nu, contact=contact, **COARSE).kappa
    res = neo_hookean_indentation(0.8, nu, contact=contact, w_over_h_max=1e-4, steps=1,
                                  contact_search=False, **COARSE)
    assert res.kappa0 == pytest.approx(lin, rel=5e-3)
    assert res.kappa_n[0] == pytest.approx(lin, rel=5e-3)
    assert res.tangent_stiffness[0] == pytest.approx(res.force[0] / 1e-4, rel=1e-3)
    searched = neo_hookean_indentation(0.8, nu, contact=contact, w_over_h_max=1e-4, steps=1,
                                       **COARSE)
    assert searched.kappa0 == res.kappa0


def test_incompressible_limit_does_not_lock():
    # nu = 0.499 and 0.5 (exact, 1/K = 0) are finite and agree with each other
    # across two meshes; locking would make kappa0 grow without bound
    k = {(nu, er): neo_hookean_indentation(0.8, nu, contact="bonded", w_over_h_max=0.04,
                                           steps=2, cell=0.25, edge_refinements=er)
         for nu in (0.499, 0.5) for er in (2, 4)}
    for res in k.values():
        assert res.complete and np.all(np.isfinite(res.kappa_n))
    assert k[0.499, 4].kappa0 == pytest.approx(k[0.5, 4].kappa0, rel=0.01)
    assert k[0.499, 2].kappa0 == pytest.approx(k[0.499, 4].kappa0, rel=0.01)
    lin = linear_indentation(0.8, 0.5, contact="bonded", cell=0.25, edge_refinements=4)
    assert k[0.5, 4].kappa0 == pytest.approx(lin.kappa, rel=5e-3)


@pytest.fixture(scope="module")
def sweeps_045():
    kw = {"w_over_h_max": 0.1, "steps": 5, "cell": 0.25, "edge_refinements": 4}
    return {c: neo_hookean_indentation(0.8, 0.45, contact=c, **kw)
            for c in ("frictionless", "bonded")}


def test_stiffening_bonded_at_least_frictionless(sweeps_045):
    fr, bo = sweeps_045["frictionless"], sweeps_045["bonded"]
    assert fr.complete and bo.complete
    assert fr.beta_secant > 0 and fr.beta_tangent > 0
    assert bo.beta_secant > 0 and bo.beta_tangent > 0
    assert np.all(bo.kappa_n >= fr.kappa_n)        # no slip is stiffer at every depth
    assert fr.linearity_r2 > 0.99 and bo.linearity_r2 > 0.99


def test_stiffening_at_nu_040_bonded():
    res = neo_hookean_indentation(0.8, 0.4, contact="bonded", w_over_h_max=0.1, steps=4,
                                  **COARSE)
    assert res.complete and res.beta_secant > 0.3 and res.beta_tangent > 0.3
    assert np.all(np.diff(res.kappa_n) > 0)


def test_beta_fit_recovers_a_quadratic_force():
    from tactilevision.fem._finite import _line_fit

    w = np.linspace(0.02, 0.2, 10)
    c0, c1, r2 = _line_fit(w, 3.0 * (1 + 0.7 * w))
    assert (c0, c1 / c0, r2) == pytest.approx((3.0, 0.7, 1.0))


@pytest.fixture
def newton_fails_beyond_005(monkeypatch):
    """Newton made to fail at every depth beyond w/h = 0.05."""
    solve = ConstrainedNewton.solve

    def failing(self, x, target, **kw):
        if self.problem.w > 0.05:
            return x, 1, False
        return solve(self, x, target, **kw)

    monkeypatch.setattr(ConstrainedNewton, "solve", failing)


def test_failed_sweep_warns_and_returns_what_it_reached(newton_fails_beyond_005):
    # the sweep stops where Newton failed, and says so
    with pytest.warns(RuntimeWarning, match=r"Newton failed beyond w/h = 0.05"):
        res = neo_hookean_indentation(0.8, 0.45, contact="bonded", w_over_h_max=0.1, steps=4,
                                      cache=False, **COARSE)   # the solver itself, patched
    assert not res.complete
    np.testing.assert_allclose(res.w_over_h, [0.025, 0.05])
    assert np.all(np.isfinite(res.kappa_n)) and np.isfinite(res.beta_secant)


def test_disk_cache_returns_the_sweep_it_stored_and_misses_on_any_change(tmp_path,
                                                                          monkeypatch):
    from tactilevision.fem import _sweep_cache

    kw = {"contact": "bonded", "w_over_h_max": 0.1, "steps": 2, "cache_dir": tmp_path, **COARSE}
    first = neo_hookean_indentation(0.8, 0.45, **kw)
    again = neo_hookean_indentation(0.8, 0.45, **kw)
    fresh = neo_hookean_indentation(0.8, 0.45, **{**kw, "cache": False})
    assert not first.from_cache and again.from_cache and not fresh.from_cache
    assert len(list(tmp_path.glob("sweep_*.npz"))) == 1
    for f in ("w_over_h", "force", "kappa_n", "tangent_stiffness", "surface_uz",
              "newton_iterations", "kappa0", "beta_secant", "n_dofs"):
        a, b, c = getattr(first, f), getattr(again, f), getattr(fresh, f)
        assert type(a) is type(b) and np.array_equal(a, b) and np.array_equal(a, c), f
    # another input, or another solver source, is another entry
    assert not neo_hookean_indentation(0.8, 0.46, **kw).from_cache
    monkeypatch.setattr(_sweep_cache, "_source_digest", lambda: "edited solver")
    assert not neo_hookean_indentation(0.8, 0.45, **kw).from_cache
    monkeypatch.undo()
    # a damaged entry is a miss: the sweep runs again and the entry is rewritten
    for p in tmp_path.glob("sweep_*.npz"):
        p.write_bytes(p.read_bytes()[:200])
    redo = neo_hookean_indentation(0.8, 0.45, **kw)
    assert not redo.from_cache and np.array_equal(redo.force, first.force)
    assert neo_hookean_indentation(0.8, 0.45, **kw).from_cache


def test_a_sweep_that_stopped_early_is_not_cached(tmp_path, newton_fails_beyond_005):
    with pytest.warns(RuntimeWarning, match="Newton failed"):
        res = neo_hookean_indentation(0.8, 0.45, contact="bonded", w_over_h_max=0.1, steps=4,
                                      cache_dir=tmp_path, **COARSE)
    assert not res.complete and not list(tmp_path.glob("sweep_*"))


@pytest.mark.parametrize(("kwargs", "name"), [
    ({"a_over_h": 0.0}, "a_over_h"), ({"nu": 0.6}, "nu"), ({"nu": -0.1}, "nu"),
    ({"contact": "glued"}, "contact"), ({"w_over_h_max": 0.0}, "w_over_h_max"),
    ({"w_over_h_max": 0.8}, "w_over_h_max"), ({"steps": 0}, "steps"), ({"steps": 2.5}, "steps"),
    ({"pad_radius_over_h": 0.5}, "pad_radius_over_h"), ({"cell": 0.0}, "cell"),
    ({"edge_refinements": -1}, "edge_refinements"),
    ({"edge_radius_over_h": -0.01}, "edge_radius_over_h"), ({"penalty": 0.0}, "penalty"),
    ({"c20_over_c10": -0.1}, "c20_over_c10"),
])
def test_bad_arguments_raise_naming_them(kwargs, name):
    args = {"a_over_h": 0.8, "nu": 0.45} | kwargs
    a, nu = args.pop("a_over_h"), args.pop("nu")
    with pytest.raises(ValueError, match=name):
        neo_hookean_indentation(a, nu, **args)


def test_surface_profile_conserves_volume_when_incompressible():
    # the deformed top surface: -w under the bonded face, ~0 far away, and at
    # nu = 0.5 (J = 1) the volume under it is unchanged (the punch's volume
    # pi a^2 w reappears as the bulge around it); at nu = 0.45 most of it is
    # compressed away instead
    lost = {}
    for nu in (0.5, 0.45):
        res = neo_hookean_indentation(0.8, nu, contact="bonded", w_over_h_max=0.1, steps=2,
                                      **COARSE)
        R, ur, uz = res.surface_r, res.surface_ur[-1], res.surface_uz[-1]
        assert res.surface_uz.shape == (2, R.size) and np.all(np.diff(R) > 0)
        np.testing.assert_allclose(uz[R <= 0.8], -0.1, atol=1e-12)
        assert np.all(np.abs(uz[R > 10]) < 1e-3)
        r = R + ur
        dv = np.trapezoid((1 + uz) * 2 * np.pi * r, r) - np.trapezoid(2 * np.pi * R, R)
        lost[nu] = -dv / (np.pi * 0.8**2 * 0.1)
    assert abs(lost[0.5]) < 0.005
    assert lost[0.45] > 0.3
