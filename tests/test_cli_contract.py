"""The command line's error contract: exit 2 and one sentence naming the fault, no
traceback, nothing written. A bad output folder is refused at once by every
sub-command (an existing file, or a path through one); implausible measurements rows are
named; Ctrl-C ends with one line and status 130."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from tactilevision import InputError
from tactilevision.cli import main
from tactilevision.io import check_output_folder, output_folder

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


@pytest.mark.parametrize(("row", "message"), [
    ("0.2,1e300", "1e+300 N is beyond any elastomer press"),
    ("0.2,-1e300", "-1e+300 N is beyond any elastomer press"),
    ("1e300,2", "1e+300 mm is beyond any elastomer press"),
])
@pytest.mark.parametrize("command", ["fit", "diagnose", "validate"])
def test_implausible_measurements_rows_are_named(tmp_path, capsys, row, message, command):
    table = tmp_path / "measurements.csv"
    table.write_text(f"depth_mm,force_n\n0.1,1.0\n{row}\n0.3,3.0\n0.4,4.2\n")
    rc = main([command, str(table), "--thickness-mm", "3", "--radius-mm", "2.5"])
    err = capsys.readouterr().err
    assert rc == 2
    assert f"{table} line 3" in err and message in err
    assert "Traceback" not in err


@pytest.mark.parametrize("force", ["-0.05", "0"])
def test_non_positive_forces_warn_in_fit_and_diagnose_and_stop_validate(tmp_path, capsys,
                                                                         force):
    """A bad tare (the catalogue's force_offset) can put the shallowest presses at or below
    zero: fit and diagnose go on and name the row; validate, which simulates each press,
    refuses it."""
    table = tmp_path / "measurements.csv"
    rows = [("0.05", force), ("0.1", "0.3"), ("0.2", "0.7"), ("0.3", "1.1"), ("0.4", "1.6"),
            ("0.5", "2.1")]
    table.write_text("depth_mm,force_n\n" + "".join(f"{d},{f}\n" for d, f in rows))
    for command in ("fit", "diagnose"):
        main([command, str(table), "--thickness-mm", "3", "--radius-mm", "2.5"])
        err = capsys.readouterr().err
        assert f"{command}: warning: {table} line 2, column force_n" in err
        assert "Traceback" not in err
    rc = main(["validate", str(table), "--thickness-mm", "3", "--radius-mm", "2.5",
               "--E-mpa", "0.2", "--nu", "0.45"])
    assert rc == 2 and "must be positive" in capsys.readouterr().err


def test_ctrl_c_ends_with_one_line_and_130(monkeypatch, capsys):
    import tactilevision.cli._fit as fit_cli

    def interrupted(args):
        raise KeyboardInterrupt

    monkeypatch.setattr(fit_cli, "run", interrupted)
    rc = main(["fit", TABLE])
    err = capsys.readouterr().err
    assert rc == 130
    assert err.strip() == "tactilevision fit: interrupted"


def test_diagnose_refuses_a_single_depth_table_as_fit_does(tmp_path, capsys):
    table = tmp_path / "measurements.csv"
    table.write_text("depth_mm,force_n\n0.2,1.0\n0.2,1.1\n0.2,0.9\n0.2,1.05\n")
    for command in ("fit", "diagnose"):
        rc = main([command, str(table), "--thickness-mm", "3", "--radius-mm", "2.5"])
        assert rc == 2
        assert "1 distinct depth(s)" in capsys.readouterr().err


@pytest.mark.parametrize(("extra", "message"), [
    (["--bins", "0"], "--bins must be at least 2"),
    (["--model", "mlp", "--epochs", "-1"], "--epochs must be at least 1"),
    (["--model", "mlp", "--hidden", "0"], "--hidden must be at least 1"),
])
def test_optics_calibrate_bad_numbers(tmp_path, capsys, extra, message):
    out = tmp_path / "o.npz"
    rc = main(["optics", "calibrate", BALLS.rsplit("/", 1)[0], "--ball-radius-mm", "2",
               "--mm-per-px", "0.0295", "--out", str(out), *extra])
    assert rc == 2 and message in capsys.readouterr().err
    assert not out.exists()


def test_optics_calibrate_out_is_a_folder(tmp_path, capsys):
    folder = tmp_path / "x.npz"
    folder.mkdir()
    rc = main(["optics", "calibrate", BALLS.rsplit("/", 1)[0], "--ball-radius-mm", "2",
               "--mm-per-px", "0.0295", "--out", str(folder)])
    assert rc == 2 and "is a folder" in capsys.readouterr().err


def test_negative_circle_radius_is_named(tmp_path, capsys):
    import shutil

    presses = tmp_path / "presses"
    shutil.copytree(SAMPLES / "gelsight_ball", presses)
    circles = presses / "frames" / "circles.csv"
    circles.write_text(circles.read_text().replace("press_09.png,250,168,59",
                                                   "press_09.png,250,168,-59"))
    rc = main(["optics", "calibrate", str(presses / "frames"), "--ball-radius-mm", "2",
               "--mm-per-px", "0.0295", "--out", str(tmp_path / "o.npz")])
    err = capsys.readouterr().err
    assert rc == 2 and "circles.csv line 3" in err and "positive radius" in err


def test_a_failed_json_write_leaves_nothing_behind(tmp_path, capsys):
    target = tmp_path / "fit.json"
    target.mkdir()                               # os.replace cannot put a file there
    rc = main(["fit", TABLE, "--json", str(target)])
    assert rc == 2 and "is a folder, not a file" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fit.json"]


def test_a_flipped_fz_axis_is_named(tmp_path, capsys):
    """forces.csv with fz_n negative while pressing (the F/T's z axis the other way) is
    refused naming the file, not blamed on the clock; nothing is written."""
    import shutil

    import numpy as np

    session = tmp_path / "s"
    shutil.copytree(SAMPLES / "taxim_gauge", session)
    log = np.genfromtxt(session / "forces.csv", delimiter=",", names=True)
    log["fz_n"] *= -1
    np.savetxt(session / "forces.csv", np.column_stack([log[n] for n in log.dtype.names]),
               delimiter=",", header=",".join(log.dtype.names), comments="", fmt="%.6g")
    out = tmp_path / "out"
    rc = main(["calibrate", str(session), "--out", str(out), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and "forces.csv: fz_n departs from its rest level downwards" in err
    assert not out.exists()


def test_the_cli_uses_only_the_public_api_of_the_other_packages():
    """The command line is a client of the library: it imports the other packages'
    public names (``from ..mechanics import diagnose``), never their private modules."""
    import re

    cli = Path(__file__).resolve().parents[1] / "tactilevision" / "cli"
    private = re.compile(r"^\s*(?:from|import)\s+\.\.(?:\w+\.)*_\w+", re.M)
    found = {p.name: private.findall(p.read_text()) for p in sorted(cli.glob("*.py"))}
    assert not {k: v for k, v in found.items() if v}
