"""A ball session (frames + F/T log, no gauge block) through calibrate: presses found, each
depth read from its contact circle, E fitted; the truth drawn by closed forms no code of ours
holds. A rigid sphere on a thick gel: Sneddon's half-space solution gives depth and force at
each contact radius (I. N. Sneddon, Int. J. Eng. Sci. 3:47, 1965), the surface is the ball's
cap inside a and Hertz's sink-in outside (K. L. Johnson, Contact Mechanics, 1985, eq. 3.42),
shaded by the Taxim authors' table of the real GelSight, the F/T log the schedule's force
with an ATI-class sensor's noise."""

from __future__ import annotations

import json
import re
import shutil

import numpy as np
import pytest
from _data import hertz_pad_sweeps

from tactilevision import InputError, default_calibration_path
from tactilevision.cli import main
from tactilevision.io import read_measurements, read_session
from tactilevision.pipeline import calibrate_ball_session, calibrate_session
from tactilevision.sim import make_ball_session, sneddon_sphere, sneddon_sphere_radius

R, H, E = 2.0, 100.0, 1.0       # ball, thick gel (mm), modulus (MPa)


def true_force(depth_mm: np.ndarray) -> np.ndarray:
    """Sneddon's force at each depth (with the layer's first-order term, 1.5 % at most)."""
    a = np.array([sneddon_sphere_radius(float(w), radius_mm=R) for w in depth_mm])
    return sneddon_sphere(a, radius_mm=R, E_mpa=E, thickness_mm=H)[1]


@pytest.fixture(scope="module")
def ball_session(tmp_path_factory):
    folder = tmp_path_factory.mktemp("ball") / "session"
    sched = make_ball_session(folder, radius_mm=R, E_mpa=E, thickness_mm=H, ft_bias_n=0.04)
    return folder, sched


@pytest.fixture(scope="module")
def calibrated(ball_session):
    folder, sched = ball_session
    return calibrate_ball_session(folder, nu=0.5, law="linear"), sched


@pytest.mark.slow
def test_every_press_found_with_its_force(calibrated):
    """The eight presses, each hold's force the closed form's at its depth (F/T noise
    1/80 N over 200 samples: the window's mean within 5 mN, once the F/T's 40 mN zero read
    between the presses is taken off), the clock found."""
    cal, sched = calibrated
    assert len(cal.used) == sched.n_presses == 8 and not cal.rejected
    order = np.argsort([cal.presses.presses[i].t_frame_s for i in cal.used])
    P_true = true_force(sched.depth_mm)
    assert np.allclose(cal.force_n[order], P_true, atol=5e-3)
    assert abs(cal.presses.clock_offset_s - 0.05) < 0.02
    zero = [float(m.group(1)) for w in cal.warnings
            if (m := re.search(r"F/T read \+([\d.]+) mN .*nothing touching", w))]
    assert zero and abs(zero[0] - 40.0) < 2.0, cal.warnings


@pytest.mark.slow
def test_depths_from_the_circles_hold_the_truth(calibrated):
    """Each depth within its stated shared bound plus two sds of Sneddon's; E's interval
    holds the truth (the detector's circles sit inside the contact, the depths shallow, E
    high: within 12 %, as on the presses rendered one by one)."""
    cal, sched = calibrated
    order = np.argsort([cal.presses.presses[i].t_frame_s for i in cal.used])
    d = cal.depths
    err = d.depth_mm[order] - sched.depth_mm
    assert np.all(np.abs(err) < d.depth_shared_mm[order] + 2 * d.depth_std_mm[order]), err
    fit = cal.fit
    assert fit.E_ci95_mpa[0] <= E <= fit.E_ci95_mpa[1], fit.E_ci95_mpa
    assert abs(fit.E_mpa / E - 1) < 0.12, fit.E_mpa
    assert not fit.nu_identified and fit.nu == 0.5


@pytest.mark.slow
def test_cli_calibrate_writes_a_table_fit_reads_back(ball_session, tmp_path, capsys):
    """`calibrate` of a ball session writes measurements.csv with its sphere sidecar and
    the shared depth error; `fit` of that table gives the same E and interval."""
    folder, _ = ball_session
    out = tmp_path / "cal"
    assert main(["calibrate", str(folder), "--out", str(out), "--law", "linear",
                 "--no-progress", "--json", str(tmp_path / "fit.json")]) == 0
    text = capsys.readouterr().out
    assert "contact circles" in text and "8 presses fitted" in text
    # a rerun replaces its own files without --overwrite
    assert main(["calibrate", str(folder), "--out", str(out), "--law", "linear",
                 "--no-progress"]) == 0
    capsys.readouterr()
    obj = json.loads((out / "fit.json").read_text())
    contract = ("E_mpa", "nu", "c_n_per_mm", "beta", "E_ci95_mpa", "nu_ci95", "rmse_n",
                "n_presses", "effects", "effect_params")
    assert all(k in obj for k in contract) and obj["effects"] == [] and obj["beta"] is None
    table = read_measurements(out / "measurements.csv")
    assert table.indenter["shape"] == "sphere" and "depth_shared_mm" not in table.covariates
    assert len(table) == 8 and (out / "circles.csv").read_text().count("\n") == 9
    assert (out / "calibration.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["fit", str(out / "measurements.csv"), "--law", "linear", "--nu", "0.5",
                 "--json", str(tmp_path / "refit.json")]) == 0
    refit = json.loads((tmp_path / "refit.json").read_text())
    assert refit["E_mpa"] == pytest.approx(obj["E_mpa"], rel=1e-3)
    assert refit["E_ci95_mpa"][1] == pytest.approx(obj["E_ci95_mpa"][1], rel=1e-2)


@pytest.mark.slow
def test_a_session_that_names_its_optics_has_its_caps_checked(ball_session, tmp_path):
    """With ``[optics] calibration`` the height map's cap of each press is read beside its
    circle (circles.csv's cap columns, a sentence in fit.json's warnings): deeper circles,
    deeper caps, within two of the caps' stated sds (two presses of one indenter, their
    circles 1 um apart, had caps 10 % apart: one press's cap is good to about 16 %).
    (The shipped GelSight calibration reads these frames, shaded by the Taxim authors'
    table, 20 to 30 % shallow: the cross-check says so.)"""
    folder, _ = ball_session
    copy = tmp_path / "s"
    shutil.copytree(folder, copy)
    (copy / "session.toml").write_text((copy / "session.toml").read_text() + (
        f"\n[optics]\ncalibration = {json.dumps(str(default_calibration_path('gelsight')))}\n"))
    out = tmp_path / "cal"
    assert main(["calibrate", str(copy), "--out", str(out), "--law", "linear",
                 "--no-progress"]) == 0
    lines = (out / "circles.csv").read_text().splitlines()
    head = lines[0].split(",")
    assert head[-4:] == ["cap_mm", "cap_expected_mm", "cap_depth_mm", "cap_depth_std_mm"]
    rows = np.array([[float(v) for v in ln.split(",")[-4:]] for ln in lines[1:]])
    depth = np.array([float(ln.split(",")[head.index("depth_mm")]) for ln in lines[1:]])
    order = np.argsort(depth)
    cap_depth, sd = rows[order, 2], rows[order, 3]           # caps follow the circles
    assert np.all(np.diff(cap_depth) > -2 * np.hypot(sd[1:], sd[:-1]))
    assert cap_depth[-1] - cap_depth[0] > 4 * np.hypot(sd[-1], sd[0])
    assert np.all(rows[:, 1] < depth) and np.all(rows[:, 3] > 0)
    warn = json.loads((out / "fit.json").read_text())["warnings"]
    assert any(w.startswith("cap cross-check: the height map's caps read") for w in warn)


@pytest.mark.slow
def test_a_sessions_dome_is_checked_and_named(ball_session, tmp_path):
    """``[sensor] gel_dome_radius_mm``: a number or refused naming the key; a dome without
    the pad's radius refused naming the file and key; no unknown-key warning."""
    folder, _ = ball_session
    bad = tmp_path / "dome"
    shutil.copytree(folder, bad)
    toml = (bad / "session.toml").read_text()
    (bad / "session.toml").write_text(toml.replace(
        "[sensor]\n", '[sensor]\ngel_dome_radius_mm = "wide"\n', 1))
    with pytest.raises(InputError, match=r"\[sensor\] gel_dome_radius_mm must be a positive"):
        read_session(bad)
    (bad / "session.toml").write_text(toml.replace(
        "[sensor]\n", "[sensor]\ngel_dome_radius_mm = 500.0\n", 1))
    assert not any("gel_dome_radius_mm" in n for n in read_session(bad).notes)
    assert read_session(bad).config.gel_dome_radius_mm == 500.0
    with pytest.raises(InputError, match=r"session.toml: \[sensor\] gel_dome_radius_mm: .*"
                                         r"needs the pad's radius"):
        calibrate_ball_session(bad, law="linear")


@pytest.mark.slow
def test_a_ball_session_is_not_a_gauge_blocks(ball_session):
    folder, _ = ball_session
    with pytest.raises(InputError, match="calibrate_ball_session"):
        calibrate_session(read_session(folder))


def test_the_closed_form_is_sneddons():
    """Sneddon's sphere against Hertz where the cap is shallow (a << R: w = a^2 / R,
    P = 4/3 E* R^1/2 w^3/2), and its inverse."""
    a = np.array([0.01, 0.05])
    w, P = sneddon_sphere(a, radius_mm=R, E_mpa=E)
    assert np.allclose(w, a * a / R, rtol=1e-3)
    assert np.allclose(P, 4 / 3 * E / 0.75 * np.sqrt(R) * w ** 1.5, rtol=2e-3)
    assert sneddon_sphere_radius(float(w[1]), radius_mm=R) == pytest.approx(0.05, rel=1e-9)
    with pytest.raises(InputError, match="contact radii"):
        sneddon_sphere([R], radius_mm=R, E_mpa=E)


@pytest.mark.slow
def test_bad_ball_sessions_refused_naming_the_key(ball_session, tmp_path):
    folder, _ = ball_session
    bad = tmp_path / "bad"
    shutil.copytree(folder, bad)
    toml = (bad / "session.toml").read_text()
    (bad / "session.toml").write_text(toml + "\n[gauge_block]\ndepths_mm = [0.2]\n")
    assert any("[gauge_block] is not used for a ball" in n for n in read_session(bad).notes)
    (bad / "session.toml").write_text(toml.replace('shape = "sphere"', 'shape = "ball"'))
    with pytest.raises(InputError, match=r"\[indenter\] shape must be"):
        read_session(bad)
    (bad / "session.toml").write_text(toml.replace("radius_mm = 2.0", "radius_mm = -2.0"))
    with pytest.raises(InputError, match="radius_mm"):
        calibrate_ball_session(bad)
    # a force window longer than the holds: every press rejected, each saying why
    (bad / "session.toml").write_text(toml.replace("window_samples = 200",
                                                   "window_samples = 2000"))
    with pytest.raises(InputError, match=r"too few to fit E \(press 0: hold too short"):
        calibrate_ball_session(bad, law="linear")
    # a ball smaller than its circles: every press refused by its circle, nothing to fit
    (bad / "session.toml").write_text(toml.replace("radius_mm = 2.0", "radius_mm = 0.5"))
    with pytest.raises(InputError, match="too few to fit"):
        calibrate_ball_session(bad, law="linear")


def test_a_sessions_depths_read_one_fem_sweep(tmp_path, monkeypatch):
    """On a finite pad (the generator's 1000 mm) every press's circle, its dw/da, the force
    check and the fit read one FEM sweep, the shallowest press's: read press by press they
    asked for one per press's own depth (its sweep's first depth the largest of a few below
    half the press's). A stand-in sweep (Hertz's a^2 = R w, force ratio 1) counts those
    asked for."""
    folder = tmp_path / "session"           # three presses, shallowest to deepest
    make_ball_session(folder, radius_mm=R, E_mpa=E, thickness_mm=H,
                      contact_radii_mm=(0.6, 0.9, 1.2), repeats=1, fps=10.0)
    with hertz_pad_sweeps(monkeypatch, 0.05) as keys:
        cal = calibrate_ball_session(folder, nu=0.5, law="linear")
    assert len(cal.used) == 3 and cal.depths.depth_mm.size == 3
    assert len(set(keys)) == 1, sorted(set(keys))
