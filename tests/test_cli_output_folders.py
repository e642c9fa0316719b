"""A bad output folder is refused at once, by every sub-command, in one sentence, with
nothing written: an existing file, or a path through one."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from tactilevision import InputError
from tactilevision.cli import main
from tactilevision.cli._out import check_output_folder, output_folder

SAMPLES = Path(__file__).resolve().parents[1] / "sample_frames"
BALLS = str(SAMPLES / "gelsight_ball" / "frames")
TABLE = str(SAMPLES / "paper_line6" / "measurements.csv")


def _commands(out: str) -> list[list[str]]:
    return [
        ["reconstruct", BALLS, "--sensor", "gelsight", "--out", out, "--no-images"],
        ["forces", BALLS, "--sensor", "gelsight", "--thickness-mm", "3", "--E-mpa", "0.2",
         "--nu", "0.48", "--out", out, "--no-progress", "--no-images"],
        ["validate", TABLE, "--E-mpa", "0.2", "--nu", "0.45", "--report", out],
        ["diagnose", TABLE, "--report", out],
        ["calibrate", str(SAMPLES / "gelsight_session"), "--out", out, "--no-progress"],
    ]


@pytest.mark.parametrize("k", range(5))
@pytest.mark.parametrize("where", ["file", "under_file"])
def test_bad_output_folder_is_refused_before_any_work(tmp_path, capsys, k, where):
    blocker = tmp_path / "taken"
    blocker.write_text("a file the user keeps")
    out = blocker if where == "file" else blocker / "sub"
    t0 = time.perf_counter()
    rc = main(_commands(str(out))[k])
    seconds = time.perf_counter() - t0
    err = capsys.readouterr().err
    assert rc == 2
    assert str(blocker) in err and "Traceback" not in err
    assert blocker.read_text() == "a file the user keeps"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["taken"]
    # refused before the work (calibrate's takes about 40 s, reconstruct's 10 s)
    assert seconds < 8.0


def test_output_folder_helpers(tmp_path):
    assert output_folder(tmp_path / "a" / "b").is_dir()
    assert check_output_folder(tmp_path / "c" / "d") == tmp_path / "c" / "d"
    assert not (tmp_path / "c").exists()                  # checked, not created
    (tmp_path / "f").write_text("x")
    with pytest.raises(InputError, match="existing file"):
        output_folder(tmp_path / "f")
    with pytest.raises(InputError, match="is a file"):
        check_output_folder(tmp_path / "f" / "g")
    with pytest.raises(InputError, match="cannot create"):
        output_folder(tmp_path / "f" / "g")
