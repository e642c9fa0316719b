"""The misfit enters every interval: the Birge ratio, the residuals' serial correlation and
the apparent E's drift (mechanics.assess_misfit), E's interval in log E, nu on a table's
edge a bound, and the refusals' true causes (issue: right or refused on real recordings).

The laws here are closed forms written in this file (no table of ours in the loop)."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest

from tactilevision import InputError, ShapeError
from tactilevision.diagnosis import diagnose
from tactilevision.io import read_measurements
from tactilevision.mechanics import (
    FlatPunch,
    Indenter,
    assess_misfit,
    carry_misfit,
    fit_indentation,
    fit_indenter,
    fit_ramp,
)
from tactilevision.mechanics._misfit import _linregress, log_interval, serial_correlation


@dataclass(frozen=True)
class HertzBall(Indenter):
    """Hertz's half-space, P = 4/3 E/(1 - nu^2) R^1/2 w^3/2, with a nu-dependent layer
    term (1 + k chi), chi = sqrt(R w)/h, k = 0.88 + 1.3 (nu - 0.3): a closed form whose
    curvature tells nu apart (the first-order term of a bonded layer)."""

    radius_mm: float
    shape: ClassVar[str] = "hertz_ball"
    contacts: ClassVar[tuple[str, ...]] = ("frictionless",)
    observes: ClassVar[str] = "nothing (a test law)"

    def reach_mm(self, thickness_mm, law="neo_hookean"):
        return 0.5 * thickness_mm

    def force(self, depth_mm, *, E_mpa, nu, thickness_mm, law="neo_hookean", contact=None):
        w = np.asarray(depth_mm, float)
        chi = np.sqrt(self.radius_mm * w) / thickness_mm
        k = 0.88 + 1.3 * (nu - 0.3)
        return 4 / 3 * E_mpa / (1 - nu**2) * np.sqrt(self.radius_mm) * w**1.5 * (1 + k * chi)

    def contact_radius(self, depth_mm, *, nu, thickness_mm, law="neo_hookean", contact=None):
        return np.sqrt(self.radius_mm * np.asarray(depth_mm, float))


BALL = HertzBall(3.0)


def test_white_residuals_on_a_flat_profile_raise_nothing():
    """Residuals drawn white at their stated sd, apparent E flat: no warning, factor 1,
    the Birge ratio near 1."""
    rng = np.random.default_rng(0)
    w = np.linspace(0.1, 1.0, 40)
    sd = np.full(w.size, 0.01)
    r = sd * rng.standard_normal(w.size)
    m = assess_misfit(w, r, 0.3 + 0.0 * w + 1e-4 * rng.standard_normal(w.size),
                      noise_sd_n=sd, n_params=1)
    assert m.warning is None and m.factor == 1.0
    assert not m.drifts and not m.beyond_noise
    assert m.birge_ratio == pytest.approx(1.0, abs=0.3)


def test_a_law_that_cannot_follow_the_curve_widens_by_its_serial_correlation():
    """Residuals that run in one long wave along depth (a wrong law): lag-1 correlation
    near 1, the factor sqrt((1 + rho) / (1 - rho)) applied and named."""
    w = np.linspace(0.1, 1.0, 100)
    r = 0.01 * np.sin(2 * np.pi * w)
    m = assess_misfit(w, r, np.full(w.size, 0.3))
    rho = m.correlation
    assert rho > 0.9
    # capped at sqrt(n): one independent residual left
    assert m.factor == pytest.approx(min(math.sqrt((1 + rho) / (1 - rho)), 10.0), rel=1e-9)
    assert "lag-1 correlation" in m.warning and f"x{m.factor:.2g}" in m.warning
    # a white sequence of the same size is not widened
    assert serial_correlation(np.random.default_rng(1).standard_normal(100))[2] == 1.0


def test_residuals_beyond_the_stated_noise_give_the_birge_ratio():
    """Residuals five times their stated sd: R_B = 5 (to the draw), chi2's p tiny; applied
    where the fit had not carried it, named only where it had."""
    rng = np.random.default_rng(2)
    w = np.linspace(0.1, 1.0, 30)
    r = rng.standard_normal(w.size)
    r *= 0.05 / np.sqrt(np.sum(r**2) / (w.size - 2))      # exactly 5 x 0.01 in chi2 / dof
    flat = np.full(w.size, 0.3)
    m = assess_misfit(w, r, flat, noise_sd_n=np.full(w.size, 0.01), carried=False)
    assert m.birge_ratio == pytest.approx(5.0, rel=1e-9)
    assert m.beyond_noise and m.chi2_p < 1e-10
    assert m.factor == pytest.approx(5.0 * max(1.0, serial_correlation(r)[2]), rel=1e-9)
    carried = assess_misfit(w, r, flat, noise_sd_n=np.full(w.size, 0.01))
    assert carried.factor == pytest.approx(serial_correlation(r)[2])
    assert "carry that scatter" in carried.warning


def test_feats_like_drift_is_found_on_four_points():
    """Four presses whose apparent E falls 21 % (the FEATS points read by the linear law):
    the drift is found at 5 %, the quarters are the end presses."""
    w = np.array([0.5, 1.0, 1.5, 2.0])
    e = np.array([0.4649, 0.4177, 0.3995, 0.3671])
    m = assess_misfit(w, np.zeros(4), e, n_params=1)
    assert m.drifts and m.drift_p == pytest.approx(0.0149, abs=0.001)
    assert m.drift == pytest.approx(0.3671 / 0.4649 - 1)
    assert (m.E_shallow_mpa, m.E_deep_mpa) == (0.4649, 0.3671)
    assert "-21.0 %" in m.warning


def test_log_interval_never_reaches_zero():
    assert log_interval(1.0, 1.0, 2.0) == pytest.approx((math.exp(-2), math.exp(2)))
    lo, hi = log_interval(5.43, 0.01, 1.96)
    assert (lo, hi) == pytest.approx((5.43 - 0.0196, 5.43 + 0.0196), rel=1e-4)


def test_an_interval_past_a_floats_exponential_is_open_not_an_overflow():
    """A delta-method interval thousands of times E wide (a table nothing pins E on: one
    of plan_effects' drawn tables raised OverflowError inside diagnose) reads in log E as
    [about 0, inf], said not identified, instead of raising."""
    lo, hi = log_interval(0.2, 1e3, 1.96)
    assert hi == math.inf and 0.0 <= lo < 1e-300
    rng = np.random.default_rng(8)
    w = np.repeat(np.linspace(0.1, 0.6, 8), 3)
    P = w * 3.5 * (1 + 1.5 * w / 3.0) + 0.002 * rng.standard_normal(w.size)
    kw = {"thickness_mm": 3.0, "radius_mm": 2.5, "beta_table": "paper", "a_over_h": 0.8}
    fit = fit_indentation(w, P, **kw)
    wide = dataclasses.replace(fit, E_ci95_mpa=(fit.E_mpa - 1e3, fit.E_mpa + 1e3), notes=())
    got = carry_misfit(wide, w, P, P)
    assert got.E_ci95_mpa[1] == math.inf and got.E_ci95_mpa[0] >= 0.0
    assert any(n.startswith("E is not identified by these presses") for n in got.notes)


def test_three_scattered_presses_give_no_modulus():
    """The golf ball's case: three presses whose forces scatter as much as they rise. The
    interval is in log E (never through zero) and E is said not identified."""
    w = np.array([0.2, 0.25, 0.3])
    P = BALL.force(w, E_mpa=0.2, nu=0.5, thickness_mm=5.0) * np.array([0.3, 2.5, 0.6])
    f = fit_indenter(w, P, BALL, thickness_mm=5.0, nu=0.5)
    assert f.E_ci95_mpa[0] > 0
    assert not f.E_identified
    assert any(n.startswith("E not identified") for n in f.notes)
    assert f.to_json_dict()["E_identified"] is False


def test_nu_on_the_table_edge_is_a_bound():
    """Ball presses drawn at nu = 0.5, the top of the range: the profile reaches the edge,
    nu is reported as a bound ('nu >= ...'), never identified; E at the stated nu holds the
    truth."""
    rng = np.random.default_rng(4)
    w = np.repeat(np.linspace(0.1, 1.0, 10), 3)
    P = BALL.force(w, E_mpa=0.3, nu=0.5, thickness_mm=2.0) + 0.002 * rng.standard_normal(w.size)
    f = fit_indenter(w, P, BALL, thickness_mm=2.0, nu_range=(0.3, 0.5))
    assert not f.nu_identified
    assert f.nu_bound is not None and f.nu_bound.startswith("nu >= ")
    assert float(f.nu_bound.split()[-1]) == pytest.approx(f.nu_ci95[0])
    assert f.nu_ci95[1] == pytest.approx(0.5)
    assert f.E_ci95_mpa[0] <= 0.3 <= f.E_ci95_mpa[1]
    assert any("a bound, not a value" in n for n in f.notes)


def _ramp(z0: float = 0.0, noise: float = 2e-4, seed: int = 0):
    """A ramp of a flat punch's near-linear curve: 0.3 mm flat, then P = k (z - z0)."""
    rng = np.random.default_rng(seed)
    z = np.linspace(-0.3, 1.0, 651)
    P = 0.01 + 0.45 * np.clip(z - z0, 0, None) + noise * rng.standard_normal(z.size)
    return z, P


def test_a_ramp_the_ball_law_cannot_follow_is_refused_for_that_reason():
    """A near-linear ramp (a flat punch's) fitted as a ball: refused because the law cannot
    follow the curve, with its residual against the force's noise, never as 'starts in
    contact' (its first 0.3 mm are flat at the baseline)."""
    z, P = _ramp()
    with pytest.raises(InputError) as err:
        fit_ramp(z, P, BALL, thickness_mm=5.0, source="bench/ramp.csv")
    msg = str(err.value)
    assert msg.startswith("bench/ramp.csv: the hertz_ball law cannot follow this curve")
    assert "starts in contact" not in msg
    assert "times the force's noise" in msg


def test_a_ramp_that_starts_in_contact_is_still_said_so():
    """The same ball law on its own curve started past the contact point: 'starts in
    contact'."""
    rng = np.random.default_rng(5)
    z = np.linspace(0.25, 1.0, 300)
    P = 0.03 + BALL.force(z, E_mpa=0.5, nu=0.5, thickness_mm=2.0) + 2e-3 * rng.standard_normal(
        z.size)
    with pytest.raises(InputError, match="starts in contact"):
        fit_ramp(z, P, BALL, thickness_mm=2.0)


@pytest.mark.slow
def test_a_flat_punch_ramp_at_the_default_nu_lies_inside_its_table():
    """The finite-strain flat punch's table stops at nu = 0.499: a ramp fitted with no nu
    stated is read at 0.499 (was refused: 'nu = 0.5 is outside the FEM kappa_n table')."""
    z, P = _ramp(noise=2e-4)
    f = fit_ramp(z, P, FlatPunch(2.0), thickness_mm=5.0, law="neo_hookean")
    assert f.nu == pytest.approx(0.499)
    assert f.E_mpa > 0


def _table(depth: np.ndarray, force: np.ndarray) -> dict[str, np.ndarray]:
    return {"depth_mm": depth, "force_n": force}


def test_diagnose_says_nothing_missing_only_with_a_noise_floor_and_in_the_table():
    """25 distinct depths (no replicate), no stated noise: not 'Nothing is missing' but that
    the table has no noise floor; a table whose beta is out of the FEM's: that the model
    gives no E or nu."""
    rng = np.random.default_rng(3)
    w = np.linspace(0.05, 0.6, 25)
    punch = FlatPunch(2.5)
    nh = punch.force(w, E_mpa=0.2, nu=0.45, thickness_mm=3.0, law="neo_hookean")
    d = diagnose(_table(w, nh * (1 + 0.002 * rng.standard_normal(w.size))), thickness_mm=3.0,
                 radius_mm=2.5, rules_out=False)
    assert "Nothing is missing" not in d.message
    assert "no noise floor" in d.message
    lin = punch.force(w, E_mpa=0.2, nu=0.45, thickness_mm=3.0, law="linear")
    d = diagnose(_table(w, lin * (1 + 0.002 * rng.standard_normal(w.size))), thickness_mm=3.0,
                 radius_mm=2.5, rules_out=False)
    assert "Nothing is missing" not in d.message
    assert "OUT OF TABLE" in d.message


def test_a_ramp_read_as_a_measurements_table_suggests_the_ramp_option(tmp_path):
    path = tmp_path / "ramp.csv"
    path.write_text("displacement_mm,force_n\n" + "".join(f"{0.01 * i},{0.1 * i}\n"
                                                        for i in range(12)))
    with pytest.raises(InputError, match=r"ramp.csv line 1: missing required column\(s\) "
                                         r"depth_mm .*fit --ramp"):
        read_measurements(path, thickness_mm=3.0, radius_mm=2.5)


def test_gauge_block_presses_a_law_cannot_follow_widen_and_warn():
    """Flat-punch presses whose P/w bends in w/h (a square term eq. 5 lacks), 10 repeats at
    each of 8 depths with 2 mN of noise, read through the paper's relation (7): the
    repeats' means lie off the line beyond their scatter; the intervals are wider than the
    same presses on eq. (5)'s own line, and the fit warns; the straight presses raise
    nothing."""
    rng = np.random.default_rng(8)
    w = np.repeat(np.linspace(0.1, 0.6, 8), 10)
    x = w / 3.0
    straight = w * 3.5 * (1 + 1.5 * x)
    bent = w * 3.5 * (1 + 1.5 * x - 8.0 * (x - 0.1) ** 2)
    noise = 0.002 * rng.standard_normal(w.size)
    kw = {"thickness_mm": 3.0, "radius_mm": 2.5, "beta_table": "paper", "a_over_h": 0.8}
    ok = fit_indentation(w, straight + noise, **kw)
    assert ok.misfit.warning is None and not any(n.startswith("warning") for n in ok.notes)
    bad = fit_indentation(w, bent + noise, **kw)
    assert math.isfinite(bad.E_mpa)
    # 10 repeats at each depth sharing its misfit: Kish's design effect, at most sqrt(10)
    assert 1.5 < bad.misfit.factor <= math.sqrt(10) + 1e-9
    assert any(n.startswith("warning: the model does not explain") and "lack of fit" in n
               for n in bad.notes)
    width = np.diff(bad.E_ci95_mpa)[0] / bad.E_mpa
    assert width > 1.5 * np.diff(ok.E_ci95_mpa)[0] / ok.E_mpa
    assert bad.to_json_dict()["misfit"]["factor"] == pytest.approx(bad.misfit.factor)


def test_an_error_each_indenters_presses_share_is_not_a_misfit():
    """Mark-rule presses: 5 indenters x 4 presses, eq. (5)'s own law exact, each indenter's
    depths off by one shared error drawn at its stated sd (its P(w0)'s) and each press's
    depth past w0 read with a slope error (the rule's dP/dw): along depth the residuals
    come in runs of four. Read per press they are a serial correlation; read on the
    indenters' means (`group`), as the stated errors say, no misfit. Across 16 indenters,
    a law that cannot follow the curve is still found on the means."""
    rng = np.random.default_rng(83)
    h, c, beta = 3.0, 3.5, 1.5

    def law(w):
        return c * w * (1 + beta * w / h)

    def presses(w0s, bend=0.0):
        ind = np.repeat(np.arange(w0s.size), 4)
        past = rng.uniform(0.0, 0.05, ind.size)
        shared = 0.015 * rng.standard_normal(w0s.size)[ind]       # mm, per indenter
        w_true = w0s[ind] + past
        P = law(w_true) * (1 - bend * (w_true / h) ** 2) \
            + 0.001 * rng.standard_normal(ind.size)
        w = w_true + shared + 0.1 * past * rng.choice([-1, 1])    # slope error per press
        return ind, w, P

    ind, w, P = presses(np.linspace(0.15, 0.6, 5))
    u = np.full(w.size, 0.015 * 2.0)            # the shared part counted n = 4 times over
    kw = {"thickness_mm": h, "radius_mm": 2.5, "beta_table": "paper", "a_over_h": 0.8,
          "depth_std_mm": u}
    plain = fit_indentation(w, P, **kw)
    grouped = fit_indentation(w, P, indenter=ind, depth_indenter_std_mm=u, **kw)
    assert plain.misfit.correlation > 0.5 and plain.misfit.factor > 1.5
    assert grouped.misfit.factor == 1.0 and not grouped.misfit.drifts
    assert grouped.E_mpa == plain.E_mpa
    assert np.diff(grouped.E_ci95_mpa)[0] < np.diff(plain.E_ci95_mpa)[0] / 1.5
    # the same law bent (a square term eq. 5 lacks) across 16 indenters: the means' run
    ind, w, P = presses(np.linspace(0.1, 0.6, 16), bend=10.0)
    m = assess_misfit(w, P - law(w), np.full(w.size, 0.2), group=ind)
    assert m.correlation > 0.5 and m.factor > 1.5
    with pytest.raises(InputError, match="go together"):
        fit_indentation(w, P, indenter=ind, **{**kw, "depth_std_mm": np.full(w.size, 0.03)})
    with pytest.raises(ShapeError, match="group"):
        assess_misfit(w, P - law(w), np.full(w.size, 0.2), group=ind[:3])


def test_the_drift_line_is_scipys_linregress():
    """The apparent E's drift is read with a local copy of ``scipy.stats.linregress``'s
    arithmetic (its argument handling cost more than the rest of the misfit): slope,
    its standard error and the two-sided p-value equal scipy's on random tables, repeated
    depths, exact lines and a constant apparent E (NaN where scipy's is NaN)."""
    from scipy import stats

    rng = np.random.default_rng(86)
    n_cases = 0
    for n in (2, 3, 4, 5, 8, 20):
        for k in range(40):
            x = (np.resize(np.repeat(rng.uniform(0.05, 0.6, n), 2), n) if k % 2
                 else rng.uniform(0.05, 0.6, n))
            if np.ptp(x) == 0:
                continue
            y = (rng.normal(1.0, 0.1, n), 0.2 + 0.3 * x, np.full(n, 0.3),
                 0.2 + 0.3 * x + 1e-12 * rng.normal(size=n))[k % 4]
            ref = stats.linregress(x, y)
            got = _linregress(x, y)
            want = (float(ref.slope), float(ref.stderr), float(ref.pvalue))
            assert all(a == b or (math.isnan(a) and math.isnan(b))
                       for a, b in zip(got, want, strict=True)), (n, k, got, want)
            n_cases += 1
    assert n_cases > 200
