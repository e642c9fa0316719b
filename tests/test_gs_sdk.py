"""Ball presses in gs_sdk's calibration layout (catalog.csv, background.png,
<diameter>mm/<i>/gelsight.png, label.npz): read, and calibrated with two ball sizes in one
calibration. The folders are written here from synthetic presses of known balls."""

from __future__ import annotations

import re
from pathlib import Path

import cv2
import numpy as np
import pytest
from _data import synthetic_presses

from tactilevision import InputError
from tactilevision.cli import main
from tactilevision.io import read_ball_presses, read_gs_sdk
from tactilevision.optics import DepthReconstructor, PhotometricCalibration

MM = 0.05
SHAPE = (120, 160)
BALLS_PX = (40.0, 28.0)          # two ball sizes: 4.0 and 2.8 mm in diameter


def _two_balls():
    """Presses of two balls on one pad (one reference): frames, centres, contact radii and
    each press's ball radius (px)."""
    sets = [synthetic_presses(n, shape=SHAPE, ball_radius=r, seed=0)
            for n, r in zip((6, 6), BALLS_PX, strict=True)]
    ref = sets[0][0]
    assert np.array_equal(ref, sets[1][0])
    frames = np.concatenate([s[1] for s in sets])
    centres = np.concatenate([s[2] for s in sets])
    radii = np.concatenate([s[3] for s in sets])
    ball_px = np.repeat(BALLS_PX, 6)
    return ref, frames, centres, radii, ball_px


def write_gs_sdk(folder: Path, labels: bool | list[bool] = True) -> tuple:
    """A gs_sdk calibration folder of :func:`_two_balls`' presses, as collect_data.py and
    label_data.py write one (catalog rows in collection order)."""
    ref, frames, centres, radii, ball_px = _two_balls()
    folder.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(folder / "background.png"), ref)
    rows = ["experiment_reldir,diameter(mm)"]
    count: dict[str, int] = {}
    reldirs = []
    for i, (f, c, r, b) in enumerate(zip(frames, centres, radii, ball_px, strict=True)):
        diameter = 2 * b * MM
        sub = f"{diameter:.3f}mm"
        k = count.setdefault(sub, 0)
        count[sub] += 1
        reldir = f"{sub}/{k}"
        (folder / reldir).mkdir(parents=True)
        cv2.imwrite(str(folder / reldir / "gelsight.png"), f)
        if labels is True or (isinstance(labels, list) and labels[i]):
            np.savez(folder / reldir / "label.npz", center=c, radius=r)
        rows.append(f"{reldir},{diameter:.3f}")
        reldirs.append(reldir)
    (folder / "catalog.csv").write_text("\n".join(rows) + "\n")
    return ref, frames, centres, radii, ball_px, reldirs


def test_read_gs_sdk_folder(tmp_path):
    ref, frames, centres, radii, ball_px, reldirs = write_gs_sdk(tmp_path / "calib")
    ps = read_ball_presses(tmp_path / "calib")          # recognised by its catalog.csv
    assert ps.names == reldirs
    np.testing.assert_array_equal(ps.reference, ref)
    np.testing.assert_array_equal(ps.frames, frames)
    np.testing.assert_allclose(ps.centers_px, centres)
    np.testing.assert_allclose(ps.radii_px, radii)
    np.testing.assert_allclose(ps.ball_radius_mm, ball_px * MM, atol=5e-4)   # 3 decimals
    # without labels: no circles (they are detected when calibrating)
    write_gs_sdk(tmp_path / "bare", labels=False)
    bare = read_gs_sdk(tmp_path / "bare")
    assert bare.centers_px is None and bare.radii_px is None
    assert bare.ball_radius_mm is not None and bare.ball_radius_mm.size == 12


def test_two_ball_sizes_in_one_calibration(tmp_path, capsys):
    """Calibrated on the even presses of both balls, each press with its own ball: the
    held-out presses of each ball come back at their own radius; taking one radius for all
    (the larger) misreads the smaller ball's presses."""
    write_gs_sdk(tmp_path / "calib")
    out = tmp_path / "cal.npz"
    assert main(["optics", "calibrate", str(tmp_path / "calib"), "--mm-per-px", str(MM),
                 "--model", "lut", "--presses", "0::2", "--no-progress",
                 "--out", str(out)]) == 0
    stdout = capsys.readouterr().out
    lines = re.findall(r"held-out presses \((\d+)\).*fitted ball radius ([\d.]+) .*\(true "
                       r"([\d.]+)\)", stdout)
    assert len(lines) == 2, stdout
    for n, fitted, true in lines:
        assert int(n) == 3
        assert float(fitted) == pytest.approx(float(true), rel=0.1)
    assert sorted(float(t) for _, _, t in lines) == pytest.approx(sorted(b * MM
                                                                         for b in BALLS_PX))
    # the same calibration as the API's with per-press radii
    ref, frames, centres, radii, ball_px = _two_balls()
    idx = np.arange(0, 12, 2)
    api = PhotometricCalibration.from_ball_presses(
        ref, frames[idx], centres[idx], radii[idx], ball_radius_mm=ball_px[idx] * MM,
        mm_per_px=MM, model="lut")
    cli = PhotometricCalibration.load(out)
    np.testing.assert_allclose(DepthReconstructor(cli)(frames[7]),
                               DepthReconstructor(api)(frames[7]), atol=1e-6)
    assert cli.provenance["ball_radius_mm"] == pytest.approx(list(ball_px[idx] * MM),
                                                             abs=5e-4)
    # one radius for every press: the small ball's labels are too steep, its presses
    # come back too deep, their normals off
    from tactilevision.optics import evaluate_ball_presses

    one = PhotometricCalibration.from_ball_presses(
        ref, frames[idx], centres[idx], radii[idx], ball_radius_mm=BALLS_PX[0] * MM,
        mm_per_px=MM, model="lut")
    small = np.arange(7, 12, 2)
    per, single = (evaluate_ball_presses(DepthReconstructor(c), frames[small], centres[small],
                                         radii[small], BALLS_PX[1]) for c in (api, one))
    # measured: 1.14 against 2.16 deg, fitted radius 1.398 against 1.552 mm (true 1.4)
    assert per.normal_angle_deg < 0.7 * single.normal_angle_deg
    assert per.fitted_radius_px == pytest.approx(BALLS_PX[1], rel=0.03)
    assert single.fitted_radius_px > 1.06 * BALLS_PX[1]


def test_gs_sdk_ball_radius_from_the_catalog_only(tmp_path, capsys):
    write_gs_sdk(tmp_path / "calib")
    out = tmp_path / "x.npz"
    assert main(["optics", "calibrate", str(tmp_path / "calib"), "--ball-radius-mm", "2",
                 "--mm-per-px", str(MM), "--model", "lut", "--out", str(out)]) == 2
    assert "leave out --ball-radius-mm" in capsys.readouterr().err
    flat = tmp_path / "flat"
    flat.mkdir()
    ref, frames, *_ = _two_balls()
    cv2.imwrite(str(flat / "reference.png"), ref)
    for i in range(2):
        cv2.imwrite(str(flat / f"press_{i}.png"), frames[i])
    assert main(["optics", "calibrate", str(flat), "--mm-per-px", str(MM), "--model", "lut",
                 "--out", str(out)]) == 2
    assert "--ball-radius-mm is needed" in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.parametrize("damage, words", [
    ("no_catalog", "has no catalog.csv"),
    ("no_background", "has no background.png"),
    ("bad_column", "must have the columns experiment_reldir,diameter(mm)"),
    ("bad_diameter", "line 3: diameter(mm) 'big' is not a positive number"),
    ("outside", "line 2: experiment_reldir '../elsewhere' must be a folder inside"),
    ("no_image", "line 2:"),
    ("some_labels", "has no label.npz while others have one"),
    ("bad_label", "is not a gs_sdk label"),
    ("wrong_size", "but background.png is 160 x 120 px"),
])
def test_gs_sdk_bad_folders_name_the_fault(tmp_path, damage, words):
    folder = tmp_path / "calib"
    labels = [i != 4 for i in range(12)] if damage == "some_labels" else True
    _, _, _, _, _, reldirs = write_gs_sdk(folder, labels=labels)
    catalog = folder / "catalog.csv"
    text = catalog.read_text().splitlines()
    if damage == "no_catalog":
        catalog.unlink()
    elif damage == "no_background":
        (folder / "background.png").unlink()
    elif damage == "bad_column":
        catalog.write_text("\n".join(["reldir,diameter", *text[1:]]) + "\n")
    elif damage == "bad_diameter":
        text[2] = text[2].split(",")[0] + ",big"
        catalog.write_text("\n".join(text) + "\n")
    elif damage == "outside":
        text[1] = "../elsewhere," + text[1].split(",")[1]
        catalog.write_text("\n".join(text) + "\n")
    elif damage == "no_image":
        (folder / reldirs[0] / "gelsight.png").unlink()
    elif damage == "bad_label":
        np.savez(folder / reldirs[3] / "label.npz", centre=[1, 2])
    elif damage == "wrong_size":
        cv2.imwrite(str(folder / reldirs[5] / "gelsight.png"), np.zeros((50, 60, 3), np.uint8))
    with pytest.raises(InputError, match=re.escape(words)):
        read_ball_presses(folder) if damage != "no_catalog" else read_gs_sdk(folder)
