"""method='fem' at its default grid (40 x 30 nodes) against Hayes (1972) and the
spectral method on contacts of a few node spacings (issue 21).

The case: a 427 x 320 image at 0.0806 mm/px (node spacing 0.88 mm), a 3 mm layer
bonded to its base, nu 0.48, contact='footprint', height maps that are zero off the
contact (a rigid indenter's profile, no sink-in). Hayes' kappa is the literature
table typed in conftest.py (no code of ours produced it); the spectral method works
at the full pixel resolution (0.993 of Hayes on these punches).
"""

from __future__ import annotations

import numpy as np
import pytest

from tactilevision.fem import ForceEstimator

HPX, WPX, DX, H, NU, E = 320, 427, 0.0806, 3.0, 0.48, 0.2


@pytest.fixture(scope="module")
def estimators():
    kw = dict(thickness_mm=H, E_mpa=E, nu=NU, contact="footprint", threshold_mm=0.01)
    # the default cache: the default grid's stiffness is built once (4 s, 58 MB)
    return (ForceEstimator((HPX, WPX), DX, method="fem", **kw),
            ForceEstimator((HPX, WPX), DX, **kw))


def _r(offset_px=(0.0, 0.0)):
    yy, xx = np.indices((HPX, WPX), dtype=np.float64)
    return np.hypot((xx - (WPX - 1) / 2 - offset_px[0]) * DX,
                    (yy - (HPX - 1) / 2 - offset_px[1]) * DX)


@pytest.mark.parametrize(("a", "offset", "lo", "hi"), [
    # the issue's case, centred and off the nodes' symmetry: measured 0.979, 0.975, 0.969
    # (0.812 / 0.801 before, the rim nodes prescribed the mean height over their
    # tributary pixels with the zero off the punch included)
    (2.5, (0.0, 0.0), 0.95, 1.05), (2.5, (5.5, 5.5), 0.95, 1.05), (2.5, (3.0, 8.0), 0.95, 1.05),
    # a = 1.5 mm (1.7 node spacings): 0.963, 0.984, 0.973 (0.677 to 0.691 before);
    # a = 4 mm: 0.959, 0.976, 0.972 (0.894 to 0.907). 6 %: the rim rule is one law for
    # a contact edge anywhere between nodes, and these punches' edges carry the
    # singular traction the 0.88 mm nodes cannot resolve
    (1.5, (0.0, 0.0), 0.94, 1.06), (1.5, (5.5, 5.5), 0.94, 1.06),
    (4.0, (0.0, 0.0), 0.94, 1.06), (4.0, (3.0, 8.0), 0.94, 1.06),
])
def test_flat_punch_against_hayes(estimators, hand_kappa, a, offset, lo, hi):
    fem, spectral = estimators
    w = 0.1
    u = np.where(_r(offset) <= a, w, 0.0)
    hayes = 2 * a * E * w * hand_kappa(NU, a / H) / (1 - NU**2)
    fm = fem(u)
    assert lo < fm.total_n[2] / hayes < hi
    assert spectral(u).total_n[2] / hayes == pytest.approx(0.99, abs=0.01)   # 0.985-0.993
    assert fm.pressure_kpa.min() >= 0 and np.all(fm.forces_n[~fm.contact] == 0)


@pytest.mark.parametrize(("R", "depth"), [(10.0, 0.3), (5.0, 0.2), (20.0, 0.4)])
def test_sphere_against_the_spectral_method(estimators, R, depth):
    """Rigid spheres, contact radius sqrt(2 R depth) 1.4 to 4 mm: FEM / spectral measured
    1.009 to 1.039 over three positions (0.82 to 0.99 before). Within 5 %: the rim
    nodes' mean over the contact pixels lies above the falling profile at the node."""
    fem, spectral = estimators
    for offset in ((0.0, 0.0), (5.5, 5.5)):
        u = np.maximum(depth - _r(offset) ** 2 / (2 * R), 0.0)
        assert fem(u).total_n[2] / spectral(u).total_n[2] == pytest.approx(1.0, abs=0.05)
