"""The main job end to end: ``tactilevision calibrate`` on simulated sessions with known truth.

The bundled sample session (sample_frames/gelsight_session, rendered through
Taxim's GelSight shading on the real reference frame; truth.json) is run once
through the command line; smaller sessions rendered on the fly test a wrong
clock offset in session.toml, a misaligned press and a press at the pad edge.
"""

from __future__ import annotations

import csv
import json
import shutil
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from tactilevision import InputError, InputWarning, calibrate_session
from tactilevision.cli import main
from tactilevision.contact import certify_session
from tactilevision.io import COLUMN_ORDER, read_measurements, read_presses, read_session
from tactilevision.mechanics import fit_indentation
from tactilevision.pipeline import (
    CalibrationResult,
    DepthState,
    Fitter,
    read_material,
    result_dict,
    take_off_zero,
    vernier_rule,
    with_shared_depth,
)
from tactilevision.planning import Design, crossing_table, measured_bracket_periods

SAMPLE = Path(__file__).resolve().parents[1] / "sample_frames" / "gelsight_session"


#: What the report's figures plotted: (axes, x, y) of every errorbar call (the sample run).
PLOTTED: list = []


@pytest.fixture(scope="module")
def sample_run(tmp_path_factory):
    from matplotlib.axes import Axes

    out = tmp_path_factory.mktemp("calibrate")
    errorbar = Axes.errorbar

    def record(ax, x, y, *args, **kwargs):
        PLOTTED.append((ax, np.array(x, float), np.array(y, float)))
        return errorbar(ax, x, y, *args, **kwargs)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(Axes, "errorbar", record)
        status = main(["calibrate", str(SAMPLE), "--out", str(out / "report"), "--json",
                       str(out / "result.json"), "--no-progress"])
    assert status == 0
    truth = json.loads((SAMPLE / "truth.json").read_text())
    return out, truth


@pytest.mark.slow
def test_figures_show_the_forces_the_fit_used(sample_run):
    """The residual plot's points are the fit's residuals (issue 39: it showed the F/T
    window's mean before the bevel's band was taken off, nearly every point above zero):
    its mean residual equals the fit's within 1 mN, and the force-depth plot shows the
    table's force_n, the force the fit used."""
    out, _ = sample_run
    fit = json.loads((out / "report" / "fit.json").read_text())
    table = read_measurements(out / "report" / "measurements.csv")
    w, p = table.columns["depth_mm"], table.columns["force_n"]
    model = w * fit["c_n_per_mm"] * (1 + fit["beta"] * w / table.thickness_mm)
    fit_res = p - model
    assert np.sqrt(np.mean(fit_res ** 2)) == pytest.approx(fit["rmse_n"], rel=1e-3)
    (res,) = [y for ax, _, y in PLOTTED if ax.get_ylabel() == "P - model (N)"]
    assert abs(np.mean(res) - np.mean(fit_res)) < 1e-3
    assert np.sqrt(np.mean(res ** 2)) == pytest.approx(fit["rmse_n"], rel=1e-3)
    shown = np.concatenate([y for ax, _, y in PLOTTED if ax.get_ylabel().startswith("force P")])
    assert np.sort(shown) == pytest.approx(np.sort(p), abs=1e-5)   # the table has 6 decimals
    html = (out / "report" / "report.html").read_text()
    assert "force P fitted (N)" in html and "less the bevel" in html


def test_sample_session_is_small_and_complete():
    size = sum(p.stat().st_size for p in SAMPLE.rglob("*") if p.is_file())
    assert size < 20e6
    for name in ("session.toml", "reference.png", "frames.csv", "forces.csv", "presses.csv",
                 "truth.json", "make_session.py", "README.md", "LICENSE", "optics.npz"):
        assert (SAMPLE / name).is_file(), name
    truth = json.loads((SAMPLE / "truth.json").read_text())
    assert len(truth["presses"]) == 50
    assert {p["indenter"] for p in truth["presses"]} == {0, 1, 2, 3, 4}


def test_report_folder(sample_run):
    out, _ = sample_run
    rep = out / "report"
    for name in ("measurements.csv", "session.toml", "fit.json", "rejected.csv", "report.html",
                 "force_depth.png", "stiffness_line.png", "residuals.png", "mosaic.png",
                 "bevel.png"):
        assert (rep / name).is_file(), name
    html = (rep / "report.html").read_text()
    assert "E = " in html and "misaligned" in html and "mosaic.png" in html
    assert "bevel.png" in html and "Certified presses" in html and "vernier" in html
    assert json.loads((out / "result.json").read_text()) == json.loads(
        (rep / "fit.json").read_text())


def test_readme_prints_what_calibrate_prints(sample_run):
    """The README's set-up shows calibrate's result on the sample session: the same
    presses certified and rejected, and E and nu with their intervals to the printed
    digits."""
    import re

    out, _ = sample_run
    fit = json.loads((out / "report" / "fit.json").read_text())
    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    n_cert, n_rej = (int(x) for x in re.search(
        r"(\d+) presses certified, (\d+) rejected", readme).groups())
    assert (n_cert, n_rej) == (fit["n_presses"], fit["n_rejected"])
    for name, key, ci in (("E ", "E_mpa", "E_ci95_mpa"), ("nu", "nu", "nu_ci95")):
        v, lo, hi = (float(x) for x in re.search(
            rf"^\s*{name} = ([\d.]+) .*95% CI \[([\d.]+), ([\d.]+)\]", readme, re.M).groups())
        assert f"{fit[key]:.4f}" == f"{v:.4f}", name
        assert [f"{x:.4f}" for x in fit[ci]] == [f"{lo:.4f}", f"{hi:.4f}"], name


def test_certified_depths_and_forces(sample_run):
    """The vernier's certified depths against the truth (a stage overshoot of 0 to 50 um
    past w0): at least 95% of the presses in view certified, every depth within 10 um, mean
    error within 2 um and sd under 3 um (the issue's targets), the stated uncertainties
    honest to a factor of two; forces within 0.01 N (the F/T window's own scatter is
    1/80 N / sqrt(200) = 0.9 mN)."""

    out, truth = sample_run
    tp = {p["press"]: p for p in truth["presses"]}
    with open(out / "report" / "measurements.csv") as fh:
        rows = list(csv.DictReader(fh))
    good = [p for p in truth["presses"] if not p["misaligned"] and not p["edge"]]
    assert len(rows) >= 0.95 * len(good)
    assert list(rows[0].keys()) == [c for c in COLUMN_ORDER if c in rows[0]]
    for col in ("press", "indenter", "depth_mm", "depth_std_mm", "overshoot_mm", "force_n",
                "force_std_n", "force_sem_n", "fx_n", "fy_n", "time_s", "hold_s", "wait_s",
                "x_mm", "y_mm"):
        assert col in rows[0], col
    # the session's F/T noise is white (1/80 N, 200 samples): the window mean's standard
    # error is the sd over sqrt(200), 0.88 mN (measured: median 0.91, 0.80 to 1.29 mN; the
    # autocorrelation estimate has its own sampling error)
    sem = np.array([float(r["force_sem_n"]) for r in rows])
    assert np.median(sem) == pytest.approx(1 / 80 / np.sqrt(200), rel=0.15)
    assert np.all((sem > 0.5e-3) & (sem < 1.6e-3)), sem
    err, z = [], []
    for r in rows:
        t = tp[int(r["press"])]
        assert int(r["indenter"]) == t["indenter"]
        assert abs(float(r["depth_mm"]) - t["depth_mm"]) < 0.010
        assert float(r["overshoot_mm"]) == pytest.approx(float(r["depth_mm"]) - t["w0_mm"],
                                                         abs=1e-6)
        assert abs(float(r["force_n"]) - t["force_n"]) < 0.01
        assert abs(float(r["x_mm"]) - t["x_mm"]) < 0.05
        assert abs(float(r["y_mm"]) - t["y_mm"]) < 0.05
        err.append(float(r["depth_mm"]) - t["depth_mm"])
        z.append(err[-1] / float(r["depth_std_mm"]))
    assert abs(np.mean(err)) < 0.002 and np.std(err) < 0.003
    assert 0.5 < np.std(z) < 2.0
    table = read_measurements(out / "report" / "measurements.csv")
    assert table.thickness_mm == 3.0 and table.radius_mm == 2.5


def test_holds_csv_has_each_press_force_over_its_hold(sample_run):
    """holds.csv: every certified press, from its arrival at depth to its release. The
    sample session's stage holds each press 0.5 s (README of the session): every hold
    found lasts 0.45 to 0.55 s (measured 0.494 to 0.499), and its mean force is the
    press's true force to 3 % (measured +0.1 to +2.5 %: the bevel's own band is not taken
    off here). Each press's loading time is the stage's 0.5 s approach to 20 ms. The gel
    does not relax (the session's forces are elastic): the relaxation fit finds nothing,
    and E stays the one fitted to the measured forces."""
    import numpy as np

    out, truth = sample_run
    rep = out / "report"
    with open(rep / "holds.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert list(rows[0]) == ["press", "t_s", "fz_n", "ramp_s"]
    press = np.array([int(r["press"]) for r in rows])
    t = np.array([float(r["t_s"]) for r in rows])
    fz = np.array([float(r["fz_n"]) for r in rows])
    ramp = np.array([float(r["ramp_s"]) for r in rows])
    np.testing.assert_allclose(ramp, 0.5, atol=0.02)
    res = json.loads((out / "result.json").read_text())
    assert res["relaxation"]["resolved"] is False and "E0_mpa" not in res["relaxation"]
    with open(rep / "measurements.csv") as fh:
        certified = {int(r["press"]) for r in csv.DictReader(fh)}
    assert set(press.tolist()) == certified
    tp = {p["press"]: p for p in truth["presses"]}
    for k in certified:
        tk = t[press == k]
        assert tk.min() < 0.002 and 0.45 < tk.max() < 0.55, (k, tk.max())
        assert np.all(np.diff(tk) > 0)
        assert np.mean(fz[press == k]) == pytest.approx(tp[k]["force_n"], rel=0.03)


def test_E_and_nu(sample_run):
    """E and nu within two of their predicted sds of the truth, and inside their intervals.
    The sds are what ``tactilevision plan`` predicts for this session's design with the
    certified depths' measured 1.8 um sd (``plan --from-calibration``, ``depth_std_um =
    1.8``): E 6.1 %, nu 0.015; this session reads E +8.3 %, nu -0.019 (its certified
    depths +1.8 um on average; the true depths with its forces give E +2.0 %)."""
    out, truth = sample_run
    res = json.loads((out / "result.json").read_text())
    assert res["E_mpa"] == pytest.approx(truth["E_mpa"], rel=0.12)
    assert res["nu"] == pytest.approx(truth["nu"], abs=0.03)
    assert res["E_ci95_mpa"][0] < truth["E_mpa"] < res["E_ci95_mpa"][1] or \
        abs(res["E_mpa"] / truth["E_mpa"] - 1) < 0.01
    assert res["clock_offset_s"] == pytest.approx(truth["clock_offset_s"], abs=0.003)
    assert res["clock_source"] == "estimated"
    assert res["depth_rule"] == "vernier"
    assert res["nu_ci95"][0] < truth["nu"] < res["nu_ci95"][1]
    assert res["depth_std_used"] is True


def test_rejections_have_reasons(sample_run):
    out, truth = sample_run
    res = json.loads((out / "result.json").read_text())
    reasons = {r["press"]: r["reason"] for r in res["rejected"]}
    mis = [p["press"] for p in truth["presses"] if p["misaligned"]]
    edge = [p["press"] for p in truth["presses"] if p["edge"]]
    assert all(reasons.get(i) == "misaligned" for i in mis) and mis
    assert all(reasons.get(i) == "footprint cut by the pad edge" for i in edge) and edge
    # a band seen above the threshold whose frames disagree on its width: the deciding
    # reason comes first, and the ratio that passed is not presented as the failure
    for r in res["rejected"]:
        if r["reason"] == "bevel band unsteady":
            assert r["detail"].startswith("the frames of the hold disagree on the width")
            assert f"{r['bevel_snr']:.1f}, passes the threshold" in r["detail"]
        if r["reason"] == "bevel never seen":
            ratio = float(r["detail"].split("signal-to-noise ratio ")[1].split(",")[0])
            assert ratio < float(r["detail"].split("threshold ")[1].split(";")[0].rstrip(")"))
    with open(out / "report" / "rejected.csv") as fh:
        assert next(csv.reader(fh)) == ["press", "reason", "detail", "t_frame_s", "bevel_snr"]
    with open(out / "report" / "measurements.csv") as fh:
        certified = {int(r["press"]) for r in csv.DictReader(fh)}
    assert certified | set(reasons) == set(range(len(truth["presses"])))
    assert not certified & set(reasons)


# ---------------------------------------------------------------- scenarios


@pytest.fixture(scope="module")
def scenario(tmp_path_factory):
    """Ten presses (two per indenter): press 2 misaligned, press 5 at the pad
    edge, and session.toml stating a clock offset 0.4 s off the truth."""
    pytest.importorskip("taxim")
    from tactilevision.sim import SessionSpec, make_session, press_profile

    folder = tmp_path_factory.mktemp("scenario") / "session"
    prof = press_profile(2.5 / 3, 0.47, w_over_h_max=0.22, steps=8, cell=0.5,
                         edge_refinements=5)
    spec = SessionSpec(E_mpa=0.15, nu=0.47, repeats=2, clock_offset_s=-0.21,
                       config_clock_offset_s=0.19, misaligned=(2,), edge_presses=(5,), seed=7,
                       overshoot_mm=(0.005, 0.045))
    truth = make_session(folder, spec, profile=prof)
    return folder, truth


@pytest.mark.slow
def test_scenario_session(scenario):
    folder, truth = scenario
    cal = calibrate_session(folder)
    c = cal.certification
    assert c.clock_source == "estimated"
    assert c.clock_offset_s == pytest.approx(-0.21, abs=0.005)
    assert any("clock_offset_s = 0.19" in w for w in cal.warnings)
    reasons = {r.press: r.reason for r in c.rejected}
    assert reasons.get(2) == "misaligned"
    assert reasons.get(5) == "footprint cut by the pad edge"
    tp = {p["press"]: p for p in truth["presses"]}
    assert len(c.presses) >= 7
    m = cal.measurements()             # force_n: the F/T's less the bevel band's own
    for p, d, f in zip(c.presses, cal.depth_mm, m["force_n"], strict=True):
        assert abs(d - tp[p.press]["depth_mm"]) < 0.010
        assert abs(f - tp[p.press]["force_n"]) < 0.01


def test_correct_clock_offset_is_kept(scenario, tmp_path):
    folder, _ = scenario
    copy = tmp_path / "s"
    shutil.copytree(folder, copy)
    toml = copy / "session.toml"
    toml.write_text(toml.read_text().replace("clock_offset_s = 0.19", "clock_offset_s = -0.2105"))
    from tactilevision.contact import certify_session
    from tactilevision.io import read_session

    c = certify_session(read_session(copy))
    assert c.clock_source == "session.toml" and c.clock_offset_s == -0.2105
    assert not c.warnings


def test_bad_sessions(scenario, tmp_path, capsys):
    folder, _ = scenario
    broken = tmp_path / "broken"
    shutil.copytree(folder, broken)
    (broken / "forces.csv").unlink()
    out = tmp_path / "out"
    assert main(["calibrate", str(broken), "--out", str(out), "--no-progress"]) == 2
    assert "forces.csv" in capsys.readouterr().err
    assert not out.exists()
    # frames without any press
    empty = tmp_path / "empty"
    shutil.copytree(folder, empty)
    frames = sorted((empty / "frames").iterdir())
    for f in frames:
        shutil.copy(folder / "frames" / frames[0].name, f)
    with pytest.raises(InputError, match="no press found"):
        calibrate_session(empty)


@pytest.mark.slow
def test_saturated_and_unseen_bevel_are_rejected(scenario, tmp_path):
    """Over-exposed frames of one press, and a bevel looked for on the wrong side."""
    import cv2

    from tactilevision.contact import certify_session
    from tactilevision.io import read_session

    folder, truth = scenario
    copy = tmp_path / "s"
    shutil.copytree(folder, copy)
    p = truth["presses"][0]
    session = read_session(copy)
    t0, t1 = p["t_start_s"], p["t_start_s"] + 1.25
    cx = p["x_mm"] / session.config.mm_per_px + (session.shape[1] - 1) / 2
    cy = p["y_mm"] / session.config.mm_per_px + (session.shape[0] - 1) / 2
    for path, t in zip(session.frame_paths, session.frame_times_s, strict=True):
        if t0 <= t <= t1:
            img = cv2.imread(str(path))
            img[int(cy) - 60:int(cy) + 60, int(cx) - 60:int(cx) + 60, 1] = 255
            cv2.imwrite(str(path), img, [cv2.IMWRITE_JPEG_QUALITY, 100])
    c = certify_session(read_session(copy))
    assert {r.press: r.reason for r in c.rejected}.get(0) == "saturated frames"
    toml = copy / "session.toml"
    toml.write_text(toml.read_text().replace("bevel_direction_deg = 0.0",
                                             "bevel_direction_deg = 90.0"))
    c = certify_session(read_session(copy))
    reasons = {r.press: r.reason for r in c.rejected}
    assert not c.presses
    assert sum(r in ("bevel never seen", "bevel out of view") for r in reasons.values()) >= 6
    assert all(r.bevel_score == r.bevel_score for r in c.rejected
               if r.reason == "bevel never seen")          # never NaN
    # the message states the rule applied, not a bare threshold
    assert all("the rule: two consecutive frames above 12, or one above 24" in r.detail
               or "threshold" in r.detail for r in c.rejected if r.reason == "bevel never seen")


def test_nothing_is_lost_when_every_press_is_rejected(scenario, tmp_path, capsys):
    """Every press rejected (the bevel looked for on the wrong side): exit 2 with one
    sentence, and rejected.csv (each press, its reason and best bevel SNR), the bevel
    panels and report.html saying why are written; no fit.json."""
    folder, truth = scenario
    copy = tmp_path / "s"
    shutil.copytree(folder, copy)
    toml = copy / "session.toml"
    toml.write_text(toml.read_text().replace("bevel_direction_deg = 0.0",
                                             "bevel_direction_deg = 180.0"))
    out = tmp_path / "out"
    assert main(["calibrate", str(copy), "--out", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "too few to fit" in err and "rejected.csv" in err and str(out) in err
    assert err.count("\n") == 1
    with open(out / "rejected.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert {int(r["press"]) for r in rows} == set(range(len(truth["presses"])))
    assert any(r["reason"] in ("bevel out of view", "bevel never seen") for r in rows)
    html = (out / "report.html").read_text()
    assert "Nothing was fitted" in html and "bevel.png" in html
    assert (out / "bevel.png").is_file() and not (out / "fit.json").exists()


@pytest.mark.slow
def test_onset_rule_without_a_vernier(tmp_path):
    """A bevel mark with no vernier (bevel_angle_deg = 0, the stage stopping at w0): the
    default 'mark' rule reads w0 plus the force's rise past the crossing (none here: within
    its stated uncertainty of w0); the paper's 'nominal' rule, w = w0, with the uncertainty
    of one frame's travel / sqrt(12)."""
    pytest.importorskip("taxim")
    import numpy as np

    from tactilevision.sim import GaugeBlock, SessionSpec, make_session, press_profile

    prof = press_profile(2.5 / 3, 0.48, w_over_h_max=0.22, steps=8, cell=0.5,
                         edge_refinements=5)
    block = GaugeBlock(depths_mm=(0.15, 0.5), bevel_angle_deg=0.0, bevel_offset_mm=4.5,
                       bevel_length_mm=2.4)
    spec = SessionSpec(block=block, repeats=2, x_range_mm=(-5.0, 2.5), y_range_mm=(-3.0, 3.0),
                       seed=4)
    truth = make_session(tmp_path / "s", spec, profile=prof)
    mark = calibrate_session(tmp_path / "s")
    assert mark.depth_rule == "mark"
    tp = {p["press"]: p for p in truth["presses"]}
    for p, d, sd in zip(mark.certification.presses, mark.depth_mm, mark.depth_std_mm,
                        strict=True):
        # the crossing, taken as uniform over the frame period before the onset (up to the
        # stop), lies here at the stop: the depth within 3 of its stated sd
        assert abs(d - tp[p.press]["depth_mm"]) < 3 * sd
    # the command line writes the report for the default rule on a mark session too
    from tactilevision.cli import main

    assert main(["calibrate", str(tmp_path / "s"), "--out", str(tmp_path / "mark_out"),
                 "--no-progress"]) == 0
    html = (tmp_path / "mark_out" / "report.html").read_text()
    assert "what the force says the stage went on by past it" in html
    cal = calibrate_session(tmp_path / "s", depth_rule="nominal")
    assert cal.depth_rule == "nominal"
    assert len(cal.certification.presses) >= 3
    for p, d, sd in zip(cal.certification.presses, cal.depth_mm, cal.depth_std_mm, strict=True):
        assert p.rule == "onset" and d == p.w0_mm == tp[p.press]["depth_mm"]
        # the stage covers w0 in the 0.5 s approach; one 0.1 s frame / sqrt(12)
        speed = p.w0_mm / 0.5
        assert sd == pytest.approx(speed * 0.1 / np.sqrt(12), rel=0.35)
        assert p.travel_mm == pytest.approx(speed * 0.1, rel=0.35)
    with pytest.raises(InputError, match="'mark' depth rule is for a bevel mark"):
        calibrate_session(SAMPLE, depth_rule="mark")
    with pytest.raises(InputError, match="needs a machined bevel"):
        calibrate_session(tmp_path / "s", depth_rule="vernier")
    # the mark's threshold is the caller's: one no frame reaches certifies nothing, and the
    # rejections state it; a threshold that is no positive number is refused before any work
    high = calibrate_session(tmp_path / "s", bevel_threshold=1e4, allow_failure=True)
    assert high.fit is None and high.certification.rejected
    assert all(r.reason == "bevel never seen" and "two consecutive frames above 10000" in r.detail
               for r in high.certification.rejected)
    for bad in (0, -1.0, float("nan"), True, "12"):
        with pytest.raises(InputError, match="bevel_threshold must be a positive number"):
            calibrate_session(tmp_path / "s", bevel_threshold=bad)
    from tactilevision.cli import main

    assert main(["calibrate", str(tmp_path / "s"), "--bevel-threshold", "0", "--no-report",
                 "--out", str(tmp_path / "o")]) == 2
    assert not (tmp_path / "o" / "measurements.csv").exists()
    # the mark looked for on the wrong side: rejected, the message stating the rule applied
    from tactilevision.contact import certify_session
    from tactilevision.io import read_session

    toml = tmp_path / "s" / "session.toml"
    assert "bevel_direction_deg = 0.0" in toml.read_text()
    toml.write_text(toml.read_text().replace("bevel_direction_deg = 0.0",
                                             "bevel_direction_deg = 90.0"))
    c = certify_session(read_session(tmp_path / "s"))
    never = [r for r in c.rejected if r.reason == "bevel never seen"]
    assert never and all("the rule from the session's own frames" in r.detail for r in never)
    assert c.mark_rule["rule"] == "auto" and c.mark_rule["n_frames"] >= 10
    fixed = certify_session(read_session(tmp_path / "s"), bevel_threshold=12.0)
    never = [r for r in fixed.rejected if r.reason == "bevel never seen"]
    assert never and all("the rule: two consecutive frames above 12, or one above 24"
                         in r.detail for r in never)


@pytest.mark.slow
def test_mark_overshoot_read_from_the_force(tmp_path):
    """Issue 39: a mark session whose stage overshoots w0 by 5 to 60 um (30 frames/s, 10
    presses): the paper's w = w0 is 37 um short on average, and E's interval must not
    exclude the truth. The 'mark' rule reads each press's depth past w0 from the force
    between the crossing (each indenter's P(w0), bracketed by the frame period before the
    mark first shows on each of its presses) and the force window: each depth consistent
    with its window's force (the FEM truth's P(w) there) within 3 stated sd; E and nu
    inside their intervals, which carry the shared part (the clock, dP/dw) and say so."""
    pytest.importorskip("taxim")
    from scipy.interpolate import PchipInterpolator

    from tactilevision.sim import GaugeBlock, SessionSpec, make_session, press_profile

    prof = press_profile(2.5 / 3, 0.48, w_over_h_max=0.23, steps=8, cell=0.5,
                         edge_refinements=5)
    spec = SessionSpec(block=GaugeBlock(bevel_angle_deg=0.0), repeats=2, fps=30.0,
                       overshoot_mm=(0.005, 0.060), seed=7)
    truth = make_session(tmp_path / "s", spec, profile=prof)
    cal = calibrate_session(tmp_path / "s")
    ps = cal.certification.presses
    assert cal.depth_rule == "mark" and len(ps) >= 9
    # the depth whose FEM force is the window's (the window may start before the stage stops)
    e_h2 = truth["E_mpa"] * 3.0 ** 2
    w_of_p = PchipInterpolator(prof.force * e_h2, prof.w_over_h * 3.0)
    # each depth's stated sd is its indenter's P(w0) error times sqrt(n) of its n presses
    # (shared by them: crossing_forces), and the window's: the error against sd / sqrt(n)
    n_of = {k: sum(p.indenter == k for p in ps) for k in {p.indenter for p in ps}}
    z = []
    for p, d, sd in zip(ps, cal.depth_mm, cal.depth_std_mm, strict=True):
        assert p.travel_mm > 0 and np.isfinite(p.force_onset_n)
        z.append((d - float(w_of_p(p.force_n))) / (sd / np.sqrt(n_of[p.indenter])))
    z = np.array(z)
    assert np.all(np.abs(z) < 3) and 0.3 < np.std(z) < 1.6, z
    # the shared part is written apart (the noise budget leaves it out of the scatter
    # within an indenter's presses): part of each depth's sd, positive where read
    cols = cal.measurements()
    shared = np.array(cols["depth_indenter_std_mm"])
    assert np.all(shared > 0) and np.all(shared <= np.array(cols["depth_std_mm"]) + 1e-12)
    # plan reads the frame periods these brackets spanned from their widths alone: the
    # spans the certification bracketed (onset_span_s, in frame periods), weighted by
    # each press's frame travel times dP/dw as the widths are, within 10 %
    design = Design(thickness_mm=3.0, radius_mm=2.5, depths_mm=spec.block.depths_mm,
                    repeats=2, E_mpa=truth["E_mpa"], nu=truth["nu"], frame_rate_hz=30.0,
                    approach_s=0.5, overshoot_um=(5.0, 60.0), force_noise_n=1 / 80)
    w0 = np.array([spec.block.depths_mm[p.indenter] for p in ps])
    got = measured_bracket_periods(design, w0, np.array(cols["force_w0_sem_n"]))
    span = np.array([30.0 * (p.onset_span_s[1] - p.onset_span_s[0]) for p in ps])
    one = crossing_table(replace(design, force_noise_n=0.0, bracket_periods=1.0))
    unit = {int(i): u for i, u in zip(one["indenter"], one["force_w0_sem_n"], strict=True)}
    want = np.average(span, weights=[unit[p.indenter] for p in ps])
    assert np.all(np.isclose(span, 1.0, atol=1e-3) | np.isclose(span, 2.0, atol=1e-3))
    # (a faint frame's period joins a bracket only where it rises 3 sds off the approach
    # and the frames before it, issue 83: on this session every bracket spans one period)
    assert 0.999 <= want <= 2.0
    assert got == pytest.approx(want, rel=0.10), (got, want)
    f = cal.fit
    assert f.E_ci95_mpa[0] <= truth["E_mpa"] <= f.E_ci95_mpa[1]
    assert f.nu_ci95[0] <= truth["nu"] <= f.nu_ci95[1]
    assert any(n.startswith("shared depth error") for n in f.notes)
    assert any("depth rule 'mark'" in w for w in cal.warnings)
    # a depth counts as certified within [gauge_block] depth_tolerance_mm at 95 %: its own
    # sd (the indenter's shared part once) and the shared bound as a uniform's
    own = np.sqrt(np.maximum(cal.depth_std_mm ** 2 - shared ** 2 * (1 - 1 / np.array(
        [n_of[p.indenter] for p in ps])), 0.0))
    assert np.all(cal.depth_half95_mm >= 1.96 * own - 1e-12)
    assert cal.depth_certified.tolist() == (cal.depth_half95_mm <= 0.02).tolist()
    obj = result_dict(cal)
    assert obj["depth_tolerance_mm"] == 0.02
    assert obj["depth_bounded"] == [p.press for p, ok in zip(ps, cal.depth_certified,
                                                              strict=True) if not ok]
    nominal = calibrate_session(tmp_path / "s", depth_rule="nominal", allow_failure=True)
    over = np.array([tp["overshoot_mm"] for tp in truth["presses"]])
    assert over.mean() > 0.02
    assert any("w = w0 leaves out" in w for w in nominal.warnings)


@pytest.mark.slow
def test_faint_mark_seen_with_the_sessions_own_threshold(tmp_path):
    """Issue 39: a mark that shows in every press but scores under the fixed threshold of
    12 was rejected. A faint drawn mark (a 10 um line, 30 frames/s, 10 presses): the fixed
    rule certifies at most 6 and finds two of them 0.2 s late; the threshold from the
    session's own frames (no-contact frames' noise, each press's approach as its baseline)
    certifies all 10, each onset within one frame after the land reached w0 (5 ms
    before it at most: the frame's own timing)."""
    pytest.importorskip("taxim")
    from tactilevision.sim import GaugeBlock, SessionSpec, make_session, press_profile

    prof = press_profile(2.5 / 3, 0.48, w_over_h_max=0.23, steps=8, cell=0.5,
                         edge_refinements=5)
    spec = SessionSpec(block=GaugeBlock(bevel_angle_deg=0.0, bevel_depth_mm=0.01), repeats=2,
                       fps=30.0, overshoot_mm=(0.005, 0.060), seed=9)
    truth = make_session(tmp_path / "s", spec, profile=prof)
    tp = {p["press"]: p for p in truth["presses"]}

    def lags(c):
        return np.array([p.t_frame_s - (tp[p.press]["t_start_s"] + 0.5 * tp[p.press]["w0_mm"]
                                        / tp[p.press]["depth_mm"]) for p in c.presses])

    fixed = certify_session(read_session(tmp_path / "s"), bevel_threshold=12.0)
    auto = certify_session(read_session(tmp_path / "s"))
    assert len(fixed.presses) <= 6 and np.max(lags(fixed)) > 0.1
    assert len(auto.presses) == 10 and auto.mark_rule["rule"] == "auto"
    assert np.all((lags(auto) > -0.006) & (lags(auto) < 1 / 30 + 1e-3)), lags(auto)
    assert any(w.startswith("bevel mark seen from the session's own frames")
               for w in auto.warnings)


@pytest.mark.slow
def test_make_session_is_deterministic(tmp_path):
    pytest.importorskip("taxim")
    from tactilevision.sim import GaugeBlock, SessionSpec, make_session, press_profile

    prof = press_profile(2.5 / 3, 0.48, w_over_h_max=0.22, steps=8, cell=0.5,
                         edge_refinements=5)
    spec = SessionSpec(block=GaugeBlock(depths_mm=(0.3,)), repeats=2, seed=11)
    a = make_session(tmp_path / "a", spec, profile=prof)
    b = make_session(tmp_path / "b", spec, profile=prof)
    assert a == b
    for name in ("forces.csv", "frames.csv", "presses.csv", "session.toml"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
    frames = sorted((tmp_path / "a" / "frames").iterdir())
    assert frames and all(f.read_bytes() == (tmp_path / "b" / "frames" / f.name).read_bytes()
                          for f in frames)
    c = make_session(tmp_path / "c", SessionSpec(block=GaugeBlock(depths_mm=(0.3,)), repeats=2,
                                                 seed=12), profile=prof)
    assert c["presses"][0]["x_mm"] != a["presses"][0]["x_mm"]
    with pytest.raises(InputError, match="not empty"):
        make_session(tmp_path / "a", spec, profile=prof)


@pytest.mark.slow
def test_the_steps_in_order_give_what_calibrate_gives(sample_run):
    """The main job run step by step, as docs/guide/calibrate.md shows it: each step's
    result can be looked at, and the steps in order give the depths, E, nu and intervals
    that calibrate wrote (the sample gel does not relax: that step changes nothing)."""
    out, truth = sample_run
    written = json.loads((out / "report" / "fit.json").read_text())
    table = read_measurements(out / "report" / "measurements.csv")
    session = read_session(SAMPLE)
    cert = certify_session(session)                      # decode, sync, certify
    assert cert.clock_offset_s == pytest.approx(written["clock_offset_s"], rel=1e-12)
    session, cert, zero, notes = take_off_zero(session, cert, "auto")
    assert zero is not None and notes
    cfg, presses = session.config, cert.presses
    force = np.array([p.force_n for p in presses])
    w0 = np.array([p.w0_mm for p in presses])
    closure = np.array([p.closure_mm for p in presses])
    fit_at = Fitter(force, thickness_mm=cfg.gel_thickness_mm,
                    radius_mm=cfg.indenter_radius_mm, beta_table="fem")
    st = DepthState(depth=w0 + closure, std=np.array([p.closure_std_mm for p in presses]),
                    bulge=np.zeros_like(w0), bevel_n=np.zeros_like(w0), notes=[])
    vernier_rule(st, presses, cert, cfg, fit_at, force, nu_start=0.48, max_rounds=8,
                 nu_tol=2e-4)
    np.testing.assert_allclose(st.depth, table.columns["depth_mm"], rtol=1e-5)  # 6 digits
    fit = st.fit
    if st.shared is not None:
        fit = with_shared_depth(fit, fit_at, st.depth, st.std, force - st.bevel_n, *st.shared)
    assert fit.E_mpa == pytest.approx(written["E_mpa"], rel=1e-12)
    assert fit.nu == pytest.approx(written["nu"], rel=1e-12)
    assert list(fit.E_ci95_mpa) == pytest.approx(written["E_ci95_mpa"], rel=1e-12)
    assert fit.E_ci95_mpa[0] <= truth["E_mpa"] <= fit.E_ci95_mpa[1]


def test_the_folder_reads_back(sample_run):
    """CalibrationResult.load reads what calibrate wrote: E, nu and their intervals, the
    presses, the rejections, the holds and the geometry."""
    out, _ = sample_run
    folder = out / "report"
    written = json.loads((folder / "fit.json").read_text())
    back = CalibrationResult.load(folder)
    assert (back.E_mpa, back.nu) == (written["E_mpa"], written["nu"])
    assert list(back.nu_ci95) == written["nu_ci95"]
    assert back.n_presses == written["n_presses"] == len(back.measurements["press"])
    assert len(back.rejected) == written["n_rejected"]
    assert [r["reason"] for r in back.rejected] == [r["reason"] for r in written["rejected"]]
    assert back.holds is not None and set(back.holds["press"]) <= set(back.measurements["press"])
    assert (back.thickness_mm, back.radius_mm) == (written["thickness_mm"],
                                                   written["radius_mm"])
    E, nu, obj = read_material(folder)
    assert (E, nu) == (back.E_mpa, back.nu) and obj["depth_rule"] == "vernier"


def test_report_says_what_this_session_could_not_test(sample_run):
    """The report's "What this session could not test": the sample session holds every
    press 1 s with the window at the hold's start (hold_s 0.1 in every row) and writes no
    day column, so relaxation and aging cannot be tested; its rests vary (incomplete
    recovery can) and so do its positions (spatial non-uniformity can). The same answer
    from measurements.csv through untestable_in_table, and from a copy with the columns
    made to vary (nothing left)."""
    import csv as _csv

    from tactilevision.planning import untestable_in_table

    out, _ = sample_run
    html = (out / "report" / "report.html").read_text()
    assert "What this session could not test" in html
    section = html[html.index("What this session could not test"):html.index("Rejected presses")]
    assert "<b>viscoelastic_relaxation</b>: every press&#x27;s force window sits" in section
    assert "window_at = &#x27;end&#x27;" in section
    assert "<b>aging</b>: needs day" in section
    assert "incomplete_recovery" not in section and "spatial_nonuniformity" not in section
    with open(out / "report" / "measurements.csv") as fh:
        rows = list(_csv.DictReader(fh))
    cols = {k: np.array([float(r[k] or "nan") for r in rows]) for k in rows[0]}
    assert set(untestable_in_table(cols, window_at="start")) == {"viscoelastic_relaxation",
                                                                  "aging"}
    n = len(rows)
    cols["hold_s"] = np.resize([0.5, 1.0, 2.0], n)
    cols["day"] = np.arange(n) % 3.0
    assert untestable_in_table(cols, window_at="end") == {}


def test_calibrate_writes_the_sessions_design(sample_run):
    """design.toml: the session's design (design_from_calibration of the folder), read
    back equal; its depths the gauge block's, its repeats the presses per depth, its E and
    nu the fit's; plan reads it."""
    from tactilevision.planning import design_from_calibration, plan, read_design

    out, _ = sample_run
    folder = out / "report"
    d = read_design(folder / "design.toml")
    assert d == design_from_calibration(folder)
    fit = json.loads((folder / "fit.json").read_text())
    assert d.depths_mm == (0.15, 0.3, 0.4, 0.5, 0.6)
    assert d.repeats == 10 and d.bevel_angle_deg == 5.0
    assert (d.E_mpa, d.nu) == (fit["E_mpa"], fit["nu"])
    assert plan(d).nu_identified
    # the session's presses.csv (what the robot commanded) is the design's schedule
    rows = read_presses(SAMPLE / "presses.csv", 5)
    assert d.schedule == tuple((int(i), float(x), float(y)) for i, x, y in zip(
        rows["indenter"], rows["x_mm"], rows["y_mm"], strict=True))


def test_a_fit_past_the_fem_tables_nu_still_writes_its_design(sample_run, tmp_path):
    """A fit whose nu lies past the FEM table's 0.499 (the paper's relation reaches 0.5)
    still writes design.toml, planned at 0.499, with a warning naming design.toml, not the
    staging folder the calibration was written through."""
    from tactilevision.io import StagedOutput
    from tactilevision.pipeline import CalibrationResult
    from tactilevision.planning import read_design

    out, _ = sample_run
    res = CalibrationResult.load(out / "report")
    res = replace(res, fit={**res.fit, "nu": 0.4996})
    with pytest.warns(InputWarning) as said, StagedOutput(tmp_path / "cal") as stage:
        res.save(stage.path)            # as write_calibration writes it
        stage.commit()
    text = [str(w.message) for w in said if "0.4996" in str(w.message)]
    assert text == ["design.toml: the fit's nu = 0.4996 lies outside the FEM table's 0.3 to "
                    "0.499, which the plan's forces are read from: planned at 0.499"]
    assert read_design(tmp_path / "cal" / "design.toml").nu == 0.499


@pytest.mark.parametrize("delta_mm", [0.015, -0.015])
def test_beta_interval_carries_the_shared_depth_error(delta_mm):
    """Issue 53: beta's printed interval must carry the depths' shared error as E's does.
    Ground truth: eq. (5) presses (c 3.5 N/mm, beta 0.8, h 3 mm) whose certified depths are
    all 15 um off, within a stated shared bound of 20 um. The press scatter alone gives a
    beta interval that misses 0.8; the interval carried through the bound holds it, with a
    note, also where E and nu are out of the table at the certified depths."""
    h, a, c, beta = 3.0, 2.5, 3.5, 0.8
    w = np.repeat(np.linspace(0.15, 0.6, 5), 4)
    P = c * w * (1 + beta * w / h) + np.random.default_rng(0).normal(0.0, 0.002, w.size)
    wm, std = w - delta_mm, np.full(w.size, 0.001)

    def fit_at(d, s, f):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return fit_indentation(d, f, depth_std_mm=s, thickness_mm=h, radius_mm=a)

    raw = fit_at(wm, std, P)
    assert not raw.beta_ci95[0] <= beta <= raw.beta_ci95[1]
    bound = np.full(w.size, 0.02)
    carried = with_shared_depth(raw, fit_at, wm, std, P, -bound, bound)
    assert carried.beta_ci95[0] <= beta <= carried.beta_ci95[1]
    assert carried.beta_ci95[0] <= raw.beta_ci95[0] and carried.beta_ci95[1] >= raw.beta_ci95[1]
    assert any("beta's interval carries the shared depth error" in n for n in carried.notes)


def test_the_tables_sidecar_says_how_its_depths_were_certified(sample_run, tmp_path):
    """calibrate writes [certification] depth_rule beside measurements.csv, so that
    diagnose knows whether the depths were read from the force (the mark rule)."""
    out, _ = sample_run
    table = read_measurements(out / "report" / "measurements.csv")
    assert table.certification == {"depth_rule": "vernier"}
    bad = tmp_path / "t"
    bad.mkdir()
    (bad / "measurements.csv").write_text("depth_mm,force_n\n0.1,0.2\n0.2,0.5\n")
    (bad / "session.toml").write_text("[sensor]\ngel_thickness_mm = 3.0\n[indenter]\n"
                                      "radius_mm = 2.5\n[certification]\ndepth_rule = 3\n")
    with pytest.raises(InputError, match=r"\[certification\] depth_rule must be one of "
                                         r"vernier, mark, nominal, land, got 3"):
        read_measurements(bad / "measurements.csv")
    (bad / "session.toml").write_text("[sensor]\ngel_thickness_mm = 3.0\n[indenter]\n"
                                      "radius_mm = 2.5\n[certification]\ndepth_rule = "
                                      "\"mark\"\ndepth_rules = \"x\"\n")
    t = read_measurements(bad / "measurements.csv")
    assert t.certification == {"depth_rule": "mark"}
    assert any("[certification] depth_rules is not a key tactilevision reads (did you mean "
               "depth_rule?" in n for n in t.notes)


def test_a_press_past_the_beta_table_is_left_out_not_the_session():
    """One press certified past the FEM beta table's reach (w/h 0.23) used to refuse the
    whole session's fit; now it is left out, named by its press number, and the fit is the
    one of the other presses; a press past the reach by less than two of its depth
    uncertainties is kept (the table read at its last w/h)."""
    h, a = 3.0, 2.5
    w = np.repeat([0.15, 0.3, 0.45, 0.6], 4)
    w = np.append(w, 0.75)                   # w/h 0.25
    P = 3.5 * w * (1 + 0.78 * w / h)
    std = np.full(w.size, 0.004)
    press = np.arange(10, 10 + w.size)
    fit_at = Fitter(P, thickness_mm=h, radius_mm=a, beta_table="fem", press=press)
    fit = fit_at(w, std)
    alone = fit_indentation(w[:-1], P[:-1], thickness_mm=h, radius_mm=a, depth_std_mm=std[:-1])
    assert fit.n_presses == w.size - 1
    assert fit.E_mpa == pytest.approx(alone.E_mpa, rel=1e-12)
    note = [n for n in fit.notes if "left out of" in n]
    assert note and "press(es) 26 (w/h 0.250)" in note[0]
    assert note[0] in fit_at.warnings_of(fit)
    # later fits (the shared error's bounds) leave it out too, even when moved inside
    assert fit_at(w - 0.1, std).n_presses == w.size - 1
    with pytest.raises(InputError, match="beyond the FEM beta"):
        fit_indentation(w, P, thickness_mm=h, radius_mm=a, depth_std_mm=std)
    near = w.copy()
    near[-1] = 0.23 * h + 0.005              # within 2 sd of the reach: kept
    assert Fitter(P, thickness_mm=h, radius_mm=a, beta_table="fem")(near, std).n_presses \
        == w.size
    paper = Fitter(P, thickness_mm=h, radius_mm=a, beta_table="paper")(w, std)
    assert paper.n_presses == w.size


def test_fit_leaves_out_a_row_past_the_beta_table_as_calibrate_does(tmp_path, capsys):
    """``fit`` on a table whose row lies past the FEM beta table's reach by more than two
    of its depth uncertainties leaves that row out, names its line and w/h, and lists it
    in the JSON (``left_out_rows``), as calibrate leaves the press out of its fit (the
    table calibrate writes keeps it); E is then the other rows' fit."""
    h = 3.0
    w = np.append(np.repeat([0.15, 0.3, 0.45, 0.6], 4), 0.75)
    P = 3.5 * w * (1 + 0.78 * w / h)
    table = tmp_path / "m.csv"
    table.write_text("press,indenter,depth_mm,force_n,depth_std_mm\n" + "".join(
        f"{i},{i % 5},{a:.4f},{b:.6f},0.004\n" for i, (a, b) in enumerate(zip(w, P,
                                                                            strict=True))))
    out = tmp_path / "f.json"
    assert main(["fit", str(table), "--thickness-mm", "3", "--radius-mm", "2.5",
                 "--json", str(out)]) == 0
    err = capsys.readouterr().err
    assert "line(s) 18 (w/h 0.250)" in err and "left out of the fit" in err
    got = json.loads(out.read_text())
    alone = fit_indentation(w[:-1], np.round(P[:-1], 6), thickness_mm=h, radius_mm=2.5,
                            depth_std_mm=np.full(w.size - 1, 0.004))
    assert got["left_out_rows"] == [18] and got["n_presses"] == w.size - 1
    assert got["E_mpa"] == pytest.approx(alone.E_mpa, rel=1e-9)
    # with the paper's relation every row is read
    assert main(["fit", str(table), "--thickness-mm", "3", "--radius-mm", "2.5",
                 "--beta-table", "paper", "--json", str(out), "--overwrite"]) == 0
    assert "left_out_rows" not in json.loads(out.read_text())


def test_a_balls_fit_refuses_crossings(tmp_path, capsys):
    """``fit --crossings`` reads a gauge block's mark crossings; a ball's table has none, and
    the fit of its force windows must not be labelled as crossing forces: exit 2 naming
    the option."""
    table = tmp_path / "m.csv"
    table.write_text("press,depth_mm,force_n\n0,0.1,0.05\n1,0.2,0.14\n2,0.3,0.26\n")
    assert main(["fit", str(table), "--shape", "sphere", "--radius-mm", "3",
                 "--thickness-mm", "3", "--crossings"]) == 2
    assert "--crossings" in capsys.readouterr().err


@pytest.mark.slow
def test_depths_wider_than_the_tolerance_are_named_only_bounded(tmp_path, capsys):
    """The sample session with [gauge_block] depth_tolerance_mm = 0.004 (its vernier
    depths' 95 % half-widths are 3.8 to 4.9 um, the band edges' shared +-2.6 um in them):
    the summary counts the presses certified within +-4 um and those only bounded, fit.json
    lists the bounded ones, a warning names them, and E is fitted from every press as with
    the default tolerance."""
    session = tmp_path / "s"
    shutil.copytree(SAMPLE, session)
    toml = session / "session.toml"
    text = toml.read_text()
    assert "[gauge_block]\n" in text
    toml.write_text(text.replace("[gauge_block]\n", "[gauge_block]\ndepth_tolerance_mm = 0.004\n"))
    assert main(["calibrate", str(session), "--out", str(tmp_path / "out"), "--no-progress",
                 "--no-report"]) == 0
    out = capsys.readouterr().out
    fit = json.loads((tmp_path / "out" / "fit.json").read_text())
    bounded = fit["depth_bounded"]
    assert fit["depth_tolerance_mm"] == 0.004 and 0 < len(bounded) < fit["n_presses"]
    n = fit["n_presses"]
    assert (f"{n} presses fitted: {n - len(bounded)} certified within +-4 um, "
            f"{len(bounded)} only bounded; 2 rejected") in out
    assert f"press(es) {', '.join(map(str, bounded))} only bounded" in out
    ref = calibrate_session(SAMPLE)
    assert fit["E_mpa"] == pytest.approx(ref.fit.E_mpa, rel=1e-9)
