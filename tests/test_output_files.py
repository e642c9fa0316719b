"""One rule for every output (issue 54, item 6): a single file tactilevision did not write
is never replaced without --overwrite (checked before any work, the file left intact); a
file it wrote may be replaced by a rerun; reconstruct and view write beside their source,
not into the current folder."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from tactilevision.cli import main
from tactilevision.io import MANIFEST, check_output_file, write_output_file

ROOT = Path(__file__).resolve().parents[1]
TABLE = ROOT / "sample_frames" / "paper_line6" / "measurements.csv"
DESIGN = ROOT / "sample_frames" / "plan" / "recommended.toml"
BALL = ROOT / "sample_frames" / "gelsight_ball"


def _mine(path: Path) -> Path:
    path.write_text("the user's own notes\n")
    return path


def test_fit_json_onto_a_users_file_needs_overwrite(tmp_path, capsys):
    target = _mine(tmp_path / "result.json")
    assert main(["fit", str(TABLE), "--json", str(target)]) == 2
    err = capsys.readouterr().err
    assert str(target) in err and "--overwrite" in err and err.count("\n") == 1
    assert target.read_text() == "the user's own notes\n"
    assert main(["fit", str(TABLE), "--json", str(target), "--overwrite"]) in (0, 3)
    assert json.loads(target.read_text())["measurements"] == str(TABLE)
    # now tactilevision's own: a rerun replaces it without --overwrite
    assert json.loads((tmp_path / MANIFEST).read_text())["files"] == ["result.json"]
    assert main(["fit", str(TABLE), "--json", str(target)]) in (0, 3)


def test_plan_write_design_and_live_csv_refuse_a_users_file(tmp_path, capsys):
    target = _mine(tmp_path / "design.toml")
    assert main(["plan", str(DESIGN), "--write-design", str(target)]) == 2
    assert "--overwrite" in capsys.readouterr().err
    assert target.read_text() == "the user's own notes\n"
    csv = _mine(tmp_path / "live.csv")
    assert main(["live", str(BALL / "frames"), "--sensor", "gelsight", "--csv", str(csv),
                 "--no-progress"]) == 2
    assert "--overwrite" in capsys.readouterr().err
    assert csv.read_text() == "the user's own notes\n"


def test_write_output_file_rules(tmp_path):
    path = _mine(tmp_path / "a.txt")
    with pytest.raises(Exception, match="--overwrite"):
        write_output_file(path, "new")
    write_output_file(path, "new", overwrite=True)
    write_output_file(path, "newer")                  # listed in the manifest now
    assert path.read_text() == "newer"
    with pytest.raises(Exception, match="is a folder"):
        check_output_file(tmp_path)
    fresh = write_output_file(tmp_path / "sub" / "b.txt", b"\x00\x01")
    assert fresh.read_bytes() == b"\x00\x01"
    assert not list(tmp_path.rglob("*tactilevision-tmp*"))


def test_a_failed_write_leaves_the_old_file_whole_and_nothing_behind(tmp_path, monkeypatch):
    path = write_output_file(tmp_path / "r.json", "old")

    def broken(src, dst):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("os.replace", broken)
    with pytest.raises(Exception, match=r"cannot write .*No space left"):
        write_output_file(path, "new")
    assert path.read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == [MANIFEST, "r.json"]


def test_reconstruct_writes_beside_its_source_not_into_the_current_folder(
        tmp_path, monkeypatch, capsys):
    frames = tmp_path / "data" / "frames"
    frames.mkdir(parents=True)
    shutil.copy(BALL / "frames" / "press_01.png", frames)
    shutil.copy(BALL / "reference.png", tmp_path / "data")
    cwd = tmp_path / "elsewhere"
    cwd.mkdir()
    monkeypatch.chdir(cwd)
    status = main(["reconstruct", str(frames), "--sensor", "gelsight", "--no-images",
                   "--no-progress", "--reference", str(tmp_path / "data" / "reference.png")])
    assert status == 0, capsys.readouterr().err
    assert (tmp_path / "data" / "frames_reconstruct" / "press_01_height.npy").is_file()
    # arrays by default, pictures on request (issue 54, item 1)
    assert not list((tmp_path / "data" / "frames_reconstruct").glob("*.png"))
    assert list(cwd.iterdir()) == []
