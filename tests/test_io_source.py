"""io.open_source: one object for a frame folder, a session folder or a video, and the
errors that name what is wrong."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.io import open_source, read_session

SAMPLES = Path(__file__).resolve().parents[1] / "sample_frames"


def test_a_session_folder_brings_its_times_reference_and_pixel_size():
    src = open_source(SAMPLES / "gelsight_session")
    s = read_session(SAMPLES / "gelsight_session")
    assert src.kind == "session" and src.n_frames == len(s.frame_paths)
    np.testing.assert_array_equal(src.times_s, s.frame_times_s)      # batch's t_s
    assert src.mm_per_px == s.config.mm_per_px
    np.testing.assert_array_equal(src.reference(src.shape), s.reference)
    np.testing.assert_array_equal(src.frame(3), s.frame(3))


def test_a_frame_folder_has_no_times_and_finds_its_reference():
    src = open_source(SAMPLES / "gelsight_ball")
    assert src.kind == "folder" and src.n_frames == 4 and src.shape == (480, 640)
    assert np.isnan(src.times_s).all() and src.mm_per_px is None
    assert src.reference_path.name == "reference.png"
    got = list(src.frames_at([0, 2]))
    assert [i for i, _ in got] == [0, 2] and got[1][1].shape == (480, 640, 3)
    bad = list(src.frames_at([1], shape=(240, 320)))        # another size: named, not raised
    assert isinstance(bad[0][1], InputError) and src.frame_name(1) in str(bad[0][1])


@pytest.mark.parametrize("make, words", [
    (lambda d: d / "nowhere", "does not exist"),
    (lambda d: (d / "notes.txt").write_text("x") and d / "notes.txt", "not a video file")])
def test_bad_sources_are_named(tmp_path, make, words):
    path = make(tmp_path)
    with pytest.raises(InputError, match=words) as exc:
        open_source(path)
    assert str(path) in str(exc.value)


def test_a_missing_reference_is_named(tmp_path):
    with pytest.raises(InputError, match=r"reference .*gone\.png does not exist"):
        open_source(SAMPLES / "gelsight_ball", reference=tmp_path / "gone.png")
