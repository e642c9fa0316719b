"""The README is a front door that tells the truth: at most 200 lines, its Python quickstart
runs from any folder and prints what its comments say, its links lead to files of the
repository, and every command of its table exists with the options its example uses."""

from __future__ import annotations

import contextlib
import io
import re
import shlex
from pathlib import Path

import pytest

from tactilevision.cli import main

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def test_readme_is_short():
    assert len(README.splitlines()) <= 200


def test_quickstart_prints_what_its_comments_say(tmp_path, monkeypatch):
    """The block under "Python quickstart", run in an empty folder: each print's comment
    (after '#') is the line it prints."""
    block = README.split("## Python quickstart", 1)[1].split("```python", 1)[1].split("```", 1)[0]
    expected = [line.split("#", 1)[1].strip() for line in block.splitlines()
                if line.startswith("print(") and "#" in line]
    assert len(expected) == 2
    monkeypatch.chdir(tmp_path)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(block, "README quickstart", "exec"), {})
    assert out.getvalue().splitlines() == expected


def test_links_lead_to_files_of_the_repository():
    links = re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", README)
    local = [x for x in links if not x.startswith(("http://", "https://"))]
    assert len(local) >= 10
    for target in local:
        assert (ROOT / target).exists(), target
    assert "../shared" not in README


def test_every_command_of_the_table_takes_its_example(capsys):
    """Each example's sub-command and options are known to the parser (--help on the same
    words exits 0, and the parser accepts every option the example names)."""
    rows = [r for r in README.splitlines() if r.startswith("| `") and "tactilevision " in r]
    assert len(rows) >= 8
    for row in rows:
        example = row.rsplit("`tactilevision ", 1)[1].rsplit("`", 1)[0]
        words = shlex.split(example)
        sub = words[:2] if words[0] in ("optics", "fem") else words[:1]
        with pytest.raises(SystemExit) as exc:
            main([*sub, "--help"])
        assert exc.value.code == 0, example
        text = capsys.readouterr().out
        for w in words:
            if w.startswith("--"):
                assert w in text, (example, w)
