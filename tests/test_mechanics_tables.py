"""kappa (Hayes 1972), the paper's beta relation (7), Neo-Hookean constants, effect names."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.mechanics import (
    EFFECT_NAMES,
    HAYES_1972,
    PAPER_BETA_RELATION,
    beta_from_nu,
    check_fit_effects,
    kappa,
    neo_hookean_constants,
    nu_from_beta,
)

# ---------------------------------------------------------------- kappa table


def test_hayes_table_is_method_md(hayes_table):
    ah, nu, rows = hayes_table
    assert HAYES_1972.a_over_h.tolist() == list(ah)
    assert HAYES_1972.nu.tolist() == list(nu)
    assert HAYES_1972.values.tolist() == [list(r) for r in rows]


def test_hayes_table_carries_source():
    src = HAYES_1972.source
    for word in ("Hayes", "1972", "J. Biomech", "541-551"):
        assert word in src
    assert HAYES_1972.doi == "10.1016/0021-9290(72)90010-3"
    with pytest.raises(ValueError):
        HAYES_1972.values[0, 0] = 1.0  # read-only


def test_kappa_exact_at_every_node(hayes_table):
    ah, nu, rows = hayes_table
    for i, r in enumerate(ah):
        for j, n in enumerate(nu):
            assert kappa(n, r) == rows[i][j]
    grid = kappa(np.array(nu)[None, :], np.array(ah)[:, None])  # broadcast 7x5
    assert grid.shape == (7, 5)
    assert np.array_equal(grid, np.array(rows))


def test_kappa_follows_documented_rule(hand_kappa):
    # off-node points in every kind of cell, incl. the paper's (0.4797, 0.8)
    # and the exact a/h of a = 2.5, h = 3.0
    for nu, ah in [(0.4797, 0.8), (0.4797, 2.5 / 3), (0.32, 0.25), (0.49, 1.9),
                   (0.43, 1.2), (0.301, 0.55), (0.5, 1.7), (0.37, 2.0)]:
        assert kappa(nu, ah) == pytest.approx(hand_kappa(nu, ah), rel=1e-12)


def test_kappa_below_bilinear_between_nu_nodes():
    # rows are convex in nu: the chord (bilinear) lies above the shape-preserving cubic
    k = kappa(0.4797, 0.8)
    chord = 2.532 + (0.4797 - 0.45) / 0.05 * (2.855 - 2.532)
    assert 2.532 < k < chord


def test_kappa_monotonic_in_nu_and_a_over_h():
    nu = np.linspace(0.30, 0.50, 81)
    ah = np.linspace(0.2, 2.0, 91)
    k = kappa(nu[None, :], ah[:, None])  # (91, 81)
    assert np.all(np.diff(k, axis=0) > 0)  # along a/h
    assert np.all(np.diff(k, axis=1) > 0)  # along nu


def test_kappa_near_prototype_fem():
    # method.md: a = 2.5, h = 3 (pad radius 15 mm), prototype FEM kappa; the
    # Hayes layer is infinite, so agreement within 0.5% is what we can expect
    for nu, fem in [(0.30, 2.185), (0.45, 2.624), (0.49, 2.888), (0.50, 2.976)]:
        assert kappa(nu, 2.5 / 3.0) == pytest.approx(fem, rel=5e-3)


def test_kappa_scalar_in_scalar_out():
    assert isinstance(kappa(0.45, 0.8), float)
    assert kappa(np.array([0.3, 0.5]), 0.2).shape == (2,)


@pytest.mark.parametrize("nu, ah, name", [
    (0.29, 0.8, "nu"), (0.51, 0.8, "nu"), (math.nan, 0.8, "nu"),
    (0.4, 0.19, "a_over_h"), (0.4, 2.01, "a_over_h"), (0.4, math.inf, "a_over_h"),
])
def test_kappa_out_of_range_names_argument_and_range(nu, ah, name):
    with pytest.raises(ValueError, match=name) as info:
        kappa(nu, ah)
    rng = "[0.3, 0.5]" if name == "nu" else "[0.2, 2]"
    assert rng in str(info.value)


def test_kappa_unknown_source():
    with pytest.raises(ValueError, match="source"):
        kappa(0.45, 0.8, source="abaqus")


# ---------------------------------------------------------- beta relation (7)


def test_paper_nu_from_beta():
    # eq. (6): beta = 5.2662 / 3.4943 = 1.5071 -> (7) nu = 0.4797
    assert 5.2662 / 3.4943 == pytest.approx(1.5071, abs=5e-5)
    assert nu_from_beta(5.2662 / 3.4943) == pytest.approx(0.4797, abs=5e-5)
    assert nu_from_beta(1.0) == pytest.approx(0.4464, abs=1e-12)


def test_beta_from_nu_matches_method_md():
    # method.md lists what (7) gives at these nu
    for nu, beta in [(0.30, 0.165), (0.40, 0.565), (0.45, 1.045), (0.48, 1.512),
                     (0.49, 1.710)]:
        assert beta_from_nu(nu) == pytest.approx(beta, abs=6e-4)


def test_beta_round_trip():
    nu = np.linspace(0.30, 0.4999, 50)
    assert np.allclose(nu_from_beta(beta_from_nu(nu)), nu, rtol=0, atol=1e-12)


def test_beta_relation_range():
    rel = PAPER_BETA_RELATION
    assert (rel.nu_min, rel.nu_max, rel.a_over_h) == (0.30, 0.50, 0.8)
    assert rel.beta_min == pytest.approx(math.exp((0.30 - 0.4464) / 0.0813), rel=1e-12)
    assert rel.beta_max == pytest.approx(math.exp((0.50 - 0.4464) / 0.0813), rel=1e-12)
    assert "eq. (7)" in rel.source and "Zhang" in rel.source


@pytest.mark.parametrize("beta", [0.16, 1.94, 1.9334125319866864 * 1.0000001, 0.0, -1.0,
                                  math.nan])
def test_beta_out_of_range_flagged_not_clamped(beta):
    with pytest.raises(InputError, match=r"beta = .*outside.*nu in \[0.30, 0.50\)"):
        nu_from_beta(beta)


@pytest.mark.parametrize("nu", [0.2999, 0.5, 0.6])
def test_nu_out_of_range_raises(nu):
    with pytest.raises(InputError, match="nu = "):
        beta_from_nu(nu)


def test_beta_fem_table_needs_a_over_h():
    # the FEM beta depends on a/h (tests/test_fem_beta_table.py checks its values)
    with pytest.raises(ValueError, match="needs a_over_h"):
        nu_from_beta(0.8, table="fem")
    with pytest.raises(ValueError, match="needs a_over_h"):
        beta_from_nu(0.45, table="fem")
    assert beta_from_nu(0.45, table="fem", a_over_h=1.5) > 0
    with pytest.raises(ValueError, match="table"):
        nu_from_beta(1.5, table="zhang")


# ------------------------------------------------------------- Neo-Hookean


def test_neo_hookean_paper_values():
    # section V.A: E = 0.1981 MPa, nu = 0.4797 -> C10 = 0.0335, D1 = 1.2297
    C10, D1 = neo_hookean_constants(0.1981, 0.4797)
    assert round(C10, 4) == 0.0335
    assert round(D1, 4) == 1.2297


def test_neo_hookean_small_strain_moduli():
    E, nu = 0.3, 0.45
    C10, D1 = neo_hookean_constants(E, nu)
    assert 2 * C10 == pytest.approx(E / (2 * (1 + nu)))  # mu0 = 2 C10
    assert 2 / D1 == pytest.approx(E / (3 * (1 - 2 * nu)))  # K0 = 2 / D1
    assert neo_hookean_constants(E, 0.5)[1] == 0.0


@pytest.mark.parametrize("E, nu", [(0.0, 0.4), (-1, 0.4), (math.inf, 0.4), (0.2, 0.51),
                                   (0.2, -1.0)])
def test_neo_hookean_bad_input(E, nu):
    with pytest.raises(ValueError):
        neo_hookean_constants(E, nu)


# ------------------------------------------------------------- effect names


def test_effect_catalogue_names():
    assert EFFECT_NAMES == (
        "large_deformation", "depth_offset", "force_offset", "force_drift",
        "viscoelastic_relaxation", "incomplete_recovery", "aging",
        "spatial_nonuniformity", "force_crosstalk", "stiffness_trend:<column>",
        "stiffness_step:<column>", "force_trend:<column>",
    )
    assert check_fit_effects([]) == ("large_deformation",)
    assert check_fit_effects(["large_deformation"]) == ("large_deformation",)
    assert check_fit_effects(["aging", "large_deformation", "aging"]) == (
        "large_deformation", "aging")
    assert check_fit_effects(["stiffness_trend:day"]) == (
        "large_deformation", "stiffness_trend:day")
    with pytest.raises(InputError, match="needs a column"):
        check_fit_effects(["stiffness_trend:"])
    with pytest.raises(InputError, match=r"unknown effect 'stiffness'.*valid names"):
        check_fit_effects(["stiffness"])


@pytest.mark.slow
def test_kappa_n_reads_only_the_nodes_that_decide_it():
    """kappa_n interpolates along w/h, then nu, then a/h (PCHIP) on the few nodes that
    decide each value (issue 86: the suite's time; a ramp's 600 depths 12x faster): the
    same numbers, to the last bit, as the three PCHIPs through the whole table, at random
    points, at the table's nodes and at its ends, for one depth, a ramp's depths and a
    set of (nu, depth) pairs."""
    from scipy.interpolate import PchipInterpolator

    from tactilevision.mechanics import kappa_n
    from tactilevision.mechanics._fem_tables import _kappa_n_nodes

    def whole(nu: float, ah: float, wh: np.ndarray) -> np.ndarray:
        data, wt, kn = _kappa_n_nodes(np.asarray(nu), np.asarray(ah), wh, "bonded")
        k_w = PchipInterpolator(wt, kn, axis=2)(wh)                          # (A, N, M)
        k_nu = PchipInterpolator(data["nu"], k_w, axis=1)(nu)                # (A, M)
        return PchipInterpolator(data["a_over_h"], k_nu, axis=0)(ah)         # (M,)

    data, wt, _ = _kappa_n_nodes(np.asarray(0.4), np.asarray(1.0), np.asarray(0.0), "bonded")
    nus, ahs = data["nu"], data["a_over_h"]
    rng = np.random.default_rng(86)
    nu_at = np.r_[nus, (nus[:-1] + nus[1:]) / 2, rng.uniform(nus[0], nus[-1], 20)]
    ah_at = np.r_[ahs, (ahs[:-1] + ahs[1:]) / 2, rng.uniform(ahs[0], ahs[-1], 20)]
    for _ in range(300):
        nu, ah = float(rng.choice(nu_at)), float(rng.choice(ah_at))
        wh = np.r_[0.0, wt[1:3], rng.uniform(0.0, wt[-1], 5)]
        assert np.array_equal(kappa_n(nu, ah, wh), whole(nu, ah, wh)), (nu, ah)
        assert kappa_n(nu, ah, wh[4]) == whole(nu, ah, wh[4:5])[0], (nu, ah)
        pair = rng.choice(nu_at, 2)
        got = kappa_n(pair, ah, wh[:2])
        assert got[0] == whole(pair[0], ah, wh[:1])[0] and got[1] == whole(pair[1], ah, wh[1:2])[0]
