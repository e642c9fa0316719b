"""A ball on a domed gel (sphere_indentation(..., dome_radius_over_h=Rd)) against Hertz's
contact of two curved bodies, a closed form that is not our code: on a thick layer the
force and contact radius are those of one sphere of radius R Rd / (R + Rd) on a flat
half-space (Johnson, Contact Mechanics, 1985, sec. 4.2)."""

from __future__ import annotations

import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.fem import sphere_indentation, sphere_mesh
from tactilevision.fem._sphere import dome_sag, hertz_force
from tactilevision.mechanics import Sphere

R, W = 0.1, np.array([1e-4, 2.5e-4])        # R/h, w/h: a thick layer (chi <= 0.005)
PAD = 0.8                                    # 160 ball radii: the half-space, pad-wise


def _hertz_layer(radius: float) -> tuple[np.ndarray, np.ndarray]:
    """Hertz's force at `radius` with the layer's first-order term (Dimitriadis et al.
    2002, eq. 12: 1 + 1.133 chi), and Hertz's contact radius."""
    chi = np.sqrt(radius * W)
    return hertz_force(radius, W, 0.5) * (1 + 1.133 * chi), np.sqrt(radius * W)


@pytest.mark.parametrize("rd", [1.0, 2.0])
def test_domed_thick_layer_is_hertz_of_the_two_curvatures(rd):
    """The dome takes 4.7 % (Rd = 10 R) and 2.4 % (20 R) off the force at a given depth;
    the FEM follows Hertz's two-curvature law within 0.5 % in force and contact radius,
    and misses it by more than the effect when the dome is left out."""
    dome = sphere_indentation(R, 0.5, W, model="linear", profile="paraboloid",
                              pad_radius_over_h=PAD, dome_radius_over_h=rd)
    flat = sphere_indentation(R, 0.5, W, model="linear", profile="paraboloid",
                              pad_radius_over_h=PAD)
    r_star = R * rd / (R + rd)
    force, radius = _hertz_layer(r_star)
    assert dome.complete and dome.dome_radius_over_h == rd
    assert dome.force / force == pytest.approx([1, 1], abs=0.005)
    assert dome.contact_radius / radius == pytest.approx([1, 1], abs=0.005)
    effect = 1 - np.sqrt(r_star / R)                         # 4.7 %, 2.4 %
    assert np.all(np.abs(flat.force / force - 1) > 0.8 * effect)
    assert dome.force / flat.force == pytest.approx(np.sqrt(r_star / R), rel=0.003)


def test_domed_mesh_and_its_limits():
    """The mesh's top lies on the cap, its base flat; a dome too steep for the pad, or not
    wider than it, is refused, naming both."""
    mesh = sphere_mesh(0.3, 0.0625, pad_radius_over_h=3.0, dome_radius_over_h=25.0)
    top = mesh.p[:, np.abs(mesh.p[1] - (1 - dome_sag(mesh.p[0], 25.0, 3.0))) < 1e-12]
    assert top.shape[1] > 20 and top[0].max() == pytest.approx(3.0)
    assert np.all(mesh.p[1] >= 0) and np.sum(mesh.p[1] == 0) > 10
    sag = 25.0 - np.sqrt(25.0**2 - 9.0)
    assert float(mesh.p[1][np.isclose(mesh.p[0], 3.0)].max()) == pytest.approx(1 - sag)
    with pytest.raises(InputError, match=r"falls by 1 h by the pad's edge"):
        sphere_indentation(1.0, 0.5, [0.1], pad_radius_over_h=3.0, dome_radius_over_h=5.0)
    with pytest.raises(InputError, match="dome of radius 2 h"):
        sphere_indentation(1.0, 0.5, [0.1], pad_radius_over_h=3.0, dome_radius_over_h=2.0)


def test_sphere_takes_a_dome_only_on_a_pad():
    """`Sphere(dome_radius_mm=...)` needs the pad; bad values are named."""
    with pytest.raises(InputError, match="needs the pad's radius"):
        Sphere(7.5, dome_radius_mm=114.0)
    with pytest.raises(InputError, match="dome_radius_mm"):
        Sphere(7.5, pad_radius_mm=12.9, dome_radius_mm=-1.0)
    with pytest.raises(InputError, match="smaller than the dome's"):
        Sphere(7.5, pad_radius_mm=12.9, dome_radius_mm=10.0)
    ball = Sphere(7.5, pad_radius_mm=12.92, dome_radius_mm=114.0)
    assert ball.config()["dome_radius_mm"] == 114.0 and ball.costly_in_nu


def test_finite_strain_on_a_dome_meets_the_same_closed_form():
    """The Neo-Hookean sphere (its contact in the current configuration, the top's nodes at
    their own heights) on the domed thick layer: within 1 % of Hertz's two curvatures at
    w/h = 2.5e-4, where finite strain is negligible."""
    rd = 1.0
    res = sphere_indentation(R, 0.5, W[1:], model="neo_hookean", contact="frictionless",
                             pad_radius_over_h=PAD, dome_radius_over_h=rd)
    force, radius = _hertz_layer(R * rd / (R + rd))
    assert res.complete
    assert res.force / force[1:] == pytest.approx([1], abs=0.01)
    assert res.contact_radius / radius[1:] == pytest.approx([1], abs=0.01)
