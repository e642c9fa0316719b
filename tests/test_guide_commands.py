"""Every command line the README and the User guide show runs as written (issue 86, item
5): each ``bash`` block's lines, in page order, from a working folder laid out as the
repository root (its ``sample_frames``), ``tactilevision`` and ``python`` as this
interpreter's. A line
run before (the sample calibration several pages start from) runs once. A line that
cannot run as written is listed below with its reason: a synopsis, an install, the
suite itself, or a placeholder for the reader's own files that no sample stands for; a
new such line fails here until it is listed or made to run.

A long check (``python -m pytest -m slow``): the sample session's calibration alone
takes a couple of minutes."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs" / "guide").glob("*.md"))]

#: text in a line -> why that line is not run as written
NOT_RUN = {
    "pip install": "an install (the suite runs on one)",
    "python -m pytest": "the suite itself",
    " [--": "a synopsis of the options, not a command",
    "CALIBRATION_DIRS...": "a synopsis of the options, not a command",
    "recordings/": "the reader's own videos and sessions: no sample ships "
                   "(the same commands run on sample_frames/gelsight_ball above them)",
    "batch/specimen_": "the reader's own specimens' tables: no sample ships",
    "batch/measurements.csv": "the reader's own table with a specimen column",
    "ramps/": "the reader's own Instron ramps: no sample ships",
    "fit presses.csv": "the reader's own ball table: the options stand for the sample's "
                       "session.toml keys shown above it",
    "live 0 ": "a camera (device 0); the next block runs the same on the sample frames",
}

#: pages whose Python examples write the files their command lines read (run first)
SNIPPETS_FIRST = {"ramps.md"}


def page_commands(page: Path) -> list[str]:
    """The command lines of a page's ``bash`` blocks (continuations joined, comments and
    blank lines dropped; ``a && b`` split in two)."""
    found = []
    for body in re.findall(r"```(?:bash|sh)\n(.*?)```", page.read_text(encoding="utf-8"),
                           re.S):
        for line in re.sub(r"\\\n\s*", " ", body).splitlines():
            line = line.split("  #", 1)[0].strip()
            if not line or line.startswith("#"):
                continue
            found += [part.strip() for part in line.split("&&")]
    return found


def page_snippets(page: Path) -> list[str]:
    """The page's ``python`` blocks."""
    return re.findall(r"```python\n(.*?)```", page.read_text(encoding="utf-8"), re.S)


def _why_not(line: str) -> str | None:
    return next((why for text, why in NOT_RUN.items() if text in line), None)


def test_the_lines_not_run_are_the_listed_ones():
    """Cheap, in the default suite: every line is either a command run by
    the long check below or listed with its reason, and every listed reason still
    matches a line (no stale entry)."""
    lines = [line for page in PAGES for line in page_commands(page)]
    assert len(lines) > 30
    for line in lines:
        assert line.startswith(("tactilevision ", "python ")) or _why_not(line), line
    for text in NOT_RUN:
        assert any(text in line for line in lines), f"NOT_RUN entry {text!r} matches no line"
    for name in SNIPPETS_FIRST:
        assert page_snippets(ROOT / "docs" / "guide" / name), name


@pytest.mark.slow
def test_every_guide_command_runs_as_written(tmp_path):
    work = tmp_path / "repo"
    work.mkdir()
    (work / "sample_frames").symlink_to(ROOT / "sample_frames")
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    py = sys.executable
    tv = f"{py} -m tactilevision"
    done: set[str] = set()
    ran = 0
    for page in PAGES:
        if page.name in SNIPPETS_FIRST:
            for code in page_snippets(page):
                run = subprocess.run([py, "-c", code], cwd=work, capture_output=True,
                                     text=True, timeout=600, env=env)
                assert run.returncode == 0, f"{page.name}'s example: {run.stderr[-1500:]}"
        for line in page_commands(page):
            if _why_not(line) or line in done:
                continue
            done.add(line)
            cmd = re.sub(r"^tactilevision ", tv + " ", re.sub(r"^python ", py + " ", line))
            run = subprocess.run(["bash", "-c", cmd], cwd=work, capture_output=True,
                                 text=True, timeout=1200, env=env)
            where = f"{page.relative_to(ROOT)}: {line}"
            assert run.returncode == 0, f"{where}\n{run.stdout[-1500:]}\n{run.stderr[-1500:]}"
            assert "Traceback" not in run.stderr, f"{where}\n{run.stderr[-1500:]}"
            ran += 1
    assert ran >= 20
