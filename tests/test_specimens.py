"""Specimens and repeats of one gel fitted together: a random effect of the specimen
(mechanics.pool_specimens; fit a.csv b.csv ..., a specimen column in fit and diagnose)."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.mechanics import FlatPunch, fit_indentation, pool_specimens

PUNCH = FlatPunch(2.5)
DEPTHS = np.repeat([0.15, 0.30, 0.40, 0.50, 0.60], 4)


def _presses(E: float, rng: np.random.Generator, noise: float = 0.005) -> np.ndarray:
    """A specimen's forces: the FEM's finite-strain flat punch (h 3 mm, nu 0.45)."""
    P = PUNCH.force(DEPTHS, E_mpa=E, nu=0.45, thickness_mm=3.0, law="neo_hookean")
    return P + noise * rng.standard_normal(DEPTHS.size)


def test_agreeing_specimens_pool_to_their_common_modulus():
    """Three specimens with the same E and overlapping intervals: Q small, no
    disagreement, the batch's E their (geometric) mean, its interval no wider than a
    specimen's by more than t(2) / z."""
    p = pool_specimens(["a", "b", "c"], [0.200, 0.202, 0.198],
                       [(0.19, 0.21), (0.192, 0.212), (0.188, 0.208)])
    assert not p.disagree and p.spread == 0.0
    assert p.E_batch_mpa == pytest.approx(math.exp(np.mean(np.log([0.2, 0.202, 0.198]))),
                                          rel=1e-3)
    lo, hi = p.E_batch_ci95_mpa
    assert lo < 0.2 < hi and (hi - lo) / 0.2 < 0.1 * 4.303 / 1.96
    assert "agree within their own intervals" in p.message


def test_a_batch_spread_of_15_percent_is_held_by_the_interval():
    """Batches of 6 specimens whose E scatter 15 % about 0.2 MPa, each fitted on its own
    (20 presses, 5 mN): every specimen's interval is far narrower than the spread, yet the
    batch's interval holds 0.2 MPa in at least 19 of 20 batches, and says the specimens
    disagree in most."""
    held = said = 0
    for seed in range(20):
        rng = np.random.default_rng(seed)
        E_true = 0.2 * np.exp(0.15 * rng.standard_normal(6))
        fits = [fit_indentation(DEPTHS, _presses(E, rng), thickness_mm=3.0, radius_mm=2.5)
                for E in E_true]
        p = pool_specimens([f"s{i}" for i in range(6)], [f.E_mpa for f in fits],
                           [f.E_ci95_mpa for f in fits])
        held += p.E_batch_ci95_mpa[0] <= 0.2 <= p.E_batch_ci95_mpa[1]
        said += p.disagree
    assert held >= 19
    assert said >= 10


def test_pooling_refuses_what_it_cannot_pool():
    with pytest.raises(InputError, match="1 specimen: pooling needs two"):
        pool_specimens(["a"], [0.2], [(0.1, 0.3)])
    with pytest.raises(InputError, match=r"specimen b: E = -0\.1"):
        pool_specimens(["a", "b"], [0.2, -0.1], [(0.1, 0.3), (-0.2, 0.1)])
    with pytest.raises(InputError, match="2 specimen labels, 3 moduli"):
        pool_specimens(["a", "b"], [0.2, 0.2, 0.2], [(0.1, 0.3)] * 3)


def _write(folder, name, rows, header="depth_mm,force_n"):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "session.toml").write_text("[sensor]\ngel_thickness_mm = 3.0\n"
                                         "[indenter]\nradius_mm = 2.5\n")
    path = folder / name
    path.write_text(header + "\n" + "".join(",".join(map(str, r)) + "\n" for r in rows))
    return path


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "tactilevision", *map(str, args)],
                          capture_output=True, text=True)


@pytest.mark.slow
def test_fit_of_several_tables_and_of_a_specimen_column(tmp_path):
    """Two specimens 30 % apart, as two files and as one table's specimen column: the same
    two fits, the batch's E between them, the disagreement said (exit 0, a warning)."""
    rng = np.random.default_rng(3)
    Pa, Pb = _presses(0.17, rng), _presses(0.23, rng)
    a = _write(tmp_path / "a", "a.csv", zip(DEPTHS, Pa, strict=True))
    b = _write(tmp_path / "b", "b.csv", zip(DEPTHS, Pb, strict=True))
    both = _write(tmp_path / "ab", "measurements.csv",
                  [("x", w, p) for w, p in zip(DEPTHS, Pa, strict=True)]
                  + [("y", w, p) for w, p in zip(DEPTHS, Pb, strict=True)],
                  header="specimen,depth_mm,force_n")
    runs = [_cli("fit", a, b, "--json", "-"), _cli("fit", both, "--json", "-")]
    objs = []
    for r in runs:
        assert r.returncode == 0, r.stderr
        assert "specimens disagree" in r.stderr
        objs.append(json.loads(r.stdout))
    Es = [[o["fits"][k]["E_mpa"] for k in o["fits"]] for o in objs]
    assert Es[0] == pytest.approx(Es[1], rel=1e-12)
    assert min(Es[0]) < objs[0]["E_mpa"] < max(Es[0])
    assert objs[0]["E_ci95_mpa"][0] < min(Es[0]) and objs[0]["E_ci95_mpa"][1] > max(Es[0])
    assert set(objs[1]["fits"]) == {"x", "y"} and set(objs[0]["fits"]) == {"a", "b"}


def test_an_empty_specimen_cell_is_named(tmp_path):
    path = _write(tmp_path, "m.csv", [("x", 0.15, 0.5), ("", 0.3, 1.1), ("x", 0.4, 1.5)],
                  header="specimen,depth_mm,force_n")
    r = _cli("fit", path)
    assert r.returncode == 2
    assert "m.csv line 3, column specimen: empty" in r.stderr
