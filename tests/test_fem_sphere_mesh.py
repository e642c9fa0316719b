"""The sphere's axisymmetric mesh stays valid for every pad, ball and gel the tables accept.

A pad whose edge falls inside the fine stretch round the contact (a ball as large as the
pad, an equal-area pad of 16.86 mm diameter under a 21.3 mm ball on a 5.5 mm gel) put a
second node on the pad's edge: cells of zero width, and SuperLU refused the stiffness
matrix ("failed to factorize matrix") with BLAS errors, not a word on the mesh.
"""

from __future__ import annotations

import numpy as np
import pytest

from tactilevision.fem import sphere_indentation, sphere_mesh


def _areas(mesh) -> np.ndarray:
    p, t = mesh.p, mesh.t
    a, b, c = p[:, t[0]], p[:, t[1]], p[:, t[2]]
    return 0.5 * np.abs((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]))


@pytest.mark.parametrize("a_max", [0.2, 0.6, 1.2, 2.5])
def test_every_pad_radius_gives_cells_of_positive_area(a_max):
    """Pads from just past 1.3 contact radii (the least the mesh accepts) to the infinite
    layer's 20 h: no cell thinner than a millionth of the base cell's area, the pad's edge
    one column of nodes."""
    for pad in np.concatenate([1.3 * a_max * np.array([1.001, 1.05, 1.2, 1.5, 2.0, 3.0]),
                               [20.0]]):
        mesh = sphere_mesh(a_max, 0.0625, pad_radius_over_h=float(pad))
        assert _areas(mesh).min() > 1e-6 * 0.125 ** 2, (a_max, pad)
        r = np.unique(np.round(mesh.p[0], 12))
        assert np.min(np.diff(r)) > 1e-6, (a_max, pad)
        assert np.isclose(mesh.p[0].max(), pad)


def test_the_equal_area_pad_under_a_large_ball_is_solved():
    """The case that failed: R 21.335 mm, h 5.5 mm, a pad of 8.43 mm radius (16.86 mm
    across), nu 0.49, one depth of 0.05 h. Right answer: a force, positive and above
    Hertz's (a layer on a rigid base is stiffer than the half-space)."""
    res = sphere_indentation(21.335 / 5.5, 0.49, np.array([0.05]),
                             pad_radius_over_h=8.43 / 5.5, surface_cell=0.0625)
    assert res.complete
    assert res.force[0] > 0 and res.hertz_ratio[0] > 1.0


def test_a_failed_sweep_names_each_mesh_and_why(monkeypatch):
    """When every mesh of a pad sweep fails, the error names the sweep (R/h, nu, law,
    contact, pad, depths) and each mesh with its own failure: Newton's (the depth it
    reached) or the linear solver's (SuperLU's singular matrix), not only the last."""
    import warnings as _w

    from tactilevision import InputError
    from tactilevision.mechanics import _indenter

    calls = []

    def failing(radius_over_h, nu, grid, **kw):
        if kw.get("cache") == "only":
            return None                          # nothing in the disk cache
        calls.append(kw)
        if len(calls) == 1:
            raise RuntimeError("Factor is exactly singular")
        _w.warn(f"Newton failed beyond w/h = {0.4 + 0.01 * len(calls):.4g}", RuntimeWarning,
                stacklevel=2)
        return None

    monkeypatch.setattr(_indenter, "sphere_indentation", failing)
    _indenter.pad_sweep_result.cache_clear()
    with pytest.raises(InputError) as err:
        _indenter.pad_sweep_result(3.9, 0.4999, 1.53, "neo_hookean", "bonded", 0.01)
    msg = str(err.value)
    assert len(calls) == 3
    assert "R/h = 3.9" in msg and "pad radius 1.53 h" in msg and "neo_hookean" in msg
    assert "RuntimeError: Factor is exactly singular" in msg
    assert "w/h = 0.42" in msg and "w/h = 0.43" in msg
    assert msg.count("load steps per depth") == 3
    _indenter.pad_sweep_result.cache_clear()
