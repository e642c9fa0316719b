"""The crossing forces' statement checked against their scatter: a change found within
indenters is named only where it also explains how much the crossing forces scatter.
Brackets drawn here from a known model (honest ones, ones narrower than the truth, and ones
read a frame late on some presses with nothing changing); none of the truth is read back
from the code under test."""

from __future__ import annotations

import json

import numpy as np
import pytest
from test_crossings import WIDTH, _crossings

from tactilevision.contact import crossing_consistency
from tactilevision.diagnosis import crossing_tests
from tactilevision.diagnosis._brackets import residual_scatter, worst_residual
from tactilevision.diagnosis._crossings import _scan, _step_places

IND = np.repeat(np.arange(5), 6)
STEP = (np.tile(np.arange(6), 5) >= 3).astype(np.float64)


def _midpoints(rng: np.random.Generator, stated: float, true: float, change: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
    """Relative crossing forces of 5 indenters x 6 presses changed by `change`, each
    crossing uniform in a bracket `true` wide (relative) about it, stated `stated` wide:
    (r, w)."""
    r = change + (rng.random(IND.size) - 0.5) * true
    return r, np.full(IND.size, 12.0 / stated ** 2)


def _scatter_left(seed: int, stated: float, true: float, n: int) -> list[np.ndarray]:
    """:func:`residual_scatter` about the true 10 % step on `n` tables of
    :func:`_midpoints`: (chi2, dof, p) as arrays."""
    rng = np.random.default_rng(seed)
    got = []
    for _ in range(n):
        r, w = _midpoints(rng, stated, true, 0.1 * STEP)
        got.append(residual_scatter(r, IND, w, STEP, 999, rng))
    return [np.array(v) for v in zip(*got, strict=True)]


def test_the_scatter_left_about_a_change_is_calibrated_under_an_honest_statement():
    """Brackets as stated, a 10 % step fitted at its true place: the scatter left is on
    average its dof (24 of 30 presses less 5 means and the step; within 5 %: 0.99 of it
    here), and p under 0.05 in about 5 % of 300 tables (2 to 9 %; 5.0 % here)."""
    chi2, dof, p = _scatter_left(11, 0.15, 0.15, 300)
    assert set(dof) == {24}
    assert abs(chi2.mean() / 24 - 1.0) < 0.05, chi2.mean()
    assert 0.02 <= np.mean(p < 0.05) <= 0.09, np.mean(p < 0.05)


def test_brackets_narrower_than_the_scatter_are_caught():
    """The crossings scatter over brackets 1.6 times what is stated: the scatter left about
    the true step has p under 0.05 in at least 80 % of 100 tables (all of these), and
    sqrt(chi2 / dof) reads the factor (its mean within 10 % of 1.6: 1.60 here)."""
    chi2, dof, p = _scatter_left(12, 0.10, 0.16, 100)
    assert np.mean(p < 0.05) >= 0.8, np.mean(p < 0.05)
    assert abs(np.mean(np.sqrt(chi2 / dof)) / 1.6 - 1.0) < 0.1


def _late(seed: int, scale, share: float = 0.3) -> dict[str, np.ndarray]:
    """:func:`test_crossings._crossings`, with `share` of the presses read a frame late:
    their bracket a full width higher than the force at the crossing (the mark's onset
    seen a frame after the one the statement assumes)."""
    c = _crossings(1000 + seed, scale)
    late = np.random.default_rng(5000 + seed).random(20) < share
    up = np.where(late, 1.0 + WIDTH, 1.0)
    return {**c, "force_w0_n": c["force_w0_n"] * up, "force_w0_sem_n": c["force_w0_sem_n"] * up}


@pytest.fixture(scope="module")
def late_null():
    """8 tables with nothing changing and 30 % of the presses read a frame late: the scan
    at the stated sds and the scan that checks the statement."""
    tables = [_late(s, lambda p, x: np.ones(20)) for s in range(8)]
    return [(_scan(c), crossing_tests(c)) for c in tables]


@pytest.mark.slow
def test_late_onsets_are_not_named_as_a_change_of_the_gel(late_null):
    """At the stated sds a change is named on at least 7 of the 8 tables (every one of
    these); checked against the scatter, on at most 3 (2 of these; 8 of 30 over seeds 0 to
    29). Where a change was withheld the statement was scaled (> 1.2) and the found change
    of the stated sds is kept as ``stated_found``."""
    assert sum(old.found is not None for old, _ in late_null) >= 7
    assert sum(new.found is not None for _, new in late_null) <= 3
    for old, new in late_null:
        if old.found is not None and new.found is None and not new.left_out:
            assert new.statement_scale > 1.2
            assert new.stated_found == old.found
            assert new.stated_p_residual < 0.05


@pytest.mark.slow
def test_the_scaled_statement_is_reported(late_null):
    """The sentence calls it a certification problem and says the scale; the JSON carries
    the scale, the withheld change and its p; the chi2 printed is the stated one."""
    old, new = next((o, n) for o, n in late_null if n.statement_scale > 1.0)
    text = new.sentence()
    assert "certification problem" in text and f"{new.statement_scale:.2f}" in text
    d = json.loads(json.dumps(new.to_json_dict()))
    assert d["statement_scale"] == pytest.approx(new.statement_scale)
    assert d["stated_found"] == old.found.effect
    assert d["stated_p_residual"] < 0.05
    assert d["chi2"] == pytest.approx(old.chi2) and d["dof"] == old.dof


def test_an_honest_step_keeps_its_statement():
    """E falls 12 % after the 10th press, the brackets as stated: the change found explains
    the scatter (statement kept, p_residual at least 0.05) in at least 7 of 8 tables, and a
    step along press order or time is named in at least 7 (8 and 8 here)."""
    scans = [crossing_tests(_crossings(s, lambda p, x: np.where(p >= 10, 0.88, 1.0)))
             for s in range(8)]
    assert sum(s.statement_scale == 1.0 and s.p_residual >= 0.05 for s in scans) >= 7
    assert sum(s.found is not None and s.found.kind == "step" for s in scans) >= 7


def test_the_worst_press_is_calibrated_and_a_gross_misread_is_found():
    """Honest brackets, no change: the largest studentized residual's p is under 0.05 in
    about 5 % of 300 tables (2 to 9 %). One press read two bracket widths low (its onset a
    frame early and more): it is the worst press in every one of 50 tables, beyond every one
    of the 999 draws (p = 1 / 1000)."""
    rng = np.random.default_rng(13)
    w = np.full(IND.size, 12.0 / 0.15 ** 2)
    p = [worst_residual(_midpoints(rng, 0.15, 0.15, 0.0 * STEP)[0], IND, w, None, 999, rng)[2]
         for _ in range(300)]
    assert 0.02 <= np.mean(np.array(p) < 0.05) <= 0.09, np.mean(np.array(p) < 0.05)
    for _ in range(50):
        r = _midpoints(rng, 0.15, 0.15, 0.0 * STEP)[0]
        r[7] -= 2 * 0.15
        k, z, p = worst_residual(r, IND, w, None, 999, rng)
        assert k == 7 and z < -3 and p == pytest.approx(1 / 1000)


@pytest.mark.slow
def test_a_gross_misread_is_left_out_not_named():
    """Nothing changes; press 10 (mid-session) is read two bracket widths low. At the stated
    sds a change is named in at least 6 of 8 tables (7 of these); checked, in at most 3 (2),
    and where it is withheld for that press, ``left_out`` names press 10 and the sentence
    says so."""
    tables = []
    for seed in range(8):
        c = _crossings(2000 + seed, lambda p, x: np.ones(20))
        down = np.where(np.arange(20) == 10, 1.0 - 2.0 * WIDTH, 1.0)
        tables.append({**c, "force_w0_n": c["force_w0_n"] * down,
                       "force_w0_sem_n": c["force_w0_sem_n"] * down})
    got = [(_scan(c), crossing_tests(c)) for c in tables]
    assert sum(old.found is not None for old, _ in got) >= 6
    assert sum(new.found is not None for _, new in got) <= 3
    left = [new for _, new in got if new.left_out]
    assert left and all(n.left_out[0][0] == 10 and n.left_out[0][1] < -3 for n in left)
    assert "press 10's lies" in left[0].sentence()
    assert json.loads(json.dumps(left[0].to_json_dict()))["left_out"][0]["press"] == 10


def test_a_step_needs_two_presses_on_each_side():
    """Along press order 0 to 5 in two indenters, a step's places leave at least two presses
    on each side among the indenters pressed on both: not after the first or the last."""
    z = np.arange(6.0)
    places = _step_places(z, np.array([0, 1, 0, 1, 0, 1]))
    assert places == [(1.0, 2.0), (2.0, 3.0), (3.0, 4.0)]
    # one indenter pressed only before the place does not count
    assert _step_places(z, np.array([0, 0, 0, 1, 1, 1])) == []


def test_the_crossings_consistency_reads_the_scatter_against_the_brackets():
    """5 indenters x 6 presses, each crossing uniform in its bracket: stated as they are,
    the Birge ratio's root mean square over 200 tables is 1 (within 5 %), and p (drawn from
    that same uniform noise) under 0.05 in about 5 % (2 to 9 %); stated at 1 / 1.5 of
    their width, the ratio reads 1.5 (within 5 %) and p is under 0.05 in at least 90 %.
    Unread presses and one-press indenters are left out; none left, NaN."""
    rng = np.random.default_rng(14)
    honest, narrow, small_p, caught = [], [], [], []
    for _ in range(200):
        f = 1.0 + (IND + 1) * 0.2 + (rng.random(IND.size) - 0.5) * 0.15
        b, p = crossing_consistency(IND, f, np.full(IND.size, 0.15 / np.sqrt(12.0)))
        honest.append(b)
        small_p.append(p < 0.05)
        b, p = crossing_consistency(IND, f, np.full(IND.size, 0.10 / np.sqrt(12.0)))
        narrow.append(b)
        caught.append(p < 0.05)
    assert abs(np.sqrt(np.mean(np.square(honest))) - 1.0) < 0.05
    assert 0.02 <= np.mean(small_p) <= 0.09, np.mean(small_p)
    assert abs(np.sqrt(np.mean(np.square(narrow))) - 1.5) < 0.075
    assert np.mean(caught) >= 0.9, np.mean(caught)
    assert np.isnan(crossing_consistency(np.arange(4), np.ones(4), np.ones(4))[0])
    one = crossing_consistency(np.array([0, 0, 1]), np.array([1.0, np.nan, 2.0]), np.ones(3))
    assert np.isnan(one[1])
