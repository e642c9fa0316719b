"""fit_indentation against the paper's numbers, hand computations and known truth."""

from __future__ import annotations

import dataclasses
import functools
import json
import math
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tactilevision import InputError, ShapeError
from tactilevision.mechanics import beta_from_nu, kappa
from tactilevision.mechanics import fit_indentation as _fit_indentation

# The paper's method (relation 7, Hayes kappa) on the paper's numbers and on
# presses made with it; the FEM tables (the default) are tested in
# tests/test_fit_depth_uncertainty.py and tests/test_validate.py.
fit_indentation = functools.partial(_fit_indentation, beta_table="paper")

H, A = 3.0, 2.5  # the paper's gel thickness and indenter radius, mm
DEPTHS = np.array([0.15, 0.30, 0.40, 0.50, 0.60])  # gauge depths, mm
CONTRACT_KEYS = ["E_mpa", "nu", "c_n_per_mm", "beta", "E_ci95_mpa", "nu_ci95", "rmse_n",
                 "n_presses", "effects", "effect_params"]


def paper_line(w):
    """Forces on the paper's fitted line (6): P/w = 5.2662 w/h + 3.4943 N/mm."""
    return w * (5.2662 * w / H + 3.4943)


def presses(E, nu, *, h=H, a=A, depths=DEPTHS, reps=1):
    """Noise-free forces of eq. (3) for a known E, nu (kappa at the exact a/h)."""
    c = 2 * a * E * kappa(nu, a / h) / (1 - nu**2)  # eq. (4)
    w = np.repeat(depths, reps)
    return w, w * c * (1 + beta_from_nu(nu) * w / h)  # eq. (3)


# ------------------------------------------------------- the paper, a/h = 0.8


def test_paper_line_at_a_over_h_08_reproduces_paper():
    w = DEPTHS
    fit = fit_indentation(w, paper_line(w), thickness_mm=H, radius_mm=A, a_over_h=0.8)
    assert fit.c_n_per_mm == pytest.approx(3.4943, abs=1e-9)
    assert fit.slope_n_per_mm == pytest.approx(5.2662, abs=1e-9)
    assert fit.beta == pytest.approx(1.5071, abs=5e-5)
    assert fit.nu == pytest.approx(0.4797, abs=1e-3)
    assert fit.E_mpa == pytest.approx(0.1981, rel=0.01)
    assert fit.C10_mpa == pytest.approx(0.0335, rel=0.01)
    assert fit.D1_per_mpa == pytest.approx(1.2297, rel=0.01)
    assert fit.r_squared == pytest.approx(1.0, abs=1e-12)
    assert fit.rmse_n == pytest.approx(0.0, abs=1e-12)
    assert fit.a_over_h == 0.8 and fit.a_over_h_exact == pytest.approx(A / H)
    assert fit.kappa == kappa(fit.nu, 0.8)
    assert not fit.out_of_table and fit.out_of_table_message is None
    assert fit.effects == ("large_deformation",)
    assert fit.effect_params == {"beta": fit.beta}


def test_paper_line_at_exact_a_over_h(hand_kappa):
    # Default: kappa at the exact a/h = 2.5 / 3.0 = 0.8333. Hand computation:
    # nu from (7), kappa by the documented PCHIP rule (conftest, no scipy), E from (4).
    w = DEPTHS
    fit = fit_indentation(w, paper_line(w), thickness_mm=H, radius_mm=A)
    nu = 0.0813 * math.log(5.2662 / 3.4943) + 0.4464
    k = hand_kappa(nu, A / H)
    E = 3.4943 * (1 - nu**2) / (2 * A * k)
    assert fit.a_over_h == pytest.approx(0.8333333333, abs=1e-9)
    assert fit.nu == pytest.approx(nu, abs=1e-12)  # nu does not depend on a/h
    assert fit.kappa == pytest.approx(k, rel=1e-12)
    assert fit.E_mpa == pytest.approx(E, rel=1e-9)
    # E scales as 1/kappa: the rounding of the paper moves E by kappa(.8)/kappa(.8333) - 1
    at_08 = fit_indentation(w, paper_line(w), thickness_mm=H, radius_mm=A, a_over_h=0.8)
    assert fit.E_mpa / at_08.E_mpa == pytest.approx(hand_kappa(nu, 0.8) / k, rel=1e-9)
    # documented in the report: exact a/h gives E about 3.4% below the paper's 0.1981
    assert fit.E_mpa / 0.1981 - 1 == pytest.approx(-0.034, abs=0.002)
    assert any("exact a/h" in n and "0.8333" in n for n in fit.notes)
    assert any("built for a/h = 0.8" in n for n in fit.notes)


# ----------------------------------------------------------- known truth


def test_known_truth_at_a_table_node():
    # a/h = 0.8 and nu = 0.45 are table nodes: kappa = 2.532 (Hayes), beta from (7) by hand
    h, a, E, nu = 3.0, 2.4, 0.31, 0.45
    c = 2 * a * E * 2.532 / (1 - nu**2)
    beta = math.exp((nu - 0.4464) / 0.0813)
    w = np.repeat(DEPTHS, 3)
    fit = fit_indentation(w, w * c * (1 + beta * w / h), thickness_mm=h, radius_mm=a)
    assert fit.a_over_h == pytest.approx(0.8)
    assert fit.nu == pytest.approx(nu, abs=1e-10)
    assert fit.E_mpa == pytest.approx(E, rel=1e-9)
    assert fit.c_n_per_mm == pytest.approx(c, rel=1e-12)


@settings(max_examples=60, deadline=None)
@given(E=st.floats(0.05, 3.0), nu=st.floats(0.301, 0.499), h=st.floats(1.0, 6.0),
       ah=st.floats(0.21, 1.99))  # inside the tables: a round-off at an edge is out of table
def test_known_truth_round_trip(E, nu, h, ah):
    w, P = presses(E, nu, h=h, a=ah * h, depths=h * np.array([0.05, 0.1, 0.15, 0.2]))
    fit = fit_indentation(w, P, thickness_mm=h, radius_mm=ah * h)
    assert fit.nu == pytest.approx(nu, abs=1e-9)
    assert fit.E_mpa == pytest.approx(E, rel=1e-8)


def test_interval_coverage_on_noisy_replicates():
    # 400 seeded replicates of a 50-press session with constant force noise
    # (0.02 N, the F/T side) and 0.3% press-to-press scatter; the intervals are
    # nominally 95%: accept 92-98% (binomial sd about 1.1%).
    E0, nu0 = 0.20, 0.47
    w, P0 = presses(E0, nu0, reps=10)
    rng = np.random.default_rng(12345)
    hit_E = hit_nu = 0
    n_rep = 400
    for _ in range(n_rep):
        P = P0 * (1 + 0.003 * rng.standard_normal(w.size)) + 0.02 * rng.standard_normal(w.size)
        fit = fit_indentation(w, P, thickness_mm=H, radius_mm=A)
        hit_E += fit.E_ci95_mpa[0] <= E0 <= fit.E_ci95_mpa[1]
        hit_nu += fit.nu_ci95[0] <= nu0 <= fit.nu_ci95[1]
    assert 0.92 <= hit_E / n_rep <= 0.98
    assert 0.92 <= hit_nu / n_rep <= 0.98


def test_interval_contains_estimate_and_narrows_with_presses():
    rng = np.random.default_rng(7)
    w, P0 = presses(0.2, 0.47, reps=40)
    P = P0 + 0.02 * rng.standard_normal(w.size)
    few = fit_indentation(w[::8], P[::8], thickness_mm=H, radius_mm=A)
    many = fit_indentation(w, P, thickness_mm=H, radius_mm=A)
    for f in (few, many):
        assert f.E_ci95_mpa[0] < f.E_mpa < f.E_ci95_mpa[1]
        assert f.nu_ci95[0] < f.nu < f.nu_ci95[1]
        assert f.nu_se > 0 and f.E_se_mpa > 0 and -1 <= f.corr_c_slope <= 1
    assert np.ptp(many.nu_ci95) < np.ptp(few.nu_ci95)
    assert any("HC3" in n and "delta method" in n for n in many.notes)


# ------------------------------------------------------ flags and warnings


@pytest.mark.parametrize("slope, intercept", [(7.5, 3.0), (0.3, 3.0), (-1.0, 3.0),
                                              (5.0, -0.5)])
def test_out_of_table_is_flagged_not_clamped(slope, intercept):
    w = DEPTHS
    fit = fit_indentation(w, w * (slope * w / H + intercept), thickness_mm=H, radius_mm=A)
    assert fit.out_of_table
    assert "[0.1652, 1.9334)" in fit.out_of_table_message
    assert "nu in [0.30, 0.50)" in fit.out_of_table_message
    assert math.isnan(fit.E_mpa) and math.isnan(fit.nu)
    assert fit.beta == pytest.approx(slope / intercept)  # the regression is still reported
    d = fit.to_json_dict()
    assert d["E_mpa"] is None and d["nu"] is None and d["E_ci95_mpa"] == [None, None]
    json.dumps(d, allow_nan=False)


def test_deep_press_warns_and_notes():
    w = np.array([0.15, 0.3, 0.45, 0.75])
    with pytest.warns(UserWarning, match=r"w/h = 0.250 > 0.2"):
        fit = fit_indentation(w, paper_line(w), thickness_mm=H, radius_mm=A)
    assert fit.max_w_over_h == pytest.approx(0.25)
    assert any("w/h = 0.250" in n for n in fit.notes)


def test_paper_depths_do_not_warn():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fit_indentation(DEPTHS, paper_line(DEPTHS), thickness_mm=H, radius_mm=A)


# ---------------------------------------------------------------- output


def test_json_dict_has_contract_keys_first():
    fit = fit_indentation(DEPTHS, paper_line(DEPTHS), thickness_mm=H, radius_mm=A)
    d = fit.to_json_dict()
    assert list(d)[:10] == CONTRACT_KEYS
    assert isinstance(d["E_ci95_mpa"], list) and len(d["E_ci95_mpa"]) == 2
    assert isinstance(d["nu_ci95"], list) and len(d["nu_ci95"]) == 2
    assert d["effects"] == ["large_deformation"]
    assert d["effect_params"] == {"beta": fit.beta}
    assert d["n_presses"] == 5
    for extra in ("C10_mpa", "D1_per_mpa", "a_over_h", "beta_table", "notes", "r_squared"):
        assert extra in d
    assert json.loads(json.dumps(d, allow_nan=False))["nu"] == fit.nu


def test_result_is_frozen():
    fit = fit_indentation(DEPTHS, paper_line(DEPTHS), thickness_mm=H, radius_mm=A)
    with pytest.raises(dataclasses.FrozenInstanceError):
        fit.E_mpa = 1.0


def test_default_is_the_fem_table():
    fit = _fit_indentation(DEPTHS, paper_line(DEPTHS), thickness_mm=H, radius_mm=A)
    assert (fit.beta_table, fit.kappa_source, fit.contact) == ("fem", "fem", "bonded")
    paper = fit_indentation(DEPTHS, paper_line(DEPTHS), thickness_mm=H, radius_mm=A)
    assert (paper.beta_table, paper.kappa_source, paper.contact) == ("paper", "hayes",
                                                                     "frictionless")


# ------------------------------------------------------------- bad input


def test_rejects_bad_input():
    w, P = DEPTHS, paper_line(DEPTHS)
    with pytest.raises(InputError, match="two depths"):
        fit_indentation(np.full(5, 0.3), P, thickness_mm=H, radius_mm=A)
    with pytest.raises(InputError, match=r"depth_mm\[1\] = -0.3"):
        fit_indentation(w * [1, -1, 1, 1, 1], P, thickness_mm=H, radius_mm=A)
    with pytest.raises(InputError, match=r"depth_mm\[0\] = 0"):
        fit_indentation(w * [0, 1, 1, 1, 1], P, thickness_mm=H, radius_mm=A)
    with pytest.raises(ShapeError, match="force_n must have shape"):
        fit_indentation(w, P[:4], thickness_mm=H, radius_mm=A)
    with pytest.raises(ShapeError, match="depth_mm must have shape"):
        fit_indentation(w[None, :], P, thickness_mm=H, radius_mm=A)
    with pytest.raises(ShapeError, match="force_n must be finite"):
        fit_indentation(w, P * [1, np.nan, 1, 1, 1], thickness_mm=H, radius_mm=A)
    with pytest.raises(InputError, match="thickness_mm must be a positive"):
        fit_indentation(w, P, thickness_mm=0.0, radius_mm=A)
    with pytest.raises(InputError, match="radius_mm must be a positive"):
        fit_indentation(w, P, thickness_mm=H, radius_mm=math.nan)
    with pytest.raises(InputError, match=r"a_over_h = 2.5 .*\[0.2, 2\]"):
        fit_indentation(w, P, thickness_mm=H, radius_mm=A, a_over_h=2.5)
    with pytest.raises(InputError, match=r"radius_mm / thickness_mm = 5 .*\[0.2, 2\]"):
        fit_indentation(w, P, thickness_mm=1.0, radius_mm=5.0)
    with pytest.raises(ValueError, match="table must be"):
        fit_indentation(w, P, thickness_mm=H, radius_mm=A, beta_table="zhang")
    with pytest.raises(ValueError, match="confidence"):
        fit_indentation(w, P, thickness_mm=H, radius_mm=A, confidence=95)


def test_two_presses_fit_without_intervals():
    w = np.array([0.15, 0.6])
    fit = fit_indentation(w, paper_line(w), thickness_mm=H, radius_mm=A, a_over_h=0.8)
    assert fit.nu == pytest.approx(0.4797, abs=1e-3)
    assert all(math.isnan(v) for v in fit.E_ci95_mpa)
    assert any("degrees of freedom" in n for n in fit.notes)

