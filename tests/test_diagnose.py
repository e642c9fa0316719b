"""``diagnose`` on tables with a known hidden effect (and none): the verdict, the
error ladder against the noise floor, E after adding the effect; the structure
tests and the noise floor on known answers; the command line and its JSON."""

from __future__ import annotations

import functools
import json
import math
import warnings
from pathlib import Path

import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.cli import main
from tactilevision.diagnosis import (
    EffectSensitivity,
    certification_tests,
    covariate_tests,
    cross_validated_rmse,
    diagnose,
    indenter_shared,
    noise_floor,
)
from tactilevision.diagnosis._diagnose import (
    Candidate,
    LadderStep,
    _choose,
    _moduli_text,
    diagnose_core,
)
from tactilevision.io import read_measurements, write_measurements
from tactilevision.mechanics import IndentationModel, fit_model
from tactilevision.sim import HIDDEN_EFFECTS, make_measurement_table
from tactilevision.sim._tables import _fem_force

SEEDS = range(4)
DATA = Path(__file__).parent / "data"
CATALOGUE = [k for k in HIDDEN_EFFECTS if k != "temperature"]
#: the generator's hidden F/T cross-talk is the catalogue's force_crosstalk
NAME = {"crosstalk": "force_crosstalk"}
#: effects whose constant trades off against beta: a one-block table does not
#: resolve E to 5 % with them in the model (its interval is wider in 97-100 % of
#: generated tables, benchmarks/bench_diagnose.py); E must lie in the interval
#: (the verdict names the tare check that separates them)
OFFSETS = ("depth_offset", "force_offset")
#: the instantaneous modulus is extrapolated to zero hold through one exponential
#: from a two-term Prony truth: within 5 % in 97 % of 30 benchmark tables, but two
#: of these four seeds miss by 5.7 and 7.5 %: E within 10 % here
RELAXATION = ("viscoelastic_relaxation",)


def _diag(t):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return diagnose(t.columns, thickness_mm=t.thickness_mm, radius_mm=t.radius_mm,
                        base=t.truth["base"])


@functools.cache
def _null_diag(seed: int):
    """``_diag`` of the generator's null table of `seed` (deterministic), read-only: several
    tests read the same verdict (seed 0's five times), its replayed sizes computed once."""
    return _diag(make_measurement_table(None, seed))


def test_generator_tables_hold_every_column_and_are_deterministic():
    cols = ("press", "indenter", "depth_mm", "force_n", "force_std_n", "fx_n", "fy_n",
            "time_s", "hold_s", "wait_s", "x_mm", "y_mm", "day", "temperature_c")
    for k in (None, *HIDDEN_EFFECTS):
        t = make_measurement_table(k, 3)
        assert tuple(t.columns) == cols
        assert np.all(np.isfinite(t.columns["force_n"]))
        assert np.ptp(t.columns["day"]) > 0 and np.ptp(t.columns["hold_s"]) > 0
    a, b = make_measurement_table("aging", 5), make_measurement_table("aging", 5)
    assert all(np.array_equal(a.columns[c], b.columns[c], equal_nan=True) for c in cols)
    with pytest.raises(ValueError, match="unknown hidden effect"):
        make_measurement_table("creep", 0)


@pytest.mark.slow
@pytest.mark.parametrize("seed", SEEDS)
def test_null_tables_give_a_null_verdict(seed):
    t = make_measurement_table(None, seed)
    d = _null_diag(seed)
    assert d.missing_effect is None and d.unexplained_covariate is None, d.message
    assert "Nothing is missing" in d.message
    assert len(d.ladder) in (1, 2)        # at most eq. (5)'s own curvature is added
    assert d.ladder[-1].cv_rmse_n <= 1.4 * d.noise_floor_n
    assert abs(d.E_mpa / t.truth["E_mpa"] - 1) < 0.05


@pytest.mark.slow
@pytest.mark.parametrize("hidden", CATALOGUE)
def test_each_catalogue_effect_is_identified(hidden):
    ok, cv_ok, E_ok = 0, 0, 0
    for seed in SEEDS:
        t = make_measurement_table(hidden, seed)
        d = _diag(t)
        named = (d.missing_effect, *d.equivalent_effects)
        # the generator's stiffness step is after one press: any stiffness_step:<column>
        effect = next((n for n in named if n == NAME.get(hidden, hidden) or (
            hidden == "stiffness_step" and n and n.startswith("stiffness_step:"))), None)
        if effect is None:
            continue
        ok += 1
        last = d.ladder[-1]
        # a held-out press next to a change point cannot be placed on its side: the
        # step's cross-validated RMSE carries that, its in-sample RMSE does not
        err = last.rmse_n if hidden == "stiffness_step" else last.cv_rmse_n
        cv_ok += err <= 1.3 * d.noise_floor_n
        E = last.E_mpa
        if effect != d.missing_effect:    # its indistinguishable partner was named first
            E = fit_model(t.columns, effect, thickness_mm=t.thickness_mm,
                          radius_mm=t.radius_mm)[0].E_mpa
        if hidden in OFFSETS:
            fit = fit_model(t.columns, hidden, thickness_mm=t.thickness_mm,
                            radius_mm=t.radius_mm)[0]
            lo, hi = fit.E_ci95_mpa
            resolved = lo >= 0.95 * fit.E_mpa and hi <= 1.05 * fit.E_mpa
            E_ok += (lo <= t.truth["E_mpa"] <= hi
                     and (not resolved or abs(E / t.truth["E_mpa"] - 1) <= 0.05))
        else:
            E_ok += abs(E / t.truth["E_mpa"] - 1) <= (0.10 if hidden in RELAXATION else 0.05)
        # the error falls: the last rung beats the model diagnosed
        assert last.cv_rmse_n < d.ladder[0].cv_rmse_n
    n = len(SEEDS)
    assert ok >= n - 1, f"{hidden} identified in {ok} of {n} tables"
    assert cv_ok >= ok - 1
    assert E_ok >= ok - 1


def test_offsets_are_reported_as_equivalent_with_the_separating_measurement():
    d = _diag(make_measurement_table("force_offset", 2))
    assert {d.missing_effect, *d.equivalent_effects} == {"depth_offset", "force_offset"}
    assert "tare" in d.separating_measurement


@pytest.mark.slow
@pytest.mark.parametrize("hidden", ["temperature"])
def test_out_of_catalogue_effects_name_their_covariate(hidden):
    hits = 0
    for seed in SEEDS:
        t = make_measurement_table(hidden, seed)
        d = _diag(t)
        hits += d.unexplained_covariate == t.truth["covariate"]
        if d.unexplained_covariate == t.truth["covariate"]:
            assert d.offered_effect == f"stiffness_trend:{t.truth['covariate']}"
    assert hits >= len(SEEDS) - 1


@pytest.mark.slow
def test_responses_are_not_scanned_unless_asked():
    """fx_n, fy_n and force_std_n follow the force: they are not scanned as covariates
    (issue 23: a stiffness trend along fx_n was offered on a 5-row table), the result
    says which columns were, and scan= adds them. A table whose F/T fz reads 6 % of fx
    (the generator's cross-talk) names force_crosstalk, which reads fx_n and fy_n as the
    sensor's conditions, with or without the scan."""
    t = make_measurement_table(None, 1)
    d = _null_diag(1)
    assert not {"fx_n", "fy_n", "force_std_n"} & set(d.scanned_columns)
    assert {"time_s", "day", "x_mm", "temperature_c"} <= set(d.scanned_columns)
    assert d.responses_not_scanned == ("fx_n", "fy_n", "force_std_n")
    assert "not scanned" in d.message and "fx_n" in d.message
    assert not any("fx_n" in c.effect and "trend" in c.effect for c in d.candidates)
    assert d.to_json_dict()["scanned_columns"] == list(d.scanned_columns)
    d2 = diagnose(t.columns, thickness_mm=t.thickness_mm, radius_mm=t.radius_mm,
                  scan=["fx_n"])
    assert "fx_n" in d2.scanned_columns and d2.responses_not_scanned == ("fy_n",
                                                                           "force_std_n")
    with pytest.raises(InputError, match="scan names columns the table does not have: "
                                         "fz_n"):
        diagnose(t.columns, thickness_mm=t.thickness_mm, radius_mm=t.radius_mm,
                 scan=["fz_n"])
    x = make_measurement_table("crosstalk", 1)
    for scan in ((), ("fx_n",)):
        dx = diagnose(x.columns, thickness_mm=x.thickness_mm, radius_mm=x.radius_mm,
                      scan=scan)
        assert dx.missing_effect == "force_crosstalk", dx.message
        k = dx.fits[-1].params["force_crosstalk.kx"]
        assert k == pytest.approx(x.truth["chi"], rel=0.2)


def test_certification_products_are_not_covariates():
    """overshoot_mm is computed by the depth rule (the certified depth less the indenter's
    w0), not a condition of the press (issue 53). Ground truth: generator tables with
    nothing missing whose certified depths carry an overshoot the press never made (the
    rule read it; the force is the nominal depth's). Taken as a covariate, it raised
    'unexplained covariate overshoot_mm'; now no verdict names it or a trend along it, the
    certification test finds it with its size (the forces' spread it explains), and the
    message does not say the model is complete."""
    for seed in range(2):
        t = make_measurement_table(None, seed)
        c = {k: np.asarray(v, np.float64) for k, v in t.columns.items()}
        over = np.random.default_rng(seed).uniform(0.0, 0.04, c["depth_mm"].size)
        c["overshoot_mm"] = over
        c["depth_mm"] = c["depth_mm"] + over
        d = _diag(type(t)(**{**t.__dict__, "columns": c}))
        assert d.unexplained_covariate is None and d.missing_effect is None, d.message
        assert "overshoot_mm" not in d.scanned_columns
        assert not any("overshoot_mm" in x.effect for x in d.candidates)
        (cert,) = d.certification
        assert cert.name == "overshoot_mm" and cert.significant
        # the structure's size: the forces' spread an overshoot of U(0, 40 um) read into
        # the depths explains, dP/dw x 11.5 um (its sd), within a factor 2
        fit = d.fits[0]
        slope = np.median(np.gradient(fit.predicted_n[np.argsort(c["depth_mm"])],
                                      np.sort(c["depth_mm"])))
        assert 0.5 < cert.size_n / (slope * 0.04 / np.sqrt(12)) < 2.0
        assert "certification problem" in d.message and "Nothing is missing" not in d.message
        assert d.to_json_dict()["certification"][0]["size_n"] == pytest.approx(cert.size_n)
    # the overshoot the press did make: forces drawn (the generator's FEM law, its noise)
    # at the nominal depth plus the overshoot, both read right: no certification alarm
    tr = t.truth
    w = c["depth_mm"]                      # nominal + overshoot, the depth the press made
    P = _fem_force(tr["E_mpa"], tr["nu"], t.radius_mm, t.thickness_mm, w) + np.random.\
        default_rng(4).normal(0.0, tr["replicate_sd_n"], w.size)
    good = {**c, "force_n": P}
    _, fit = fit_model(good, thickness_mm=t.thickness_mm, radius_mm=t.radius_mm)
    (cert,) = certification_tests(fit.residuals_n, fit.predicted_n, good)
    assert not cert.significant, cert
    with pytest.raises(InputError, match="overshoot_mm: computed by the depth rule"):
        diagnose(c, thickness_mm=t.thickness_mm, radius_mm=t.radius_mm, scan=["overshoot_mm"])


def test_nothing_missing_says_what_it_rules_out():
    """A null verdict states, per catalogue effect, the smallest size this very table would
    have named (issue 53). Ground truth: the same seed's table drawn again with a force
    offset (the generator's parameter is the catalogue's) at 1.5 times that size is named;
    at 0.3 times it is not. Effects the table cannot test say why; a verdict that names
    an effect states no sizes."""
    t = make_measurement_table(None, 0)
    d = _null_diag(0)
    assert d.missing_effect is None and d.unexplained_covariate is None, d.message
    sizes = d.rules_out
    assert set(sizes) >= {"depth_offset", "force_offset", "spatial_nonuniformity"}
    size = sizes["force_offset"].size_param
    assert 0 < size < 1.0
    assert "None larger than: " in d.message and "force_offset" in d.message.split(
        "None larger than: ")[1]
    obj = d.to_json_dict()
    assert obj["rules_out"]["force_offset"]["size"] == pytest.approx(
        sizes["force_offset"].size)
    assert "replays" in obj["rules_out_note"]
    unit = make_measurement_table("force_offset", 0).truth["offset_n"]
    big = _diag(make_measurement_table("force_offset", 0, strength=1.5 * size / unit))
    assert "force_offset" in (big.missing_effect, *big.equivalent_effects), big.message
    assert big.rules_out == {}
    small = _diag(make_measurement_table("force_offset", 0, strength=0.3 * size / unit))
    assert small.missing_effect is None
    # the table's untestable effects keep their reason (this generator varies every column)
    for v in sizes.values():
        assert math.isfinite(v.size) or v.why
    plain = diagnose(t.columns, thickness_mm=t.thickness_mm, radius_mm=t.radius_mm,
                     rules_out=False)
    assert plain.rules_out == {} and "None larger than" not in plain.message


@pytest.mark.slow
@pytest.mark.parametrize("effect", ["stiffness_trend:time_s", "stiffness_step:press"])
def test_nothing_missing_rules_out_a_stiffness_change_over_the_session(effect):
    """A table without crossing forces states the softening over time and the stiffness
    step it rules out (issue 53: "nothing missing" on a vernier's softening said nothing
    of it). Ground truth: the same null table's forces scaled by that change (the
    catalogue's parametrisation) at 1.5 times the stated size are named; at 0.3 times
    they are not."""
    t = make_measurement_table(None, 0)
    d = _null_diag(0)
    assert d.missing_effect is None and d.unexplained_covariate is None, d.message
    e = d.rules_out[effect]
    assert 0 < e.size_param < math.inf and e.unit in ("%/min", "%")
    said = f"{effect} {e.size:.3g} {e.unit}"
    assert said in d.message
    # the step is sized half-way, and says so, with what one near an end needs
    half = "(half-way through the presses; anywhere after presses"
    assert (half in d.message.split(said)[1][:len(half) + 1]) == (effect == "stiffness_step:press")
    c = t.columns

    def changed(x, after=None):
        if effect.startswith("stiffness_trend"):
            f = np.exp(-x * (c["time_s"] - c["time_s"].mean()))
        else:
            f = 1 - x * (c["press"] > (np.median(c["press"]) if after is None else after))
        return _diag(type(t)(**{**vars(t), "columns": {**c, "force_n": c["force_n"] * f}}))

    big = changed(1.5 * e.size_param)
    assert effect in (big.missing_effect, *big.equivalent_effects, big.offered_effect), \
        big.message
    small = changed(0.3 * e.size_param)
    assert small.missing_effect is None and small.unexplained_covariate is None, \
        small.message
    if effect == "stiffness_step:press":
        # near the start the step needs more (the fewest presses before it), and that
        # size is named there
        after, first = e.at_places[0]
        assert after < np.median(c["press"]) and first > 1.5 * e.size
        early = changed(1.5 * first / 100, after)
        assert effect in (early.missing_effect, *early.equivalent_effects), early.message


def test_rules_out_is_replayed_for_a_gel_fitted_at_the_tables_edge():
    """A gel whose fit reaches nu at or past the FEM table's edge (0.499; the paper's
    relation reaches 0.5) is replayed there, said so, not left without sizes (the vernier
    sessions of issue 53 fitted nu = 0.4999 and stated no size). Ground truth: the same
    steepened table with a force offset of 1.5 times the size it states is named."""
    t = make_measurement_table(None, 0)
    x = t.columns["depth_mm"] / t.thickness_mm
    steep = {**t.columns, "force_n": t.columns["force_n"] * (1 + x)}
    kw = dict(thickness_mm=t.thickness_mm, radius_mm=t.radius_mm, base="paper",
              beta_table="paper")
    d = diagnose(steep, **kw)
    assert d.missing_effect is None and d.ladder[-1].nu > 0.499, d.message
    assert "taken at the FEM table's edge" in d.rules_out_note
    size = d.rules_out["force_offset"].size_param
    assert 0 < size < 1.0
    big = diagnose({**steep, "force_n": steep["force_n"] + 1.5 * size}, **kw)
    assert "force_offset" in (big.missing_effect, *big.equivalent_effects), big.message


def test_a_mark_certified_table_does_not_rule_out_what_the_rule_absorbs():
    """Under the mark rule the depth past w0 is read from the force (w = w0 + (P -
    P(w0)) / (dP/dw)): an effect that changes the force between an indenter's presses is
    read as depth. The verdict says so and rules none of them out; an offset keeps its
    size (it moves the crossing force too)."""
    t = make_measurement_table(None, 0)
    plain = _null_diag(0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = diagnose(t.columns, thickness_mm=t.thickness_mm, radius_mm=t.radius_mm,
                     depth_rule="mark")
    assert "certified by the mark rule" in d.message
    assert "certified by the mark rule" not in plain.message
    for name in ("force_drift", "spatial_nonuniformity", "force_crosstalk"):
        assert math.isfinite(plain.rules_out[name].size)
        assert math.isnan(d.rules_out[name].size) and "absorbed" in d.rules_out[name].why
    assert d.rules_out["depth_offset"].size == pytest.approx(
        plain.rules_out["depth_offset"].size)
    assert "is largely absorbed): force_drift, " in d.message


def _shared_by_indenter(hidden, seed, s_mm=0.015):
    """A generator table whose presses at one depth are one indenter's, each indenter's
    depths off by one error (sd 15 um, as a mark's P(w0) crossing puts them), stated as
    calibrate states it: depth_indenter_std_mm = s sqrt(n), inside depth_std_mm."""
    t = make_measurement_table(hidden, seed)
    c = {k: np.asarray(v, np.float64) for k, v in t.columns.items()}
    levels, ind = np.unique(np.round(c["depth_mm"], 6), return_inverse=True)
    c["indenter"] = ind.astype(np.float64)
    delta = np.random.default_rng(seed + 77).normal(0.0, s_mm, levels.size)
    c["depth_mm"] = c["depth_mm"] + delta[ind]
    c["force_sem_n"] = np.full(ind.size, t.truth["noise_n"])
    c["depth_indenter_std_mm"] = s_mm * np.sqrt(np.bincount(ind)[ind])
    c["depth_std_mm"] = np.hypot(t.truth["depth_jitter_mm"], c["depth_indenter_std_mm"])
    return t, c


@pytest.mark.slow
def test_a_depth_error_shared_by_each_indenter_is_carried_by_every_fit():
    """Issue 53, item 1. Ground truth: generator tables with each indenter's depths off by
    one shared error, stated. Taken as independent, null tables name an offset (seeds 1
    and 3: the shared errors mimic it); under generalized least squares with the stated
    shared part they name nothing and list that offset as not testable; a stiffness step
    within the indenters, missed on seed 0 when the depths are taken as independent, is
    named."""
    for seed in (1, 3):
        t, c = _shared_by_indenter(None, seed)
        kw = dict(thickness_mm=t.thickness_mm, radius_mm=t.radius_mm)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            plain = diagnose_core(c, **kw)
            d = diagnose(c, **kw, rules_out=False)
        assert plain.missing_effect in ("depth_offset", "force_offset")
        assert d.missing_effect is None and d.unexplained_covariate is None, d.message
        assert plain.missing_effect in d.shared_depth["not_testable"]
        assert 0 < d.shared_depth["theta_min"] <= d.shared_depth["theta_max"] < 1
        assert "generalized least squares" in d.message
        assert d.to_json_dict()["shared_depth"]["not_testable"]
    t, c = _shared_by_indenter("stiffness_step", 0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        plain = diagnose_core(c, thickness_mm=t.thickness_mm, radius_mm=t.radius_mm)
        d = diagnose(c, thickness_mm=t.thickness_mm, radius_mm=t.radius_mm, rules_out=False)
    assert plain.missing_effect is None
    assert d.missing_effect == "stiffness_step:press", d.message
    # a null verdict under the shared error does not claim to rule out what that error
    # looks like (the replay draws independent presses)
    t, c = _shared_by_indenter(None, 1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = diagnose(c, thickness_mm=t.thickness_mm, radius_mm=t.radius_mm)
    for name in ("depth_offset", "force_offset"):
        assert math.isnan(d.rules_out[name].size)
        assert "each indenter's presses share" in d.rules_out[name].why
    # without the column, nothing changes
    c.pop("depth_indenter_std_mm")
    assert indenter_shared(c) is None


@pytest.mark.slow
def test_the_folds_take_the_fits_noise_model_under_a_shared_error():
    """Issue 53, item 1 (one noise model): the cross-validation fits each fold by the same
    generalized least squares and predicts a held-out press with its indenter's share of
    the error (BLUP). Before, the folds scored the raw shared error, which no effect can
    lower: a force drift (seeds 0 and 5) and a spatial gradient (seed 0), varying within
    each indenter and passing the BIC, were refused by the folds. Known answer for the
    folds: presses of the true law plus a shared error per group of 10 (sd 0.2 N) and
    their own noise (sd 5 mN): the raw folds' RMSE is about the shared sd, under the
    stated noise model about the presses' own."""
    for hidden, seeds in (("force_drift", (0, 5)), ("spatial_nonuniformity", (0,))):
        for seed in seeds:
            t, c = _shared_by_indenter(hidden, seed)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                d = diagnose(c, thickness_mm=t.thickness_mm, radius_mm=t.radius_mm,
                             rules_out=False)
            assert d.missing_effect == hidden, (hidden, seed, d.message)
    rng = np.random.default_rng(3)
    group = np.repeat(np.arange(8), 10).astype(np.float64)
    w = rng.uniform(0.1, 0.5, group.size)
    force = 2.0 * w + 0.4 * w**2 + rng.normal(0, 0.2, 8)[group.astype(int)] \
        + rng.normal(0, 0.005, group.size)
    cols = {"depth_mm": w, "force_n": force}
    model = IndentationModel()
    raw = cross_validated_rmse(model, cols, thickness_mm=2.0)
    rho = (0.2 / 0.005) ** 2
    theta = np.full(group.size, 1 - 1 / np.sqrt(1 + 10 * rho))
    gls = cross_validated_rmse(model, {**cols, "_group": group, "_theta": theta},
                               thickness_mm=2.0)
    assert raw > 0.1
    assert gls < 0.012


def test_covariate_tests_and_noise_floor_on_known_answers():
    rng = np.random.default_rng(0)
    n = 200
    cols = {"depth_mm": np.repeat([0.1, 0.2, 0.3, 0.4], n // 4), "x": rng.uniform(0, 1, n),
            "y": rng.uniform(0, 1, n)}
    noise = rng.normal(0, 0.01, n)
    pred = np.ones(n)
    r = noise + 0.02 * (cols["x"] - 0.5)     # a linear trend along x of known size
    tests = {t.name: t for t in covariate_tests(r, pred, cols)}
    assert tests["x"].significant and tests["x"].p_value < 1e-6
    expected = np.var(0.02 * cols["x"]) / np.var(r)
    assert tests["x"].explained_fraction == pytest.approx(expected, abs=0.08)
    assert not tests["y"].significant
    assert noise_floor(noise, cols) == pytest.approx(0.01, rel=0.15)
    # one press per depth: no replicates, no floor
    assert np.isnan(noise_floor(noise[:3], {"depth_mm": np.array([0.1, 0.2, 0.3])}))


def test_untestable_effects_name_the_columns_they_need():
    t = make_measurement_table("incomplete_recovery", 0)
    cols = {k: v for k, v in t.columns.items() if k not in ("day", "x_mm", "y_mm")}
    d = diagnose(cols, thickness_mm=t.thickness_mm, radius_mm=t.radius_mm)
    assert d.untestable["aging"] == ("day",)
    assert d.untestable["spatial_nonuniformity"] == ("x_mm", "y_mm")
    assert d.missing_effect == "incomplete_recovery"
    assert "Not testable on this table: " in d.message


def _write(tmp_path, t):
    return write_measurements(tmp_path / "measurements.csv", t.columns,
                              thickness_mm=t.thickness_mm, radius_mm=t.radius_mm)


@pytest.mark.slow
def test_cli_json_follows_the_contract_and_report(tmp_path, capsys):
    t = make_measurement_table("incomplete_recovery", 1)
    csv = _write(tmp_path, t)
    rep = tmp_path / "report"
    assert main(["diagnose", str(csv), "--json", "-", "--report", str(rep)]) == 0
    d = json.loads(capsys.readouterr().out)
    for key in ("model", "params", "rmse_n", "cv_rmse_n", "noise_floor_n", "covariates",
                "candidates", "verdict"):
        assert key in d
    assert d["model"] == ["layer", "large_deformation"]
    assert set(d["params"]) == {"E_mpa", "nu"}
    assert set(d["covariates"][0]) >= {"name", "p_value", "explained_fraction"}
    assert set(d["candidates"][0]) >= {"effect", "delta_bic", "cv_rmse_n", "params"}
    assert d["candidates"][0]["effect"] == "incomplete_recovery"
    v = d["verdict"]
    assert v["missing_effect"] == "incomplete_recovery"
    assert v["equivalent_effects"] == [] and v["unexplained_covariate"] is None
    wait = next(c for c in d["covariates"] if c["name"] == "wait_s")
    assert wait["p_value"] < 1e-6 and wait["explained_fraction"] > 0.3
    assert d["ladder"][1]["cv_rmse_n"] < 0.5 * d["ladder"][0]["cv_rmse_n"]
    for f in ("residuals_by_covariate.png", "error_ladder.png", "report.html"):
        assert (rep / f).stat().st_size > 1000
    assert "incomplete_recovery" in (rep / "report.html").read_text()
    # the human summary
    assert main(["diagnose", str(csv), "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "verdict: missing effect incomplete_recovery" in out


@pytest.mark.slow
def test_cli_layer_base_and_given_effects(tmp_path, capsys):
    t = make_measurement_table(None, 1)
    csv = _write(tmp_path, t)
    assert main(["diagnose", str(csv), "--base", "layer", "--json", "-"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["model"] == ["layer"] and d["verdict"]["missing_effect"] == "large_deformation"
    assert d["params"]["E_mpa"] is None       # no beta: E and nu not derived
    assert main(["diagnose", str(csv), "--effects", "aging", "--json", "-"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["model"] == ["layer", "large_deformation", "aging"]
    assert main(["diagnose", str(csv), "--scan", "fx_n, force_std_n", "--json", "-"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert {"fx_n", "force_std_n"} <= set(d["scanned_columns"])
    assert d["responses_not_scanned"] == ["fy_n"]


@pytest.mark.parametrize("argv, expected", [
    (["--effects", "creep"], "unknown effect 'creep'"),
    (["--effects", "aging"], "needs the column(s) day"),
    (["--scan", "fx_n,fz_n"], "scan names columns the table does not have: fz_n"),
])
def test_cli_bad_input(tmp_path, capsys, argv, expected):
    t = make_measurement_table(None, 0)
    cols = {k: v for k, v in t.columns.items() if k != "day"}
    csv = write_measurements(tmp_path / "m.csv", cols, thickness_mm=t.thickness_mm,
                             radius_mm=t.radius_mm)
    (tmp_path / "out.json").write_text("{}")
    assert main(["diagnose", str(csv), *argv, "--json", str(tmp_path / "out.json"),
                 "--overwrite"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and expected in err[0]
    assert (tmp_path / "out.json").read_text() == "{}"     # nothing already written is lost


@pytest.mark.slow
def test_sample_session_with_a_hidden_effect(tmp_path, capsys):
    """The README's walk-through: calibrate the sample session, diagnose, add the effect."""
    from pathlib import Path

    session = Path(__file__).resolve().parent.parent / "sample_frames" / "gelsight_recovery"
    truth = json.loads((session / "truth.json").read_text())
    out = tmp_path / "recovery"
    assert main(["calibrate", str(session), "--out", str(out), "--no-progress",
                 "--no-report"]) == 0
    capsys.readouterr()
    csv = out / "measurements.csv"
    assert main(["diagnose", str(csv), "--json", "-"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["verdict"]["missing_effect"] == "incomplete_recovery"
    assert d["verdict"]["unexplained_covariate"] is None
    assert d["covariates"][[c["name"] for c in d["covariates"]].index("wait_s")][
        "explained_fraction"] > 0.8
    base, added = d["ladder"][0], d["ladder"][1]
    assert added["cv_rmse_n"] < 0.25 * base["cv_rmse_n"]
    assert added["cv_rmse_n"] < 1.5 * d["noise_floor_n"]
    assert main(["fit", str(csv), "--effects", "incomplete_recovery", "--json", "-"]) == 0
    fit = json.loads(capsys.readouterr().out)
    assert fit["E_ci95_mpa"][0] < truth["E_mpa"] < fit["E_ci95_mpa"][1]
    assert abs(fit["E_mpa"] / truth["E_mpa"] - 1) < 0.08


def test_a_rung_without_E_says_so_instead_of_printing_nan():
    """A rung whose model gives no E (its beta outside the FEM's for it, as the force
    offset rung on a Taxim relaxation session) is printed as "no E or nu", not "E = nan
    MPa"; a rung with E prints it to four figures."""
    def rung(E, nu):
        return LadderStep(model=("layer",), rmse_n=0.01, cv_rmse_n=0.01, bic=0.0, E_mpa=E,
                          nu=nu, added=None)

    assert _moduli_text(rung(0.2046, 0.48)) == "E = 0.2046 MPa, nu = 0.48"
    text = _moduli_text(rung(float("nan"), float("nan")))
    assert text.startswith("no E or nu") and "nan" not in text


def test_a_stiffness_trend_competes_where_the_step_along_its_column_passes():
    """The trend along time is force_drift's counterpart: alone it raises no alarm (a null
    table would by chance), but where the stiffness step along time passes the alarm is
    raised already, and the trend, that change's other shape, competes for its name. The
    candidates of Taxim's vernier seed 103 with a softening over the session (ground
    truth: a trend in time): the trend 11.7 in BIC better than the step, force_drift not
    passing. Before 2026-11-27 the step was named and the trend not even listed."""
    cands = [Candidate("stiffness_trend:time_s", -23.39, 0.0340, 0.030, {}, 19),
             Candidate("stiffness_step:press", -11.74, 0.0418, 0.034, {}, 19),
             Candidate("stiffness_step:time_s", -11.74, 0.0448, 0.034, {}, 19),
             Candidate("force_drift", -4.0, math.nan, 0.038, {}, 19)]
    partner = {"stiffness_trend:time_s": "force_drift"}
    best, eq = _choose(cands, 0.05, partner, ("law_curvature",), "gate")
    assert best.effect == "stiffness_trend:time_s" and eq == ()
    # without the step along time passing, the trend stays silent: the step along press
    # order is named
    no_step = [c for c in cands if c.effect != "stiffness_step:time_s"]
    best, _ = _choose(no_step, 0.05, partner, ("law_curvature",), "gate")
    assert best.effect == "stiffness_step:press"
    # nor does it raise an alarm of its own
    assert _choose([cands[0], cands[3]], 0.05, partner, ("law_curvature",), "gate") is None


@pytest.mark.slow
def test_an_offset_along_depth_under_the_mark_rule_needs_the_crossing_forces():
    """A generated drawn-mark session with nothing hidden (tests/data/mark_null_8919):
    within each indenter the mark's depths are read through the force, and the ladder on
    them named depth_offset (BIC lower by 26); the crossing forces, at depths the frames
    certify apart from the force, name nothing. The verdict is then nothing, the offsets
    not identified. Ground truth the other way: the same presses with every depth said
    100 um shallower than it was (lands 100 um off) name an offset, which the crossing
    forces show too."""
    t = read_measurements(DATA / "mark_null_8919" / "measurements.csv")
    cols = {**t.columns, "depth_mm": t.depth_mm, "force_n": t.force_n}
    kw = dict(thickness_mm=t.thickness_mm, radius_mm=t.radius_mm, rules_out=False)
    group, theta = indenter_shared(cols)
    ladder = diagnose_core({**cols, "_group": group, "_theta": theta},
                           thickness_mm=t.thickness_mm, radius_mm=t.radius_mm)
    assert ladder.missing_effect in ("depth_offset", "force_offset")
    d = diagnose(cols, depth_rule="mark", **kw)
    assert d.missing_effect is None and d.unexplained_covariate is None, d.message
    assert "not identified under the mark rule" in d.untestable_reasons["depth_offset"]
    assert "not identified on this table" in d.message
    off = diagnose({**cols, "depth_mm": cols["depth_mm"] - 0.1}, depth_rule="mark", **kw)
    assert off.missing_effect in ("depth_offset", "force_offset"), off.message


def test_a_step_at_a_place_no_size_reaches_reads_as_such():
    """A place where no step size the parameter allows is named (inf) says so in the
    sentence and is null in the JSON (strict JSON has no Infinity); the largest is found
    and the ends of the places named."""
    e = EffectSensitivity("stiffness_step:press", "s", "%", 7.0, 0.07, 0.95, math.nan, "w",
                          at_places=((1.0, math.inf), (5.0, 7.0), (9.0, 12.0)))
    assert e.places_sentence() == ("half-way through the presses; anywhere after presses 1 "
                                   "to 9: not at any size the parameter allows, the most "
                                   "after press 1")
    out = json.loads(json.dumps(e.to_json_dict(), allow_nan=False))
    assert out["at_places"] == [{"after_press": 1.0, "size": None},
                                {"after_press": 5.0, "size": 7.0},
                                {"after_press": 9.0, "size": 12.0}]
    assert EffectSensitivity("x", "p", "", 1.0, 1.0, 0.95, 1.0, "w").to_json_dict()[
        "at_places"] is None
