"""The paper's FEA validation: fit, then simulate, on presses made by the FEM itself.

Synthetic measurements at known E and nu come from a finer finite-strain mesh
(8 edge refinements) than the tables and the validation use (7), with force
noise per press of 0.002 N (an ATI-class sensor's 1/80 N per sample, averaged
over the paper's 200 samples per press, is 0.0009 N; doubled for press-to-press
scatter), so neither the fit nor the validation sees its own forward model
exactly. Over 40 seeds this noise gives E errors of sd 0.7% (largest 2.0%) and
nu errors of sd 0.001 (largest 0.003); noise-free, E is 0.14% high and nu
0.0002 low (the finer mesh of the presses against the tables'). With 1/80 N
per press the sd would be 4.5% in E and 0.006 in nu.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from tactilevision import InputError, ShapeError
from tactilevision.cli import main
from tactilevision.diagnosis import validate_indentation
from tactilevision.fem import neo_hookean_indentation
from tactilevision.mechanics import fit_indentation

H, A = 2.5, 3.0             # mm: a/h = 1.2, where beta depends on nu strongly enough
E_TRUE, NU_TRUE = 0.15, 0.47
W_OVER_H = np.array([0.06, 0.10, 0.14, 0.17, 0.20])
REPEATS, NOISE_N = 10, 0.002


@pytest.fixture(scope="module")
def presses():
    """Ten noisy presses at each of five depths, on the FEM force-depth curve."""
    truth = neo_hookean_indentation(A / H, NU_TRUE, contact="bonded", w_over_h_max=0.2,
                                    steps=20, cell=0.25, edge_refinements=8)
    assert truth.complete
    idx = [int(np.argmin(np.abs(truth.w_over_h - x))) for x in W_OVER_H]
    np.testing.assert_allclose(truth.w_over_h[idx], W_OVER_H, atol=1e-12)
    force = E_TRUE * H**2 * truth.force[idx]                       # P = E h^2 (P / E h^2)
    rng = np.random.default_rng(7)
    w = np.repeat(W_OVER_H * H, REPEATS)
    p = np.repeat(force, REPEATS) + rng.normal(0.0, NOISE_N, w.size)
    return w, p


@pytest.fixture(scope="module")
def fitted(presses):
    return fit_indentation(*presses, thickness_mm=H, radius_mm=A)


def test_fit_recovers_E_and_nu_of_the_fem(fitted):
    assert fitted.beta_table == "fem" and not fitted.out_of_table
    assert fitted.E_mpa == pytest.approx(E_TRUE, rel=0.02)
    assert fitted.nu == pytest.approx(NU_TRUE, abs=0.01)
    assert fitted.E_ci95_mpa[0] < E_TRUE < fitted.E_ci95_mpa[1]


def test_validation_at_the_fitted_values(presses, fitted):
    w, p = presses
    val = validate_indentation(w, p, E_mpa=fitted.E_mpa, nu=fitted.nu, thickness_mm=H,
                               radius_mm=A)
    assert val.contact == "bonded" and val.pad_radius_mm == 20 * H
    assert np.all(np.isfinite(val.simulated_depth_mm))
    # the paper reports 6%; the issue asks for 2%
    assert val.max_abs_rel_error < 0.02
    assert val.mean_abs_rel_error < 0.01
    # the simulated depth of the mean force at each depth is within 1%
    for x in W_OVER_H * H:
        sim = np.interp(p[w == x].mean(), val.curve_force_n, val.curve_depth_mm)
        assert sim == pytest.approx(x, rel=0.01)
    np.testing.assert_allclose(val.rel_error, val.simulated_depth_mm / w - 1)
    d = val.to_json_dict()
    assert len(d["presses"]) == w.size and d["curve"]["depth_mm"][0] == 0.0


def test_validation_sees_a_wrong_modulus(presses):
    # 20% too stiff: every simulated depth falls short, by about 1 / 1.2
    w, p = presses
    val = validate_indentation(w, p, E_mpa=1.2 * E_TRUE, nu=NU_TRUE, thickness_mm=H,
                               radius_mm=A, mesh={"cell": 0.5, "edge_refinements": 5})
    assert np.all(val.rel_error < -0.1)       # (a coarser mesh: a 15 % effect, not 1 %)
    assert np.median(val.rel_error) == pytest.approx(-0.15, abs=0.04)


def test_forces_beyond_the_sweep_are_reported(presses):
    w, p = presses
    val = validate_indentation(w[:3], p[:3] * [1, 1, 50], E_mpa=E_TRUE, nu=NU_TRUE,
                               thickness_mm=H, radius_mm=A, steps=3)
    assert np.isnan(val.simulated_depth_mm[2]) and np.isfinite(val.simulated_depth_mm[:2]).all()
    assert any("above the largest simulated force" in n for n in val.notes)


@pytest.mark.parametrize(("kwargs", "exc", "match"), [
    ({"E_mpa": 0.0}, InputError, "E_mpa"),
    ({"nu": 0.6}, InputError, "nu must lie"),
    ({"thickness_mm": -1.0}, InputError, "thickness_mm"),
    ({"depth_mm": [0.1, -0.2]}, InputError, "press 1"),
    ({"force_n": [1.0]}, ShapeError, "force_n"),
    ({"force_n": [1.0, np.nan]}, ShapeError, "force_n must be finite"),
])
def test_bad_input(kwargs, exc, match):
    args = {"depth_mm": [0.1, 0.2], "force_n": [0.5, 1.0], "E_mpa": 0.15, "nu": 0.47,
            "thickness_mm": H, "radius_mm": A} | kwargs
    with pytest.raises(exc, match=match):
        validate_indentation(args.pop("depth_mm"), args.pop("force_n"), **args)


# ------------------------------------------------------------------- the CLI


def _table(folder, presses, gel_radius_mm=40.0):
    """The presses as a measurements table (every digit kept: the command fits what the
    fixture fitted) beside a session.toml naming the pad's radius."""
    w, p = presses
    rows = "".join(f"{i},{float(x)!r},{float(f)!r}\n"
                   for i, (x, f) in enumerate(zip(w, p, strict=True)))
    csv = folder / "measurements.csv"
    csv.write_text("press,depth_mm,force_n\n" + rows)
    (folder / "session.toml").write_text(
        f"[sensor]\ngel_thickness_mm = {H}\ngel_radius_mm = {gel_radius_mm}\n\n"
        f"[indenter]\nradius_mm = {A}\n")
    return csv


def test_cli_validate_given_values(tmp_path, capsys, presses):
    csv = _table(tmp_path, presses)
    report = tmp_path / "report"
    assert main(["validate", str(csv), "--E-mpa", str(E_TRUE), "--nu", str(NU_TRUE),
                 "--json", "-", "--report", str(report)]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["E_mpa"] == E_TRUE and d["nu"] == NU_TRUE and d["E_nu_source"] == "given"
    assert d["pad_radius_mm"] == 40.0 and d["contact"] == "bonded"
    assert len(d["presses"]) == presses[0].size
    assert d["max_abs_rel_error"] < 0.02
    assert (report / "validation.png").stat().st_size > 10_000
    lines = (report / "validation.csv").read_text().splitlines()
    assert lines[0] == "depth_mm,force_n,simulated_depth_mm,rel_error"
    assert len(lines) == presses[0].size + 1


def test_cli_validate_fits_first(tmp_path, capsys, presses, fitted):
    # the pad 20 h, the default's: the command's sweep is the one the fixture's fit validated
    csv = _table(tmp_path, presses, gel_radius_mm=20 * H)
    assert main(["validate", str(csv)]) == 0
    out = capsys.readouterr().out
    assert f"E = {fitted.E_mpa:.4f} MPa" in out and "fit (fem beta table)" in out
    assert "max |error|" in out and "the paper: within 6%" in out


@pytest.mark.parametrize(("argv", "expected"), [
    (["--E-mpa", "0.15"], "give both --E-mpa and --nu"),
    (["--E-mpa", "0.15", "--nu", "0.7"], "nu must lie in [0, 0.5]"),
    (["--E-mpa", "-1", "--nu", "0.45"], "E_mpa must be positive"),
])
def test_cli_validate_bad_options(tmp_path, capsys, presses, argv, expected):
    csv = _table(tmp_path, presses)
    assert main(["validate", str(csv), *argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("tactilevision validate: error: ")
    assert expected in err[0]


def test_cli_validate_paper_line_out_of_fem_table(tmp_path, capsys):
    # the paper's line (6) has beta = 1.507, beyond any bonded Neo-Hookean layer
    # at a/h = 0.83: the default fit gives no E, nu and says what to do
    w = np.array([0.15, 0.30, 0.40, 0.50, 0.60])
    csv = tmp_path / "measurements.csv"
    csv.write_text("depth_mm,force_n\n" + "".join(
        f"{x},{x * (5.2662 * x / 3.0 + 3.4943):.6f}\n" for x in w))
    assert main(["validate", str(csv), "--thickness-mm", "3", "--radius-mm", "2.5"]) == 2
    err = capsys.readouterr().err
    assert "the fit gives no E and nu" in err and "--E-mpa and --nu" in err
