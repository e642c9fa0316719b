"""Issue 86: ``tactilevision COMMAND --help`` of every command loads no command's stack.

Each command's module holds its parser alone (the standard library and the package root);
its ``run`` imports the work from ``_<name>_run`` when the command runs. These tests run
each ``--help`` in a fresh interpreter and list what it imported: a parser module that
imports NumPy, SciPy, OpenCV or one of the package's subpackages at its top fails here,
whatever the machine's speed (benchmarks/bench_cli_help.py times the same commands).
"""

from __future__ import annotations

import argparse
import importlib
import json
import subprocess
import sys

import pytest

from tactilevision.cli import COMMANDS, build_parser

#: Third-party packages no ``--help`` may import (numpy included: the parsers need none).
HEAVY = ("numpy", "scipy", "cv2", "skfem", "matplotlib", "tqdm", "torch", "dask", "plotly",
         "PIL", "pandas")

#: The package's modules a ``--help`` may import: the root's light modules, the command
#: line's package and the parser modules (each command's, the shared option groups).
ALLOWED = ({"tactilevision", "tactilevision._errors", "tactilevision._assets",
            "tactilevision._version", "tactilevision.cli", "tactilevision.cli._options",
            "tactilevision.cli._out"}
           | {f"tactilevision.cli.{module}" for module, _ in COMMANDS.values()})

#: Run ``main(argv)`` (``--help`` exits; no argv: build the whole parser), then print
#: its status and what was imported as JSON.
_PROBE = """
import json, sys
from tactilevision.cli import build_parser, main
argv = json.loads(sys.argv[1])
code = 0
try:
    if argv:
        code = main(argv)
    else:
        build_parser()
except SystemExit as exc:                   # --help
    code = exc.code
print(json.dumps({"code": code, "modules": sorted(sys.modules)}))
"""


def _commands() -> list[list[str]]:
    """Every command line of the parser tree: ``fit``, and ``optics calibrate`` beside
    ``optics`` for the groups."""
    out = []
    sub = next(a for a in build_parser()._actions
               if isinstance(a, argparse._SubParsersAction))
    for name, parser in sub.choices.items():
        out.append([name])
        inner = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        if inner:
            out += [[name, child] for child in inner[0].choices]
    return out


COMMAND_LINES = _commands()


def _imported(argv: list[str]) -> tuple[int, list[str]]:
    r = subprocess.run([sys.executable, "-c", _PROBE, json.dumps(argv)],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    found = json.loads(r.stdout.strip().splitlines()[-1])
    return found["code"], found["modules"]


def _too_heavy(modules: list[str]) -> list[str]:
    return sorted(m for m in modules
                  if m.split(".")[0] in HEAVY
                  or (m.startswith("tactilevision") and m not in ALLOWED))


def test_the_tree_has_every_command():
    """15 command lines with options of their own (as docs/guide/cli.md's synopses), the
    groups' (``optics calibrate``, ``fem tables``, ``cache info|clear``) among them."""
    leaves = [c for c in COMMAND_LINES
              if not any(len(o) > len(c) and o[:len(c)] == c for o in COMMAND_LINES)]
    assert len(leaves) == 15
    assert ["optics", "calibrate"] in leaves and ["cache", "clear"] in leaves


@pytest.mark.parametrize("argv", COMMAND_LINES, ids=" ".join)
def test_help_imports_no_command_stack(argv):
    code, modules = _imported([*argv, "--help"])
    assert code == 0
    assert _too_heavy(modules) == []


def test_the_whole_parser_imports_no_command_stack():
    """``build_parser()`` with every command (the synopses, the docs' tests) stays light."""
    code, modules = _imported([])
    assert code == 0
    assert _too_heavy(modules) == []


def test_the_probe_sees_a_command_that_runs():
    """The check above can fail: a command that runs imports its work, and the probe
    lists it (here fit, refusing a table that does not exist: exit 2)."""
    code, modules = _imported(["fit", "no-such-table.csv"])
    assert code == 2
    heavy = _too_heavy(modules)
    assert "tactilevision.cli._fit_run" in heavy and "numpy" in heavy


def test_import_tactilevision_loads_no_numpy():
    """The package root loads its errors and version only: not the assets' module (and its
    pathlib), whose import would run before the command line's Ctrl-C guard."""
    r = subprocess.run([sys.executable, "-c", "import sys, tactilevision\n"
                        "print(sorted(m for m in sys.modules if m.startswith(('numpy', "
                        "'tactilevision'))))"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == ("['tactilevision', 'tactilevision._errors', "
                                "'tactilevision._version']")


def test_the_effect_names_fit_help_lists_are_the_catalogues():
    """``fit --effects``'s help lists the catalogue from a copy (the catalogue's own list
    is read from its classes, which import SciPy): the copy follows the catalogue."""
    from tactilevision.cli._fit import EFFECT_NAMES
    from tactilevision.mechanics import EFFECT_NAMES as CATALOGUE

    assert EFFECT_NAMES == CATALOGUE


@pytest.mark.parametrize("name", list(COMMANDS))
def test_each_run_names_its_work(name):
    """Each parser module's ``run`` functions (the ones its parsers set) have their
    counterpart in ``_<name>_run``, which they import when the command runs."""
    module = importlib.import_module(f"tactilevision.cli.{COMMANDS[name][0]}")
    work = importlib.import_module(f"tactilevision.cli.{COMMANDS[name][0]}_run")
    runs = [n for n in vars(module) if n == "run" or n.startswith("run_")]
    assert runs
    for n in runs:
        assert callable(getattr(work, n)), f"{work.__name__}.{n}"
