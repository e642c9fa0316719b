"""A fuzz suite for the readers (issue 18 part 4): whatever bytes a session folder's files
or a measurements table hold, reading them either succeeds or raises ``InputError`` with
one sentence naming the file; never another exception. Hypothesis drives the damage
(random bytes, truncations, foreign encodings, hostile cells) on a tiny session, so the
suite stays fast."""

from __future__ import annotations

import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tactilevision import InputError
from tactilevision.io import read_frame, read_holds, read_measurements, read_session

SESSION_TOML = """[sensor]
name = "gelsight"
mm_per_px = 0.1
gel_thickness_mm = 3.0
gel_radius_mm = 9.0

[indenter]
radius_mm = 2.5

[gauge_block]
depths_mm = [0.15, 0.3]
bevel_offset_mm = 9.0
bevel_direction_deg = 0.0
bevel_angle_deg = 5.0
bevel_length_mm = 3.0

[force_sensor]
rate_hz = 100
window_samples = 20
"""

HOSTILE = ["", " ", "nan", "NaN", "inf", "-inf", "1e300", "-1", "0", "abc", "0x10", "1,5",
           "\x00", "é", "1e-320", "True", "[1]", '"1"']

FILES = ("session.toml", "frames.csv", "forces.csv", "presses.csv")

SETTINGS = settings(max_examples=40, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture,
                                           HealthCheck.too_slow])


@pytest.fixture(scope="module")
def tiny_session(tmp_path_factory) -> Path:
    """A valid session of 3 frames of 48 x 64 px, 2 s of F/T log at 100 Hz."""
    folder = tmp_path_factory.mktemp("fuzz") / "session"
    (folder / "frames").mkdir(parents=True)
    rng = np.random.default_rng(0)
    ref = rng.integers(80, 160, (48, 64, 3)).astype(np.uint8)
    cv2.imwrite(str(folder / "reference.png"), ref)
    rows = ["frame,t_s"]
    for i in range(3):
        cv2.imwrite(str(folder / "frames" / f"{i:05d}.png"), ref)
        rows.append(f"{i:05d}.png,{0.5 + 0.1 * i:.3f}")
    (folder / "frames.csv").write_text("\n".join(rows) + "\n")
    t = np.arange(0, 2.0, 0.01)
    f = np.column_stack([t, np.zeros_like(t), np.zeros_like(t), 0.01 * np.sin(t)])
    np.savetxt(folder / "forces.csv", f, fmt="%.4f", delimiter=",", header="t_s,fx_n,fy_n,fz_n",
               comments="")
    (folder / "presses.csv").write_text("press,indenter,x_mm,y_mm\n0,1,-1.0,0.5\n")
    (folder / "session.toml").write_text(SESSION_TOML)
    read_session(folder)                     # the base case is valid
    return folder


def _damaged_copy(base: Path, dest: Path, name: str, data: bytes) -> Path:
    if dest.exists():
        shutil.rmtree(dest)
    shutil.copytree(base, dest)
    (dest / name).write_bytes(data)
    return dest


def _check(exc: InputError, *names: str) -> None:
    msg = str(exc)
    assert msg and "\n" not in msg.strip(), msg
    assert any(n in msg for n in names), msg


def _mutations(text: str):
    """Truncations, random bytes, foreign encodings, a hostile cell in place of a token."""
    raw = text.encode()
    tokens = [m for m in text.replace("\n", ",").replace("=", ",").split(",") if m.strip()]
    return st.one_of(
        st.integers(0, len(raw)).map(lambda k: raw[:k]),
        st.binary(max_size=300),
        st.sampled_from(["utf-16", "utf-32", "latin-1"]).map(
            lambda enc: text.replace("gelsight", "gélsight").encode(enc)),
        st.tuples(st.sampled_from(tokens), st.sampled_from(HOSTILE)).map(
            lambda p: text.replace(p[0].strip(), p[1], 1).encode("utf-8", "surrogatepass")),
        st.text(max_size=200).map(lambda s: s.encode("utf-8", "surrogatepass")),
    )


def _one_edit(word: str):
    """A deletion, a doubled letter, a swap of neighbours or a letter replaced."""
    letters = st.sampled_from("abcdefghijklmnopqrstuvwxyz_")
    i = st.integers(0, len(word) - 1)
    return st.one_of(
        i.map(lambda k: word[:k] + word[k + 1:]),
        i.map(lambda k: word[:k] + word[k] + word[k:]),
        st.integers(0, len(word) - 2).map(lambda k: word[:k] + word[k + 1] + word[k]
                                          + word[k + 2:]),
        st.tuples(i, letters).map(lambda p: word[:p[0]] + p[1] + word[p[0] + 1:]),
    ).filter(lambda w: w != word and w.strip("_") == w and w)


_KEYS = [(t, k) for t, keys in {"sensor": ("name", "mm_per_px", "gel_thickness_mm",
                                           "gel_radius_mm"),
                                "indenter": ("radius_mm",),
                                "gauge_block": ("depths_mm", "bevel_offset_mm",
                                                "bevel_direction_deg", "bevel_angle_deg",
                                                "bevel_length_mm"),
                                "force_sensor": ("rate_hz", "window_samples")}.items()
         for k in keys]
_REQUIRED = {"mm_per_px", "gel_thickness_mm", "radius_mm", "depths_mm"}


@SETTINGS
@given(data=st.sampled_from(_KEYS).flatmap(
    lambda tk: st.tuples(st.just(tk), _one_edit(tk[1]))))
def test_a_typo_in_a_key_is_refused_or_named(tiny_session, tmp_path_factory, data):
    """One edit in a key of session.toml (formats.md section 1): a required key is then
    missing, and the refusal names it; an optional one falls back to its default, and the
    notes name the typo, with the known key when it is one edit away."""
    from tactilevision.io._session import KNOWN_KEYS

    (table, key), typo = data
    text = SESSION_TOML.replace(f"\n{key} =", f"\n{typo} =", 1)
    folder = _damaged_copy(tiny_session, tmp_path_factory.mktemp("typo") / "s",
                           "session.toml", text.encode())
    if typo in KNOWN_KEYS[table]:           # the edit made another known key: a duplicate
        return
    try:
        s = read_session(folder)
    except InputError as exc:
        _check(exc, "session.toml")
        assert key in _REQUIRED or key in str(exc), str(exc)
        return
    assert key not in _REQUIRED
    notes = "\n".join(s.notes)
    assert f"[{table}] {typo} is not a key tactilevision reads" in notes
    import difflib

    if difflib.get_close_matches(typo, list(KNOWN_KEYS[table]), n=1, cutoff=0.75) == [key]:
        assert f"did you mean {key}?" in notes


@pytest.mark.parametrize("name", FILES)
def test_session_readers_survive_any_damage(tiny_session, tmp_path, name):
    text = (tiny_session / name).read_text()

    @SETTINGS
    @given(data=_mutations(text))
    def run(data: bytes) -> None:
        folder = _damaged_copy(tiny_session, tmp_path / "s", name, data)
        try:
            read_session(folder)
        except InputError as exc:
            _check(exc, name, str(folder))

    run()


@SETTINGS
@given(data=st.one_of(st.binary(max_size=2000),
                      st.integers(1, 400).map(lambda k: k)))
def test_frames_of_any_bytes_are_refused_by_name(tmp_path_factory, data):
    folder = tmp_path_factory.mktemp("img")
    good = folder / "good.png"
    cv2.imwrite(str(good), np.full((48, 64, 3), 100, np.uint8))
    path = folder / "frame.png"
    if isinstance(data, int):                       # a truncated real PNG
        path.write_bytes(good.read_bytes()[:data])
    else:
        path.write_bytes(data)
    try:
        img = read_frame(path, (48, 64))
    except InputError as exc:
        _check(exc, "frame.png")
    else:
        assert img.shape == (48, 64, 3) and img.dtype == np.uint8


MEASUREMENTS = ("press,depth_mm,force_n,hold_s,time_s\n"
                "0,0.15,0.5,0.1,1\n1,0.3,1.1,0.1,5\n2,0.45,1.8,0.1,9\n3,0.6,2.6,0.1,13\n")
HOLDS = "press,t_s,fz_n,ramp_s\n0,0.0,1.5,0.5\n0,0.1,1.4,0.5\n1,0.0,2.0,0.5\n"


@pytest.mark.parametrize(("name", "text", "reader"), [
    ("measurements.csv", MEASUREMENTS, read_measurements),
    ("holds.csv", HOLDS, read_holds),
])
def test_table_readers_survive_any_damage(tmp_path, name, text, reader):
    (tmp_path / "session.toml").write_text("[sensor]\ngel_thickness_mm = 3.0\n\n"
                                           "[indenter]\nradius_mm = 2.5\n")

    @SETTINGS
    @given(data=_mutations(text))
    def run(data: bytes) -> None:
        path = tmp_path / name
        path.write_bytes(data)
        try:
            reader(path)
        except InputError as exc:
            _check(exc, name)

    run()


@SETTINGS
@given(cell=st.sampled_from(HOSTILE), row=st.integers(1, 4), col=st.integers(1, 2))
def test_fit_and_diagnose_answer_any_cell_with_a_status(tmp_path_factory, cell, row, col):
    """A hostile cell in depth_mm or force_n: fit and diagnose end with exit 0, 2 or 3 and
    print no traceback."""
    import contextlib
    import io

    from tactilevision.cli import main

    folder = tmp_path_factory.mktemp("m")
    lines = MEASUREMENTS.splitlines()
    cells = lines[row].split(",")
    cells[col] = cell
    lines[row] = ",".join(cells)
    path = folder / "measurements.csv"
    path.write_text("\n".join(lines) + "\n")
    (folder / "session.toml").write_text("[sensor]\ngel_thickness_mm = 3.0\n\n"
                                         "[indenter]\nradius_mm = 2.5\n")
    for argv in (["fit", str(path)], ["diagnose", str(path), "--no-progress"]):
        err = io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            status = main(argv)
        assert status in (0, 2, 3), (argv, cell, err.getvalue())
        assert "Traceback" not in err.getvalue()
        if status == 2:
            assert "measurements.csv" in err.getvalue()
