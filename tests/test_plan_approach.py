"""A stage that reaches every press's depth in a fixed time (``[plan] approach_s``): each
indenter passes its mark at its own speed, and ``plan`` sizes the mark's lag with it."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.cli import main
from tactilevision.planning import (
    Design,
    crossing_table,
    depth_uncertainty,
    design_from_calibration,
    design_toml,
    indenter_speeds,
    planned_columns,
    read_design,
)
from tactilevision.planning._design import press_indenters
from tactilevision.planning._plan_recommend import _changes

DEPTHS = (0.15, 0.30, 0.40, 0.50, 0.60)
TIMED = Design(thickness_mm=3.0, radius_mm=2.5, depths_mm=DEPTHS, repeats=4, E_mpa=0.2,
               nu=0.48, bevel_angle_deg=0.0, frame_rate_hz=15.0, approach_s=0.5,
               overshoot_um=(5.0, 60.0))


def test_a_move_of_fixed_duration_passes_each_mark_at_its_depth_over_that_time():
    # constant speed to w0 + overshoot, the overshoot the middle of its range (32.5 um)
    np.testing.assert_allclose(indenter_speeds(TIMED),
                               (np.asarray(DEPTHS) + 0.0325) / 0.5, rtol=1e-12)
    np.testing.assert_allclose(indenter_speeds(replace(TIMED, approach_s=None)), 0.1)
    # one frame's travel: 0.365 mm/s / 15 to 1.265 mm/s / 15, the lag bound the longest
    sd, shared, how = depth_uncertainty(TIMED)
    travel = 1e3 * np.repeat((np.asarray(DEPTHS) + 0.0325) / 0.5 / 15.0, 4)
    assert shared == pytest.approx(travel.max()) == pytest.approx(1e3 * 0.6325 / 0.5 / 15)
    assert sd == pytest.approx(np.sqrt(np.mean(travel**2) / 12.0))
    assert "0.365 to 1.26 mm/s" in how and "reached in 0.5 s" in how


def test_press_times_count_each_press_rest_approach_and_hold():
    """A press follows the last after its rest (from the last release), its approach and
    its hold: 2 + 0.5 + 0.5 s apart with a 0.5 s move (the times the crossing table and
    the measurements table plan with), and at 0.1 mm/s each press's approach is its depth
    plus the middle overshoot over the speed (1.8 to 6.3 s), as a generated session
    spends them; before, the approach was left out and a change with time was sized on a
    session 17 to 63 % shorter than it runs."""
    d = replace(TIMED, hold_s=0.5, waits_s=(2.0,))
    t = planned_columns(d)["time_s"]
    np.testing.assert_allclose(np.diff(t), 3.0, rtol=1e-12)
    np.testing.assert_allclose(crossing_table(d)["time_s"], t, rtol=1e-12)
    slow = replace(d, approach_s=None, stage_speed_mm_s=0.1)
    ind = press_indenters(slow)
    gaps = np.diff(np.concatenate([[0.0], planned_columns(slow)["time_s"]]))
    np.testing.assert_allclose(gaps, 2.5 + (np.asarray(DEPTHS)[ind] + 0.0325) / 0.1,
                               rtol=1e-12)
    # the crossing table presses round the indenters: its own order's approaches
    tab = crossing_table(slow)
    own = np.diff(np.concatenate([[0.0], tab["time_s"]]))
    np.testing.assert_allclose(own, 2.5 + (np.asarray(DEPTHS)[tab["indenter"].astype(int)]
                                           + 0.0325) / 0.1, rtol=1e-12)


def test_each_indenters_crossing_bracket_is_a_constant_speed_designs_at_its_speed():
    """The crossing table of the timed design, indenter by indenter, is the one a stage at
    that indenter's own speed would give; the deepest brackets widest (a faster pass and
    a steeper P(w))."""
    tab = crossing_table(TIMED)
    ind = tab["indenter"].astype(int)
    for i, v in enumerate(indenter_speeds(TIMED)):
        same = crossing_table(replace(TIMED, approach_s=None, stage_speed_mm_s=float(v)))
        np.testing.assert_allclose(tab["force_w0_sem_n"][ind == i],
                                   same["force_w0_sem_n"][ind == i], rtol=1e-12)
    one = tab["force_w0_sem_n"][::5][0], tab["force_w0_sem_n"][4::5][0]    # press 0 and 4
    assert one[1] > 3 * one[0]


def test_a_slower_stage_is_offered_as_a_longer_move_and_the_file_round_trips(tmp_path):
    slower = [new for _, new, _ in _changes(TIMED) if new.approach_s != TIMED.approach_s]
    assert [new.approach_s for new in slower] == [1.5]
    assert slower[0].stage_speed_mm_s == TIMED.stage_speed_mm_s
    path = tmp_path / "d.toml"
    path.write_text(design_toml(TIMED))
    assert "approach_s = 0.5" in path.read_text()
    assert "stage_speed_mm_s" not in path.read_text()
    assert read_design(path) == TIMED


@pytest.mark.parametrize(("plan", "match"), [
    ("approach_s = 0.5\nstage_speed_mm_s = 0.1", "both stage_speed_mm_s and approach_s"),
    ("approach_s = 0", "approach_s must be positive"),
    ('approach_s = "fast"', "approach_s must be a number"),
])
def test_bad_approaches_are_refused_naming_the_key(tmp_path, capsys, plan, match):
    path = tmp_path / "d.toml"
    path.write_text("[sensor]\ngel_thickness_mm = 3.0\n[indenter]\nradius_mm = 2.5\n"
                    "[gauge_block]\ndepths_mm = [0.15, 0.3, 0.45]\nbevel_angle_deg = 0\n"
                    f"[plan]\n{plan}\n")
    with pytest.raises(InputError, match=match):
        read_design(path)
    assert main(["plan", str(path)]) == 2
    err = capsys.readouterr().err
    assert "approach_s" in err and str(path) in err and "Traceback" not in err


def _calibration(tmp_path, ramp_of, name):
    """A calibration folder of 12 presses at w0 0.15, 0.30, 0.45 mm (overshoot 10 to 40 um)
    whose holds.csv times each press's loading as `ramp_of(depth)`, s."""
    cal = tmp_path / name
    cal.mkdir()
    (cal / "fit.json").write_text(json.dumps({"E_mpa": 0.2, "nu": 0.48, "thickness_mm": 3.0,
                                              "radius_mm": 2.5}))
    rng = np.random.default_rng(3)
    rows, holds = ["press,depth_mm,overshoot_mm,force_n,force_std_n"], ["press,t_s,fz_n,ramp_s"]
    for k in range(12):
        w0, o = (0.15, 0.30, 0.45)[k % 3], rng.uniform(0.010, 0.040)
        rows.append(f"{k},{w0 + o:.6f},{o:.6f},1.0,0.01")
        holds += [f"{k},{t:.3f},1.0,{ramp_of(w0 + o) * rng.uniform(0.98, 1.02):.4f}"
                  for t in (0.0, 0.1)]
    (cal / "measurements.csv").write_text("\n".join(rows) + "\n")
    (cal / "holds.csv").write_text("\n".join(holds) + "\n")
    return cal


def test_a_calibration_says_how_its_stage_moved(tmp_path):
    """plan --from-calibration reads the stage's motion from the presses' loading times
    (holds.csv's ramp_s): the same 0.5 s at every depth is a move of fixed duration
    (approach_s 0.5), times growing with depth a constant speed (0.2 mm/s); without the
    loading times the default speed stays."""
    timed = design_from_calibration(_calibration(tmp_path, lambda w: 0.5, "timed"))
    assert timed.approach_s == pytest.approx(0.5, rel=0.02)
    steady = design_from_calibration(_calibration(tmp_path, lambda w: w / 0.2, "steady"))
    assert steady.approach_s is None
    assert steady.stage_speed_mm_s == pytest.approx(0.2, rel=0.02)
    bare = _calibration(tmp_path, lambda w: 0.5, "bare")
    (bare / "holds.csv").unlink()
    assert design_from_calibration(bare).stage_speed_mm_s == Design.stage_speed_mm_s
    assert design_from_calibration(bare).approach_s is None
    (bare / "holds.csv").write_text("press,t_s,fz_n,ramp_s\n0,zero,1.0,0.5\n")
    assert design_from_calibration(bare).approach_s is None      # unreadable: not used
    path = tmp_path / "next.toml"
    assert main(["plan", "--from-calibration", str(tmp_path / "timed"), "--write-design",
                 str(path)]) == 0
    assert read_design(path) == timed
