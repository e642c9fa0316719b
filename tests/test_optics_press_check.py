"""Only ball presses are ball presses: frames of other objects among the ball presses are
refused by file before a calibration trains on them or scores them (issue 55).

The folder is drawn by Taxim's own renderer (none of our shading): ten presses of a 2 mm
ball and, among them, a ring, a flat punch and a slotted screw head, each with a circle
drawn for it. Real ball presses (taxim's 48 GelSight presses, circles annotated by hand;
the shared GelSight Mini's 22) lose none.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from _data import TAXIM_BALL_RADIUS_MM, TAXIM_MM_PER_PX, flat_gel_taxim, taxim_mixed_presses

from tactilevision.cli import main
from tactilevision.io import read_ball_presses, taxim_datapack
from tactilevision.optics import PhotometricCalibration, non_ball_presses

MINI = Path(__file__).resolve().parents[2] / "shared" / "real" / "gelsight_mini"


@pytest.fixture(scope="module")
def mixed(tmp_path_factory):
    pytest.importorskip("taxim")
    pytest.importorskip("jax")
    folder = tmp_path_factory.mktemp("mixed") / "presses"
    with flat_gel_taxim() as sim:
        others = taxim_mixed_presses(sim, folder)
    return folder, others


@pytest.mark.slow
def test_other_objects_are_refused_by_file(mixed, tmp_path, capsys):
    """The ring, the punch and the screw head are refused, named by file, and neither
    trained on nor scored; every ball press is kept."""
    folder, others = mixed
    out = tmp_path / "optics.npz"
    assert main(["optics", "calibrate", str(folder), "--ball-radius-mm",
                 str(TAXIM_BALL_RADIUS_MM), "--mm-per-px", str(TAXIM_MM_PER_PX), "--model",
                 "lut", "--no-progress", "--out", str(out)]) == 0
    stdout = capsys.readouterr().out
    report = json.loads((tmp_path / "optics_accuracy.json").read_text())
    refused = {r["file"] for r in report["refused"]}
    assert refused == set(others)
    for name in others:
        assert f"({name}): its contact is not the 2 mm ball's" in stdout
    cal = PhotometricCalibration.load(out)
    assert not set(cal.provenance["files"]) & set(others)
    assert len(cal.provenance["files"]) == 10
    scored = {f for b in report["balls"] for f in b["files"]}
    assert scored and not scored & set(others)
    # the folder's numbering survives the refusals: ring.png is the folder's press 11
    names = read_ball_presses(folder).names
    assert {r["press"] for r in report["refused"]} == {names.index(n) for n in others}
    assert all(names[i] == f for b in report["balls"] for i, f in zip(b["presses"], b["files"],
                                                                        strict=True))


@pytest.mark.slow
def test_with_detected_circles_too(mixed):
    folder, others = mixed
    from tactilevision.optics import detect_contact_circles

    ps = read_ball_presses(folder)
    c, r = detect_contact_circles(ps.frames, ps.reference, edge="contact")
    refused, angle, threshold = non_ball_presses(
        ps.reference, ps.frames, c, r, np.full(len(ps.frames), 2.0 / TAXIM_MM_PER_PX))
    assert {ps.names[i] for i in np.flatnonzero(refused)} == set(others)
    assert np.all(angle[refused] > threshold) and np.all(angle[~refused] <= threshold)


@pytest.mark.parametrize("which", ["taxim", "mini"])
def test_real_ball_presses_are_all_kept(which):
    """No real ball press is refused, with hand-annotated circles (taxim) or detected ones
    (the GelSight Mini, 6.31 mm ball)."""
    from tactilevision.optics import detect_contact_circles

    if which == "taxim":
        ps = read_ball_presses(taxim_datapack("gelsight"))
        c, r, ball = ps.centers_px, ps.radii_px, 2.0 / TAXIM_MM_PER_PX
    else:
        if not MINI.is_dir():
            pytest.skip("../shared/real/gelsight_mini is absent")
        ps = read_ball_presses(MINI)
        c, r = detect_contact_circles(ps.frames, ps.reference, edge="contact")
        ball = ps.ball_radius_mm / 0.0634
    refused, angle, threshold = non_ball_presses(ps.reference, ps.frames, c, r,
                                                 np.broadcast_to(ball, (len(ps.frames),)))
    assert not refused.any(), [ps.names[i] for i in np.flatnonzero(refused)]
    assert np.nanmax(angle) < threshold


def test_a_frame_without_contact_is_refused_by_file(tmp_path, capsys):
    """Circles detected: a frame with no contact (the reference again) is refused with its
    file name, the others calibrated; a circle larger than the ball is an error naming its
    file, not its place among the presses trained on."""
    import cv2
    from _data import synthetic_presses

    ref, frames, centres, radii = synthetic_presses(8, shape=(120, 160), ball_radius=40.0,
                                                    seed=0)
    folder = tmp_path / "presses"
    folder.mkdir()
    cv2.imwrite(str(folder / "reference.png"), ref)
    for i, f in enumerate(frames):
        cv2.imwrite(str(folder / f"press_{i}.png"), f)
    cv2.imwrite(str(folder / "press_8.png"), ref)
    out = tmp_path / "o.npz"
    assert main(["optics", "calibrate", str(folder), "--ball-radius-mm", "2", "--mm-per-px",
                 "0.05", "--model", "lut", "--no-progress", "--out", str(out)]) == 0
    stdout = capsys.readouterr().out
    assert "refused press 8 (press_8.png): no contact found" in stdout
    assert "press_8.png" not in PhotometricCalibration.load(out).provenance["files"]
    rows = ["frame,x_px,y_px,radius_px"] + [
        f"press_{i}.png,{centres[i, 0]},{centres[i, 1]},{radii[i] if i != 5 else 45.0}"
        for i in range(8)]
    (folder / "press_8.png").unlink()
    (folder / "circles.csv").write_text("\n".join(rows) + "\n")
    assert main(["optics", "calibrate", str(folder), "--ball-radius-mm", "2", "--mm-per-px",
                 "0.05", "--model", "lut", "--no-progress", "--presses", "1::2",
                 "--out", str(tmp_path / "p.npz")]) == 2
    err = capsys.readouterr().err
    assert "press_5.png: contact radius 45.0 px is not smaller than the ball radius" in err
