"""The calibration folder's readers name what is broken (the steps of the main job, and
the folder read back, are tested on the sample session in test_calibrate.py)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tactilevision import InputError
from tactilevision.pipeline import (
    CalibrationResult,
    read_material,
)

SAMPLE = Path(__file__).resolve().parents[1] / "sample_frames" / "gelsight_session"


@pytest.mark.parametrize("content, words", [
    ("not json", "is not valid JSON"), ("[1, 2]", "is not a JSON object"),
    ('{"E_mpa": "x", "nu": 0.4}', "no numeric E_mpa and nu")])
def test_a_broken_fit_json_is_named(tmp_path, content, words):
    bad = tmp_path / "fit.json"
    bad.write_text(content)
    with pytest.raises(InputError, match=words) as exc:
        read_material(bad)
    assert str(bad) in str(exc.value)


def test_a_folder_without_fit_json_is_named(tmp_path):
    with pytest.raises(InputError, match=r"has no fit\.json"):
        CalibrationResult.load(tmp_path)
    (tmp_path / "rejected.csv").write_text("press,reason,detail,t_frame_s,bevel_snr\nx,a,b,c,\n")
    with pytest.raises(InputError, match=r"rejected.csv, line 2"):
        CalibrationResult.load(tmp_path, require_fit=False)
