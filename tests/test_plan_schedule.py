"""A design's press schedule (``[plan] schedule``: each press's indenter and position, in
order, as ``presses.csv`` lists them): what ``plan`` sizes within-indenter effects on."""

from __future__ import annotations

import json
import warnings
from dataclasses import replace

import numpy as np
import pytest

from tactilevision import InputError, InputWarning
from tactilevision.cli import main
from tactilevision.diagnosis import crossing_sizes
from tactilevision.planning import (
    BRACKET_PERIODS,
    Design,
    crossing_effect_sizes,
    crossing_sessions,
    crossing_table,
    design_from_calibration,
    design_toml,
    measured_bracket_periods,
    plan_session,
    planned_columns,
    press_bracket_periods,
    read_design,
    read_schedule,
)
from tactilevision.planning._plan_recommend import _changes

DEPTHS = (0.15, 0.30, 0.40, 0.50, 0.60)
MARK = Design(thickness_mm=3.0, radius_mm=2.5, depths_mm=DEPTHS, repeats=4, E_mpa=0.2,
              nu=0.48, bevel_angle_deg=0.0, frame_rate_hz=15.0, stage_speed_mm_s=0.1)


def _random_schedule(seed: int, spread: float = 1.0) -> tuple[tuple[int, float, float], ...]:
    """Each indenter 4 times, shuffled, at positions drawn over a 5.2 x 8 mm patch."""
    rng = np.random.default_rng(seed)
    ind = rng.permutation(np.repeat(np.arange(len(DEPTHS)), 4))
    x = spread * rng.uniform(-6.5, -1.3, ind.size)
    y = rng.uniform(-4.0, 4.0, ind.size)
    return tuple((int(i), float(a), float(b)) for i, a, b in zip(ind, x, y, strict=True))


def test_the_schedule_sets_the_presses_order_indenters_and_places():
    sch = _random_schedule(1)
    d = replace(MARK, schedule=sch)
    cols, tab = planned_columns(d), crossing_table(d)
    ind = np.array([s[0] for s in sch])
    np.testing.assert_array_equal(cols["depth_mm"], np.asarray(DEPTHS)[ind])
    np.testing.assert_array_equal(cols["x_mm"], [s[1] for s in sch])
    np.testing.assert_array_equal(cols["y_mm"], [s[2] for s in sch])
    np.testing.assert_array_equal(tab["indenter"], ind)
    np.testing.assert_array_equal(tab["x_mm"], [s[1] for s in sch])
    # each press's crossing force is its own indenter's (the FEM's at its w0)
    first = {int(i): f for i, f in zip(tab["indenter"], tab["force_w0_n"], strict=True)}
    assert np.all(np.diff([first[i] for i in range(len(DEPTHS))]) > 0)


def test_crossing_brackets_span_the_periods_the_mark_rule_gives():
    """By default a drawn mark's crossing bracket spans one frame period and two in turn,
    press by press (BRACKET_PERIODS 1.5: the mark rule's brackets on Taxim's designs, 1.0
    to 1.7 periods): without F/T noise, each press's
    width over its periods is one frame's travel (0.1 mm/s at 15 frames/s) times dP/dw at
    its indenter's w0, the same for all of an indenter's presses and growing with w0."""
    tab = crossing_table(replace(MARK, force_noise_n=0.0))
    width = tab["force_w0_sem_n"] * np.sqrt(12.0)
    periods = press_bracket_periods(BRACKET_PERIODS, width.size)
    np.testing.assert_array_equal(periods, np.resize([1.0, 2.0], width.size))
    ind = tab["indenter"].astype(int)
    unit = width / periods
    per_indenter = []
    for i in range(len(DEPTHS)):
        np.testing.assert_allclose(unit[ind == i], unit[ind == i][0], rtol=1e-12)
        assert set(periods[ind == i]) == {1.0, 2.0}        # each indenter sees both
        per_indenter.append(unit[ind == i][0])
    assert np.all(np.diff(per_indenter) > 0)
    # dP/dw of a 3 mm layer under a 2.5 mm punch at E 0.2 MPa: a few N/mm
    assert 1.0 < per_indenter[0] / (0.1 / 15.0) < 10.0


@pytest.mark.slow
def test_a_gradient_is_sized_on_the_spread_of_each_indenters_places():
    """The crossing test sees a gradient only through x within each indenter: a schedule
    pressing every indenter at one place cannot see one, and stretching every x by 2
    halves the gradient it names (the effect is 1 + g (x - mean x))."""
    sch = _random_schedule(2)
    one = crossing_effect_sizes(replace(MARK, schedule=sch))["spatial_nonuniformity"]
    two = crossing_effect_sizes(replace(MARK, schedule=_random_schedule(2, 2.0)))
    assert np.isfinite(one.size_param) and one.size_param > 0
    assert two["spatial_nonuniformity"].size_param == pytest.approx(one.size_param / 2,
                                                                     rel=0.03)
    fixed = tuple((i, -2.0 - 0.7 * i, 0.5 * i) for i, _, _ in sch)
    assert not np.isfinite(
        crossing_effect_sizes(replace(MARK, schedule=fixed))["spatial_nonuniformity"].size)
    # the design's sizes are the crossing test's own on the sessions it draws of the table
    # it plans, within a tenth of the evenly spread table's
    d = replace(MARK, schedule=sch)
    got = crossing_sizes(crossing_table(d), sessions=crossing_sessions(d))
    assert got["spatial_nonuniformity"] == pytest.approx(one.size_param)
    even = crossing_sizes(crossing_table(d))["spatial_nonuniformity"]
    assert one.size_param == pytest.approx(even, rel=0.10)


@pytest.mark.slow
def test_the_gradient_named_grows_as_each_indenters_places_spread_less():
    """Drawn schedules: the gradient the crossings name falls with the sd of x within each
    indenter (the only x the within-indenter test sees)."""
    sizes, spreads = [], []
    for seed in range(5):
        d = replace(MARK, schedule=_random_schedule(10 + seed))
        tab = crossing_table(d)
        spreads.append(np.sqrt(np.mean([np.var(tab["x_mm"][tab["indenter"] == i])
                                        for i in range(len(DEPTHS))])))
        sizes.append(crossing_effect_sizes(d)["spatial_nonuniformity"].size_param)
    assert np.corrcoef(spreads, sizes)[0, 1] < -0.7


@pytest.mark.slow
def test_the_schedule_reads_from_presses_csv_and_sets_repeats(tmp_path, capsys):
    sch = _random_schedule(3)
    (tmp_path / "presses.csv").write_text("press,indenter,x_mm,y_mm\n" + "".join(
        f"{k},{i},{x!r},{y!r}\n" for k, (i, x, y) in reversed(list(enumerate(sch)))))
    path = tmp_path / "d.toml"
    path.write_text("[sensor]\ngel_thickness_mm = 3.0\n[indenter]\nradius_mm = 2.5\n"
                    f"[gauge_block]\ndepths_mm = {list(DEPTHS)}\nbevel_angle_deg = 0.0\n"
                    "[plan]\nschedule = \"presses.csv\"\n")
    d = read_design(path)
    assert d.repeats == 4 and d.schedule == sch       # in press order, not the file's
    assert read_schedule(tmp_path / "presses.csv", len(DEPTHS)) == sch
    again = tmp_path / "again.toml"
    again.write_text(design_toml(d))
    with warnings.catch_warnings():
        warnings.simplefilter("error")             # written without a positions to ignore
        assert read_design(again).schedule == sch
    both = tmp_path / "both.toml"
    both.write_text(path.read_text() + "positions = 6\n")
    with pytest.warns(InputWarning, match="positions is not read"):
        assert read_design(both).schedule == sch
    assert main(["plan", str(path), "--json", str(tmp_path / "p.json")]) == 0
    assert "presses in the order and places of [plan] schedule" in capsys.readouterr().out
    saved = json.loads((tmp_path / "p.json").read_text())["design"]["schedule"]
    assert [tuple(v) for v in saved] == list(sch)


@pytest.mark.parametrize(("plan", "csv", "match"), [
    ("schedule = \"missing.csv\"", None, "missing.csv"),
    ("schedule = \"p.csv\"", "press,indenter,x_mm,y_mm\n0,7,1.0,2.0\n",
     "line 2, column indenter: 7 is not an indenter"),
    ("schedule = \"p.csv\"", "press,indenter,x_mm\n0,1,1.0\n", "missing column"),
    ("schedule = [[0, 1.0, 2.0], [1, 1.0]]", None, "press 1 must be"),
    ("schedule = [[0, 1.0, 2.0], [5, 1.0, 2.0]]", None, "press 1's indenter 5"),
    ("repeats = 2\nschedule = [[0, 1.0, 2.0], [1, 1.0, 2.0]]", None,
     "presses indenter 0 1 time"),
    ("schedule = 3", None, "schedule must be a presses.csv"),
    ("schedule = [[]]", None, "press 0 must be"),
])
def test_bad_schedules_name_the_file_and_the_press(tmp_path, capsys, plan, csv, match):
    if csv is not None:
        (tmp_path / "p.csv").write_text(csv)
    path = tmp_path / "d.toml"
    path.write_text("[sensor]\ngel_thickness_mm = 3.0\n[indenter]\nradius_mm = 2.5\n"
                    "[gauge_block]\ndepths_mm = [0.15, 0.30]\nbevel_angle_deg = 0.0\n"
                    f"[plan]\n{plan}\n")
    with pytest.raises(InputError, match=match) as err:
        read_design(path)
    assert str(path) in str(err.value)
    assert main(["plan", str(path)]) == 2
    assert "Traceback" not in capsys.readouterr().err


def test_changes_of_repeats_depths_or_positions_leave_the_schedule():
    d = replace(MARK, schedule=_random_schedule(4))
    changed = {label: new for label, new, _ in _changes(d)}
    assert any(new.repeats == 8 and new.schedule is None for new in changed.values())
    for new in changed.values():
        if new.repeats == d.repeats and new.depths_mm == d.depths_mm:
            assert new.schedule == d.schedule


@pytest.mark.parametrize("mean", [1.0, 1.25, 5.0 / 3.0, 1.94, 2.0, 2.5, 4.0])
def test_bracket_periods_average_what_the_design_says(mean):
    """Each press spans floor(mean) or one more frame period, spread evenly, their mean
    the design's to within one press in 600 (every press the same at a whole number)."""
    p = press_bracket_periods(mean, 600)
    assert set(np.unique(p)) <= {np.floor(mean), np.floor(mean) + 1}
    assert p.mean() == pytest.approx(mean, abs=1 / 600)
    if mean.is_integer():
        assert np.all(p == mean)


@pytest.mark.slow
def test_brackets_twice_as_wide_double_what_the_crossings_can_name():
    """Without F/T noise a bracket's width is its periods times one frame's travel times
    dP/dw, so every bracket two periods wide instead of one doubles it, and the crossing
    test (on log force, brackets softened by 2 % of their width) names changes about
    twice as large: the gradient, the steady change and the step half-way."""
    quiet = replace(MARK, force_noise_n=0.0)
    one = crossing_effect_sizes(replace(quiet, bracket_periods=1.0))
    two = crossing_effect_sizes(replace(quiet, bracket_periods=2.0))
    w1 = crossing_table(replace(quiet, bracket_periods=1.0))["force_w0_sem_n"]
    w2 = crossing_table(replace(quiet, bracket_periods=2.0))["force_w0_sem_n"]
    np.testing.assert_allclose(w2, 2 * w1, rtol=1e-12)
    for name in ("spatial_nonuniformity", "stiffness_trend:time_s", "stiffness_step:press"):
        assert two[name].size / one[name].size == pytest.approx(2.0, rel=0.06), name


@pytest.mark.parametrize("periods", [1.0, 2.0, 3.0])
def test_a_sessions_brackets_give_back_their_periods(periods):
    """measured_bracket_periods inverts crossing_table's widths, F/T noise and each
    indenter's own speed included: brackets of a whole number of periods on every press
    read back exactly; a vernier's and a table of two presses give none."""
    d = replace(MARK, bracket_periods=periods, approach_s=0.5, force_noise_n=0.02,
                schedule=_random_schedule(3))
    tab = crossing_table(d)
    w0 = np.asarray(DEPTHS)[tab["indenter"].astype(int)]
    assert measured_bracket_periods(d, w0, tab["force_w0_sem_n"]) == pytest.approx(
        periods, rel=1e-9)
    assert measured_bracket_periods(replace(d, bevel_angle_deg=8.0), w0,
                                    tab["force_w0_sem_n"]) is None
    assert measured_bracket_periods(d, w0[:2], tab["force_w0_sem_n"][:2]) is None


def test_bracket_periods_round_trip_and_are_checked(tmp_path, capsys):
    """[plan] bracket_periods and unseen_share are read, written by design_toml and refused
    outside [1, 4] and [0, 0.5) with the key named."""
    d = replace(MARK, bracket_periods=1.94)
    path = tmp_path / "d.toml"
    path.write_text(design_toml(d))
    assert read_design(path) == d
    path.write_text(design_toml(d).replace("bracket_periods = 1.94", "bracket_periods = 0.5"))
    with pytest.raises(InputError, match=r"\[plan\] bracket_periods must lie in \[1, 4\]"):
        read_design(path)
    assert main(["plan", str(path)]) == 2
    assert "bracket_periods" in capsys.readouterr().err
    d = replace(MARK, unseen_share=0.1)
    path.write_text(design_toml(d))
    assert read_design(path) == d
    path.write_text(design_toml(d).replace("unseen_share = 0.1", "unseen_share = 0.5"))
    with pytest.raises(InputError, match=r"\[plan\] unseen_share must lie in \[0, 0.5\)"):
        read_design(path)


def test_sessions_draw_each_press_s_periods_and_losses_as_the_design_says():
    """crossing_sessions: each press two periods with probability frac(bracket_periods)
    (1.94: 94 % of 1000 x 20 presses, to 1 %), its width one or two periods' travel
    times dP/dw plus the F/T widening; without unseen presses one session keeping every
    press, with unseen_share 0.25 five sessions keeping about three quarters; the same
    draws every time."""
    d = replace(MARK, bracket_periods=1.94)
    one = crossing_table(replace(d, bracket_periods=1.0))["force_w0_sem_n"]
    two = crossing_table(replace(d, bracket_periods=2.0))["force_w0_sem_n"]
    (keep, sem), = crossing_sessions(d)
    assert keep.all() and sem.shape == (1000, one.size)
    is_two = np.isclose(sem, two[None], rtol=1e-12)
    assert np.all(is_two | np.isclose(sem, one[None], rtol=1e-12))
    assert is_two.mean() == pytest.approx(0.94, abs=0.01)
    lossy = crossing_sessions(replace(d, unseen_share=0.25))
    assert len(lossy) == 5 and sum(s.shape[0] for _, s in lossy) == 1000
    kept = np.mean([k.mean() for k, _ in lossy])
    assert 0.6 < kept < 0.9
    again = crossing_sessions(replace(d, unseen_share=0.25))
    assert all(np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
               for a, b in zip(lossy, again, strict=True))


@pytest.mark.slow
def test_unseen_presses_raise_what_the_crossings_can_name():
    """With whole periods and every press seen, the drawn sessions are the planned table
    (the sizes its own, to the bisection's 2 %); losing each press with probability 0.3
    leaves fewer presses per indenter, and the gradient, the steady change and the step
    named in 95 % of sessions are larger."""
    d = replace(MARK, bracket_periods=2.0)
    plan = crossing_effect_sizes(d)
    table = crossing_sizes(crossing_table(d))
    lossy = crossing_effect_sizes(replace(d, unseen_share=0.3))
    for name in ("spatial_nonuniformity", "stiffness_trend:time_s", "stiffness_step:press"):
        assert plan[name].size_param == pytest.approx(table[name], rel=0.03), name
        assert lossy[name].size_param > 1.05 * plan[name].size_param, name
    assert "30 % of presses unseen" in lossy["stiffness_step:press"].why


def test_a_calibration_gives_its_brackets_periods_and_unseen_share(tmp_path):
    """plan --from-calibration reads a mark session's brackets back: a calibration folder
    whose crossing forces' sds are those of brackets two periods wide on every press
    (crossing_table at 30 frames/s, 0.1 mm/s, the defaults a folder without frames or
    holds keeps) gives bracket_periods 2; 3 presses rejected beside its 20 an
    unseen_share of 3/23."""
    d = replace(MARK, frame_rate_hz=30.0, bracket_periods=2.0, force_noise_n=0.0125)
    tab = crossing_table(d)
    cal = tmp_path / "cal"
    cal.mkdir()
    (cal / "fit.json").write_text(json.dumps({"E_mpa": d.E_mpa, "nu": d.nu, "thickness_mm": 3.0,
                                              "radius_mm": 2.5, "n_rejected": 3}))
    rows = ["press,indenter,depth_mm,overshoot_mm,force_n,force_std_n,force_w0_n,"
            "force_w0_sem_n"]
    for k, (i, f, sd) in enumerate(zip(tab["indenter"].astype(int), tab["force_w0_n"],
                                       tab["force_w0_sem_n"], strict=True)):
        rows.append(f"{k},{i},{DEPTHS[i] + 0.02:.6f},0.020000,{f * 1.05:.8g},0.0125,"
                    f"{f:.8g},{sd:.8g}")
    (cal / "measurements.csv").write_text("\n".join(rows) + "\n")
    got = design_from_calibration(cal)
    assert got.frame_rate_hz == 30.0 and got.stage_speed_mm_s == pytest.approx(0.1)
    assert got.bracket_periods == pytest.approx(2.0, rel=1e-4)
    assert got.unseen_share == pytest.approx(3 / 23, abs=1e-4)


def test_unseen_presses_widen_e_and_nu_as_fewer_presses_do():
    """E's and nu's predicted spread with a quarter of 8 repeats unseen is that of 6
    repeats (the same depths and noise) within 2 %, and wider than all 8 seen; the note
    says on how many presses it counts."""
    d = replace(MARK, repeats=8, frame_rate_hz=30.0)
    lossy = plan_session(replace(d, unseen_share=0.25), effect_sizes=False)
    six = plan_session(replace(d, repeats=6), effect_sizes=False)
    eight = plan_session(d, effect_sizes=False)
    assert lossy.E_sigma_mpa == pytest.approx(six.E_sigma_mpa, rel=0.02)
    assert lossy.nu_sigma == pytest.approx(six.nu_sigma, rel=0.02)
    assert lossy.E_sigma_mpa > 1.05 * eight.E_sigma_mpa
    assert any("75 % of presses" in n for n in lossy.notes)
