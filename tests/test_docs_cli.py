"""docs/guide/cli.md's synopses are the parsers' own (issue 54, item 8): a test fails when
an option is added, renamed or dropped without the page following."""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
from pathlib import Path

from tactilevision.cli import COMMANDS, build_parser, synopses

PAGE = Path(__file__).resolve().parents[1] / "docs" / "guide" / "cli.md"


def test_the_synopses_on_the_page_are_the_parsers():
    block = re.search(r"```bash\n(tactilevision calibrate.*?)```", PAGE.read_text(), re.S)
    assert block is not None, "cli.md lost its synopsis block"
    assert block.group(1).strip().splitlines() == synopses()


def test_every_option_of_every_command_is_in_its_synopsis():
    lines = synopses()
    assert len(lines) == 15 and all(ln.startswith("tactilevision ") for ln in lines)
    fit = next(ln for ln in lines if ln.startswith("tactilevision fit "))
    for opt in ("--json", "--overwrite", "--ramp", "--friction", "--holds"):
        assert opt in fit


def test_each_commands_one_line_help_is_its_modules_own():
    """The command list that --help shows without importing the commands is theirs."""
    sub = next(a for a in build_parser()._actions
               if isinstance(a, argparse._SubParsersAction))
    shown = {c.dest: c.help for c in sub._choices_actions}
    assert shown == {name: help_text for name, (_, help_text) in COMMANDS.items()}


def test_version_and_help_do_not_import_the_commands():
    """issue 54, item 9: --version and --help load no command's stack (pipeline, optics,
    fem, dask); a command loads its own."""
    code = ("import sys\nfrom tactilevision.cli import main\n"
            "for argv in (['--version'], ['--help']):\n"
            "    try:\n        main(argv)\n    except SystemExit:\n        pass\n"
            "heavy = [m for m in ('tactilevision.pipeline', 'tactilevision.optics', "
            "'tactilevision.fem', 'tactilevision.io', 'scipy', 'cv2') if m in sys.modules]\n"
            "print('HEAVY', heavy)\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "HEAVY []" in r.stdout, r.stdout
