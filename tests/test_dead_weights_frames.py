"""Dead weights with depth from the frames: a ball at rest under known masses, P = m g, each
depth read from the ball's contact circle. The truth is Sneddon's closed form (a rigid
sphere on a half-space: the depth where its force is m g), the frames shaded by the Taxim
authors' GelSight table; none of it is our FEM."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from tactilevision import InputError, default_calibration_path
from tactilevision.cli import main
from tactilevision.io import read_dead_weights
from tactilevision.pipeline import calibrate_dead_weights
from tactilevision.sim import make_dead_weight_session

E = 1.0
MASSES = (0.02, 0.05, 0.1, 0.15, 0.2)       # kg: 0.2 to 2 N on a 2 mm ball


@pytest.fixture(scope="module")
def weights(tmp_path_factory):
    folder = tmp_path_factory.mktemp("weights") / "w"
    depth = make_dead_weight_session(folder, MASSES, repeats=3, E_mpa=E, seed=1)
    return folder, depth


@pytest.mark.slow
def test_depths_and_E_from_the_frames(weights):
    """Every frame's depth within its shared bound plus two sds of Sneddon's; E's 95 %
    interval holds the truth, E within 12 % (the detector's small circles sit inside the
    contact: the depths shallow, E high, as for an F/T session)."""
    folder, depth = weights
    cal = calibrate_dead_weights(folder, nu=0.5, law="linear")
    assert cal.presses is None and len(cal.used) == 15 and not cal.rejected
    d = cal.depths
    err = d.depth_mm - depth
    assert np.all(np.abs(err) < d.depth_shared_mm + 2 * d.depth_std_mm), err
    assert np.allclose(cal.force_n, np.repeat(MASSES, 3) * 9.80665)
    fit = cal.fit
    assert fit.E_ci95_mpa[0] <= E <= fit.E_ci95_mpa[1], fit.E_ci95_mpa
    assert abs(fit.E_mpa / E - 1) < 0.12, fit.E_mpa


@pytest.mark.slow
def test_dead_weights_take_an_optics_calibration_for_their_caps(weights):
    """With an optics calibration each resting weight's cap is read beside its circle:
    finite, deeper for the heavier weights, and said in the warnings."""
    folder, depth = weights
    cal = calibrate_dead_weights(folder, nu=0.5, law="linear",
                                 optics=default_calibration_path("gelsight"))
    caps = cal.caps
    assert caps is not None and caps.cap_mm.shape == (15,)
    heavy, light = np.argmax(depth), np.argmin(depth)
    assert caps.cap_mm[heavy] > 2 * caps.cap_mm[light] > 0
    assert np.all(caps.expected_mm < cal.depths.depth_mm)
    assert any(w.startswith("cap cross-check") for w in cal.warnings)
    # a calibration that cannot be read leaves the calibration standing, said so
    bad = calibrate_dead_weights(folder, nu=0.5, law="linear", optics=folder / "nope.npz")
    assert bad.caps is None and bad.fit.E_mpa == pytest.approx(cal.fit.E_mpa)
    assert any(w.startswith("cap cross-check not made") and "nope.npz" in w
               for w in bad.warnings)


@pytest.mark.slow
def test_cli_calibrate_reads_a_dead_weight_folder(weights, tmp_path, capsys):
    folder, _ = weights
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "fit.json").write_text("my own notes")
    # a file tactilevision did not write is not replaced without --overwrite
    assert main(["calibrate", str(folder), "--out", str(mine), "--law", "linear"]) == 2
    assert (mine / "fit.json").read_text() == "my own notes"
    out = tmp_path / "cal"
    assert main(["calibrate", str(folder), "--out", str(out), "--law", "linear",
                 "--depth-rule", "nominal", "--no-report"]) == 0
    assert (out / "fit.json").is_file() and not (out / "calibration.png").exists()
    text = capsys.readouterr().out
    assert "dead weights: P = m g" in text
    assert "--depth-rule nominal is a gauge block's option" in text
    obj = json.loads((out / "fit.json").read_text())
    assert obj["clock_offset_s"] is None and obj["n_presses"] == 15
    assert "dead weights" in obj["source"]


@pytest.mark.parametrize(("row", "message"), [
    ("000.png,-0.02,0.0001", r"weights.csv line 2, column mass_kg: -0.02 \(a mass must be > 0"),
    ("000.png,0.02,-1", r"line 2, column mass_std_kg: -1"),
    ("nothere.png,0.02,0.0001", r"line 2, column frame: 'nothere.png' is not a file"),
    ("000.png,heavy,0.0001", r"line 2, column mass_kg: 'heavy' is not a number"),
])
def test_bad_weights_named_by_line(weights, tmp_path, row, message):
    folder, _ = weights
    bad = tmp_path / "bad"
    (bad / "frames").mkdir(parents=True)
    for name in ("session.toml", "reference.png"):
        (bad / name).write_bytes((folder / name).read_bytes())
    (bad / "frames" / "000.png").write_bytes((folder / "frames" / "000.png").read_bytes())
    (bad / "weights.csv").write_text("frame,mass_kg,mass_std_kg\n" + row + "\n")
    with pytest.raises(InputError, match=message):
        read_dead_weights(bad)
    # the CLI: exit 2, one sentence, nothing written
    assert main(["calibrate", str(bad), "--out", str(tmp_path / "out")]) == 2
    assert not (tmp_path / "out").exists()


def test_an_unknown_column_is_warned(weights, tmp_path):
    folder, _ = weights
    odd = tmp_path / "odd"
    shutil.copytree(folder, odd)
    text = (odd / "weights.csv").read_text().splitlines()
    (odd / "weights.csv").write_text("\n".join([text[0] + ",colour"]
                                               + [r + ",red" for r in text[1:]]) + "\n")
    assert any("column colour is not read" in n for n in read_dead_weights(odd).notes)


def test_a_flat_punch_is_not_a_dead_weight(weights, tmp_path):
    folder, _ = weights
    bad = tmp_path / "punch"
    bad.mkdir()
    toml = (folder / "session.toml").read_text().replace('shape = "sphere"\n', "")
    (bad / "session.toml").write_text(toml + "\n[gauge_block]\ndepths_mm = [0.2]\n")
    with pytest.raises(InputError, match=r"shape must be \"sphere\" for dead weights"):
        read_dead_weights(bad)
