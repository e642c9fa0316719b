"""Finite elements of the gel pad: axisymmetric indentation (linear and
Neo-Hookean) for the kappa and beta tables; the 3D pad's condensed surface
stiffness (inverse FEM) and the layer's spectral Green's function for contact
force maps. Assembled with scikit-fem (the axisymmetric models in units of h).
"""

from ._mesh import indentation_mesh

__all__ = ["indentation_mesh"]

# linear small-strain indentation: names appended below
from ._linear import LinearIndentation, LinearIndentationSolver, linear_indentation

__all__ += ["LinearIndentation", "LinearIndentationSolver", "linear_indentation"]

# finite-strain Neo-Hookean indentation: names appended below
from ._finite import FiniteIndentation, neo_hookean_indentation  # noqa: E402

__all__ += ["FiniteIndentation", "neo_hookean_indentation"]

# contact force distribution: the spectral layer model and the inverse FEM
from ._forces import AUTO_BIN_MAX, ForceEstimator, ForceMap, auto_binning  # noqa: E402
from ._layer import layer_normal_stiffness, layer_surface_stiffness, wavevectors  # noqa: E402
from ._pad import PadStiffness, pad_surface_stiffness  # noqa: E402

__all__ += ["AUTO_BIN_MAX", "ForceEstimator", "ForceMap", "PadStiffness", "auto_binning",
            "layer_normal_stiffness", "layer_surface_stiffness", "pad_surface_stiffness",
            "wavevectors"]

# the gel's surface under a flat-punch press, from the finite-strain sweep (tactilevision.sim
# draws sessions with it, tactilevision.contact reads the bulge at the bevel from it)
from ._press import PressProfile, press_profile  # noqa: E402

__all__ += ["PressProfile", "press_profile"]
# the kappa and beta tables of tactilevision.mechanics, rebuilt (``tactilevision fem tables``)
from ._tables import build_beta_table, build_kappa_table, write_table  # noqa: E402

__all__ += ["build_beta_table", "build_kappa_table", "write_table"]

# a rigid sphere (a ball) on the bonded layer: P(w) and a(w), linear and Neo-Hookean,
# frictionless and tied; its table (models/sphere_fem.npz) rebuilt by ``fem tables``
from ._sphere import (  # noqa: E402
    SPHERE_CONTACTS,
    SPHERE_MODELS,
    SphereIndentation,
    hertz_force,
    sphere_indentation,
    sphere_mesh,
)
from ._sphere_tables import SPHERE_W_GRID, build_sphere_table, sphere_reach  # noqa: E402

__all__ += ["SPHERE_CONTACTS", "SPHERE_MODELS", "SPHERE_W_GRID", "SphereIndentation",
            "build_sphere_table", "hertz_force", "sphere_indentation", "sphere_mesh",
            "sphere_reach"]
