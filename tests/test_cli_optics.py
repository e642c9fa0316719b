"""``optics calibrate`` and ``reconstruct``: files written, exit status, stderr sentences."""

from __future__ import annotations

import csv
import re
from pathlib import Path

import cv2
import numpy as np
import pytest
from _data import TAXIM_BALL_RADIUS_MM, TAXIM_MM_PER_PX, ball_depth, synthetic_presses

from tactilevision import InputError
from tactilevision.cli import main
from tactilevision.optics import PhotometricCalibration

BALL_PX = 40.0
MM = 0.05
SHAPE = (120, 160)


def errors(stderr: str) -> list[str]:
    """The error sentences (progress bars share standard error)."""
    return [ln for ln in stderr.replace("\r", "\n").splitlines() if ": error: " in ln]


@pytest.fixture(scope="module")
def presses():
    return synthetic_presses(8, shape=SHAPE, ball_radius=BALL_PX, seed=0)


@pytest.fixture(scope="module")
def presses_npz(presses, tmp_path_factory):
    ref, frames, centres, radii = presses
    path = tmp_path_factory.mktemp("presses") / "presses.npz"
    np.savez(path, reference=ref, frames=frames, centers_px=centres, radii_px=radii)
    return path


@pytest.fixture(scope="module")
def calibration(presses_npz, tmp_path_factory):
    out = tmp_path_factory.mktemp("cal") / "optics.npz"
    status = main(["optics", "calibrate", str(presses_npz), "--ball-radius-mm",
                   str(BALL_PX * MM), "--mm-per-px", str(MM), "--model", "lut",
                   "--presses", "0::2", "--out", str(out), "--credit", "synthetic frames"])
    assert status == 0
    return out


def frames_dir(folder: Path, presses, idx=(1, 3, 5)) -> Path:
    ref, frames, _, _ = presses
    folder.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(folder / "reference.png"), ref)
    for i in idx:
        cv2.imwrite(str(folder / f"press_{i}.png"), frames[i])
    cv2.imwrite(str(folder / "press_9.png"), ref)  # no contact
    return folder


# ------------------------------------------------------------------ calibrate
def test_calibrate_writes_calibration(calibration, capsys):
    cal = PhotometricCalibration.load(calibration)
    assert cal.model == "lut" and cal.lut is not None
    assert cal.shape == SHAPE and cal.mm_per_px == MM
    assert cal.provenance["presses"] == [0, 2, 4, 6]
    assert cal.provenance["credit"] == "synthetic frames"
    assert cal.provenance["circles"] == "given"


def test_calibrate_reports_held_out(presses_npz, tmp_path, capsys):
    out = tmp_path / "o.npz"
    assert main(["optics", "calibrate", str(presses_npz), "--ball-radius-mm", "2",
                 "--mm-per-px", str(MM), "--model", "lut", "--presses", "1,3,5",
                 "--out", str(out)]) == 0
    stdout = capsys.readouterr().out
    assert f"wrote lut calibration from 3 presses to {out}" in stdout
    assert "held-out presses (5)" in stdout
    # the printed fitted radius is the synthetic ball's 2.0 mm to 10%
    fitted = float(stdout.split("fitted ball radius ")[1].split()[0])
    assert fitted == pytest.approx(2.0, rel=0.1)


def test_calibrate_provenance_command(calibration, presses_npz):
    cmd = PhotometricCalibration.load(calibration).provenance["command"]
    assert "optics calibrate" in cmd and presses_npz.name in cmd


def test_calibrate_mlp_from_folder(presses, tmp_path, capsys, torch_one_thread):
    ref, frames, centres, radii = presses
    folder = tmp_path / "balls"
    folder.mkdir()
    cv2.imwrite(str(folder / "ref.png"), ref)
    rows = ["frame,x_px,y_px,radius_px"]
    for i in range(4):
        cv2.imwrite(str(folder / f"b{i}.png"), frames[i])
        rows.append(f"b{i}.png,{centres[i, 0]},{centres[i, 1]},{radii[i]}")
    (folder / "circles.csv").write_text("\n".join(rows) + "\n")
    out = tmp_path / "mlp.npz"
    assert main(["optics", "calibrate", str(folder), "--ball-radius-mm", "2", "--mm-per-px",
                 str(MM), "--model", "mlp", "--epochs", "1", "--out", str(out)]) == 0
    cal = PhotometricCalibration.load(out)
    assert cal.model == "mlp" and cal.onnx_bytes
    assert cal.provenance["n_presses"] == 4


@pytest.mark.parametrize("sel", ["abc", "0:9:1:2", "99", "-9", "5:5"])
def test_calibrate_bad_presses(presses_npz, tmp_path, capsys, sel):
    out = tmp_path / "never.npz"
    status = main(["optics", "calibrate", str(presses_npz), "--ball-radius-mm", "2",
                   "--mm-per-px", str(MM), "--model", "lut", "--presses", sel,
                   "--out", str(out)])
    assert status == 2
    err = errors(capsys.readouterr().err)
    assert len(err) == 1 and f"--presses '{sel}'" in err[0]
    assert not out.exists()


def test_calibrate_lut_cells(presses_npz, tmp_path, capsys):
    out = tmp_path / "cells.npz"
    assert main(["optics", "calibrate", str(presses_npz), "--ball-radius-mm", "2",
                 "--mm-per-px", str(MM), "--model", "lut", "--lut-cells", "2,3",
                 "--out", str(out)]) == 0
    cal = PhotometricCalibration.load(out)
    assert cal.cell_luts.shape == (3, 2, 32, 32, 32, 2)
    assert cal.provenance["lut_cells"] == [2, 3]


@pytest.mark.parametrize(("cells", "model", "words"), [
    ("8", "lut", "two positive integers"), ("8,x", "lut", "two positive integers"),
    ("0,2", "lut", "two positive integers"), ("2,2", "mlp", "needs --model lut")])
def test_calibrate_bad_lut_cells(presses_npz, tmp_path, capsys, cells, model, words):
    out = tmp_path / "never.npz"
    assert main(["optics", "calibrate", str(presses_npz), "--ball-radius-mm", "2",
                 "--mm-per-px", str(MM), "--model", model, "--lut-cells", cells,
                 "--out", str(out)]) == 2
    err = errors(capsys.readouterr().err)
    assert len(err) == 1 and "--lut-cells" in err[0] and words in err[0]
    assert not out.exists()


def test_calibrate_missing_presses_file(tmp_path, capsys):
    missing = tmp_path / "absent.npz"
    assert main(["optics", "calibrate", str(missing), "--ball-radius-mm", "2", "--mm-per-px",
                 "0.05", "--model", "lut", "--out", str(tmp_path / "x.npz")]) == 2
    err = errors(capsys.readouterr().err)
    assert len(err) == 1 and str(missing) in err[0]


def test_calibrate_nonpositive_scale(presses_npz, tmp_path, capsys):
    assert main(["optics", "calibrate", str(presses_npz), "--ball-radius-mm", "-2",
                 "--mm-per-px", "0.05", "--out", str(tmp_path / "x.npz")]) == 2
    assert "--ball-radius-mm" in errors(capsys.readouterr().err)[0]


def test_calibrate_from_taxim_package(tmp_path, capsys):
    # 'taxim:gelsight' names the data pack inside the installed taxim package
    out = tmp_path / "gelsight.npz"
    assert main(["optics", "calibrate", "taxim:gelsight", "--ball-radius-mm",
                 str(TAXIM_BALL_RADIUS_MM), "--mm-per-px", str(TAXIM_MM_PER_PX), "--model", "lut",
                 "--presses", "0:40", "--out", str(out)]) == 0
    stdout = capsys.readouterr().out
    assert "held-out presses (8)" in stdout
    # same loose bound as test_taxim_lut_smoke: 2.0 mm ball to 15%
    fitted = float(stdout.split("fitted ball radius ")[1].split()[0])
    assert fitted == pytest.approx(TAXIM_BALL_RADIUS_MM, rel=0.15)
    assert PhotometricCalibration.load(out).shape == (480, 640)


def test_calibrate_unknown_taxim_sensor(tmp_path, capsys):
    assert main(["optics", "calibrate", "taxim:nosuch", "--ball-radius-mm", "2", "--mm-per-px",
                 "0.03", "--model", "lut", "--out", str(tmp_path / "x.npz")]) == 2
    err = errors(capsys.readouterr().err)
    assert len(err) == 1 and "nosuch" in err[0]


# ---------------------------------------------------------------- reconstruct
def test_reconstruct_folder(calibration, presses, tmp_path, capsys):
    src = frames_dir(tmp_path / "frames", presses)
    out = tmp_path / "out"
    assert main(["reconstruct", str(src), "--calibration", str(calibration),
                 "--out", str(out), "--images"]) == 0
    stdout = capsys.readouterr().out
    assert "reconstructed 4 frame(s)" in stdout and "reference.png" in stdout
    stems = ["press_1", "press_3", "press_5", "press_9"]
    for stem in stems:
        h = np.load(out / f"{stem}_height.npy")
        assert h.shape == SHAPE and h.dtype == np.float32
        png = cv2.imread(str(out / f"{stem}_depth.png"))
        assert png is not None and png.shape[:2] == (430, 1040)  # frame + map, 100 dpi
    assert not (out / "reference_height.npy").exists()
    with (out / "heights.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert [r["frame"] for r in rows] == [f"{s}.png" for s in stems]
    assert set(rows[0]) == {"frame", "max_depth_mm", "contact_area_mm2", "out_of_range_px"}
    assert all(int(r["out_of_range_px"]) >= 0 for r in rows)
    _, _, centres, radii = presses
    for r, i in zip(rows[:3], (1, 3, 5), strict=True):
        depth, _, _ = ball_depth(SHAPE, centres[i], radii[i], BALL_PX)
        cap_mm = depth.max() * MM
        # the LUT's height error is at most its slope error (<= 0.1 at these
        # rims, test_lut_mlp) times the contact radius: ~30% of the cap depth
        assert float(r["max_depth_mm"]) == pytest.approx(cap_mm, rel=0.3)
        # the saved height map is the one summarised
        assert np.load(out / f"press_{i}_height.npy").max() == pytest.approx(
            float(r["max_depth_mm"]), abs=1e-4)
    # no contact: a small fraction of a press depth
    assert float(rows[3]["max_depth_mm"]) < 0.1 * float(rows[0]["max_depth_mm"])


def test_out_of_range_flags_colours_the_calibration_never_saw(calibration, presses,
                                                             tmp_path):
    """A press the calibration has seen the like of: almost no pixel flagged; the same
    press with a patch painted a colour far outside the calibrated range: the patch
    flagged, and counted in heights.csv."""
    from tactilevision.optics import DepthReconstructor, PhotometricCalibration

    ref, frames, _, _ = presses
    cal = PhotometricCalibration.load(calibration)
    recon = DepthReconstructor(cal, reference=ref)
    plain = recon.out_of_range(frames[3])
    assert plain.shape == SHAPE and plain.mean() < 0.01
    painted = frames[3].copy()
    painted[10:30, 20:50] = (255, 0, 255)
    flagged = recon.out_of_range(painted)
    assert flagged[12:28, 22:48].all()
    assert flagged.sum() - plain.sum() <= 20 * 30 + 4 * 50    # the patch, a blur's width
    src = tmp_path / "frames"
    src.mkdir()
    cv2.imwrite(str(src / "reference.png"), ref)
    cv2.imwrite(str(src / "painted.png"), painted)
    out = tmp_path / "out"
    assert main(["reconstruct", str(src), "--calibration", str(calibration), "--out", str(out),
                 "--no-images", "--no-progress"]) == 0
    with (out / "heights.csv").open() as fh:
        (row,) = list(csv.DictReader(fh))
    assert int(row["out_of_range_px"]) == int(flagged.sum())


def test_reconstruct_no_images(calibration, presses, tmp_path):
    src = frames_dir(tmp_path / "frames", presses, idx=(1,))
    out = tmp_path / "out"
    assert main(["reconstruct", str(src), "--calibration", str(calibration), "--out", str(out),
                 "--no-images"]) == 0
    assert (out / "press_1_height.npy").is_file()
    assert not list(out.glob("*.png"))


def test_reconstruct_boundary_and_engine(calibration, presses, tmp_path, capsys):
    """--boundary picks the Poisson solve (the same maps as the API's), --level contact is
    --boundary contact, --engine onnx needs a network, and --no-progress draws no bar."""
    from tactilevision.optics import DepthReconstructor, PhotometricCalibration

    src = frames_dir(tmp_path / "frames", presses, idx=(3,))
    cal = PhotometricCalibration.load(calibration)
    ref = cv2.imread(str(src / "reference.png"))
    frame = cv2.imread(str(src / "press_3.png"))
    maps = {}
    for opts in (["--boundary", "dirichlet"], ["--boundary", "contact"], ["--level", "contact"]):
        out = tmp_path / "_".join(opts).strip("-")
        assert main(["reconstruct", str(src), "--calibration", str(calibration), "--out",
                     str(out), "--no-images", "--no-progress", *opts]) == 0
        assert "reconstruct:" not in capsys.readouterr().err          # no progress bar
        maps[opts[1]] = np.load(out / "press_3_height.npy")
    for boundary in ("dirichlet", "contact"):
        api = DepthReconstructor(cal, reference=ref, boundary=boundary)(frame)
        np.testing.assert_array_equal(maps[boundary], api)
    np.testing.assert_array_equal(maps["contact"], np.load(
        tmp_path / "level_contact" / "press_3_height.npy"))
    neumann = DepthReconstructor(cal, reference=ref)(frame)
    assert np.abs(maps["dirichlet"] - neumann).max() > 1e-3       # a different solve
    # contact: zero outside the contact region
    assert np.count_nonzero(maps["contact"]) < 0.5 * maps["contact"].size
    # --zero-background: the API's map, the gradients outside the contact set to zero
    out = tmp_path / "zero_background"
    assert main(["reconstruct", str(src), "--calibration", str(calibration), "--out",
                 str(out), "--no-images", "--no-progress", "--zero-background"]) == 0
    zb = np.load(out / "press_3_height.npy")
    np.testing.assert_array_equal(
        zb, DepthReconstructor(cal, reference=ref, zero_background=True)(frame))
    assert np.abs(zb - neumann).max() > 1e-3
    # a LUT has no network for onnx; contradictory options name both
    for opts, words in ((["--engine", "onnx"], "engine='table'"),
                        (["--level", "contact", "--boundary", "dirichlet"], "--boundary dirichlet"),
                        (["--level", "far_field", "--boundary", "contact"], "--level far_field")):
        out = tmp_path / "bad"
        assert main(["reconstruct", str(src), "--calibration", str(calibration), "--out",
                     str(out), "--no-progress", *opts]) == 2
        err = errors(capsys.readouterr().err)
        assert len(err) == 1 and words in err[0], err
        assert not list(out.glob("*.npy")) if out.exists() else True


def test_calibrate_label_fraction(presses, presses_npz, tmp_path, capsys):
    """--label-fraction reaches the calibration (the same LUT as the API's), and a value
    outside (0, 1] is refused before any work."""
    from tactilevision.optics import DepthReconstructor, PhotometricCalibration

    ref, frames, centres, radii = presses
    out = tmp_path / "lf.npz"
    assert main(["optics", "calibrate", str(presses_npz), "--ball-radius-mm",
                 str(BALL_PX * MM), "--mm-per-px", str(MM), "--model", "lut", "--presses",
                 "0::2", "--label-fraction", "0.6", "--no-progress", "--out", str(out)]) == 0
    assert "%|" not in capsys.readouterr().err
    idx = np.arange(0, len(frames), 2)
    cli = PhotometricCalibration.load(out)
    kw = dict(ball_radius_mm=BALL_PX * MM, mm_per_px=MM, model="lut")
    api = PhotometricCalibration.from_ball_presses(ref, frames[idx], centres[idx], radii[idx],
                                                   label_fraction=0.6, **kw)
    full = PhotometricCalibration.from_ball_presses(ref, frames[idx], centres[idx], radii[idx],
                                                    **kw)
    heights = [DepthReconstructor(c, reference=ref)(frames[1]) for c in (cli, api, full)]
    np.testing.assert_array_equal(heights[0], heights[1])
    assert np.abs(heights[0] - heights[2]).max() > 1e-4        # fewer rim pixels learnt
    _refused_before_any_work("--label-fraction", ("0", "1.5", "-0.2"), presses_npz, tmp_path,
                             capsys)


def _refused_before_any_work(option, bads, presses_npz, tmp_path, capsys):
    """`optics calibrate OPTION BAD` exits 2 with one error naming the option and writes
    nothing, for every BAD."""
    for bad in bads:
        assert main(["optics", "calibrate", str(presses_npz), "--ball-radius-mm", "1",
                     "--mm-per-px", str(MM), "--model", "lut", option, bad,
                     "--out", str(tmp_path / "x.npz")]) == 2
        err = errors(capsys.readouterr().err)
        assert len(err) == 1 and option in err[0]
        assert not (tmp_path / "x.npz").exists()


def test_calibrate_flat_fraction(presses, presses_npz, tmp_path, capsys):
    """--flat-fraction reaches the calibration (the same LUT as the API's, saved in its
    provenance), and a value outside (0, 1] is refused before any work."""
    from tactilevision.optics import DepthReconstructor, PhotometricCalibration

    ref, frames, centres, radii = presses
    out = tmp_path / "ff.npz"
    assert main(["optics", "calibrate", str(presses_npz), "--ball-radius-mm",
                 str(BALL_PX * MM), "--mm-per-px", str(MM), "--model", "lut", "--presses",
                 "0::2", "--flat-fraction", "0.2", "--no-progress", "--out", str(out)]) == 0
    idx = np.arange(0, len(frames), 2)
    cli = PhotometricCalibration.load(out)
    assert cli.provenance["flat_fraction"] == 0.2
    api = PhotometricCalibration.from_ball_presses(
        ref, frames[idx], centres[idx], radii[idx], ball_radius_mm=BALL_PX * MM,
        mm_per_px=MM, model="lut", flat_fraction=0.2)
    np.testing.assert_array_equal(DepthReconstructor(cli, reference=ref)(frames[1]),
                                  DepthReconstructor(api, reference=ref)(frames[1]))
    _refused_before_any_work("--flat-fraction", ("0", "1.5", "nan"), presses_npz, tmp_path,
                             capsys)

def test_reconstruct_missing_folder(calibration, tmp_path, capsys):
    missing = tmp_path / "nowhere"
    assert main(["reconstruct", str(missing), "--calibration", str(calibration),
                 "--out", str(tmp_path / "o")]) == 2
    err = errors(capsys.readouterr().err)
    assert len(err) == 1 and str(missing) in err[0] and "does not exist" in err[0]


def test_reconstruct_empty_folder(calibration, tmp_path, capsys):
    empty = tmp_path / "empty"
    empty.mkdir()
    assert main(["reconstruct", str(empty), "--calibration", str(calibration),
                 "--out", str(tmp_path / "o")]) == 2
    err = errors(capsys.readouterr().err)
    assert len(err) == 1 and str(empty) in err[0]


def test_reconstruct_wrong_size_frame_skipped(calibration, presses, tmp_path, capsys):
    src = frames_dir(tmp_path / "frames", presses, idx=(1, 3))
    cv2.imwrite(str(src / "press_2.png"), np.zeros((SHAPE[0], SHAPE[1] + 10, 3), np.uint8))
    out = tmp_path / "out"
    out.mkdir()
    (out / "keep.txt").write_text("written before")
    assert main(["reconstruct", str(src), "--calibration", str(calibration), "--out", str(out),
                 "--no-images"]) == 2
    err = errors(capsys.readouterr().err)
    assert len(err) == 1
    assert "press_2.png" in err[0] and "170 x 120" in err[0] and "160 x 120" in err[0]
    # the others are processed; nothing already written is deleted
    for stem in ("press_1", "press_3", "press_9"):
        assert (out / f"{stem}_height.npy").is_file()
    assert not (out / "press_2_height.npy").exists()
    assert (out / "keep.txt").read_text() == "written before"
    with (out / "heights.csv").open() as fh:
        assert [r["frame"] for r in csv.DictReader(fh)] == ["press_1.png", "press_3.png",
                                                          "press_9.png"]
    # a folder with no frame it can read: nothing written, not even an empty table
    only_bad = tmp_path / "only_bad"
    only_bad.mkdir()
    (only_bad / "press_0.png").write_bytes(b"not a png")
    out2 = tmp_path / "out2"
    out2.mkdir()
    (out2 / "keep.txt").write_text("written before")
    assert main(["reconstruct", str(only_bad), "--calibration", str(calibration),
                 "--out", str(out2), "--no-images"]) == 2
    captured = capsys.readouterr()
    assert "reconstructed 0" not in captured.out
    err = errors(captured.err)
    assert len(err) == 1 and "nothing written" in err[0] and "press_0.png" in err[0]
    assert sorted(p.name for p in out2.iterdir()) == ["keep.txt"]


def test_reconstruct_missing_calibration(presses, tmp_path, capsys):
    src = frames_dir(tmp_path / "frames", presses, idx=(1,))
    missing = tmp_path / "no_cal.npz"
    assert main(["reconstruct", str(src), "--calibration", str(missing),
                 "--out", str(tmp_path / "o")]) == 2
    err = errors(capsys.readouterr().err)
    assert len(err) == 1 and str(missing) in err[0]


def test_corrupt_calibration_files_are_named(calibration, tmp_path):
    """A calibration .npz cut short or with damaged bytes is refused with the file named
    (it raised zipfile.BadZipFile or zlib.error before)."""
    data = Path(calibration).read_bytes()
    cut = tmp_path / "cut.npz"
    cut.write_bytes(data[: len(data) // 2])
    flipped = tmp_path / "flipped.npz"
    flipped.write_bytes(data[:600] + bytes(b ^ 0xFF for b in data[600:1600]) + data[1600:])
    for bad in (cut, flipped):
        with pytest.raises(InputError, match=re.escape(f"calibration file {bad} is not a "
                                                       "readable .npz")):
            PhotometricCalibration.load(bad)


def test_reconstruct_calibration_not_npz(presses, tmp_path, capsys):
    src = frames_dir(tmp_path / "frames", presses, idx=(1,))
    bad = tmp_path / "bad.npz"
    bad.write_text("nope")
    assert main(["reconstruct", str(src), "--calibration", str(bad),
                 "--out", str(tmp_path / "o")]) == 2
    assert str(bad) in errors(capsys.readouterr().err)[0]


def test_reconstruct_bad_reference(calibration, presses, tmp_path, capsys):
    src = frames_dir(tmp_path / "frames", presses, idx=(1,))
    missing = tmp_path / "ref_missing.png"
    assert main(["reconstruct", str(src), "--calibration", str(calibration), "--reference",
                 str(missing), "--out", str(tmp_path / "o")]) == 2
    assert str(missing) in errors(capsys.readouterr().err)[0]
    small = tmp_path / "small_ref.png"
    cv2.imwrite(str(small), np.zeros((10, 10, 3), np.uint8))
    assert main(["reconstruct", str(src), "--calibration", str(calibration), "--reference",
                 str(small), "--out", str(tmp_path / "o")]) == 2
    err = errors(capsys.readouterr().err)
    assert len(err) == 1 and str(small) in err[0] and "10 x 10" in err[0]


def test_reconstruct_sensor_without_shipped_calibration(presses, tmp_path, capsys,
                                                       monkeypatch):
    """An install whose shipped calibration is missing (the asset folder empty) is
    refused naming the sensor."""
    import tactilevision._assets as assets

    empty = tmp_path / "assets"
    empty.mkdir()
    monkeypatch.setattr(assets, "asset_dir", lambda kind: empty)
    src = frames_dir(tmp_path / "frames", presses, idx=(1,))
    assert main(["reconstruct", str(src), "--sensor", "gelsight",
                 "--out", str(tmp_path / "o")]) == 2
    err = errors(capsys.readouterr().err)
    assert len(err) == 1 and "gelsight" in err[0]


def test_reconstruct_sensor_gelsight(taxim_presses, tmp_path, capsys):
    ps = taxim_presses
    src = tmp_path / "frames"
    src.mkdir()
    cv2.imwrite(str(src / "reference.png"), ps.reference)
    idx = (1, 7)
    for i in idx:
        cv2.imwrite(str(src / f"press_{i}.png"), ps.frames[i])
    out = tmp_path / "out"
    assert main(["reconstruct", str(src), "--sensor", "gelsight", "--out", str(out),
                 "--no-images"]) == 0
    for i in idx:
        h = np.load(out / f"press_{i}_height.npy")
        assert h.shape == (480, 640)
        # pressed in at the annotated centre by at least the spherical cap
        # R - sqrt(R^2 - a^2), 20% allowance (as in test_taxim_lut_smoke)
        a = ps.radii_px[i] * TAXIM_MM_PER_PX
        cap = TAXIM_BALL_RADIUS_MM - np.sqrt(TAXIM_BALL_RADIUS_MM**2 - a * a)
        cx, cy = (round(float(v)) for v in ps.centers_px[i])
        assert h[cy, cx] > 0.8 * cap


# ----------------------------------------------------------------------- help
@pytest.mark.parametrize("argv", [[], ["reconstruct"], ["optics"], ["optics", "calibrate"],
                                  ["fit"]])
def test_help_exits_zero(argv, capsys):
    with pytest.raises(SystemExit) as exc:
        main([*argv, "--help"])
    assert exc.value.code == 0
    assert "usage: tactilevision" in capsys.readouterr().out


def test_reconstruct_requires_calibration_or_sensor(tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["reconstruct", str(tmp_path)])
    assert exc.value.code == 2
    assert "--calibration" in capsys.readouterr().err
