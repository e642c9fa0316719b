"""tactilevision: vision-based tactile sensors from raw frames to forces.

Subpackages
-----------
io         session folders, frame folders, F/T logs
optics     photometric stereo: colour -> surface gradient -> height map
contact    contact mask, indenter footprint, bevel onset, certified depth
mechanics  kappa and beta tables, the in-situ fit of E and nu
fem        indentation FEM and inverse FEM
viz        depth-map images, plots, reports
cli        the ``tactilevision`` command
"""

from ._checks import InputError, ShapeError

__version__ = "0.1.0"
__all__ = ["InputError", "ShapeError", "__version__"]
