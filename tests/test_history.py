"""``tactilevision history``: each gel's calibrations over days (docs/guide/history.md).

Against known truth: the shipped sample ``sample_frames/history_aging/`` (four
calibrations of a simulated gel whose E falls 8 % of E0 every two weeks,
``truth.json``), copies of one calibration under other dates (a gel that does
not change), and small synthetic fit.json files of known values.
"""

from __future__ import annotations

import datetime
import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.cli import main
from tactilevision.history import (
    HISTORY_COLUMNS,
    assess,
    gather,
    relative_change,
    weighted_line,
)

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "sample_frames" / "history_aging"
TRUTH = json.loads((SAMPLE / "truth.json").read_text())
DAYS = [SAMPLE / c["folder"] for c in TRUTH["calibrations"]]


def _true_E(day: float) -> float:
    return TRUTH["E0_mpa"] * (1.0 + TRUTH["E_rate_per_day"] * day)


def _fake(folder: Path, *, E: float, half: float, date: str | None, sensor: str = "gelA",
          drop: tuple[str, ...] = ()) -> Path:
    """A minimal calibrate fit.json of known values (E +- half, nu 0.48 +- 0.02)."""
    folder.mkdir(parents=True)
    obj = {"E_mpa": E, "E_ci95_mpa": [E - half, E + half], "E_se_mpa": half / 1.96,
           "nu": 0.48, "nu_ci95": [0.46, 0.5], "c_n_per_mm": 3.7, "c_se_n_per_mm": 0.02,
           "beta": 0.8, "beta_ci95": [0.76, 0.84], "beta_se": 0.02, "n_presses": 20,
           "confidence": 0.95, "n_rejected": 1, "clock_offset_s": 0.137,
           "sensor_name": sensor, "session_date": date}
    for k in drop:
        obj.pop(k)
    (folder / "fit.json").write_text(json.dumps(obj))
    return folder


def _run(capsys, *argv: str) -> tuple[int, str, str]:
    rc = main(["history", *map(str, argv)])
    out, err = capsys.readouterr()
    return rc, out, err


@pytest.fixture(scope="module")
def sample_cli(tmp_path_factory):
    """``history`` run once on the sample with --json and --report (the pooled diagnosis
    is its costly part): return code, stdout, stderr, the JSON and the report folder."""
    import contextlib
    import io

    tmp = tmp_path_factory.mktemp("history_cli")
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main(["history", *map(str, DAYS), "--json", str(tmp / "h.json"),
                   "--report", str(tmp / "rep")])
    obj = json.loads((tmp / "h.json").read_text()) if rc == 0 else None
    return rc, out.getvalue(), err.getvalue(), obj, tmp / "rep"


# ------------------------------------------------------------------ the shipped sample


def test_sample_recovers_each_days_E_within_its_interval():
    recs = gather(DAYS)["gelsight"]
    assert [r.date.isoformat() for r in recs] == [c["date"] for c in TRUTH["calibrations"]]
    for r, c in zip(recs, TRUTH["calibrations"], strict=True):
        assert r.date_source == "fit.json"              # calibrate copied [session] date
        lo, hi = r.E_ci95_mpa
        assert lo <= c["E_mpa"] <= hi, (r.folder, r.E_mpa, (lo, hi), c["E_mpa"])
        assert r.nu_ci95[0] <= c["nu"] <= r.nu_ci95[1]
        assert r.n_presses >= 20


def test_sample_aging_detected_with_the_true_trend_and_change():
    recs = gather(DAYS)["gelsight"]
    a = assess(recs)
    true_slope = TRUTH["E0_mpa"] * TRUTH["E_rate_per_day"]          # MPa / day, < 0
    lo, hi = a.trend.slope_ci()
    assert hi < 0                                                   # a fall, resolved
    assert lo <= true_slope <= hi
    last_day = TRUTH["calibrations"][-1]["day"]
    true_change = _true_E(last_day) / _true_E(0) - 1               # -24 %
    assert a.change_ci[0] <= true_change <= a.change_ci[1]
    assert a.change_ci[1] < 0
    assert a.recalibrate and a.beyond[-1]
    # the first stale date: where the true E leaves day 0's interval, to within the
    # calibrations' spacing (the data cannot place it closer than that)
    E_lo0 = recs[0].E_ci95_mpa[0]
    t_true = (E_lo0 - _true_E(0)) / true_slope
    stale_day = (a.stale_from - recs[0].date).days
    spacing = np.diff([c["day"] for c in TRUTH["calibrations"]]).max()
    assert 0 < stale_day <= TRUTH["calibrations"][-1]["day"]
    assert abs(stale_day - t_true) <= spacing, (stale_day, t_true)


def test_pooled_presses_name_aging_at_the_true_rate():
    """All 96 presses of the sample in one table, diagnosed along the day: aging, at the
    truth's -0.571 %/day (E0 and nu of the pooled fit near the truth's too)."""
    from tactilevision.history import pooled_diagnosis

    p = pooled_diagnosis(gather(DAYS)["gelsight"])
    assert p.missing_effect == "aging" and p.n_presses > 80
    lo, hi = p.rate_ci_per_day
    assert lo <= TRUTH["E_rate_per_day"] <= hi
    assert p.rate_per_day == pytest.approx(TRUTH["E_rate_per_day"], rel=0.05)
    assert p.E0_mpa == pytest.approx(TRUTH["E0_mpa"], rel=0.08)
    assert abs(p.nu - TRUTH["nu"]) < 0.02
    assert "name aging" in p.summary()


def test_pooled_presses_of_a_steady_gel_name_no_change(tmp_path):
    """The same presses under three dates: nothing along the day."""
    from tactilevision.history import pooled_diagnosis

    folders = []
    for i in range(3):
        f = tmp_path / f"c{i}"
        shutil.copytree(DAYS[0], f)
        folders.append(f)
    dates = {f: datetime.date(2027, 1, 1) + datetime.timedelta(days=d)
             for f, d in zip(folders, (0, 20, 45), strict=True)}
    p = pooled_diagnosis(gather(folders, dates=dates)["gelsight"])
    assert p.missing_effect not in ("aging", "stiffness_step:day")
    assert np.isnan(p.rate_per_day)


def test_sample_cli_says_recalibrate_and_names_the_stale_date(sample_cli):
    rc, out, err, full, _ = sample_cli
    assert rc == 0, err
    obj = full["sensors"]["gelsight"]
    assert obj["recalibrate"] is True
    m = re.search(r"E fell ([\d.]+) % \[([\d.]+), ([\d.]+)\] since 2026-11-02 \(day 0\)", out)
    assert m, out
    assert float(m[1]) == pytest.approx(-100 * obj["E_change"], abs=0.06)
    assert "recalibrate" in out
    assert f"sessions after {obj['stale_from']}" in out and "used a stale E" in out
    assert out.count("*") == sum(r["beyond_day0_ci"] for r in obj["calibrations"])
    assert obj["pooled_diagnosis"]["missing_effect"] == "aging"
    assert obj["pooled_note"] in out


# ------------------------------------------------------------------ a gel that does not change


def test_a_steady_gel_gives_no_warning(capsys, tmp_path):
    folders = []
    for i in range(3):
        f = tmp_path / f"c{i}"
        shutil.copytree(DAYS[0], f)
        folders.append(f)
    dates = [f"--date={f}={(datetime.date(2027, 1, 1) + datetime.timedelta(days=d))}"
             for f, d in zip(folders, (0, 20, 45), strict=True)]
    rc, out, err = _run(capsys, *folders, *dates, "--json", "-", "--no-pooled")
    assert rc == 0, err
    obj = json.loads(out)["sensors"]["gelsight"]
    assert "pooled_diagnosis" not in obj
    assert obj["recalibrate"] is False and obj["stale_from"] is None
    assert obj["E_change"] == pytest.approx(0.0, abs=1e-12)
    assert [c["date_source"] for c in obj["calibrations"]] == ["--date"] * 3
    rc, out, _ = _run(capsys, *folders, *dates, "--no-pooled")
    assert "recalibrate" not in out.replace("no recalibration needed", "")
    assert "no recalibration needed" in out


def test_scatter_within_the_intervals_is_not_aging(tmp_path):
    rng = np.random.default_rng(5)
    folders = [_fake(tmp_path / f"c{i}", E=0.2 * (1 + 0.02 * rng.standard_normal()), half=0.02,
                     date=f"2026-0{i + 1}-01") for i in range(5)]
    a = assess(gather(folders)["gelA"])
    assert not a.recalibrate and a.stale_from is None
    lo, hi = a.trend.slope_ci()
    assert lo <= 0.0 <= hi


# ------------------------------------------------------------------ sensors, reports, JSON


def test_two_sensors_two_tables_and_sensor_filters(capsys, tmp_path):
    fs = [_fake(tmp_path / "a0", E=0.20, half=0.01, date="2026-01-01", sensor="gelA"),
          _fake(tmp_path / "a1", E=0.15, half=0.01, date="2026-02-01", sensor="gelA"),
          _fake(tmp_path / "b0", E=0.30, half=0.02, date="2026-01-05", sensor="gel B"),
          _fake(tmp_path / "b1", E=0.30, half=0.02, date="2026-01-25", sensor="gel B")]
    rc, out, err = _run(capsys, *fs, "--report", tmp_path / "rep", "--json", tmp_path / "h.json")
    assert rc == 0, err
    sensors = json.loads((tmp_path / "h.json").read_text())["sensors"]
    assert set(sensors) == {"gelA", "gel B"}
    assert sensors["gelA"]["recalibrate"] is True and sensors["gel B"]["recalibrate"] is False
    # two calibrations: the line through them leaves [0.19, 0.21] at 0.19, 0.01 / (0.05 / 31 d)
    t = round(0.01 / (0.05 / 31))
    assert sensors["gelA"]["stale_from"] == f"2026-01-{1 + t:02d}"
    for name, n in (("history_gelA.csv", 2), ("history_gel_B.csv", 2)):
        lines = (tmp_path / "rep" / name).read_text().splitlines()
        assert lines[0].split(",") == list(HISTORY_COLUMNS) and len(lines) == 1 + n
    rc, out, err = _run(capsys, *fs, "--sensor", "gel B", "--report", tmp_path / "rep_b",
                        "--json", "-")
    assert rc == 0, err
    assert set(json.loads(out)["sensors"]) == {"gel B"}
    assert sorted(p.name for p in (tmp_path / "rep_b").glob("history_*.csv")) == [
        "history_gel_B.csv"]
    rc, _, err = _run(capsys, *fs, "--sensor", "gelC")
    assert rc == 2 and "gelC" in err and "gelA" in err


def test_report_html_and_figures_are_written(sample_cli):
    rc, out, err, _, rep = sample_cli
    assert rc == 0, err
    for png in ("E_gelsight.png", "nu_gelsight.png"):
        data = (rep / png).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 5000
    page = (rep / "report.html").read_text()
    assert page.count("data:image/png;base64,") == 2          # self-contained
    assert "recalibrate" in page and "2026-12-14" in page
    assert "name aging" in page                               # the pooled diagnosis
    rows = (rep / "history_gelsight.csv").read_text().splitlines()
    assert len(rows) == 1 + len(DAYS)
    assert str(rep / "report.html") in out


def _documented_keys() -> set[str]:
    text = (ROOT / "docs" / "formats.md").read_text()
    section = text[text.index("## Calibration history (history)"):]
    return set(re.findall(r"`([A-Za-z_0-9]+)`", section))


def test_json_has_the_documented_keys(sample_cli, capsys):
    rc, _, err, obj, _ = sample_cli
    assert rc == 0, err
    # --json - writes the same object to stdout (the steady gel's copies: no pooled aging)
    rc, out, err = _run(capsys, DAYS[0], "--json", "-")
    assert rc == 0, err
    assert set(json.loads(out)) == set(obj)
    doc = _documented_keys()
    assert set(obj) <= doc
    s = obj["sensors"]["gelsight"]
    assert set(s) == {"sensor", "n_calibrations", "first_date", "last_date", "calibrations",
                      "E_change", "E_change_ci", "recalibrate", "stale_from", "trend",
                      "nu_beyond", "message", "csv", "pooled_diagnosis", "pooled_note"}
    assert set(s) <= doc and set(s["trend"]) <= doc and set(s["pooled_diagnosis"]) <= doc
    assert set(s["calibrations"][0]) == set(HISTORY_COLUMNS) <= doc


# ------------------------------------------------------------------ bad input: exit 2, folder named


def test_folder_without_fit_json(capsys, tmp_path):
    (tmp_path / "empty").mkdir()
    rc, _, err = _run(capsys, DAYS[0], tmp_path / "empty", "--report", tmp_path / "rep")
    assert rc == 2 and str(tmp_path / "empty") in err and "fit.json" in err
    assert not (tmp_path / "rep").exists()                   # nothing written


def test_fit_json_without_E(capsys, tmp_path):
    f = _fake(tmp_path / "noE", E=0.2, half=0.01, date="2026-01-01", drop=("E_mpa",))
    rc, _, err = _run(capsys, f)
    assert rc == 2 and str(f) in err and "E_mpa" in err


def test_missing_date_names_the_folder_and_both_fixes(capsys, tmp_path):
    f = _fake(tmp_path / "nodate", E=0.2, half=0.01, date=None)
    rc, _, err = _run(capsys, f)
    assert rc == 2 and str(f) in err
    assert "[session] date" in err and f"--date {f}=YYYY-MM-DD" in err
    rc, _, err = _run(capsys, f, f"--date={f}=2026-13-01")
    assert rc == 2 and "2026-13-01" in err
    rc, out, err = _run(capsys, f, f"--date={f}=2026-03-01")
    assert rc == 0 and "2026-03-01" in out


def test_existing_report_files_not_written_by_us_are_kept(capsys, tmp_path):
    rep = tmp_path / "rep"
    rep.mkdir()
    (rep / "report.html").write_text("mine")
    rc, _, err = _run(capsys, *DAYS, "--report", rep, "--no-pooled")
    assert rc == 2 and "--overwrite" in err
    assert (rep / "report.html").read_text() == "mine"


# ------------------------------------------------------------------ the pure functions


def test_weighted_line_recovers_a_known_line_and_its_error():
    x = np.array([0.0, 10.0, 20.0, 30.0])
    s = np.array([0.01, 0.02, 0.01, 0.02])
    fit = weighted_line(x, 0.2 - 0.001 * x, s)
    assert fit.intercept == pytest.approx(0.2) and fit.slope == pytest.approx(-0.001)
    w = 1 / s ** 2                                   # var(b) = S / (S Sxx - Sx^2)
    var_b = w.sum() / (w.sum() * (w * x * x).sum() - (w * x).sum() ** 2)
    assert fit.cov[1, 1] == pytest.approx(var_b) and not fit.scaled
    noisy = weighted_line(x, 0.2 - 0.001 * x + np.array([0.05, -0.05, 0.05, -0.05]), s)
    assert noisy.scaled and noisy.cov[1, 1] > var_b       # scatter beyond the sigmas widens
    with pytest.raises(InputError):
        weighted_line(np.array([1.0, 1.0]), np.array([0.2, 0.2]), np.array([0.01, 0.01]))


def test_relative_change_interval():
    ch, lo, hi = relative_change(0.2, 0.01, 0.16, 0.008)
    assert ch == pytest.approx(-0.2)
    se = np.hypot(0.05, 0.05)
    assert np.log1p(lo) == pytest.approx(np.log(0.8) - 1.959964 * se, rel=1e-5)
    assert np.log1p(hi) == pytest.approx(np.log(0.8) + 1.959964 * se, rel=1e-5)


def test_session_date_is_read_without_a_warning_and_checked(tmp_path):
    from test_io_session import make_session

    from tactilevision.io import read_session

    folder = make_session(tmp_path / "s")
    toml = folder / "session.toml"
    base = toml.read_text()
    assert read_session(folder).config.date is None
    toml.write_text(base + "\n[session]\ndate = 2026-11-02\n")
    s = read_session(folder)
    assert s.config.date == datetime.date(2026, 11, 2)
    assert not [n for n in s.notes if "session" in n and "not" in n]     # a known key
    toml.write_text(base + "\n[session]\ndate = 20261102\n")
    with pytest.raises(InputError, match=r"session.toml: \[session\] date must be a date"):
        read_session(folder)


def test_the_specimen_column_makes_each_specimen_a_series(tmp_path):
    """Two gels of one sensor's batch, each calibration folder's measurements.csv naming its
    specimen: two series, not one; a folder naming two specimens is refused, naming it."""
    for i, (spec, E) in enumerate((("A", 0.20), ("B", 0.26), ("A", 0.199), ("B", 0.261))):
        f = _fake(tmp_path / f"c{i}", E=E, half=0.01, date=f"2026-01-{1 + i:02d}")
        (f / "measurements.csv").write_text(f"specimen,depth_mm,force_n\n{spec},0.3,1.0\n")
    by = gather(sorted(tmp_path.glob("c*")))
    assert sorted(by) == ["gelA (specimen A)", "gelA (specimen B)"]
    assert [r.E_mpa for r in by["gelA (specimen B)"]] == [0.26, 0.261]
    bad = _fake(tmp_path / "mixed", E=0.2, half=0.01, date="2026-02-01")
    (bad / "measurements.csv").write_text("specimen,depth_mm,force_n\nA,0.3,1.0\nB,0.3,1.1\n")
    with pytest.raises(InputError, match=r"mixed: its measurements.csv names 2 specimens"):
        gather([bad])
