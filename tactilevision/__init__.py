"""tactilevision: vision-based tactile sensors from raw frames to forces.

Subpackages
-----------
io         session folders, frame folders, F/T logs
optics     photometric stereo: colour -> surface gradient -> height map
contact    contact mask, indenter footprint, bevel onset, certified depth
sim        simulated sessions with known truth (FEM surfaces, Taxim shading)
mechanics  kappa and beta tables, the in-situ fit of E and nu
fem        indentation FEM and inverse FEM
viz        depth-map images, plots, reports
cli        the ``tactilevision`` command
"""

from ._errors import InputError, InputWarning, ShapeError
from ._version import __version__

__all__ = ["KNOWN_SENSORS", "InputError", "InputWarning", "SessionCalibration", "ShapeError",
           "__version__", "cache_info", "cache_limit_bytes", "cache_root", "calibrate_session",
           "clear_cache", "default_calibration_path", "plan"]


def __getattr__(name: str):
    # imported on first use so that ``import tactilevision`` stays light: no NumPy, nor
    # anything heavier (the command line's start and every --help load only the standard
    # library and these few modules; tests/test_cli_help_imports.py). Not even pathlib
    # (the assets' paths): what the package root imports runs before the command line's
    # Ctrl-C guard (tactilevision.__main__), 17 of its 19 ms
    if name in ("KNOWN_SENSORS", "default_calibration_path"):
        from . import _assets

        return getattr(_assets, name)
    if name in ("cache_info", "cache_limit_bytes", "cache_root", "clear_cache"):
        from . import _cache

        return getattr(_cache, name)
    if name in ("calibrate_session", "SessionCalibration"):
        from . import pipeline

        return getattr(pipeline, name)
    if name == "plan":        # tactilevision.plan(design): before the first press
        from .planning import plan

        return plan
    raise AttributeError(f"module 'tactilevision' has no attribute {name!r}")
