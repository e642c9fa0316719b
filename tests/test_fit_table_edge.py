"""E and nu at the edges of the FEM beta table (issue 39: say only what the data supports).

Forces are made from the FEM table itself, P(w) = c w (1 + beta w/h), with two
presses per depth whose P/w lie at +e and -e around the line: the fit of eq. (5)
then gives exactly this c and beta, and e sets the width of beta's interval.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from tactilevision.mechanics import fit_indentation, fit_model, kappa
from tactilevision.mechanics._beta import beta_relation

H, A = 3.0, 2.5  # mm: a/h = 0.833, where the bonded FEM beta peaks near nu = 0.485
DEPTHS = np.array([0.15, 0.30, 0.45, 0.60])  # mm
W = np.repeat(DEPTHS, 2)
SIGN = np.tile([1.0, -1.0], DEPTHS.size)
E0 = 0.20  # MPa


def relation():
    """The FEM relation the fit reads: at these depths and the exact a/h."""
    return beta_relation("fem", a_over_h=A / H, w_over_h=tuple(np.round(DEPTHS / H, 12)))


def intercept(rel, nu):
    """c of eq. (4) for E0 at `nu`, with the FEM kappa line the fit uses, N/mm."""
    return 2 * A * E0 * rel.kappa_line(nu) / (1 - nu**2)


def presses(c, beta, scatter):
    """(w, P): two presses per depth at P/w = c (1 + beta w/h) (1 +- scatter)."""
    return W, W * c * (1 + beta * W / H) * (1 + scatter * SIGN)


def test_beta_below_the_table_within_its_interval_is_read_at_the_bottom():
    rel = relation()
    nu_b = rel.nu_min                  # the nu of the table's smallest beta
    assert rel.beta(nu_b) == pytest.approx(rel.beta_min, rel=1e-12)
    assert (nu_b, round(rel.beta_min, 4)) == (pytest.approx(0.36), 0.6910)
    c, b = intercept(rel, nu_b), rel.beta_min - 0.02
    fit = fit_indentation(*presses(c, b, 0.0025), thickness_mm=H, radius_mm=A)
    assert fit.c_n_per_mm == pytest.approx(c, rel=1e-12)
    assert fit.beta == pytest.approx(b, abs=1e-12)
    b_hi = fit.beta_ci95[1]
    assert fit.beta < rel.beta_min <= b_hi          # the case of the issue
    assert b_hi == pytest.approx(0.7394, abs=1e-4)
    assert not fit.out_of_table and fit.out_of_table_message is None
    assert fit.nu == nu_b
    assert fit.nu_bound == f"nu <= {fit.nu_ci95[1]:.4g}"   # at the table's edge: a bound
    # E of eq. (4) at that nu, with the FEM kappa line at these depths: E0 back
    assert fit.kappa == pytest.approx(rel.kappa_line(nu_b), rel=1e-12)
    assert fit.E_mpa == pytest.approx(c * (1 - nu_b**2) / (2 * A * rel.kappa_line(nu_b)),
                                      rel=1e-12)
    assert fit.E_mpa == pytest.approx(E0, rel=1e-12)
    # nu's interval: every tabulated nu whose beta is at most b_hi. The FEM beta dips
    # from nu = 0.30 (0.7095 <= b_hi) to the bottom at 0.36, then rises to b_hi
    lo, hi = fit.nu_ci95
    assert lo == rel.nu_grid[0] == 0.30
    assert rel.beta(hi) == pytest.approx(b_hi, abs=2e-4) and nu_b < hi < 0.44
    assert rel.beta(hi + 1e-3) > b_hi
    # E's interval: E over that range of nu and c at its own bounds (E falls with nu)
    tq = stats.t.ppf(0.975, W.size - 2)
    c_lo = fit.c_n_per_mm - tq * fit.c_se_n_per_mm
    c_hi = fit.c_n_per_mm + tq * fit.c_se_n_per_mm

    def modulus(cc, nu):
        return cc * (1 - nu**2) / (2 * A * rel.kappa_line(nu))

    assert fit.E_ci95_mpa[0] == pytest.approx(modulus(c_lo, hi), rel=1e-12)
    assert fit.E_ci95_mpa[1] == pytest.approx(modulus(c_hi, lo), rel=1e-12)
    assert fit.E_ci95_mpa[0] < fit.E_mpa < fit.E_ci95_mpa[1]
    assert lo < fit.nu < hi
    assert fit.nu_se == pytest.approx((hi - lo) / (2 * tq))
    note = next(n for n in fit.notes if n.startswith("beta lies below"))
    assert "smallest beta of the table (0.6910, at nu = 0.360)" in note
    assert "upper bound 0.7394" in note and "the table's bottom, 0.360" in note
    assert "[0.3000, " in note
    assert all(math.isfinite(v) for v in (fit.C10_mpa, fit.D1_per_mpa))


def test_wide_interval_below_the_table_spans_the_whole_table():
    # beta's upper bound above the table's peak: every tabulated nu is possible
    rel = relation()
    fit = fit_indentation(*presses(intercept(rel, rel.nu_min), rel.beta_min - 0.02, 0.01),
                          thickness_mm=H, radius_mm=A)
    assert fit.beta_ci95[1] > float(np.max(rel.beta_grid))
    assert fit.nu == rel.nu_min and fit.E_mpa == pytest.approx(E0, rel=1e-12)
    assert fit.nu_ci95 == (0.30, 0.499)


def test_interval_not_reaching_the_bottom_is_not_computed():
    rel = relation()
    fit = fit_indentation(*presses(intercept(rel, rel.nu_min), rel.beta_min - 0.02, 0.0005),
                          thickness_mm=H, radius_mm=A)
    assert fit.beta_ci95[1] < rel.beta_min
    assert fit.out_of_table and "E and nu not computed" in fit.out_of_table_message
    assert "beta in [0.6910, " in fit.out_of_table_message
    assert math.isnan(fit.E_mpa) and math.isnan(fit.nu)
    assert not any(n.startswith("beta lies below") for n in fit.notes)


def test_paper_relation_below_its_range_stays_out_of_table():
    # relation (7) has no grid: its lower end (nu = 0.30) is the end of the Hayes kappa
    # table, and a beta below it gives no E and nu even when its interval reaches it
    w, P = presses(3.0, 0.15, 0.01)
    fit = fit_indentation(w, P, thickness_mm=H, radius_mm=A, beta_table="paper")
    assert fit.beta == pytest.approx(0.15, abs=1e-12)
    assert fit.beta_ci95[1] > 0.1652
    assert fit.out_of_table and "not computed" in fit.out_of_table_message


def test_beta_above_the_table_within_its_interval_is_read_at_the_top():
    # the existing rule at the other edge, for comparison: nu at the peak
    rel = relation()
    last = rel.branch[1]
    nu_p = float(rel.nu_grid[last])
    assert nu_p == 0.485
    c, b = intercept(rel, nu_p), float(rel.beta_grid[last]) + 0.005
    fit = fit_indentation(*presses(c, b, 0.0025), thickness_mm=H, radius_mm=A)
    assert fit.beta_ci95[0] < rel.beta_max <= fit.beta
    assert not fit.out_of_table and fit.nu == nu_p
    assert fit.E_mpa == pytest.approx(E0, rel=1e-12)
    lo, hi = fit.nu_ci95
    assert rel.beta(lo) == pytest.approx(fit.beta_ci95[0], abs=2e-4) and hi == 0.499
    assert fit.nu_bound == f"nu >= {lo:.4g}"       # at the table's edge: a bound
    assert fit.E_ci95_mpa[0] < fit.E_mpa < fit.E_ci95_mpa[1]
    assert any(n.startswith("beta lies above") and "table's top, 0.485" in n
               for n in fit.notes)


def test_model_fit_below_the_table_is_read_at_the_bottom():
    # fit_model reads E and nu through the model fitted to the FEM's P(w) on a grid of nu
    # (0.33 to 0.495): the same rule at that grid's bottom
    rel = relation()
    w, P = presses(intercept(rel, rel.nu_min), 0.671, 0.0025)
    fit, mf = fit_model({"depth_mm": w, "force_n": P}, "paper", thickness_mm=H, radius_mm=A)
    assert mf.params["large_deformation.beta"] == pytest.approx(0.671, abs=1e-6)
    assert not fit.out_of_table and fit.out_of_table_message is None
    assert fit.nu == pytest.approx(0.36)   # the grid's node where the model's beta rises
    assert fit.nu_ci95[0] == pytest.approx(0.33) and fit.nu < fit.nu_ci95[1] < 0.42
    assert fit.E_mpa == pytest.approx(E0, rel=0.02)
    assert fit.E_ci95_mpa[0] < fit.E_mpa < fit.E_ci95_mpa[1]
    notes = [n for n in fit.notes if "lies below" in n]
    assert len(notes) == 1 and "of the model large_deformation" in notes[0]
    assert "nu is put at the bottom, 0.360" in notes[0]
    # an interval that does not reach the model's table: not computed
    fit, _ = fit_model({"depth_mm": w, "force_n": presses(intercept(rel, rel.nu_min), 0.671,
                                                          0.0002)[1]},
                       "paper", thickness_mm=H, radius_mm=A)
    assert fit.out_of_table and "not computed" in fit.out_of_table_message
    assert math.isnan(fit.E_mpa) and math.isnan(fit.nu)



def test_beta_above_the_papers_relation_within_its_interval_is_read_at_nu_half():
    """The paper's relation (7) ends at nu = 0.5 (beta 1.9334): a beta just above it whose
    interval reaches back below is an incompressible gel within the scatter; E and nu are
    reported there (the Taxim spatial session of issue 39 fitted beta 1.996 [1.73, 2.26]
    and got no E). E at nu = 0.5 is eq. (4) with Hayes' kappa at 0.5."""
    rel = beta_relation("paper")
    assert rel.nu_max == 0.5 and round(rel.beta_max, 4) == 1.9334
    ah = A / H
    k_half = float(kappa(0.5, ah, source="hayes", contact="frictionless"))
    c = 2 * A * E0 * k_half / (1 - 0.25)                    # eq. (4) at nu = 0.5: E0 back
    b = rel.beta_max + 0.03
    fit = fit_indentation(*presses(c, b, 0.01), thickness_mm=H, radius_mm=A,
                          beta_table="paper")
    assert fit.beta == pytest.approx(b, abs=1e-12)
    lo = fit.beta_ci95[0]
    assert lo < rel.beta_max < fit.beta                     # the case of the issue
    assert not fit.out_of_table
    assert fit.nu == 0.5 and fit.E_mpa == pytest.approx(E0, rel=1e-12)
    assert fit.nu_ci95 == (pytest.approx(float(rel.nu(lo)), abs=1e-12), 0.5)
    assert fit.E_ci95_mpa[0] < E0 < fit.E_ci95_mpa[1]
    assert any("relation's top, 0.50" in n for n in fit.notes)
    # an interval that does not reach back: still no E and nu
    far = fit_indentation(*presses(c, rel.beta_max + 0.5, 0.002), thickness_mm=H,
                          radius_mm=A, beta_table="paper")
    assert far.beta_ci95[0] > rel.beta_max
    assert far.out_of_table and math.isnan(far.E_mpa) and math.isnan(far.nu)
