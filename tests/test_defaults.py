"""One default per choice (issue 86): every option a command and its Python function both
expose has the same default in both. The walk covers each pair's every shared name, so an
option added to one side with another default fails here until the two agree or the
difference is listed below with its reason."""

from __future__ import annotations

import argparse
import inspect

import pytest

from tactilevision.batch import BatchSettings
from tactilevision.cli import build_parser
from tactilevision.cli._inputs import beta_from_args
from tactilevision.cli._reconstruct_run import _boundary_and_level
from tactilevision.diagnosis import diagnose, validate_indentation
from tactilevision.fem import ForceEstimator
from tactilevision.live import Pipeline
from tactilevision.mechanics import fit_indentation
from tactilevision.optics import DepthReconstructor, PhotometricCalibration
from tactilevision.pipeline import calibrate_session

#: command -> the Python callable it runs with the same option names
PAIRS = {
    "optics calibrate": PhotometricCalibration.from_ball_presses,
    "reconstruct": DepthReconstructor,
    "forces": ForceEstimator,
    "live": Pipeline,
    "batch": BatchSettings,
    "calibrate": calibrate_session,
    "fit": fit_indentation,
    "diagnose": diagnose,
    "validate": validate_indentation,
}


def _pair(text: str) -> tuple[int, int]:
    return tuple(int(v) for v in text.split(","))


def _names(text: str) -> tuple[str, ...]:
    return tuple(v for v in text.split(",") if v)


#: (command, option) -> the command line's text as the Python value
AS_PYTHON = {
    ("optics calibrate", "lut_cells"): _pair,
    ("forces", "grid"): _pair,
    ("batch", "grid"): _pair,
    ("diagnose", "effects"): _names,
    ("diagnose", "candidates"): _names,
    ("diagnose", "scan"): _names,
}

#: (command, option) -> the command's default resolved as the command resolves it (None on
#: the command line: read from its inputs, else this), to equal the Python default
RESOLVED = {
    ("reconstruct", "boundary"): lambda: _boundary_and_level(None, "median")[0],
    ("forces", "beta"): lambda: beta_from_args(argparse.Namespace(beta=None), {}, "")[0],
    ("batch", "beta"): lambda: beta_from_args(argparse.Namespace(beta=None), {}, "")[0],
}

#: (command, option) -> why the two differ on purpose
DIFFERENT = {
    ("reconstruct", "reference"): "None: the session's own, else one beside the frames, "
                                  "else the calibration's (the Python default)",
    ("batch", "level"): "None: 'contact' for batch forces, 'median' (the settings' "
                        "default) for batch reconstruct",
    ("fit", "contact"): "another choice of that name: a ball's contact with the gel "
                        "(session.toml's, else frictionless); fit_indentation's is the "
                        "punch's ('bonded')",
    ("validate", "contact"): "None: 'bonded' for a punch (the Python default), a ball's "
                             "from session.toml, else frictionless",
}


def _options(path: str) -> dict[str, object]:
    parser = build_parser()
    for name in path.split():
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        parser = sub.choices[name]
    return {a.dest: a.default for a in parser._actions if a.dest != "help"}


def _shared(command: str) -> list[tuple[str, object, object]]:
    params = inspect.signature(PAIRS[command]).parameters
    return [(name, cli, params[name].default) for name, cli in _options(command).items()
            if name in params and params[name].default is not inspect.Parameter.empty]


@pytest.mark.parametrize("command", list(PAIRS))
def test_a_command_and_its_function_share_every_default(command):
    shared = _shared(command)
    assert shared, f"{command} shares no option with {PAIRS[command].__qualname__}"
    for name, cli, py in shared:
        key = (command, name)
        if key in DIFFERENT:
            assert cli is None, (key, cli)
            continue
        if key in RESOLVED:
            assert cli is None and RESOLVED[key]() == py, (key, RESOLVED[key](), py)
            continue
        value = AS_PYTHON[key](cli) if key in AS_PYTHON else cli
        assert value == py, f"{command} --{name.replace('_', '-')}: {cli!r}, Python {py!r}"


def test_the_engine_choice_and_the_force_region_are_among_the_pairs():
    """The two defaults issue 86 and issue 85 name: the photometric engine (auto in both)
    and the forces' traction region (the footprint above 0.02 mm in forces, live, batch
    and Python)."""
    assert ("model", "auto", "auto") in _shared("optics calibrate")
    for command in ("forces", "live"):
        assert ("contact", "footprint", "footprint") in _shared(command)
        assert ("threshold_mm", 0.02, 0.02) in _shared(command)
    settings = inspect.signature(BatchSettings).parameters
    assert settings["contact"].default == "footprint"
    assert settings["threshold_mm"].default == 0.02
    # every listed exception is still a shared option (a stale entry would hide nothing)
    for command, name in [*DIFFERENT, *RESOLVED, *AS_PYTHON]:
        assert name in {n for n, _, _ in _shared(command)}, (command, name)
