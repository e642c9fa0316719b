"""Nothing lost (issue 18): outputs are written whole or not at all, and files that
tactilevision did not write are never replaced without --overwrite."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.cli import main
from tactilevision.io import MANIFEST, StagedOutput, check_overwrite, remove_staging

ROOT = Path(__file__).resolve().parents[1]
BALL_FRAMES = ROOT / "sample_frames" / "gelsight_ball" / "frames"


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file()}


def test_staged_output_commits_whole_and_keeps_a_manifest(tmp_path):
    out = tmp_path / "out"
    with StagedOutput(out) as stage:
        assert stage.path.parent == out and stage.path.name.startswith(".tactilevision-tmp-")
        (stage.path / "a.csv").write_text("1\n")
        (stage.path / "sub").mkdir()
        (stage.path / "sub" / "b.png").write_bytes(b"png")
        assert not (out / "a.csv").exists()          # nothing in place before the commit
        assert stage.commit() == ["a.csv", "sub/b.png"]
    assert (out / "a.csv").read_text() == "1\n" and (out / "sub" / "b.png").exists()
    assert json.loads((out / MANIFEST).read_text())["files"] == ["a.csv", "sub/b.png"]
    assert not list(out.glob(".tactilevision-tmp-*"))
    # a rerun may replace what it wrote
    with StagedOutput(out) as stage:
        (stage.path / "a.csv").write_text("2\n")
        stage.commit()
    assert (out / "a.csv").read_text() == "2\n"


@pytest.mark.parametrize("error", [RuntimeError("boom"), KeyboardInterrupt()])
def test_staged_output_leaves_the_folder_as_it_was_on_error_or_ctrl_c(tmp_path, error):
    out = tmp_path / "out"
    out.mkdir()
    (out / "a.csv").write_text("old\n")
    before = _snapshot(out)
    with pytest.raises(type(error)), StagedOutput(out) as stage:
        (stage.path / "a.csv").write_text("half")
        raise error
    assert _snapshot(out) == before
    assert not list(out.glob(".tactilevision-tmp-*"))


@pytest.mark.parametrize("error", [RuntimeError("boom"), KeyboardInterrupt()])
def test_a_folder_the_block_created_is_removed_again_when_nothing_was_moved(tmp_path, error):
    """Issue 86: an interrupted run leaves no empty output folder (nor the parents it
    made); a folder that was there before, or holds anything, stays."""
    out = tmp_path / "a" / "b" / "out"
    with pytest.raises(type(error)), StagedOutput(out) as stage:
        assert out.is_dir()
        (stage.path / "x.csv").write_text("half")
        raise error
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "mine.txt").write_text("the user's")
    with pytest.raises(type(error)), StagedOutput(out):
        raise error
    assert [p.name for p in (tmp_path / "a").iterdir()] == ["mine.txt"]
    with StagedOutput(out) as stage:                  # committed: kept
        (stage.path / "x.csv").write_text("whole")
        stage.commit()
    assert (out / "x.csv").read_text() == "whole"


def test_the_watchdogs_cleanup_removes_the_folders_open_blocks_created(tmp_path):
    """remove_staging (what the command line's watchdog calls before it exits 130, the
    block never left) removes the staging folder and the empty folders the block made."""
    out = tmp_path / "new" / "out"
    stage = StagedOutput(out).__enter__()
    (stage.path / "x.csv").write_text("half")
    remove_staging()
    assert list(tmp_path.iterdir()) == []


def test_files_tactilevision_did_not_write_stop_the_run(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "fit.json").write_text("mine")
    with pytest.raises(InputError, match=r"already holds fit.json, not written by "
                                         r"tactilevision: give --overwrite"):
        check_overwrite(out, ["fit.json", "holds.csv"])
    check_overwrite(out, ["holds.csv"])                      # not in the way
    check_overwrite(out, ["fit.json"], overwrite=True)
    # at the commit too: nothing moved, the user's file intact
    with pytest.raises(InputError, match=r"fit\.json"), StagedOutput(out) as stage:
        (stage.path / "fit.json").write_text("{}")
        (stage.path / "other.csv").write_text("x")
        stage.commit()
    assert (out / "fit.json").read_text() == "mine" and not (out / "other.csv").exists()
    with StagedOutput(out, overwrite=True) as stage:
        (stage.path / "fit.json").write_text("{}")
        stage.commit()
    assert (out / "fit.json").read_text() == "{}"


def test_reconstruct_refuses_foreign_files_and_keeps_nothing_on_ctrl_c(tmp_path, capsys,
                                                                       monkeypatch):
    """reconstruct: a heights.csv of the user's in --out stops it before any work (exit 2,
    one line, the file byte-identical); Ctrl-C after the first frame leaves --out as it
    was (exit 130); a rerun over its own output needs no --overwrite."""
    out = tmp_path / "out"
    out.mkdir()
    (out / "heights.csv").write_text("the user's own\n")
    before = _snapshot(out)
    args = ["reconstruct", str(BALL_FRAMES), "--sensor", "gelsight", "--out", str(out),
            "--no-images"]
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "heights.csv" in err[0] and "--overwrite" in err[0]
    assert _snapshot(out) == before
    # Ctrl-C in the middle: nothing of the run is left
    import tactilevision.optics as optics

    calls = {"n": 0}
    real = optics.DepthReconstructor.__call__

    def interrupted(self, frames):
        calls["n"] += 1
        if calls["n"] == 2:
            raise KeyboardInterrupt
        return real(self, frames)

    monkeypatch.setattr(optics.DepthReconstructor, "__call__", interrupted)
    assert main([*args, "--overwrite"]) == 130
    assert _snapshot(out) == before and not list(out.glob(".tactilevision-tmp-*"))
    monkeypatch.setattr(optics.DepthReconstructor, "__call__", real)
    assert main([*args, "--overwrite"]) == 0
    assert (out / "heights.csv").read_text() != "the user's own\n"
    heights = sorted(p.name for p in out.glob("*_height.npy"))
    assert len(heights) == 4 and np.load(out / heights[0]).ndim == 2
    assert main(args) == 0                          # its own files: no --overwrite needed


@pytest.mark.slow
def test_diagnose_and_validate_reports_refuse_foreign_files(tmp_path, capsys):
    from tactilevision.io import write_measurements
    from tactilevision.sim import make_measurement_table

    t = make_measurement_table(None, 2)
    csv = write_measurements(tmp_path / "m.csv", t.columns, thickness_mm=t.thickness_mm,
                             radius_mm=t.radius_mm)
    rep = tmp_path / "report"
    rep.mkdir()
    (rep / "report.html").write_text("<p>the user's</p>")
    assert main(["diagnose", str(csv), "--report", str(rep), "--no-progress"]) == 2
    assert "report.html" in capsys.readouterr().err
    assert (rep / "report.html").read_text() == "<p>the user's</p>"
    assert main(["diagnose", str(csv), "--report", str(rep), "--no-progress",
                 "--overwrite"]) == 0
    assert "Nothing is missing" in (rep / "report.html").read_text()
    (rep / "validation.csv").write_text("mine")
    assert main(["validate", str(csv), "--report", str(rep), "--E-mpa", "0.2", "--nu",
                 "0.45"]) == 2
    assert (rep / "validation.csv").read_text() == "mine"


def test_optics_calibrate_writes_its_file_whole_and_may_replace_its_own(tmp_path, capsys):
    """optics calibrate: the .npz and its accuracy report go into place through the stage
    and the folder's manifest lists them, so a rerun replaces them without --overwrite
    (LUT: a few seconds)."""
    from tactilevision.optics import PhotometricCalibration

    ball = ROOT / "sample_frames" / "gelsight_ball" / "frames"
    argv = ["optics", "calibrate", str(ball), "--ball-radius-mm", "2", "--mm-per-px", "0.0295",
            "--model", "lut", "--out", str(tmp_path / "cal")]
    assert main(argv) == 0
    assert json.loads((tmp_path / MANIFEST).read_text())["files"] == ["cal.npz",
                                                                      "cal_accuracy.json"]
    assert PhotometricCalibration.load(tmp_path / "cal.npz").model == "lut"
    assert main(argv) == 0                               # its own file: replaced
    assert not list(tmp_path.glob(".tactilevision-tmp-*"))
    assert not list(tmp_path.glob(".cal.npz.tmp"))
