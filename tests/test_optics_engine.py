"""``optics calibrate --model auto``: the engine chosen by presses it was not trained on.

Checked against truth no code of ours drew: the 48 real GelSight ball presses of the
``taxim`` package, whose contact circles were annotated by hand. Calibrated on 7 of them,
the engine kept must be, on the 41 others, near the best candidate (issue 55 asks for 0.3 deg
of the normal angle inside 0.8 of the radius and 3 % of inner cap).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from _data import TAXIM_BALL_RADIUS_MM, TAXIM_MM_PER_PX

from tactilevision import InputError
from tactilevision.cli import main
from tactilevision.cli._optics_run import _engine_text
from tactilevision.io import read_ball_presses, taxim_datapack
from tactilevision.optics import (
    CAP_DEG,
    MIN_NETWORK_PRESSES,
    UNDECIDED,
    DepthReconstructor,
    Engine,
    PhotometricCalibration,
    calibration_accuracy,
    engine_candidates,
    engine_cost,
    engine_margin,
    pooled_cost,
    pooled_presses,
    position_cells,
    undecided_choice,
)
from tactilevision.optics._engine_choice import _margin

SEVEN = "0:42:6"           # presses 0, 6, ..., 36: seven, spread over the folder


def test_candidates_and_their_reasons():
    """The table and its position cells always; the network with enough presses and torch,
    else its reason."""
    assert position_cells((480, 640)) == (8, 6) and position_cells((240, 320)) == (4, 3)
    c, left = engine_candidates((240, 320), MIN_NETWORK_PRESSES, network=None)
    assert [e.name for e in c] == ["table", "table_cells", "network"] and not left
    c, left = engine_candidates((240, 320), MIN_NETWORK_PRESSES - 1, network=None)
    assert [e.name for e in c] == ["table", "table_cells"]
    assert f"a network needs at least {MIN_NETWORK_PRESSES}" in left["network"]
    c, left = engine_candidates((240, 320), 50, network="torch is not installed")
    assert "network" not in [e.name for e in c] and left["network"] == "torch is not installed"


def test_cost_weighs_the_balls_by_their_presses():
    rep = {"balls": [{"n_scored": 3, "normal_angle_08_deg": 2.0, "inner_cap": 0.04},
                     {"n_scored": 1, "normal_angle_08_deg": 6.0, "inner_cap": -0.08},
                     {"n_scored": 0}]}
    s = engine_cost(rep)
    assert s["angle_08_deg"] == pytest.approx(3.0) and s["n_scored"] == 4
    assert s["inner_cap"] == pytest.approx(0.01)
    assert s["cost"] == pytest.approx(3.0 + CAP_DEG * 0.05)
    assert np.isnan(engine_cost({"balls": []})["cost"])


def test_the_folds_pooled_take_the_reports_medians_over_their_presses():
    """Folds of one press each: the cost is each ball's median over every press the folds
    scored (the report's statistic), so one press far off does not carry it, as a mean of
    the folds' medians (the rule before) would."""
    def fold(angle: float, cap: float, r: float = 40.0) -> dict:
        return {"balls": [{"ball_radius_px": r, "n_scored": 1, "normal_angle_08_deg": angle,
                           "inner_cap": cap, "normal_angle_08_per_press_deg": [angle],
                           "inner_cap_per_press": [cap]}]}
    folds = [fold(4.0, 0.01), fold(5.0, -0.02), fold(6.0, 0.03), fold(14.0, -0.21)]
    s = pooled_cost(folds)
    assert s["angle_08_deg"] == pytest.approx(5.5) and s["n_scored"] == 4
    assert s["inner_cap"] == pytest.approx(-0.005)
    assert s["cost"] == pytest.approx(5.5 + CAP_DEG * 0.005)
    mean = engine_cost({"balls": [b for f in folds for b in f["balls"]]})
    assert mean["angle_08_deg"] == pytest.approx(7.25)        # the far press carries it
    # two balls: each its own median, weighed by its presses
    two = pooled_cost([*folds[:3], fold(2.0, 0.05, 60.0)])
    assert two["angle_08_deg"] == pytest.approx((3 * 5.0 + 2.0) / 4)
    assert np.isnan(pooled_cost([{"balls": []}])["cost"])


def _pooled(angles, caps, r: float = 40.0) -> dict:
    return pooled_presses([{"balls": [{"ball_radius_px": r, "n_scored": len(angles),
                                       "normal_angle_08_per_press_deg": list(angles),
                                       "inner_cap_per_press": list(caps)}]}])


def test_the_margin_tells_apart_what_every_press_agrees_on_and_not_a_coin_toss():
    """Paired presses: a candidate 1 deg worse on every press of 7 is told apart, its
    difference exactly 1 deg at every draw; one better on 3 and worse on 4 presses by a
    press-sized scatter is not. Candidates scored on different presses are not paired."""
    rng = np.random.default_rng(5)
    a = rng.uniform(3, 9, 7)                 # the presses differ far more than the engines
    caps = rng.normal(0.0, 0.1, 7)
    m = engine_margin(_pooled(a, caps), _pooled(a + 1.0, caps))
    assert m["cost_difference"] == pytest.approx(1.0)
    assert m["ci95"] == pytest.approx((1.0, 1.0)) and m["told_apart"] and m["n_presses"] == 7
    m = engine_margin(_pooled(a, caps), _pooled(a - 1.0, caps))     # the other is better
    assert m["ci95"] == pytest.approx((-1.0, -1.0)) and m["told_apart"]
    swing = np.array([1.5, -1.5, 1.5, -1.5, 1.5, -1.5, -0.2])
    m = engine_margin(_pooled(a, caps), _pooled(a + swing, caps))
    assert not m["told_apart"] and m["ci95"][0] < 0 < m["ci95"][1]
    # its observed difference is the pooled costs' difference
    assert m["cost_difference"] == pytest.approx(
        pooled_cost([{"balls": [{"ball_radius_px": 40.0, "n_scored": 7,
                                 "normal_angle_08_per_press_deg": list(a + swing),
                                 "inner_cap_per_press": list(caps)}]}])["cost"]
        - pooled_cost([{"balls": [{"ball_radius_px": 40.0, "n_scored": 7,
                                   "normal_angle_08_per_press_deg": list(a),
                                   "inner_cap_per_press": list(caps)}]}])["cost"])
    assert engine_margin(_pooled(a, caps), _pooled(a[:3], caps[:3])) is None
    # two presses that agree are too few to tell anything apart (a sign test cannot)
    m = engine_margin(_pooled(a[:2], caps[:2]), _pooled(a[:2] + 1.0, caps[:2]))
    assert m["ci95"] == pytest.approx((1.0, 1.0)) and not m["told_apart"]
    assert engine_margin(_pooled(a, caps), _pooled(a, caps, r=60.0)) is None


def test_a_table_the_presses_cannot_tell_from_its_cells_gives_way_to_them():
    toss = {"runner_up": "table_cells", "told_apart": False}
    assert undecided_choice("table", toss) == "table_cells"
    assert undecided_choice("table", {**toss, "told_apart": True}) == "table"
    assert undecided_choice("table_cells", {**toss, "runner_up": "table"}) == "table_cells"
    assert undecided_choice("table", {**toss, "runner_up": "network"}) == "table"
    assert undecided_choice("network", toss) == "network"
    assert undecided_choice("table", None) == "table"


def test_a_network_is_weighed_against_the_best_table_on_its_one_fold():
    """The network scores one fold; it is compared with the table of the lowest first-fold
    cost on that fold's presses, not with the tables' every fold."""
    rng = np.random.default_rng(8)
    a, caps = rng.uniform(3, 9, 8), rng.normal(0.0, 0.05, 8)
    first = {"table": (_pooled(a + 2.0, caps), _pooled(a[:3] + 2.0, caps[:3])),
             "table_cells": (_pooled(a + 0.5, caps), _pooled(a[:3] + 0.5, caps[:3])),
             "network": (_pooled(a[:3], caps[:3]), _pooled(a[:3], caps[:3]))}
    rows = [{"engine": "table", "model": "lut", "cost": 5.0, "first_fold": {"cost": 9.0}},
            {"engine": "table_cells", "model": "lut", "cost": 6.0,
             "first_fold": {"cost": 7.0}},
            {"engine": "network", "model": "mlp", "cost": 4.0, "first_fold": {"cost": 6.0}}]
    m = _margin(rows, "network", first)
    assert m["runner_up"] == "table_cells" and m["n_presses"] == 3
    assert m["cost_difference"] == pytest.approx(0.5) and not m["told_apart"]
    m = _margin(rows, "table", first)          # tables against tables, every fold
    assert m["runner_up"] == "table_cells" and m["n_presses"] == 8
    assert m["cost_difference"] == pytest.approx(-1.5) and m["told_apart"]


@pytest.fixture(scope="module")
def seven(tmp_path_factory):
    out = tmp_path_factory.mktemp("engine") / "gelsight.npz"
    assert main(["optics", "calibrate", "taxim:gelsight", "--ball-radius-mm",
                 str(TAXIM_BALL_RADIUS_MM), "--mm-per-px", str(TAXIM_MM_PER_PX),
                 "--presses", SEVEN, "--out", str(out), "--no-progress"]) == 0
    report = json.loads(out.with_name("gelsight_accuracy.json").read_text())
    return out, report


@pytest.mark.slow
def test_seven_presses_keep_a_table_and_say_why_not_the_network(seven):
    """Seven presses: the tables cross-validated over them, the first fold's split too few
    for a network, which the report says. The engine kept is the candidate that scored best and
    the calibration saved is of its kind."""
    out, report = seven
    choice = report["engine"]
    assert [r["engine"] for r in choice["candidates"]] == ["table", "table_cells"]
    assert "a network needs at least" in choice["left_out"]["network"]
    assert len(choice["scored_on"]) >= 1 and len(choice["fitted_on"]) >= 2
    assert not set(choice["scored_on"]) & set(choice["fitted_on"])
    best = min(choice["candidates"], key=lambda r: r["cost"])
    m = choice["margin"]
    if best["engine"] == "table" and not m["told_apart"]:    # a toss: the cells are kept
        assert choice["chosen"] == "table_cells" and UNDECIDED in choice["by"]
    else:
        assert choice["chosen"] == best["engine"] and UNDECIDED not in choice["by"]
    for r in choice["candidates"]:       # the cost is the medians of the presses it saves
        pp = r["per_press"]
        assert len(pp["angle_08_deg"]) == len(pp["inner_cap"]) == r["n_scored"] == 7
        assert r["angle_08_deg"] == pytest.approx(np.median(pp["angle_08_deg"]))
        assert r["inner_cap"] == pytest.approx(np.median(pp["inner_cap"]))
    # the kept against the other, on the same 7
    kept = next(r for r in choice["candidates"] if r["engine"] == choice["chosen"])
    other = next(r for r in choice["candidates"] if r["engine"] != choice["chosen"])
    assert m["runner_up"] == other["engine"] and m["n_presses"] == 7
    assert m["cost_difference"] == pytest.approx(other["cost"] - kept["cost"], abs=1e-6)
    assert m["ci95"][0] <= m["cost_difference"] <= m["ci95"][1]
    assert m["told_apart"] == (m["ci95"][0] > 0)
    assert ("the presses tell the two apart" if m["told_apart"] else
            "cannot tell the two apart") in _engine_text(choice)
    cal = PhotometricCalibration.load(out)
    assert cal.model == "lut" and cal.provenance["engine"]["chosen"] == choice["chosen"]
    # the report's presses are the 41 the choice never saw
    assert report["balls"][0]["n_scored"] >= 35


@pytest.mark.slow
def test_engine_kept_is_near_the_best_on_the_other_presses(seven):
    """Each candidate trained on the same seven presses and scored on the other 41 against
    their hand-annotated circles: the one kept is within 1 deg and 3 % of cap of the best
    of them. (Issue 55 asks for 0.3 deg: ``benchmarks/bench_engine_choice.py`` met it on 6
    of 6 spread seven-press selections of this folder and 9 of 10 random ones, 2026-11-27;
    on this one, until the folds' scores were medians over their presses, the table was
    kept, 0.84 deg above the 4 x 3 cells.) Before the cells were scaled to the presses,
    8 x 6 cells kept on two scored presses read 7.9 deg here against the table's 6.3."""
    _, report = seven
    ps = read_ball_presses(taxim_datapack("gelsight"))
    n = len(ps.frames)
    train = np.arange(n)[slice(0, 42, 6)]
    rest = np.setdiff1d(np.arange(n), train)
    scores = {}
    for r in report["engine"]["candidates"]:
        engine = Engine(r["engine"], r["model"], tuple(r["lut_cells"]))
        cal = PhotometricCalibration.from_ball_presses(
            ps.reference, ps.frames[train], ps.centers_px[train], ps.radii_px[train],
            ball_radius_mm=TAXIM_BALL_RADIUS_MM, mm_per_px=TAXIM_MM_PER_PX,
            model=engine.model, lut_cells=engine.lut_cells)
        sel = np.concatenate([train, rest])
        trained = np.arange(sel.size) < train.size
        rep = calibration_accuracy(DepthReconstructor(cal), ps.frames[sel], ps.centers_px[sel],
                                   ps.radii_px[sel],
                                   np.full(sel.size, TAXIM_BALL_RADIUS_MM / TAXIM_MM_PER_PX),
                                   trained=trained, label_fraction=1.0)
        scores[engine.name] = engine_cost(rep)
    assert report["engine"]["candidates"][1]["lut_cells"] == [4, 3]
    kept = scores[report["engine"]["chosen"]]
    assert kept["angle_08_deg"] <= min(s["angle_08_deg"] for s in scores.values()) + 1.0
    assert abs(kept["inner_cap"]) <= min(abs(s["inner_cap"]) for s in scores.values()) + 0.03


@pytest.mark.slow
def test_the_python_default_chooses_as_the_command_does(seven):
    """Issue 86, one default per choice: ``from_ball_presses`` with its defaults chooses the
    engine by the procedure of ``optics calibrate``'s default ``--model auto``: on the same
    seven presses the same candidates, each with the same cross-validated cost, the same
    engine kept, the calibration returned of its kind."""
    _, report = seven
    ps = read_ball_presses(taxim_datapack("gelsight"))
    train = np.arange(len(ps.frames))[slice(0, 42, 6)]
    cal = PhotometricCalibration.from_ball_presses(
        ps.reference, ps.frames[train], ps.centers_px[train], ps.radii_px[train],
        ball_radius_mm=TAXIM_BALL_RADIUS_MM, mm_per_px=TAXIM_MM_PER_PX)
    mine, cli = cal.provenance["engine"], report["engine"]
    assert [r["engine"] for r in mine["candidates"]] == [r["engine"] for r in cli["candidates"]]
    for a, b in zip(mine["candidates"], cli["candidates"], strict=True):
        assert a["cost"] == pytest.approx(b["cost"], rel=1e-9, abs=1e-12)
        assert a["lut_cells"] == b["lut_cells"]
    assert mine["chosen"] == cli["chosen"] and mine["left_out"] == cli["left_out"]
    assert cal.model == cli["model"]


def test_auto_refuses_an_option_that_names_one_engine():
    """``model='auto'`` chooses the engine: a LUT's position cells or a network to start
    from name one, and are refused before any training, naming the option."""
    ref = np.zeros((40, 50, 3), np.uint8)
    frames = np.zeros((3, 40, 50, 3), np.uint8)
    kw = dict(ball_radius_mm=2.0, mm_per_px=0.05)
    with pytest.raises(InputError, match="lut_cells needs model='lut'"):
        PhotometricCalibration.from_ball_presses(ref, frames, lut_cells=(4, 3), **kw)
    with pytest.raises(InputError, match="warm_start needs model='mlp'"):
        PhotometricCalibration.from_ball_presses(ref, frames, warm_start=object(), **kw)
    with pytest.raises(InputError, match="detected=False needs the circles"):
        PhotometricCalibration.from_ball_presses(ref, frames, detected=False, **kw)
