"""A rigid sphere on the bonded layer (tactilevision.fem.sphere_indentation) against truth
that is not our code: Hertz's half-space, Dimitriadis et al.'s bonded-layer series, and the
FEM's own mesh convergence."""

from __future__ import annotations

import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.fem import sphere_indentation, sphere_mesh

# Dimitriadis, Horkay, Maresca, Kachar, Chadwick, Biophys. J. 82:2798-2810 (2002), eq. (12):
# a paraboloid on an incompressible layer bonded to a rigid substrate, chi = sqrt(R w) / h,
# P = 16/9 E R^(1/2) w^(3/2) (1 + 1.133 chi + 1.283 chi^2 + 0.769 chi^3 + 0.0975 chi^4).
DIMITRIADIS_12 = (1.133, 1.283, 0.769, 0.0975)


def dimitriadis(chi: np.ndarray) -> np.ndarray:
    c1, c2, c3, c4 = DIMITRIADIS_12
    return 1 + c1 * chi + c2 * chi**2 + c3 * chi**3 + c4 * chi**4


def test_thick_layer_is_hertz():
    """R/h = 0.1 at w/h = 1e-4 and 2.5e-4 (chi = sqrt(R w)/h = 0.003, 0.005): force and
    contact radius within 1 % of Hertz's P = 4/3 E* R^1/2 w^3/2, a = sqrt(R w), once the
    layer's first-order term (1.133 chi, 0.6 % here) is taken off."""
    R, w = 0.1, np.array([1e-4, 2.5e-4])
    res = sphere_indentation(R, 0.5, w, model="linear", profile="paraboloid")
    chi = np.sqrt(R * w)
    assert res.complete
    assert res.hertz_ratio / (1 + DIMITRIADIS_12[0] * chi) == pytest.approx([1, 1], abs=0.01)
    assert res.hertz_ratio == pytest.approx([1, 1], abs=0.01)       # Hertz itself
    assert res.contact_radius / np.sqrt(R * w) == pytest.approx([1, 1], abs=0.01)
    # the disk cache alone: this sweep back, another one not computed
    hit = sphere_indentation(R, 0.5, w, model="linear", profile="paraboloid", cache="only")
    assert hit is not None and np.array_equal(hit.hertz_ratio, res.hertz_ratio)
    assert sphere_indentation(R, 0.5, w * 1.5, model="linear", profile="paraboloid",
                              cache="only") is None


def test_bonded_layer_follows_dimitriadis_in_its_range():
    """Incompressible bonded layer, paraboloid (eq. 12's assumptions): within 2 % of the
    series for chi = sqrt(R w)/h up to 0.25; past it the series' truncation falls behind
    (measured: +2.8 % at chi = 0.3, +8.4 % at 0.5; benchmarks/bench_fem_sphere.py)."""
    chi = np.array([0.1, 0.15, 0.2, 0.25])
    res = sphere_indentation(1.0, 0.5, chi**2, model="linear", profile="paraboloid")
    ratio = res.hertz_ratio / dimitriadis(chi)
    assert np.all(np.abs(ratio - 1) < 0.02), ratio
    # and the FEM does rise above the truncated series with chi, not below
    assert ratio[-1] > ratio[0]


def test_incompressible_tied_equals_frictionless():
    """At nu = 0.5 a rigid sphere's shear traction does no work on the normal problem of a
    half-space (Dundurs' second constant is 0): tied and frictionless agree at small w/R
    (here w/R = 0.01; the sweeps from w/R = 0.0025, on a mesh twice as fine, take about
    45 s from an empty cache and run with the long checks:
    :func:`test_incompressible_tied_equals_frictionless_from_shallower`)."""
    w = np.array([0.01])
    fr = sphere_indentation(1.0, 0.5, w, model="neo_hookean", contact="frictionless")
    ti = sphere_indentation(1.0, 0.5, w, model="neo_hookean", contact="tied")
    assert ti.force / fr.force == pytest.approx([1], abs=0.003)


@pytest.mark.slow
def test_incompressible_tied_equals_frictionless_from_shallower():
    """Tied against frictionless as above from w/R = 0.0025 (measured 0.9977 and 1.0000)."""
    w = np.array([0.0025, 0.01])
    fr = sphere_indentation(1.0, 0.5, w, model="neo_hookean", contact="frictionless")
    ti = sphere_indentation(1.0, 0.5, w, model="neo_hookean", contact="tied")
    assert ti.force / fr.force == pytest.approx([1, 1], abs=0.003)


@pytest.mark.slow
def test_the_finite_strain_sweep_converges_with_the_mesh():
    """Two meshes of the Neo-Hookean sweep (the default surface cell and half of it) agree
    within 0.5 % in force. The finer mesh's sweep takes about a minute from an empty cache
    on this project's 2-core machine, so it runs with the long checks (report
    ``long_checks``), not the default suite."""
    w = np.array([0.0025, 0.01])
    fr = sphere_indentation(1.0, 0.5, w, model="neo_hookean", contact="frictionless")
    fine = sphere_indentation(1.0, 0.5, w, model="neo_hookean", contact="frictionless",
                              surface_cell=0.5 * fr.surface_cell)
    assert fine.force / fr.force == pytest.approx([1, 1], abs=0.005)


def test_finite_strain_and_the_sphere_soften_against_the_linear_paraboloid():
    """The exact sphere sits above its paraboloid (R - sqrt(R^2 - r^2) >= r^2 / 2R): less
    force at the same depth; the Neo-Hookean layer at w/R = 0.1 is softer than linear."""
    w = np.array([0.1])
    par = sphere_indentation(1.0, 0.5, w, model="linear", profile="paraboloid")
    sph = sphere_indentation(1.0, 0.5, w, model="linear")
    nh = sphere_indentation(1.0, 0.5, w, model="neo_hookean")
    assert sph.force[0] < par.force[0]
    assert nh.force[0] < sph.force[0]


def test_bad_arguments_are_named():
    with pytest.raises(InputError, match="radius_over_h"):
        sphere_indentation(-1.0, 0.5, [0.1])
    with pytest.raises(InputError, match="nu"):
        sphere_indentation(1.0, 0.7, [0.1])
    with pytest.raises(InputError, match="w_over_h"):
        sphere_indentation(1.0, 0.5, [0.2, 0.1])
    with pytest.raises(InputError, match="equator"):
        sphere_indentation(0.5, 0.5, [0.55])
    with pytest.raises(InputError, match="contact"):
        sphere_indentation(1.0, 0.5, [0.1], contact="glued")
    with pytest.raises(InputError, match="profile"):
        sphere_indentation(1.0, 0.5, [0.1], model="neo_hookean", profile="paraboloid")
    with pytest.raises(InputError, match="pad radius"):
        sphere_mesh(5.0, 0.05, pad_radius_over_h=6.0)


def _counted_factorisations(counts: dict):
    """:class:`~tactilevision.fem._finite_solver._Factorised` adding 1 to ``counts['lu']``
    per factorisation."""
    import tactilevision.fem._finite_solver as fs

    class Counted(fs._Factorised):
        def __init__(self, k_ff):
            counts["lu"] += 1
            super().__init__(k_ff)

    return Counted


def test_a_linear_sweep_factorises_once_per_contact_set(monkeypatch):
    """Small strain: K0 is the same at every depth, so a sweep factorises it once per set
    of held nodes at most, not at every Newton iteration (twice per solve before), and
    gives the numbers a factorisation per iteration gives (a pure saving: the suite's
    thick-gel sweep took 37 s from an empty cache, 21 s now)."""
    import tactilevision.fem._finite_solver as fs
    import tactilevision.fem._sphere as sph

    counts = {"lu": 0, "solve": 0}

    solve = sph._Sweep._solve

    def counted_solve(self, x, w):
        counts["solve"] += 1
        return solve(self, x, w)

    monkeypatch.setattr(fs, "_Factorised", _counted_factorisations(counts))
    monkeypatch.setattr(sph._Sweep, "_solve", counted_solve)
    R, w = 0.5, np.array([0.01, 0.02, 0.04])
    kw = dict(model="linear", contact="frictionless", surface_cell=0.04, cache=False)
    res = sphere_indentation(R, 0.5, w, **kw)
    assert res.complete and counts["solve"] > 0
    assert counts["lu"] <= counts["solve"], counts
    monkeypatch.setattr(sph._LinearSolid, "constant_tangent", False)
    again = sphere_indentation(R, 0.5, w, **kw)
    np.testing.assert_allclose(res.force, again.force, rtol=1e-12)
    np.testing.assert_allclose(res.contact_radius, again.contact_radius, rtol=1e-12)


def test_a_finite_strain_sweep_factorises_once_per_newton_iteration(monkeypatch):
    """Neo-Hookean: one factorised tangent per Newton iteration, none at the converged
    state (the sphere's sweep reads no dP/dw from it and the next solve starts afresh: a
    quarter of the factorisations saved, the numbers unchanged)."""
    import tactilevision.fem._finite_solver as fs

    counts = {"lu": 0, "iterations": 0}

    solve = fs.ConstrainedNewton.solve

    def counted(self, *args, **kwargs):
        out = solve(self, *args, **kwargs)
        counts["iterations"] += out[1]
        return out

    monkeypatch.setattr(fs, "_Factorised", _counted_factorisations(counts))
    monkeypatch.setattr(fs.ConstrainedNewton, "solve", counted)
    res = sphere_indentation(0.5, 0.45, np.array([0.01, 0.02]), model="neo_hookean",
                             contact="tied", surface_cell=0.04, cache=False)
    assert res.complete and counts["iterations"] > 0
    assert counts["lu"] == counts["iterations"], counts


def test_a_sphere_sweeps_cache_key_covers_the_code_it_runs():
    """Every module of the package a sphere sweep imports (bar the cache's own reader)
    enters its cache key: a change to the Newton solver or the Neo-Hookean forms misses
    the old sweeps (the key once hashed _sphere.py alone, so such a change read sweeps
    the old code had computed)."""
    import ast
    from pathlib import Path

    import tactilevision.fem._sphere as sph

    tree = ast.parse(Path(sph.__file__).read_text())
    imported = {f"{node.module}.py" for node in ast.walk(tree)
                if isinstance(node, ast.ImportFrom) and node.level == 1 and node.module}
    assert imported - {"_sweep_cache.py"} <= set(sph.SPHERE_SOURCES) - {"_sphere.py"}
    assert "_sphere.py" in sph.SPHERE_SOURCES
