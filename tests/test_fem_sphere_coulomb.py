"""Coulomb friction between a rigid sphere and the bonded layer
(``sphere_indentation(..., contact='coulomb', friction=mu)``): its two limits are the
frictionless and the tied contacts, every node in contact obeys Coulomb's law, and on an
incompressible half-space friction does nothing (Dundurs' second constant is 0)."""

from __future__ import annotations

import functools
import json
import subprocess
import sys

import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.fem import sphere_indentation
from tactilevision.mechanics import Sphere

# the FEATS geometry in units of h: R/h = 7.5 / 4, pad 12.92 / 4 (coarse cells, for speed)
GEOMETRY = dict(radius_over_h=1.875, nu=0.5, w_over_h=np.array([0.0625, 0.25]),
                model="linear", pad_radius_over_h=3.23, surface_cell=0.0625, cache=False)


@functools.cache
def _run(contact: str, mu: float | None):
    """The sweep of GEOMETRY (read-only; computed once per module: mu = 0.2's is read by
    two tests)."""
    res = sphere_indentation(contact=contact, friction=mu, **GEOMETRY)
    assert res.complete
    return res


@pytest.mark.slow
def test_limits_are_the_frictionless_and_the_tied_contact():
    """mu = 1e6 is the tied contact exactly; mu = 0 the frictionless one (within 0.1 %); a
    finite mu lies between, its stick zone inside the contact, shrinking as mu falls."""
    free, tied = _run("frictionless", None), _run("tied", None)
    huge, zero = _run("coulomb", 1e6), _run("coulomb", 0.0)
    assert huge.force == pytest.approx(tied.force, rel=1e-6)
    assert zero.force == pytest.approx(free.force, rel=1e-3)
    assert tied.force[-1] > 1.03 * free.force[-1]        # the thin layer: friction matters
    some, less = _run("coulomb", 0.2), _run("coulomb", 0.05)
    assert np.all(free.force <= less.force * (1 + 1e-9))
    assert np.all(less.force <= some.force * (1 + 1e-9))
    assert np.all(some.force <= tied.force * (1 + 1e-9))
    assert less.slip_radius[-1] < some.slip_radius[-1] <= some.contact_radius_nodes[-1]


def test_every_node_in_contact_obeys_coulombs_law():
    """|shear| <= mu |normal| at every node the sphere holds (the axis node's shear is
    the axis's), with equality on an annulus of slipping nodes at the contact's edge; the
    nodal forces add up to the force."""
    mu = 0.2
    res = _run("coulomb", mu)
    for k in range(res.w_over_h.size):
        fz, fr = res.surface_fz[k], res.surface_fr[k]
        held = (fz != 0) & (res.surface_r > 0)
        scale = np.abs(fz).max()
        assert np.all(np.abs(fr[held]) <= mu * np.abs(fz[held]) + 1e-6 * scale)
        at_limit = held & (np.abs(fr) >= mu * np.abs(fz) - 1e-6 * scale)
        edge = held & (res.surface_r > 0.5 * res.contact_radius_nodes[k])
        assert at_limit.sum() >= 3
        if k == res.w_over_h.size - 1:                   # node-wise: the annulus is ragged
            assert at_limit[edge].mean() > 0.5
        assert res.slip_radius[k] == pytest.approx(res.surface_r[at_limit].min())
        assert -2 * np.pi * fz.sum() == pytest.approx(res.force[k], rel=1e-6)


@pytest.mark.slow
def test_friction_does_nothing_on_an_incompressible_half_space():
    """A small contact (a/h ~ 0.05) on an incompressible layer is a half-space whose
    normal and shear problems uncouple (Dundurs' beta = 0; Johnson, Contact Mechanics,
    1985, sec. 5.4): friction leaves the force within 0.3 %; at nu = 0.3 (beta = 0.29) it
    does not."""
    w = np.array([0.0025])
    kw = dict(model="linear", cache=False)
    free = sphere_indentation(1.0, 0.5, w, contact="frictionless", **kw)
    fric = sphere_indentation(1.0, 0.5, w, contact="coulomb", friction=0.5, **kw)
    assert fric.force[0] == pytest.approx(free.force[0], rel=0.003)
    free3 = sphere_indentation(1.0, 0.3, w, contact="frictionless", **kw)
    tied3 = sphere_indentation(1.0, 0.3, w, contact="tied", **kw)
    assert tied3.force[0] > 1.01 * free3.force[0]


@pytest.mark.slow
def test_a_ball_with_friction_fits_through_the_indenter():
    """Sphere(friction=mu) answers contact='coulomb' (law 'linear'): with mu large, the
    tied ball's force (two pad sweeps, about 34 s from an empty cache: a long check; the
    Coulomb law node by node stays in the default suite)."""
    ball = Sphere(4.0, pad_radius_mm=12.0, friction=1e6)
    w = np.array([1.0, 1.6])
    kw = dict(E_mpa=0.4, nu=0.5, thickness_mm=4.0, law="linear")
    assert ball.force(w, contact="coulomb", **kw) == pytest.approx(
        ball.force(w, contact="tied", **kw), rel=1e-4)


def test_a_balls_bad_friction_or_contact_is_named():
    """A negative friction, coulomb without a friction, coulomb under the Neo-Hookean law:
    each refused naming it, before any sweep."""
    ball = Sphere(4.0, pad_radius_mm=12.0, friction=1e6)
    w = np.array([1.0, 1.6])
    kw = dict(E_mpa=0.4, nu=0.5, thickness_mm=4.0, law="linear")
    with pytest.raises(InputError, match="friction"):
        Sphere(7.5, friction=-1.0)
    with pytest.raises(InputError, match="friction"):
        Sphere(7.5).force(w, contact="coulomb", **kw)
    with pytest.raises(InputError, match="linear"):
        ball.force(w, contact="coulomb", **{**kw, "law": "neo_hookean"})


@pytest.mark.slow
def test_cli_fit_reads_friction(tmp_path):
    """``fit --contact coulomb --friction MU`` on presses drawn from that law gives back
    E; the two options alone are refused with exit 2 naming them."""
    ball = Sphere(4.0, pad_radius_mm=12.0, friction=1e6)
    w = np.array([1.0, 1.3, 1.6])
    P = ball.force(w, E_mpa=0.4, nu=0.5, thickness_mm=4.0, law="linear", contact="coulomb")
    path = tmp_path / "presses.csv"
    rows = "".join(f"{a},{b:.9f}\n" for a, b in zip(w, P, strict=True))
    path.write_text("depth_mm,force_n\n" + rows)
    (tmp_path / "session.toml").write_text(
        '[sensor]\ngel_thickness_mm = 4.0\n[indenter]\nshape = "sphere"\nradius_mm = 4.0\n')
    base = [sys.executable, "-m", "tactilevision", "fit", str(path), "--pad-radius-mm", "12",
            "--nu", "0.5"]
    r = subprocess.run([*base, "--contact", "coulomb", "--friction", "1e6", "--json",
                               str(tmp_path / "fit.json")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    obj = json.loads((tmp_path / "fit.json").read_text())
    assert obj["E_mpa"] == pytest.approx(0.4, rel=1e-3)
    assert obj["law"] == "linear" and obj["contact"] == "coulomb"
    for extra in (["--friction", "0.3"], ["--contact", "coulomb"]):
        r = subprocess.run([*base, *extra], capture_output=True, text=True)
        assert r.returncode == 2 and "--friction" in r.stderr, r.stderr


def test_bad_friction_is_named():
    with pytest.raises(InputError, match="friction"):
        sphere_indentation(1.0, 0.5, [0.1], model="linear", contact="coulomb")
    with pytest.raises(InputError, match="friction"):
        sphere_indentation(1.0, 0.5, [0.1], model="linear", friction=0.3)
    with pytest.raises(InputError, match="friction"):
        sphere_indentation(1.0, 0.5, [0.1], model="linear", contact="coulomb",
                           friction=float("nan"))
    with pytest.raises(InputError, match="linear"):
        sphere_indentation(1.0, 0.5, [0.1], model="neo_hookean", contact="coulomb",
                           friction=0.3)
