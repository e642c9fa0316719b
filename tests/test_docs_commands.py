"""Every command line the documentation shows names a sub-command and options that the
parser knows (the README's table is run by test_readme; these pages' examples are checked
here): a renamed or removed option fails the suite, not the reader."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

from tactilevision.cli import build_parser

ROOT = Path(__file__).resolve().parents[1]
PAGES = [*sorted((ROOT / "docs").rglob("*.md")), ROOT / "README.md"]
GROUPS = ("optics", "fem", "cache")  # sub-commands with sub-commands of their own


def command_lines(text: str) -> list[str]:
    """The ``tactilevision ...`` command lines of a page: in code blocks (continuations
    joined) and in inline code."""
    found = []
    for block in re.findall(r"```[a-z]*\n(.*?)```", text, re.S):
        joined = re.sub(r"\\\n\s*", " ", block)
        for line in joined.splitlines():
            line = line.strip().lstrip("$ ").split("  #", 1)[0].split(" # ", 1)[0]
            for part in re.split(r"&&|\|", line):
                part = " ".join(part.split())
                if part.startswith("tactilevision "):
                    found.append(part)
    text_out = re.sub(r"```.*?```", "", text, flags=re.S)
    found += [m for m in re.findall(r"`(tactilevision [^`]+)`", text_out)]
    return found


def _options(parser) -> dict[str, set[str]]:
    """Each sub-command's (and group's sub-command's) option strings."""
    out = {}
    sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    for name, p in sub.choices.items():
        inner = [a for a in p._actions if a.__class__.__name__ == "_SubParsersAction"]
        if inner:
            for name2, p2 in inner[0].choices.items():
                out[f"{name} {name2}"] = {s for a in p2._actions for s in a.option_strings}
        out[name] = {s for a in p._actions for s in a.option_strings}
    return out


OPTIONS = _options(build_parser())
CASES = [(p.relative_to(ROOT).as_posix(), line) for p in PAGES
         for line in command_lines(p.read_text())]


def test_the_pages_show_commands():
    assert len(CASES) >= 40


@pytest.mark.parametrize("page, line", CASES)
def test_each_command_line_uses_known_options(page, line):
    try:
        words = shlex.split(line)[1:]
    except ValueError:
        words = line.split()[1:]
    if not words or words[0].startswith("-") or words[0].endswith(":") or "<" in words[0]:
        return            # `tactilevision --help`; a message it prints; a placeholder
    sub = " ".join(words[:2]) if words[0] in GROUPS and len(words) > 1 else words[0]
    assert sub in OPTIONS, f"{page}: unknown sub-command in {line!r}"
    for w in words:
        if w.startswith("--"):
            opt = w.split("=", 1)[0]
            assert opt in OPTIONS[sub], f"{page}: {sub} has no option {opt} ({line!r})"


def test_a_wrong_option_is_caught():
    assert "--no-such-option" not in OPTIONS["calibrate"]
    assert command_lines("```bash\ntactilevision calibrate S \\\n  --out O\n```") == [
        "tactilevision calibrate S --out O"]
