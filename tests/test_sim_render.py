"""The session renderer: Taxim's fitted shading against the real GelSight ball presses."""

from __future__ import annotations

import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.sim import ShadingTable, taxim_shading

pytest.importorskip("taxim")

BALL_RADIUS_MM = 2.0
MM_PER_PX = 0.0295


@pytest.fixture(scope="module")
def shading():
    return taxim_shading("gelsight")


@pytest.fixture(scope="module")
def datapack():
    from tactilevision.io import taxim_datapack

    with np.load(taxim_datapack("gelsight")) as d:
        return {k: d[k] for k in ("imgs", "touch_center", "touch_radius")}


def _ball_height(shape, centre, rc_px):
    rows, cols = np.indices(shape)
    r2 = (cols - centre[0]) ** 2 + (rows - centre[1]) ** 2
    rb = BALL_RADIUS_MM / MM_PER_PX
    cap = np.sqrt(np.maximum(rb ** 2 - r2, 0)) - np.sqrt(rb ** 2 - rc_px ** 2)
    z = np.where(r2 < rc_px ** 2, cap, 0)
    return z * MM_PER_PX, r2 < rc_px ** 2


def test_renders_real_ball_presses(shading, datapack):
    """Inside the annotated contact of all 48 real presses the rendered colour
    change matches the real one to a median 23% of its size (12% to 57%
    measured; the worst are presses whose hand-drawn circle is off), and in the
    frames' BGR order: the channels reversed are far off."""
    table, ref = shading
    ratios, swapped = [], []
    for i in range(len(datapack["touch_radius"])):
        z, inside = _ball_height(table.shape, datapack["touch_center"][i],
                                 datapack["touch_radius"][i])
        change = table.shading(z)
        real = datapack["imgs"][i].astype(float) - ref
        size = np.sqrt(np.mean(real[inside] ** 2))
        ratios.append(np.sqrt(np.mean((change - real)[inside] ** 2)) / size)
        swapped.append(np.sqrt(np.mean((change[..., ::-1] - real)[inside] ** 2)) / size)
    assert np.median(ratios) < 0.25
    assert max(ratios) < 0.6
    assert min(swapped) > 1.0


def test_flat_gel_is_the_reference(shading):
    table, ref = shading
    img = table.render(np.zeros(table.shape), ref)
    np.testing.assert_array_equal(img, ref)


def test_noise_level_and_determinism(shading):
    table, ref = shading
    a = table.render(np.zeros(table.shape), ref, noise_dn=2.0, rng=np.random.default_rng(3))
    b = table.render(np.zeros(table.shape), ref, noise_dn=2.0, rng=np.random.default_rng(3))
    np.testing.assert_array_equal(a, b)
    d = (a.astype(float) - ref)[(ref > 10).all(-1) & (ref < 245).all(-1)]
    assert 1.8 < d.std() < 2.2


def test_bad_input(shading):
    table, ref = shading
    with pytest.raises(InputError, match="does not match"):
        table.shading(np.zeros((10, 10)))
    with pytest.raises(InputError, match="NaN"):
        table.shading(np.full(table.shape, np.nan))
    with pytest.raises(InputError, match="reference"):
        table.render(np.zeros(table.shape), ref[:10])
    with pytest.raises(InputError, match="rng"):
        table.render(np.zeros(table.shape), ref, noise_dn=1.0)
    with pytest.raises(InputError, match="no polynomial table"):
        taxim_shading("no_such_sensor")
    assert isinstance(table, ShadingTable) and table.num_bins == 125
