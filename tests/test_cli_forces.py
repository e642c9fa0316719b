"""``tactilevision forces`` on a folder of real GelSight ball presses (MIT frames in
sample_frames/gelsight_ball): images and forces.csv written, totals positive and
linear in E; bad input names what is wrong and writes nothing."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from tactilevision.cli import main

FRAMES = Path(__file__).resolve().parents[1] / "sample_frames" / "gelsight_ball" / "frames"


def test_forces_on_a_frames_folder(tmp_path):
    out = tmp_path / "forces"
    rc = main(["forces", str(FRAMES), "--sensor", "gelsight", "--thickness-mm", "3.0",
               "--E-mpa", "0.2", "--nu", "0.48", "--out", str(out), "--no-progress"])
    assert rc == 0
    rows = list(csv.DictReader((out / "forces.csv").open()))
    assert len(rows) == 4
    assert list(rows[0]) == ["frame", "t_s", "fx_n", "fy_n", "fz_n", "max_pressure_kpa",
                             "contact_area_mm2", "ft_fz_n"]
    fz = np.array([float(r["fz_n"]) for r in rows])
    # pressed in: positive. (The magnitude is not asserted: with 'field' the height
    # map's low-frequency error dominates the total, see the README's forces section.)
    assert np.all(fz > 0)
    assert all((out / f"{Path(r['frame']).stem}_force.png").stat().st_size > 10_000
               for r in rows)
    # the contact's area in the default mode too: the annotated contact disc (radius a)
    # lies inside it; the region of visible colour change reaches past the disc, where the
    # gel bends down to the ball, but not to twice its radius
    circles = {r["frame"]: r for r in csv.DictReader((FRAMES / "circles.csv").open())}
    for r in rows:
        disc = np.pi * (float(circles[r["frame"]]["radius_px"]) * 0.0295) ** 2
        assert disc < float(r["contact_area_mm2"]) < 4 * disc, (r, disc)
    # the force scales with E
    out2 = tmp_path / "forces2"
    main(["forces", str(FRAMES), "--sensor", "gelsight", "--thickness-mm", "3.0",
          "--E-mpa", "0.4", "--nu", "0.48", "--out", str(out2), "--no-progress", "--no-images"])
    fz2 = np.array([float(r["fz_n"]) for r in csv.DictReader((out2 / "forces.csv").open())])
    np.testing.assert_allclose(fz2, 2 * fz, rtol=1e-3)


@pytest.mark.parametrize(("extra", "message"), [
    ([], "--thickness-mm"),
    (["--thickness-mm", "3"], "E-mpa"),
    (["--thickness-mm", "3", "--E-mpa", "0.2"], "both --E-mpa and --nu"),
    (["--thickness-mm", "3", "--fit", "missing.json"], "missing.json does not exist"),
    (["--thickness-mm", "3", "--E-mpa", "0.2", "--nu", "0.5"], "nu must be within"),
])
def test_forces_bad_input(tmp_path, capsys, extra, message):
    out = tmp_path / "out"
    rc = main(["forces", str(FRAMES), "--sensor", "gelsight", "--out", str(out),
               "--no-progress", *extra])
    assert rc == 2
    assert message in capsys.readouterr().err
    assert not (out / "forces.csv").exists()


def test_forces_reads_E_and_nu_from_a_fit_json(tmp_path):
    fit = tmp_path / "fit.json"
    fit.write_text(json.dumps({"E_mpa": "x", "nu": 0.4}))
    rc = main(["forces", str(FRAMES), "--sensor", "gelsight", "--thickness-mm", "3",
               "--fit", str(fit), "--out", str(tmp_path / "o"), "--no-progress"])
    assert rc == 2


def test_forces_on_a_no_contact_frame_read_near_zero(tmp_path, capsys):
    """The sample session's first frame has no contact (F/T -4 mN): levelled at the far
    field (the default) it reads tens of mN, not the 1.1 N of the frame's median zero."""
    session = FRAMES.parents[1] / "gelsight_session"
    fz = {}
    for level in ("far_field", "median"):
        out = tmp_path / level
        rc = main(["forces", str(session), "--E-mpa", "0.2", "--nu", "0.48", "--every", "1000",
                   "--level", level, "--out", str(out), "--no-progress", "--no-images"])
        assert rc == 0
        rows = list(csv.DictReader((out / "forces.csv").open()))
        assert [r["frame"] for r in rows] == ["00000.jpg"]
        fz[level] = float(rows[0]["fz_n"])
    printed = capsys.readouterr().out
    assert "levelled at the far field" in printed
    # the sample session gives no clock offset and no fit.json is at hand: no F/T column
    # rather than a misaligned one
    assert "ft_fz_n left empty" in printed
    assert rows[0]["ft_fz_n"] == ""
    assert abs(fz["far_field"]) < 0.05
    assert fz["median"] > 0.5


def test_forces_takes_the_clock_offset_from_fit_json(tmp_path):
    """With calibrate's fit.json (its clock_offset_s) the F/T column is filled: at the
    sample session's frame 40, in the hold of its first press, it reads the log's force
    at the frame's time on the log's clock (0.137 s later; truth.json)."""
    session = FRAMES.parents[1] / "gelsight_session"
    truth = json.loads((session / "truth.json").read_text())
    fit = tmp_path / "fit.json"
    fit.write_text(json.dumps({"E_mpa": 0.2, "nu": 0.48,
                               "clock_offset_s": truth["clock_offset_s"]}))
    out = tmp_path / "o"
    assert main(["forces", str(session), "--fit", str(fit), "--every", "40", "--out", str(out),
                 "--no-progress", "--no-images"]) == 0
    rows = {r["frame"]: r for r in csv.DictReader((out / "forces.csv").open())}
    t = float(rows["00040.jpg"]["t_s"])
    log = np.loadtxt(session / "forces.csv", delimiter=",", skiprows=1, usecols=(0, 3))
    expected = np.interp(t + truth["clock_offset_s"], log[:, 0], log[:, 1])
    assert float(rows["00040.jpg"]["ft_fz_n"]) == pytest.approx(expected, abs=1e-4)
    assert expected > 1.0
