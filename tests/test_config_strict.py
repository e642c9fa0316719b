"""Configuration read strictly (issue 54, item 7): every value a design reads is
type-checked with one sentence naming file, table and key (a boolean is never a number);
an unknown key is warned with the nearest known one; a missing optional extra gives one
sentence naming the extra to install."""

from __future__ import annotations

import subprocess
import sys
import warnings
from pathlib import Path

import pytest

from tactilevision import InputError, InputWarning
from tactilevision.cli import main
from tactilevision.planning import read_design

ROOT = Path(__file__).resolve().parents[1]
DESIGN = (ROOT / "sample_frames" / "plan" / "recommended.toml").read_text()


def _design(tmp_path: Path, old: str, new: str) -> Path:
    assert old in DESIGN
    path = tmp_path / "design.toml"
    path.write_text(DESIGN.replace(old, new, 1))
    return path


@pytest.mark.parametrize(("old", "new", "fragment"), [
    ("repeats = 10", 'repeats = "ten"', "[plan] repeats must be a whole number, got 'ten'"),
    ("repeats = 10", "repeats = true", "[plan] repeats must be a whole number, got True"),
    ("repeats = 10", "repeats = 2.5", "[plan] repeats must be a whole number"),
    ("gel_thickness_mm = 3.0", 'gel_thickness_mm = "3"',
     "[sensor] gel_thickness_mm must be a number, got '3'"),
    ("E_mpa = 0.2", 'E_mpa = "0.2"', "[plan] E_mpa must be a number"),
    ("bevel_angle_deg = 5.0", "bevel_angle_deg = true",
     "[gauge_block] bevel_angle_deg must be a number, got True"),
    ("overshoot_um = [30, 60]", 'overshoot_um = [30, "60"]',
     "[plan] overshoot_um must be a list of numbers"),
    ("hold_s = 1.0", "hold_sec = 1.0", "[plan] hold_sec is not a design key (did you mean "
     "hold_s?)"),
])
def test_a_mistyped_value_names_file_table_and_key(tmp_path, capsys, old, new, fragment):
    """The reader raises it, and the command says it in one line and exits 2 (run in this
    process: :func:`test_the_command_says_it_in_one_line_from_a_shell` runs one case as a
    shell does)."""
    path = _design(tmp_path, old, new)
    with pytest.raises(InputError) as err:
        read_design(path)
    assert fragment in str(err.value) and str(path) in str(err.value)
    assert main(["plan", str(path)]) == 2
    stderr = capsys.readouterr().err
    assert "Traceback" not in stderr
    assert stderr.count("\n") == 1 and fragment in stderr


def test_the_command_says_it_in_one_line_from_a_shell(tmp_path):
    path = _design(tmp_path, "repeats = 10", 'repeats = "ten"')
    r = subprocess.run([sys.executable, "-m", "tactilevision", "plan", str(path)],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert r.stderr.count("\n") == 1
    assert "[plan] repeats must be a whole number, got 'ten'" in r.stderr


def test_an_unknown_key_is_warned_with_the_nearest_and_the_default_used(tmp_path):
    path = _design(tmp_path, "mm_per_px = 0.0295", "mm_per_pix = 0.05")
    with pytest.warns(InputWarning, match=r"\[sensor\] mm_per_pix is not a key tactilevision "
                                          r"reads \(did you mean mm_per_px\? its default is "
                                          r"used\)"):
        d = read_design(path)
    assert d.mm_per_px == type(d).mm_per_px != 0.05
    # a session key a design does not use is no mistake
    path = _design(tmp_path, "[indenter]", '[indenter]\nshape = "flat_punch"')
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_design(path)
    r = subprocess.run([sys.executable, "-m", "tactilevision", "plan",
                        str(_design(tmp_path, "mm_per_px = 0.0295", "mm_per_pix = 0.0295"))],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert r.stderr.startswith("tactilevision plan: warning: ") and "Traceback" not in r.stderr


def test_a_missing_extra_is_one_sentence_naming_it(tmp_path):
    """torch hidden from the interpreter: training the network exits 2, naming the extra."""
    ball = ROOT / "sample_frames" / "gelsight_ball"
    code = ("import sys, importlib.abc\n"
            "class Block(importlib.abc.MetaPathFinder):\n"
            "    def find_spec(self, name, path, target=None):\n"
            "        if name.split('.')[0] == 'torch':\n"
            "            raise ModuleNotFoundError(f'No module named {name!r}', name=name)\n"
            "sys.meta_path.insert(0, Block())\n"
            "from tactilevision.cli import main\n"
            f"sys.exit(main(['optics', 'calibrate', {str(ball)!r}, '--ball-radius-mm', '2', "
            f"'--mm-per-px', '0.0295', '--model', 'mlp', '--out', "
            f"{str(tmp_path / 'o.npz')!r}]))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 2, r.stderr
    assert "Traceback" not in r.stderr
    assert "pip install 'tactilevision[torch]'" in r.stderr
