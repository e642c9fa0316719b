"""A table-driven walk of every sub-command through bad inputs (issue 18 part 4): exit 2,
one sentence on stderr naming the fault, no traceback, and every file that was there
before byte-identical afterwards (nothing already written is lost)."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import pytest

from tactilevision.cli import main

ROOT = Path(__file__).resolve().parents[1]
SESSION = ROOT / "sample_frames" / "gelsight_session"
BALL = ROOT / "sample_frames" / "gelsight_ball"

GOOD_TABLE = ("press,depth_mm,force_n,hold_s\n0,0.15,0.5,0.1\n1,0.3,1.1,0.1\n"
              "2,0.45,1.8,0.1\n3,0.6,2.6,0.1\n")


def _setup(tmp: Path) -> None:
    (tmp / "m.csv").write_text(GOOD_TABLE)
    (tmp / "session.toml").write_text("[sensor]\ngel_thickness_mm = 3.0\n\n"
                                      "[indenter]\nradius_mm = 2.5\n")
    (tmp / "empty.csv").write_text("")
    (tmp / "a_file").write_text("I am a file")
    (tmp / "holds.csv").write_text("press,t_s,fz_n\n0,0,1\n")
    (tmp / "out").mkdir()
    (tmp / "out" / "fit.json").write_text('{"the user": "keeps this"}')
    (tmp / "noframes").mkdir()
    (tmp / "theirs.npz").write_bytes(b"someone else's calibration")


CASES = [
    # (argv, a fragment the one line must hold)
    (["calibrate", "{t}/nowhere"], "nowhere"),
    (["calibrate", "{t}/noframes"], "session.toml"),
    (["calibrate", str(SESSION), "--out", "{t}/a_file"], "a_file"),
    (["calibrate", str(SESSION), "--out", "{t}/out"], "--overwrite"),
    (["fit", "{t}/nowhere.csv"], "nowhere.csv"),
    (["fit", "{t}/empty.csv"], "empty.csv"),
    (["fit", "{t}/m.csv", "--effects", "creep"], "creep"),
    (["fit", "{t}/m.csv", "--a-over-h", "nan"], "--a-over-h"),
    (["fit", "{t}/m.csv", "--holds", "{t}/holds.csv"], "holds.csv"),
    (["fit", "{t}/m.csv", "--json", "{t}/noframes"], "noframes"),
    (["diagnose", "{t}/m.csv", "--scan", "fz_n", "--no-progress"], "fz_n"),
    (["diagnose", "{t}/m.csv", "--report", "{t}/a_file", "--no-progress"], "a_file"),
    (["validate", "{t}/m.csv", "--E-mpa", "0.2"], "--nu"),
    (["reconstruct", "{t}/noframes", "--sensor", "gelsight", "--out", "{t}/r"], "noframes"),
    (["reconstruct", str(BALL / "frames"), "--sensor", "gelsight", "--out", "{t}/a_file"],
     "a_file"),
    (["forces", "{t}/a_file"], "a_file"),
    (["forces", str(BALL / "frames"), "--sensor", "gelsight", "--thickness-mm", "3",
      "--E-mpa", "0.2", "--nu", "0.48", "--every", "0", "--out", "{t}/f"], "--every"),
    (["optics", "calibrate", "{t}/nowhere", "--ball-radius-mm", "2", "--mm-per-px", "0.03",
      "--out", "{t}/o.npz"], "nowhere"),
    (["optics", "calibrate", str(BALL), "--ball-radius-mm", "2", "--mm-per-px", "0.0295",
      "--model", "lut", "--bins", "0", "--out", "{t}/o.npz"], "bins"),
    (["optics", "calibrate", str(BALL), "--ball-radius-mm", "2", "--mm-per-px", "0.0295",
      "--model", "lut", "--out", "{t}/theirs.npz"], "--overwrite"),
    (["optics", "calibrate", str(BALL), "--ball-radius-mm", "2", "--mm-per-px", "0.0295",
      "--model", "lut", "--out", "{t}/theirs"], "--overwrite"),
]


@pytest.mark.parametrize(("argv", "fragment"), CASES,
                         ids=[" ".join(a[:2]) + f" #{i}" for i, (a, _) in enumerate(CASES)])
def test_bad_input_exits_2_with_one_line_and_loses_nothing(tmp_path, argv, fragment):
    _setup(tmp_path)
    before = {str(p.relative_to(tmp_path)): p.read_bytes() for p in tmp_path.rglob("*")
              if p.is_file()}
    argv = [a.replace("{t}", str(tmp_path)) for a in argv]
    err, out = io.StringIO(), io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
        status = main(argv)
    lines = [x for x in err.getvalue().splitlines() if x.strip()]
    assert status == 2, (argv, err.getvalue())
    assert "Traceback" not in err.getvalue()
    errors = [x for x in lines if ": error: " in x]
    assert len(errors) == 1 and fragment in errors[0], lines
    after = {str(p.relative_to(tmp_path)): p.read_bytes() for p in tmp_path.rglob("*")
             if p.is_file()}
    assert after == before, set(after) ^ set(before)
