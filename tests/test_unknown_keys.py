"""No silent key (issue 84, item 4): every reader of a ``session.toml`` names each table and
key it does not read, with the file and the nearest known key, and says nothing of a file
holding only known keys; a rectangular pad's width and length are read as the disc of the
same area (formats.md section 1). One test per kind of file; nothing here runs a FEM."""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path

import cv2
import numpy as np
import pytest

from tactilevision import InputError, InputWarning
from tactilevision.cli import main
from tactilevision.history import read_calibration
from tactilevision.io import (
    read_dead_weights,
    read_measurements,
    read_session,
    sidecar_geometry,
)
from tactilevision.io._keys import KNOWN_KEYS, equal_area_radius, unknown_key_notes
from tactilevision.planning import design_from_calibration, read_design

ROOT = Path(__file__).resolve().parents[1]
DESIGN = (ROOT / "sample_frames" / "plan" / "recommended.toml").read_text()

#: The typo every test makes, and what it must be told.
TYPO, KEY, NEAR = "gel_widht_mm", "[sensor] gel_widht_mm", "did you mean gel_width_mm?"

SESSION = """\
[sensor]
name = "test"
mm_per_px = 0.05
gel_thickness_mm = 3.0
gel_radius_mm = 15.0

[indenter]
radius_mm = 2.5

[gauge_block]
depths_mm = [0.15, 0.30]

[force_sensor]
rate_hz = 1000
clock_offset_s = 0.0
window_samples = 20
"""

BALL = """\
[sensor]
mm_per_px = 0.05
gel_thickness_mm = 3.0

[indenter]
radius_mm = 2.0
shape = "sphere"
contact = "frictionless"
"""

SIDECAR = """\
[sensor]
gel_thickness_mm = 3.0

[indenter]
radius_mm = 2.5

[certification]
depth_rule = "vernier"
"""


def _typo(text: str) -> str:
    """`text` with a mistyped width under ``[sensor]`` (its first line)."""
    assert text.startswith("[sensor]\n")
    return text.replace("[sensor]\n", f"[sensor]\n{TYPO} = 30.0\n", 1)


def _said(messages: list[str], toml: Path) -> list[str]:
    """The messages naming the typo; each must name the file and the nearest key."""
    hits = [m for m in messages if KEY in m]
    assert hits, messages
    for m in hits:
        assert str(toml) in m and NEAR in m, m
    return hits


def _unread(messages: list[str]) -> list[str]:
    """The messages about a key or table not read."""
    return [m for m in messages if "is not a key tactilevision reads" in m
            or "not read by tactilevision" in m]


def _warned(call, *args, **kwargs) -> tuple[object, list[str]]:
    """`call`'s result and the InputWarnings it raised."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = call(*args, **kwargs)
    return out, [str(w.message) for w in caught if issubclass(w.category, InputWarning)]


def _images(folder: Path, names: list[str]) -> None:
    (folder / "frames").mkdir(parents=True)
    img = np.full((12, 16, 3), 90, np.uint8)
    cv2.imwrite(str(folder / "reference.png"), img)
    for name in names:
        cv2.imwrite(str(folder / "frames" / name), img)


def _session(folder: Path, toml: str) -> Path:
    """A tiny F/T session folder: two frames, 40 F/T samples."""
    _images(folder, ["f0.png", "f1.png"])
    (folder / "session.toml").write_text(toml)
    (folder / "frames.csv").write_text("frame,t_s\nf0.png,0.0\nf1.png,0.1\n")
    t = np.arange(40) / 1000.0
    (folder / "forces.csv").write_text("t_s,fx_n,fy_n,fz_n\n" + "".join(
        f"{x:.4f},0,0,0.1\n" for x in t))
    return folder


def test_the_helper_names_keys_tables_and_loose_keys():
    doc = {"sensor": {TYPO: 1.0, "name": "x"}, "forcesensr": {"rate_hz": 1}, "lab": {},
           "mm_per_pxx": 0.1}
    notes = unknown_key_notes(doc, Path("s.toml"), KNOWN_KEYS)
    assert notes == [
        f"s.toml: {KEY} is not a key tactilevision reads ({NEAR} it stays unset)",
        "s.toml: table [forcesensr] is not read by tactilevision (did you mean "
        "[force_sensor]?)",
        "s.toml: table [lab] is not read by tactilevision",
        "s.toml: key mm_per_pxx (outside any table) is not read by tactilevision (did you "
        "mean [sensor] mm_per_px?)"]
    assert unknown_key_notes({"sensor": {"name": "x"}}, "s.toml", KNOWN_KEYS) == []


def test_a_session_folder(tmp_path):
    """read_session: the session's notes (calibrate prints them as warnings)."""
    folder = _session(tmp_path / "s", _typo(SESSION))
    s = read_session(folder)
    _said(list(s.notes), folder / "session.toml")
    clean = read_session(_session(tmp_path / "c", SESSION))
    assert _unread(list(clean.notes)) == []


def test_a_dead_weights_folder(tmp_path):
    """read_dead_weights: the folder's notes (calibrate prints them as warnings)."""
    folder = tmp_path / "w"
    _images(folder, ["a.png"])
    (folder / "weights.csv").write_text("frame,mass_kg\na.png,0.02\n")
    (folder / "session.toml").write_text(_typo(BALL))
    _said(list(read_dead_weights(folder).notes), folder / "session.toml")
    (folder / "session.toml").write_text(BALL)
    assert _unread(list(read_dead_weights(folder).notes)) == []


def _table(folder: Path, toml: str) -> Path:
    folder.mkdir(parents=True)
    (folder / "measurements.csv").write_text("depth_mm,force_n\n0.1,0.2\n0.2,0.5\n")
    (folder / "session.toml").write_text(toml)
    return folder / "measurements.csv"


def test_a_measurements_tables_sidecar(tmp_path, capsys):
    """read_measurements (fit, diagnose, validate): the table's notes, which the command
    line prints as warnings; given h and a the sidecar is still read for its other keys."""
    path = _table(tmp_path / "t", _typo(SIDECAR) + "\n[certificaton]\nx = 1\n")
    table = read_measurements(path)
    _said(list(table.notes), path.parent / "session.toml")
    assert any("table [certificaton] is not read by tactilevision (did you mean "
               "[certification]?)" in n for n in table.notes)
    given = read_measurements(path, thickness_mm=3.0, radius_mm=2.5)
    _said(list(given.notes), path.parent / "session.toml")
    # fit prints them as warnings, one line each
    w = np.repeat([0.15, 0.30, 0.45, 0.60], 2)
    path.write_text("depth_mm,force_n\n" + "".join(
        f"{d},{d * (3.4943 + 5.2662 * d / 3.0):.5f}\n" for d in w))
    assert main(["fit", str(path), "--beta-table", "paper"]) == 0
    err = capsys.readouterr().err
    assert _said(err.splitlines(), path.parent / "session.toml")[0].startswith(
        "tactilevision fit: warning: ")
    # [certification] keys go through the same rule
    odd = _table(tmp_path / "r", SIDECAR + "depth_rules = \"mark\"\n")
    assert any("[certification] depth_rules is not a key tactilevision reads (did you mean "
               "depth_rule?" in n for n in read_measurements(odd).notes)
    # a session's own keys in a sidecar are no mistake
    clean = _table(tmp_path / "c", SESSION + "\n[certification]\ndepth_rule = \"mark\"\n")
    assert _unread(list(read_measurements(clean).notes)) == []


def test_a_ramps_sidecar(tmp_path):
    """sidecar_geometry (fit --ramp): InputWarnings."""
    path = tmp_path / "r" / "ramp.csv"
    path.parent.mkdir()
    path.write_text("displacement_mm,force_n\n0,0\n")
    (path.parent / "session.toml").write_text(_typo(BALL))
    (h, a, _, keys), said = _warned(sidecar_geometry, path)
    assert (h, a, keys["shape"]) == (3.0, 2.0, "sphere")
    _said(said, path.parent / "session.toml")
    (path.parent / "session.toml").write_text(BALL)
    _, said = _warned(sidecar_geometry, path)
    assert said == []


def test_a_design(tmp_path):
    """read_design (plan): InputWarnings; an unknown [plan] key stays refused."""
    path = tmp_path / "design.toml"
    path.write_text(_typo(DESIGN[DESIGN.index("[sensor]"):]))
    _, said = _warned(read_design, path)
    _said(said, path)
    assert all("its default is used" in m for m in said)
    path.write_text(DESIGN)
    _, said = _warned(read_design, path)
    assert said == []
    path.write_text(DESIGN.replace("repeats = 10", "repeat = 10"))
    with pytest.raises(InputError, match=r"\[plan\] repeat is not a design key \(did you "
                                         r"mean repeats\?\)"):
        read_design(path)


def test_the_session_a_calibration_is_planned_from(tmp_path):
    """design_from_calibration (plan --from-calibration): its session's session.toml,
    InputWarnings."""
    cal = tmp_path / "cal"
    cal.mkdir()
    (cal / "fit.json").write_text(json.dumps({"E_mpa": 0.2, "nu": 0.48, "thickness_mm": 3.0,
                                              "radius_mm": 2.5}))
    (cal / "measurements.csv").write_text("depth_mm,force_n\n0.15,0.5\n0.30,1.1\n")
    session = tmp_path / "s"
    session.mkdir()
    (session / "session.toml").write_text(_typo(SESSION))
    _, said = _warned(design_from_calibration, cal, session)
    _said(said, session / "session.toml")
    (session / "session.toml").write_text(SESSION)
    _, said = _warned(design_from_calibration, cal, session)
    assert said == []


def test_a_calibration_folders_copy(tmp_path):
    """read_calibration (history): the folder's session.toml, InputWarnings."""
    folder = tmp_path / "cal"
    folder.mkdir()
    obj = {"E_mpa": 0.2, "E_ci95_mpa": [0.19, 0.21], "E_se_mpa": 0.005, "nu": 0.48,
           "nu_ci95": [0.46, 0.5], "c_n_per_mm": 3.7, "c_se_n_per_mm": 0.02, "beta": 0.8,
           "beta_ci95": [0.76, 0.84], "beta_se": 0.02, "n_presses": 20, "confidence": 0.95,
           "n_rejected": 1, "clock_offset_s": 0.1, "sensor_name": "gelA",
           "session_date": "2026-11-02"}
    (folder / "fit.json").write_text(json.dumps(obj))
    (folder / "session.toml").write_text(_typo(SIDECAR))
    record, said = _warned(read_calibration, folder)
    assert record.sensor == "gelA"
    _said(said, folder / "session.toml")
    (folder / "session.toml").write_text(SIDECAR)
    _, said = _warned(read_calibration, folder)
    assert said == []


def test_a_rectangular_pad_is_its_equal_area_disc(tmp_path):
    """gel_width_mm and gel_length_mm: the disc of the same area where gel_radius_mm is not
    given, said in a note; one without the other, or beside gel_radius_mm, named as not
    read; a bad value refused naming the key."""
    rect = "[sensor]\ngel_width_mm = 30.0\ngel_length_mm = 20.0\n"
    r = math.sqrt(30.0 * 20.0 / math.pi)
    toml = tmp_path / "s.toml"
    radius, notes = equal_area_radius({"sensor": {"gel_width_mm": 30, "gel_length_mm": 20}},
                                      toml)
    assert radius == pytest.approx(r) and "same area" in notes[0] and str(toml) in notes[0]
    # a session folder: the pad's radius
    s = read_session(_session(tmp_path / "s", SESSION.replace(
        "gel_radius_mm = 15.0\n", "gel_width_mm = 30.0\ngel_length_mm = 20.0\n")))
    assert s.config.gel_radius_mm == pytest.approx(r)
    assert any("read as the disc of the same area" in n for n in s.notes)
    assert _unread(list(s.notes)) == []
    # a table's sidecar: the ball's pad radius, as gel_radius_mm would be
    path = _table(tmp_path / "t", BALL.replace("[sensor]\n", rect, 1))
    table = read_measurements(path)
    assert table.indenter["pad_radius_mm"] == pytest.approx(r)
    assert any("read as the disc of the same area" in n for n in table.notes)
    # beside gel_radius_mm, or alone: named as not read
    for extra, why in (("gel_radius_mm = 12.0\n", "gel_radius_mm gives the pad's radius"),
                       ("", None)):
        text = BALL.replace("[sensor]\n", "[sensor]\ngel_width_mm = 30.0\n" + extra, 1)
        (path.parent / "session.toml").write_text(text)
        table = read_measurements(path)
        note = "\n".join(table.notes)
        assert "[sensor] gel_width_mm is not read" in note, note
        assert (why or "without [sensor] gel_length_mm") in note
        assert table.indenter.get("pad_radius_mm") == (12.0 if extra else None)
    (path.parent / "session.toml").write_text(BALL.replace("[sensor]\n", rect, 1).replace(
        "30.0", "-1"))
    with pytest.raises(InputError, match=r"\[sensor\] gel_width_mm must be a positive number"):
        read_measurements(path)
