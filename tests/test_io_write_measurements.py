"""write_measurements: round trip through read_measurements, column order, refusals."""

from __future__ import annotations

import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.io import read_measurements, write_measurements


def table():
    return {"force_n": [0.55, 1.21, 1.68], "depth_mm": [0.15, 0.30, 0.40], "press": [0, 1, 2],
            "indenter": [0, 1, 2], "hold_s": [1.5, np.nan, 1.5], "x_mm": [1.0, -2.0, 0.5],
            "humidity": [40.0, 41.0, 42.0]}


def test_round_trip(tmp_path):
    path = write_measurements(tmp_path / "out" / "measurements.csv", table(), thickness_mm=3.0,
                              radius_mm=2.5)
    header = path.read_text().splitlines()[0]
    assert header == "press,indenter,depth_mm,force_n,hold_s,x_mm,humidity"
    assert path.read_text().splitlines()[2] == "1,1,0.3,1.21,,-2,41"
    m = read_measurements(path)
    np.testing.assert_allclose(m.depth_mm, [0.15, 0.30, 0.40])
    np.testing.assert_allclose(m.force_n, [0.55, 1.21, 1.68])
    assert np.isnan(m.columns["hold_s"][1]) and m.columns["humidity"][2] == 42.0
    assert (m.thickness_mm, m.radius_mm) == (3.0, 2.5)
    assert not list(path.parent.glob("*.tmp"))


def test_keeps_an_agreeing_session_toml_and_refuses_another(tmp_path):
    session = "[sensor]\ngel_thickness_mm = 3.0\nmm_per_px = 0.05\n\n[indenter]\nradius_mm = 2.5\n"
    (tmp_path / "session.toml").write_text(session)
    write_measurements(tmp_path / "m.csv", table(), thickness_mm=3.0, radius_mm=2.5)
    assert (tmp_path / "session.toml").read_text() == session
    with pytest.raises(InputError, match="exists and does not hold"):
        write_measurements(tmp_path / "m2.csv", table(), thickness_mm=2.0, radius_mm=2.5)
    assert not (tmp_path / "m2.csv").exists()


@pytest.mark.parametrize(("change", "match"), [
    ({"depth_mm": None}, "column depth_mm is required"),
    ({"force_n": [0.5, np.nan, 1.0]}, "force_n must be finite"),
    ({"x_mm": [1.0, 2.0]}, "column x_mm has 2 values, depth_mm 3"),
])
def test_refusals(tmp_path, change, match):
    cols = table()
    for k, v in change.items():
        if v is None:
            cols.pop(k)
        else:
            cols[k] = v
    with pytest.raises(InputError, match=match):
        write_measurements(tmp_path / "m.csv", cols, thickness_mm=3.0, radius_mm=2.5)
    assert not (tmp_path / "m.csv").exists()
    with pytest.raises(InputError, match="thickness_mm must be positive"):
        write_measurements(tmp_path / "m.csv", table(), thickness_mm=0.0, radius_mm=2.5)
