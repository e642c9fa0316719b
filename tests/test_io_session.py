"""The session folder of formats.md section 1: a valid one read back, every broken part named."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.io import read_session

TOML = """\
[sensor]
name = "test"
mm_per_px = 0.05
gel_thickness_mm = 3.0
gel_radius_mm = 15.0

[indenter]
radius_mm = 2.5

[gauge_block]
depths_mm = [0.15, 0.30, 0.40, 0.50, 0.60]

[force_sensor]
rate_hz = 1000
clock_offset_s = 0.25
window_samples = 50
"""
H, W = 30, 40


def make_session(folder: Path, n_frames: int = 5, n_samples: int = 100) -> Path:
    """A small valid session: 40 x 30 px frames at 10 Hz, 1 kHz forces, two presses."""
    rng = np.random.default_rng(0)
    (folder / "frames").mkdir(parents=True)
    (folder / "session.toml").write_text(TOML)
    cv2.imwrite(str(folder / "reference.png"), rng.integers(0, 255, (H, W, 3), dtype=np.uint8))
    lines = ["frame,t_s"]
    for i in range(n_frames):
        cv2.imwrite(str(folder / "frames" / f"f{i}.png"),
                    np.full((H, W, 3), 10 * i, dtype=np.uint8))
        lines.append(f"f{i}.png,{0.1 * i:.3f}")
    (folder / "frames.csv").write_text("\n".join(lines) + "\n")
    t = 0.25 + np.arange(n_samples) / 1000.0
    rows = "".join(f"{x:.4f},0.01,-0.02,{0.5 * x:.5f},1,2,3\n" for x in t)
    (folder / "forces.csv").write_text("t_s,fx_n,fy_n,fz_n,tx_nmm,ty_nmm,tz_nmm\n" + rows)
    (folder / "presses.csv").write_text("press,indenter,x_mm,y_mm\n0,2,1.5,-0.5\n1,4,0,0\n")
    return folder


def test_reads_a_valid_session(tmp_path):
    s = read_session(make_session(tmp_path / "s"))
    c = s.config
    assert (c.sensor_name, c.mm_per_px, c.gel_thickness_mm, c.gel_radius_mm) == ("test", 0.05,
                                                                                3.0, 15.0)
    assert c.indenter_radius_mm == 2.5 and c.depths_mm == (0.15, 0.30, 0.40, 0.50, 0.60)
    assert (c.rate_hz, c.clock_offset_s, c.window_samples, c.calibration) == (1000.0, 0.25, 50,
                                                                             None)
    assert s.n_frames == 5 and s.shape == (H, W) and s.reference.dtype == np.uint8
    np.testing.assert_allclose(s.frame_times_s, [0.0, 0.1, 0.2, 0.3, 0.4])
    assert s.frame(3).shape == (H, W, 3) and int(s.frame(3)[0, 0, 0]) == 30
    assert s.forces_n.shape == (100, 3) and s.torques_nmm.shape == (100, 3)
    np.testing.assert_allclose(s.forces_n[:, 2], 0.5 * s.force_times_s, atol=1e-5)
    assert s.presses["indenter"].tolist() == [2, 4] and s.presses["press"].dtype == np.int64
    np.testing.assert_allclose(s.presses["x_mm"], [1.5, 0.0])
    assert s.notes == ()


def test_defaults_and_notes(tmp_path):
    folder = make_session(tmp_path / "s")
    toml = TOML.replace("clock_offset_s = 0.25\n", "").replace("gel_radius_mm = 15.0\n", "")
    (folder / "session.toml").write_text(toml + '\n[optics]\ncalibration = "optics.npz"\n')
    (folder / "optics.npz").write_bytes(b"")
    (folder / "presses.csv").unlink()
    cv2.imwrite(str(folder / "frames" / "stray.png"), np.zeros((H, W, 3), np.uint8))
    s = read_session(folder)
    assert s.config.clock_offset_s is None and s.config.gel_radius_mm == 60.0
    assert s.config.calibration == folder / "optics.npz" and s.presses is None
    assert len(s.notes) == 1 and "stray.png" in s.notes[0] and "not listed" in s.notes[0]


def test_unknown_keys_are_noted_with_the_near_known_one(tmp_path):
    folder = make_session(tmp_path / "s")
    toml = TOML.replace("clock_offset_s = 0.25", "clock_ofset_s = 0.25").replace(
        "window_samples = 50", "window_samples = 200")
    (folder / "session.toml").write_text(toml + "\n[forcesensr]\nrate = 1\n[lab]\nroom = 3\n")
    s = read_session(folder)
    assert s.config.clock_offset_s is None                 # the typo sets nothing
    notes = "\n".join(s.notes)
    assert "[force_sensor] clock_ofset_s is not a key" in notes
    assert "did you mean clock_offset_s?" in notes
    assert "table [forcesensr] is not read by tactilevision (did you mean [force_sensor]?)" in notes
    assert "table [lab] is not read by tactilevision" in notes and "[lab]?" not in notes
    # the fixture's window (200 samples) is longer than its 100-sample log: said, not hidden
    assert "window_samples = 200 is more than the 100 samples" in notes
    assert "no press can be certified" in notes


def test_a_force_log_slower_than_the_frames_is_said(tmp_path):
    """An F/T log at 8 Hz beside frames at 10 frames/s (rate_hz saying so: no unit
    mistake) is read, with a warning naming both files and both rates."""
    folder = make_session(tmp_path / "s")
    t = 0.25 + np.arange(20) / 8.0
    rows = "".join(f"{x:.4f},0.01,-0.02,{0.5 * x:.5f}\n" for x in t)
    (folder / "forces.csv").write_text("t_s,fx_n,fy_n,fz_n\n" + rows)
    _edit(folder / "session.toml", "rate_hz = 1000", "rate_hz = 8")
    _edit(folder / "session.toml", "window_samples = 50", "window_samples = 4")
    notes = "\n".join(read_session(folder).notes)
    assert "forces.csv samples at 8 Hz, less than twice the 10 frames/s of" in notes
    assert "frames.csv" in notes
    assert "frames/s" not in "\n".join(read_session(make_session(tmp_path / "ok")).notes)


def _edit(path: Path, old: str, new: str) -> None:
    text = path.read_text()
    assert old in text, old
    path.write_text(text.replace(old, new, 1))


BROKEN = {
    "no session.toml": (lambda f: (f / "session.toml").unlink(), ["has no session.toml"]),
    "missing key": (lambda f: _edit(f / "session.toml", "mm_per_px = 0.05\n", ""),
                    ["session.toml", "missing key [sensor] mm_per_px"]),
    "bad number": (lambda f: _edit(f / "session.toml", "radius_mm = 2.5", "radius_mm = -2.5"),
                   ["[indenter] radius_mm must be a positive number"]),
    "bad depths": (lambda f: _edit(f / "session.toml", "[0.15,", "['a',"),
                   ["[gauge_block] depths_mm must be a list of positive numbers"]),
    "window": (lambda f: _edit(f / "session.toml", "window_samples = 50", "window_samples = 2.5"),
               ["window_samples must be a whole number"]),
    "window of 1": (lambda f: _edit(f / "session.toml", "window_samples = 50",
                                    "window_samples = 1"), ["of at least 2, got 1"]),

    "calibration": (lambda f: (f / "session.toml").write_text(
        TOML + '[optics]\ncalibration = "nowhere.npz"\n'), ["[optics] calibration", "nowhere.npz",
                                                           "does not exist"]),
    "bad toml": (lambda f: (f / "session.toml").write_text("[sensor\n"), ["not valid TOML"]),
    "no reference": (lambda f: (f / "reference.png").unlink(), ["has no reference.png"]),
    "frame absent": (lambda f: (f / "frames" / "f3.png").unlink(),
                     ["frames.csv line 5", "frame f3.png is listed but", "does not exist"]),
    "frame size": (lambda f: cv2.imwrite(str(f / "frames" / "f2.png"),
                                         np.zeros((10, 20, 3), np.uint8)),
                   ["f2.png is 20 x 10 px, the reference 40 x 30 px"]),
    "frame times": (lambda f: _edit(f / "frames.csv", "f3.png,0.300", "f3.png,0.150"),
                    ["frames.csv line 5, column t_s: 0.15 does not increase",
                     "strictly increasing"]),
    "frames.csv absent": (lambda f: (f / "frames.csv").unlink(), ["frames.csv is missing"]),
    "frame listed twice": (lambda f: _edit(f / "frames.csv", "f4.png", "f3.png"),
                           ["frame f3.png is listed twice"]),
    "force nan": (lambda f: _edit(f / "forces.csv", "0.2540,0.01,-0.02,0.12700",
                                  "0.2540,0.01,-0.02,nan"),
                  ["forces.csv line 6, column fz_n: nan", "finite number"]),
    "force empty": (lambda f: _edit(f / "forces.csv", "0.2540,0.01,", "0.2540,,"),
                    ["forces.csv line 6, column fx_n: empty cell"]),
    "force absurd": (lambda f: _edit(f / "forces.csv", "0.2540,0.01,-0.02,0.12700",
                                     "0.2540,0.01,-0.02,1e300"),
                     ["forces.csv line 6, column fz_n: 1e300 is beyond +-100000"]),
    "force text": (lambda f: _edit(f / "forces.csv", "0.2540,0.01,", "0.2540,abc,"),
                   ["forces.csv line 6, column fx_n: 'abc' is not a number"]),
    "force column": (lambda f: _edit(f / "forces.csv", "t_s,fx_n,fy_n,fz_n,", "t_s,fx_n,fy_n,fq,"),
                     ["forces.csv line 1: missing column(s) fz_n"]),
    "force times": (lambda f: _edit(f / "forces.csv", "0.2540,", "0.2520,"),
                    ["forces.csv line 6, column t_s: 0.252 does not increase"]),
    "force cells": (lambda f: _edit(f / "forces.csv", "0.2540,0.01,", "0.2540,"),
                    ["forces.csv line 6 has 6 cells, the header has 7"]),
    "forces absent": (lambda f: (f / "forces.csv").unlink(), ["forces.csv is missing"]),
    "press indenter": (lambda f: _edit(f / "presses.csv", "1,4,0,0", "1,7,0,0"),
                       ["presses.csv line 3, column indenter: 7 is not an indenter",
                        "0 to 4"]),
    "press whole": (lambda f: _edit(f / "presses.csv", "0,2,1.5", "0.5,2,1.5"),
                    ["presses.csv line 2, column press: 0.5 is not a whole number"]),
    "rate huge": (lambda f: _edit(f / "session.toml", "rate_hz = 1000", "rate_hz = 1e9"),
                  ["[force_sensor] rate_hz = 1e+09 is beyond any F/T sensor"]),
    "times in ms": (lambda f: (f / "forces.csv").write_text(
        "t_s,fx_n,fy_n,fz_n\n" + "".join(f"{250 + i},0,0,0.1\n" for i in range(100))),
        ["the samples are 1 s apart", "rate_hz = 1000 (times in milliseconds? t_s must be "
         "seconds)"]),
}


@pytest.mark.parametrize("case", sorted(BROKEN))
def test_broken_sessions_name_the_fault(tmp_path, case):
    folder = make_session(tmp_path / "s")
    breaks, expected = BROKEN[case]
    breaks(folder)
    with pytest.raises(InputError) as err:
        read_session(folder)
    for part in expected:
        assert part in str(err.value), (case, str(err.value))


def test_missing_folder(tmp_path):
    with pytest.raises(InputError, match="does not exist"):
        read_session(tmp_path / "nowhere")


def test_frame_changed_after_reading(tmp_path):
    folder = make_session(tmp_path / "s")
    s = read_session(folder)
    cv2.imwrite(str(folder / "frames" / "f1.png"), np.zeros((10, 20, 3), np.uint8))
    with pytest.raises(InputError, match=r"f1\.png is 20 x 10 px"):
        s.frame(1)
