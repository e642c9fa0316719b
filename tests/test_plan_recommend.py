"""``plan --recommend`` and ``--target-E-pct`` / ``--target-nu``: ranked changes and the
cheapest design meeting the targets, checked against generated sessions of it."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from _data import plan_sessions

from tactilevision import InputError
from tactilevision.cli import main
from tactilevision.planning import (
    Design,
    design_toml,
    error_totals,
    plan_session,
    read_design,
    recommend,
)

PAPER_DEPTHS = (0.15, 0.30, 0.40, 0.50, 0.60)
PAPER = Path(__file__).resolve().parents[1] / "sample_frames" / "plan" / "paper_gauge_block.toml"


def test_error_totals_add_the_systematic_part_in_quadrature():
    d = Design(thickness_mm=3.0, radius_mm=3.0, depths_mm=PAPER_DEPTHS, repeats=4,
               frame_rate_hz=30.0, force_zero_n=0.002)
    p = plan_session(d, effect_sizes=False)
    e, n, e_sys, n_sys = error_totals(p)
    shared = [v for k, v in p.bias.items() if k not in ("model", "noise")]
    assert e_sys == pytest.approx(abs(p.bias["noise"][0]) + max(abs(v[0]) for v in shared))
    assert n_sys == pytest.approx(abs(p.bias["noise"][1]) + max(abs(v[1]) for v in shared))
    assert e == pytest.approx(math.hypot(p.E_sigma_pct, e_sys))
    assert n == pytest.approx(math.hypot(p.nu_sigma, n_sys))


@pytest.mark.slow
def test_the_cheapest_design_meets_the_targets_on_generated_sessions():
    """The recommended design: its plan meets the targets, one repeat fewer does not (above
    the search's floor of two), and
    300 sessions drawn of it (the FEM's forces, the design's noise) have an RMS error of E
    and nu within 20 % of the targets (the plan's sds are within 20 % of the scatter:
    benchmarks/bench_plan.py)."""
    d = Design(thickness_mm=3.0, radius_mm=2.5, depths_mm=PAPER_DEPTHS, repeats=4,
               bevel_angle_deg=5.0, overshoot_um=(30.0, 60.0))
    rec = recommend(d, target_E_pct=4.0, target_nu=0.01)
    c = rec.cheapest
    assert c is not None
    assert c.E_total_pct <= 4.0 and c.nu_total <= 0.01
    if c.design.repeats > 2:                    # the search's floor: two per depth
        fewer = plan_session(replace(c.design, repeats=c.design.repeats - 1),
                             effect_sizes=False)
        e, n, _, _ = error_totals(fewer)
        assert e > 4.0 or n > 0.01
    est = plan_sessions(c.design, 300, seed=5)
    err = np.column_stack([100 * (est[:, 0] / c.design.E_mpa - 1), est[:, 1] - c.design.nu])
    ok = np.isfinite(err).all(axis=1)
    assert ok.mean() > 0.97
    rms = np.sqrt(np.mean(err[ok] ** 2, axis=0))
    assert rms[0] <= 1.2 * 4.0
    assert rms[1] <= 1.2 * 0.01
    # the design as given at 2 x the repeats was offered, and the cheapest is no dearer
    assert any("repeats per depth (was 4)" in x.what for x in rec.changes)
    assert c.n_presses <= len(PAPER_DEPTHS) * 30


def test_a_thin_punch_is_told_to_widen_for_nu():
    """a/h 0.5: nu is not identified; the wider indenter (a/h 1.2) identifies it and ranks
    first."""
    d = Design(thickness_mm=3.0, radius_mm=1.5, depths_mm=PAPER_DEPTHS, repeats=4,
               bevel_angle_deg=5.0, overshoot_um=(30.0, 60.0))
    assert not plan_session(d, effect_sizes=False).nu_identified
    rec = recommend(d)
    assert rec.changes and "a/h 1.2" in rec.changes[0].what
    assert rec.changes[0].prediction.nu_identified


@pytest.mark.slow
def test_a_shared_lag_beyond_the_target_meets_it_at_no_repeats(tmp_path, capsys):
    """A mark at 30 frames/s and 0.1 mm/s: one frame's travel, 3.3 um, may be shared by every
    press and moves E by up to 14 % (a/h 1.2): no number of repeats meets E within 2 %;
    the cheapest design shortens the travel per frame (a faster camera, a slower stage).
    A target nothing meets: --write-recommended exits 2 naming the file."""
    d = Design(thickness_mm=3.0, radius_mm=3.6, depths_mm=PAPER_DEPTHS, repeats=4,
               frame_rate_hz=30.0, stage_speed_mm_s=0.1)
    _, _, e_sys, _ = error_totals(plan_session(replace(d, repeats=30), effect_sizes=False))
    assert e_sys > 10.0
    rec = recommend(d, target_E_pct=2.0, target_nu=0.02)
    c = rec.cheapest
    assert c is not None and c.E_total_pct <= 2.0
    travel = c.design.stage_speed_mm_s / c.design.frame_rate_hz
    assert c.design.bevel_angle_deg > 0 or travel < 0.1 / 30.0 / 2
    path = tmp_path / "d.toml"
    path.write_text(design_toml(d))
    out = tmp_path / "never.toml"
    status = main(["plan", str(path), "--target-E-pct", "0.01", "--write-recommended",
                   str(out)])
    assert status == 2
    assert str(out) in capsys.readouterr().err
    assert not out.exists()


def test_changes_that_open_effects_to_diagnose():
    d = Design(thickness_mm=3.0, radius_mm=3.0, depths_mm=PAPER_DEPTHS, repeats=4,
               bevel_angle_deg=5.0, overshoot_um=(30.0, 60.0), days=1, positions=1)
    rec = recommend(d)
    opens = {e for c in rec.changes for e in c.opens}
    assert {"aging", "spatial_nonuniformity", "viscoelastic_relaxation"} <= opens


@pytest.mark.slow
def test_cli_recommends_and_writes_the_cheapest_design(tmp_path, capsys):
    d = Design(thickness_mm=3.0, radius_mm=2.5, depths_mm=PAPER_DEPTHS, repeats=4,
               bevel_angle_deg=5.0, overshoot_um=(30.0, 60.0))
    path = tmp_path / "d.toml"
    path.write_text(design_toml(d))
    out = tmp_path / "next.toml"
    assert main(["plan", str(path), "--target-E-pct", "4", "--target-nu", "0.01",
                 "--write-recommended", str(out), "--json", str(tmp_path / "p.json")]) == 0
    text = capsys.readouterr().out
    assert "changes, by predicted gain" in text
    assert "cheapest design meeting the targets (E within 4 %, nu within 0.01)" in text
    e, n, _, _ = error_totals(plan_session(read_design(out), effect_sizes=False))
    assert e <= 4.0 and n <= 0.01
    import json

    doc = json.loads((tmp_path / "p.json").read_text())
    assert doc["recommendation"]["cheapest"]["n_presses"] == read_design(out).repeats * len(
        read_design(out).depths_mm)


@pytest.mark.parametrize("argv, key", [(["--target-E-pct", "-1"], "target_E_pct"),
                                       (["--target-nu", "0"], "target_nu"),
                                       (["--write-recommended", "x.toml"], "target")])
def test_bad_targets_exit_2(tmp_path, capsys, monkeypatch, argv, key):
    """Refused before any planning (the plan of a design takes seconds)."""
    d = Design(thickness_mm=3.0, radius_mm=2.5, depths_mm=PAPER_DEPTHS)
    path = tmp_path / "d.toml"
    path.write_text(design_toml(d))

    def planned(*args, **kwargs):
        raise AssertionError("planned before the targets were checked")

    monkeypatch.setattr("tactilevision.cli._plan_run.plan_session", planned)
    assert main(["plan", str(path), *argv]) == 2
    assert key in capsys.readouterr().err
    with pytest.raises(InputError, match="target_nu"):
        recommend(d, target_nu=float("nan"))


@pytest.mark.slow
def test_the_recommendation_is_a_fixed_point():
    """Issue 54, item 10: recommending again on the recommended design, with the same
    targets, finds nothing cheaper. On the paper's block (targets E 3 %, nu 0.01) the
    greedy path alone stopped at 50 presses; run again from there it found a tare and a
    longer F/T window at 40 (before the search was repeated to a fixed point)."""
    first = recommend(read_design(PAPER), target_E_pct=3.0, target_nu=0.01)
    assert first.cheapest is not None and first.cheapest.n_presses <= 40
    again = recommend(first.cheapest.design, target_E_pct=3.0, target_nu=0.01)
    assert again.cheapest is not None
    assert again.cheapest.n_presses == first.cheapest.n_presses
    assert again.cheapest.E_total_pct == pytest.approx(first.cheapest.E_total_pct, abs=1e-9)
    assert again.cheapest.what.endswith("repeats per depth") and ";" not in again.cheapest.what
