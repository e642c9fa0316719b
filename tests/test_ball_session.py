"""A ball session (frames + F/T log, no gauge block) through calibrate: presses found, each
depth read from its contact circle, E fitted; the truth drawn by closed forms no code of ours
holds. A rigid sphere on a thick gel: Sneddon's half-space solution gives depth and force at
each contact radius (I. N. Sneddon, Int. J. Eng. Sci. 3:47, 1965), the surface is the ball's
cap inside a and Hertz's sink-in outside (K. L. Johnson, Contact Mechanics, 1985, eq. 3.42),
shaded by the Taxim authors' table of the real GelSight, the F/T log the schedule's force
with an ATI-class sensor's noise."""

from __future__ import annotations

import json
import shutil

import cv2
import numpy as np
import pytest
from scipy.optimize import brentq

from tactilevision import InputError
from tactilevision.cli import main
from tactilevision.io import read_measurements, read_session
from tactilevision.pipeline import calibrate_ball_session, calibrate_session
from tactilevision.sim import taxim_shading
from tactilevision.sim._schedule import depth_trajectory, ft_log, press_schedule

R, H, PAD, E = 2.0, 100.0, 1000.0, 1.0     # ball, thick gel, its pad (mm), modulus (MPa)
A_TRUE = np.linspace(0.6, 1.2, 4)          # contact radii of the four depths, mm
FPS = 20.0


def sneddon(a):
    """Depth (mm) and force (N) of a rigid sphere at contact radius a on the half-space,
    nu = 0.5, times the layer's first-order term 1 + 1.133 sqrt(R w)/h (Dimitriadis et al.,
    Biophys. J. 82:2798, 2002; 1.5 % at most here)."""
    a = np.asarray(a, np.float64)
    lg = np.log((R + a) / (R - a))
    w = 0.5 * a * lg
    P = 0.5 * E / 0.75 * ((a * a + R * R) * lg - 2 * a * R)
    return w, P * (1 + 1.133 * np.sqrt(R * w) / H)


def contact_radius(w: float) -> float:
    """Sneddon's a at depth w (the inverse of :func:`sneddon`'s w(a))."""
    return brentq(lambda a: float(sneddon(a)[0]) - w, 1e-9, R * (1 - 1e-9), xtol=1e-13)


def surface(shape, centre, a, mm_per_px):
    """The gel's surface, mm into the gel: the ball's cap inside a, Hertz's sink-in outside,
    scaled to meet the cap at a."""
    rows, cols = np.indices(shape, dtype=np.float64)
    r = np.hypot(cols - centre[0], rows - centre[1]) * mm_per_px
    w = float(sneddon(a)[0])
    edge = w - (R - np.sqrt(R * R - a * a))
    out = np.empty(shape)
    inside = r < a
    out[inside] = w - (R - np.sqrt(R * R - r[inside] ** 2))
    ro = r[~inside]
    out[~inside] = edge * ((2 * a * a - ro ** 2) * np.arcsin(a / ro)
                           + a * np.sqrt(ro ** 2 - a * a)) / (np.pi * a * a / 2)
    return out


def make_ball_session(folder, *, seed: int = 3, clock_offset_s: float = 0.05):
    """Write a ball session: 8 presses (4 depths x 2) at 20 frames/s, F/T at 1 kHz."""
    table, ref = taxim_shading("gelsight")
    s = table.mm_per_px
    w_true = sneddon(A_TRUE)[0]
    sched = press_schedule(tuple(w_true), repeats=2, position_radius_mm=2.5,
                           wait_s=(0.5, 0.8), approach_s=0.3, hold_s=0.8, release_s=0.3,
                           start_s=0.5, seed=seed)
    duration = float(sched.t_start_s[-1] + 1.6)
    times = np.arange(0.0, duration, 1.0 / FPS)
    depth, press = depth_trajectory(sched, times)
    rng = np.random.default_rng(seed)
    (folder / "frames").mkdir(parents=True)
    cx, cy = (table.shape[1] - 1) / 2, (table.shape[0] - 1) / 2
    rows = ["frame,t_s"]
    for i, (t, w, k) in enumerate(zip(times, depth, press, strict=True)):
        if w > 0:
            centre = (cx + sched.x_mm[k] / s, cy + sched.y_mm[k] / s)
            height = surface(table.shape, centre, contact_radius(float(w)), s)
        else:
            height = np.zeros(table.shape)
        name = f"{i:05d}.png"
        cv2.imwrite(str(folder / "frames" / name),
                    table.render(height, ref, noise_dn=2.0, rng=rng))
        rows.append(f"{name},{t:.6f}")
    cv2.imwrite(str(folder / "reference.png"), ref)
    (folder / "frames.csv").write_text("\n".join(rows) + "\n")
    t_ft, f = ft_log(sched, lambda i, w: sneddon(np.array([contact_radius(float(x)) if x > 0
                                                           else 0.0 for x in w]))[1],
                     duration_s=duration, clock_offset_s=clock_offset_s, seed=seed)
    np.savetxt(folder / "forces.csv", np.column_stack([t_ft, f]), delimiter=",", fmt="%.6f",
               header="t_s,fx_n,fy_n,fz_n", comments="")
    (folder / "session.toml").write_text(
        f'[sensor]\nname = "gelsight"\nmm_per_px = {s}\ngel_thickness_mm = {H}\n'
        f'gel_radius_mm = {PAD}\n\n[indenter]\nradius_mm = {R}\nshape = "sphere"\n'
        f'contact = "frictionless"\n\n[force_sensor]\nrate_hz = 1000\nwindow_samples = 200\n')
    return sched


@pytest.fixture(scope="module")
def ball_session(tmp_path_factory):
    folder = tmp_path_factory.mktemp("ball") / "session"
    sched = make_ball_session(folder)
    return folder, sched


@pytest.fixture(scope="module")
def calibrated(ball_session):
    folder, sched = ball_session
    return calibrate_ball_session(folder, nu=0.5, law="linear"), sched


def test_every_press_found_with_its_force(calibrated):
    """The eight presses, each hold's force the closed form's at its depth (F/T noise
    1/80 N over 200 samples: the window's mean within 5 mN), the clock found."""
    cal, sched = calibrated
    assert len(cal.used) == sched.n_presses == 8 and not cal.rejected
    order = np.argsort([cal.presses.presses[i].t_frame_s for i in cal.used])
    P_true = sneddon(np.array([contact_radius(w) for w in sched.depth_mm]))[1]
    assert np.allclose(cal.force_n[order], P_true, atol=5e-3)
    assert abs(cal.presses.clock_offset_s - 0.05) < 0.02


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


def test_cli_calibrate_writes_a_table_fit_reads_back(ball_session, tmp_path, capsys):
    """`calibrate` of a ball session writes measurements.csv with its sphere sidecar and
    the shared depth error; `fit` of that table gives the same E and interval."""
    folder, _ = ball_session
    out = tmp_path / "cal"
    assert main(["calibrate", str(folder), "--out", str(out), "--law", "linear",
                 "--no-progress", "--json", str(tmp_path / "fit.json")]) == 0
    text = capsys.readouterr().out
    assert "contact circles" in text and "8 presses fitted" in text
    obj = json.loads((out / "fit.json").read_text())
    table = read_measurements(out / "measurements.csv")
    assert table.indenter["shape"] == "sphere" and "depth_shared_mm" not in table.covariates
    assert len(table) == 8 and (out / "circles.csv").read_text().count("\n") == 9
    assert main(["fit", str(out / "measurements.csv"), "--law", "linear", "--nu", "0.5",
                 "--json", str(tmp_path / "refit.json")]) == 0
    refit = json.loads((tmp_path / "refit.json").read_text())
    assert refit["E_mpa"] == pytest.approx(obj["E_mpa"], rel=1e-3)
    assert refit["E_ci95_mpa"][1] == pytest.approx(obj["E_ci95_mpa"][1], rel=1e-2)


def test_a_ball_session_is_not_a_gauge_blocks(ball_session):
    folder, _ = ball_session
    with pytest.raises(InputError, match="calibrate_ball_session"):
        calibrate_session(read_session(folder))


def test_bad_ball_sessions_refused_naming_the_key(ball_session, tmp_path):
    folder, _ = ball_session
    bad = tmp_path / "bad"
    shutil.copytree(folder, bad)
    toml = (bad / "session.toml").read_text()
    (bad / "session.toml").write_text(toml.replace('shape = "sphere"', 'shape = "ball"'))
    with pytest.raises(InputError, match=r"\[indenter\] shape must be"):
        read_session(bad)
    (bad / "session.toml").write_text(toml.replace("radius_mm = 2.0", "radius_mm = -2.0"))
    with pytest.raises(InputError, match="radius_mm"):
        calibrate_ball_session(bad)
    # a ball smaller than its circles: every press refused by its circle, nothing to fit
    (bad / "session.toml").write_text(toml.replace("radius_mm = 2.0", "radius_mm = 0.5"))
    with pytest.raises(InputError, match="too few to fit"):
        calibrate_ball_session(bad, law="linear")
