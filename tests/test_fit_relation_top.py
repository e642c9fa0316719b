"""E and nu where beta's interval reaches the paper relation's top (nu = 0.5).

Relation (7) reaches nu = 0.5, an incompressible gel, at beta = 1.933; no solid lies past
it. The delta method's interval of nu ran past 0.5 there, and E's, symmetric, over gels
that cannot be. The fit's confidence region of (c, c beta) is projected instead; these
tests check the projection against a brute-force one over the whole region, against the
delta method where the map is nearly linear, and the intervals' coverage on drawn presses.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

import tactilevision.mechanics._fit as fit_module
from tactilevision.mechanics import fit_indentation, kappa
from tactilevision.mechanics._beta import PAPER_BETA_RELATION as REL

H, A = 3.0, 2.5                                     # mm
W = np.repeat(np.linspace(0.10, 0.55, 5), 4)        # mm, 20 presses
NU0, E0 = 0.48, 0.20
C0 = 2 * A * E0 * kappa(NU0, A / H) / (1 - NU0**2)  # eq. (4): c of this gel, N/mm
BETA0 = float(REL.beta(NU0))


def _presses(rng: np.random.Generator, sd_n: float, beta: float = BETA0) -> np.ndarray:
    return C0 * W * (1 + beta * W / H) + rng.normal(0.0, sd_n, W.size)


def _cov(fit) -> np.ndarray:
    sc, ss = fit.c_se_n_per_mm, fit.slope_se_n_per_mm
    off = fit.corr_c_slope * sc * ss
    return np.array([[sc**2, off], [off, ss**2]])


def test_nu_stays_at_most_a_half_and_E_is_the_region_projected():
    rng = np.random.default_rng(3)
    fit = fit_indentation(W, _presses(rng, 0.03), thickness_mm=H, radius_mm=A,
                          beta_table="paper")
    assert fit.beta < REL.beta_max <= fit.beta_ci95[1]        # the case: the top in reach
    assert fit.misfit.factor == 1.0                          # no lack of fit widening it
    assert fit.nu_ci95[1] == pytest.approx(0.5, abs=1e-12)
    assert fit.nu_ci95[0] < fit.nu < 0.5
    assert any("relation's top" in n for n in fit.notes)
    assert fit.nu_bound == f"nu >= {fit.nu_ci95[0]:.4g}"     # reaches the edge: a bound
    # brute force: E of eq. (4) over 20000 points filling the 1-dof ellipse of radius t,
    # nu clamped at the relation's top, kappa read point by point on a coarse nu grid
    tq = stats.t.ppf(0.975, W.size - 2)
    u = rng.normal(size=(2, 20000))
    u *= np.sqrt(rng.random(20000)) / np.linalg.norm(u, axis=0)
    c, s = np.array([fit.c_n_per_mm, fit.slope_n_per_mm])[:, None] + tq * (
        np.linalg.cholesky(_cov(fit)) @ u)
    nu = np.minimum(REL.nu(np.minimum(s / c, REL.beta_max)), 0.5)
    grid = np.linspace(nu.min(), nu.max(), 400)
    E = c * (1 - nu**2) / (2 * A * np.interp(nu, grid, kappa(grid, A / H)))
    assert fit.E_ci95_mpa[0] == pytest.approx(E.min(), rel=2e-3)
    assert fit.E_ci95_mpa[1] == pytest.approx(E.max(), rel=2e-3)
    assert fit.nu_ci95[0] == pytest.approx(nu.min(), abs=2e-4)


def test_the_projection_is_the_delta_method_where_the_map_is_nearly_linear():
    rng = np.random.default_rng(3)
    fit = fit_indentation(W, _presses(rng, 0.002, beta=1.2), thickness_mm=H, radius_mm=A,
                          beta_table="paper")
    assert fit.beta_ci95[1] < REL.beta_max                   # the delta method's own path
    tq = stats.t.ppf(0.975, W.size - 2)
    got = fit_module._over_ellipse(REL, fit.c_n_per_mm, fit.slope_n_per_mm, _cov(fit), tq,
                                   a=A, ah=A / H, kappa_source="hayes",
                                   contact="frictionless")
    (nu_lo, nu_hi), (E_lo, E_hi) = got
    for (lo, hi), (dlo, dhi) in (((nu_lo, nu_hi), fit.nu_ci95), ((E_lo, E_hi), fit.E_ci95_mpa)):
        assert abs(lo - dlo) < 0.02 * (dhi - dlo) and abs(hi - dhi) < 0.02 * (dhi - dlo)


def test_the_intervals_hold_the_gel_as_often_as_they_say_near_the_top():
    rng = np.random.default_rng(5)
    held_E, held_nu, top = 0, 0, 0
    for _ in range(200):
        fit = fit_indentation(W, _presses(rng, 0.03), thickness_mm=H, radius_mm=A,
                              beta_table="paper")
        held_E += fit.E_ci95_mpa[0] <= E0 <= fit.E_ci95_mpa[1]
        held_nu += fit.nu_ci95[0] <= NU0 <= fit.nu_ci95[1]
        top += fit.nu_ci95[1] == 0.5
        assert fit.nu_ci95[1] <= 0.5
    assert top > 100                                 # most draws reach the top
    # 95 % intervals: 190 of 200 expected, binomial sd 3
    assert held_E >= 181 and held_nu >= 181
