"""The paper's FEA validation: simulated depth at each measured force.

The paper (section V.A) checks calibrated E and nu by simulating the
indentation in Abaqus with a Neo-Hookean gel and comparing the simulated
depth at each measured force with the certified depth (within 6% there).
Here the simulation is our own finite-strain axisymmetric FEM
(:func:`tactilevision.fem.neo_hookean_indentation`): one depth sweep gives
the force-depth curve P(w), which is inverted at every measured force.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .._checks import InputError, check_array
from ..fem import neo_hookean_indentation

__all__ = ["IndentationValidation", "validate_indentation"]


@dataclass(frozen=True)
class IndentationValidation:
    """Measured against simulated depths of a set of presses.

    Attributes
    ----------
    E_mpa, nu : float
        Material constants simulated (MPa; dimensionless).
    thickness_mm, radius_mm, pad_radius_mm : float
        Gel thickness h, indenter radius a and pad radius, mm.
    contact : str
        Punch condition of the simulation ('frictionless' or 'bonded').
    depth_mm, force_n : (N,) float64 ndarray
        The measured presses.
    simulated_depth_mm : (N,) float64 ndarray
        FEM depth at each measured force (NaN beyond the simulated range).
    rel_error : (N,) float64 ndarray
        ``simulated / measured - 1``.
    curve_depth_mm, curve_force_n : (K,) float64 ndarray
        The simulated force-depth curve (starts at 0, 0).
    notes : tuple of str
    """

    E_mpa: float
    nu: float
    thickness_mm: float
    radius_mm: float
    pad_radius_mm: float
    contact: str
    depth_mm: np.ndarray
    force_n: np.ndarray
    simulated_depth_mm: np.ndarray
    rel_error: np.ndarray
    curve_depth_mm: np.ndarray
    curve_force_n: np.ndarray
    notes: tuple[str, ...] = field(default=())

    @property
    def max_abs_rel_error(self) -> float:
        """Largest |simulated / measured - 1| over the presses."""
        return float(np.nanmax(np.abs(self.rel_error)))

    @property
    def mean_abs_rel_error(self) -> float:
        """Mean |simulated / measured - 1| over the presses."""
        return float(np.nanmean(np.abs(self.rel_error)))

    def to_json_dict(self) -> dict:
        """Plain-JSON form (lists for arrays, None for NaN)."""
        def clean(a: np.ndarray) -> list:
            return [None if not np.isfinite(v) else float(v) for v in np.ravel(a)]

        return {
            "E_mpa": self.E_mpa, "nu": self.nu, "thickness_mm": self.thickness_mm,
            "radius_mm": self.radius_mm, "pad_radius_mm": self.pad_radius_mm,
            "contact": self.contact,
            "max_abs_rel_error": self.max_abs_rel_error,
            "mean_abs_rel_error": self.mean_abs_rel_error,
            "presses": [
                {"depth_mm": d, "force_n": f, "simulated_depth_mm": s, "rel_error": e}
                for d, f, s, e in zip(clean(self.depth_mm), clean(self.force_n),
                                      clean(self.simulated_depth_mm), clean(self.rel_error),
                                      strict=True)
            ],
            "curve": {"depth_mm": clean(self.curve_depth_mm),
                      "force_n": clean(self.curve_force_n)},
            "notes": list(self.notes),
        }


def validate_indentation(depth_mm: np.ndarray, force_n: np.ndarray, *, E_mpa: float, nu: float,
                         thickness_mm: float, radius_mm: float,
                         pad_radius_mm: float | None = None, contact: str = "bonded",
                         steps: int = 12, margin: float = 1.25,
                         mesh: dict | None = None) -> IndentationValidation:
    """Simulate the presses at E and nu and compare depths at equal force.

    Parameters
    ----------
    depth_mm : (N,) array_like of float
        Measured (certified) depths w, mm, positive.
    force_n : (N,) array_like of float
        Measured forces P, N, positive.
    E_mpa : float
        Young's modulus, MPa.
    nu : float
        Poisson's ratio, in [0, 0.5].
    thickness_mm, radius_mm : float
        Gel thickness h and flat indenter radius a, mm.
    pad_radius_mm : float, optional
        Gel pad radius (the paper's pad: 15 mm); default 20 h, close to the
        infinite layer.
    contact : {'bonded', 'frictionless'}, default 'bonded'
        Punch condition: no slip on the face (the FEM tables' condition, and
        the one that converges to w/h = 0.2), or frictionless (a sharp
        frictionless punch folds the edge elements, often before w/h = 0.1;
        the notes then say where the sweep stopped).
    steps : int, default 12
        Depth increments of the sweep.
    margin : float, default 1.25
        The sweep goes to ``margin`` times the deepest measured press.
    mesh : dict, optional
        Mesh options for :func:`tactilevision.fem.neo_hookean_indentation`
        (``cell``, ``edge_refinements``).

    Returns
    -------
    validation : IndentationValidation

    Raises
    ------
    ShapeError
        For depth and force arrays of different length, non-finite or not 1-D.
    InputError
        For non-positive depths, forces, E, h or a, or nu outside [0, 0.5].

    Notes
    -----
    The FEM works in units of h and E: it returns ``P / (E h^2)`` against
    ``w / h``, so ``P = E h^2 force`` (N with E in MPa and h in mm). The
    simulated depth at a measured force is the linear interpolation of the
    monotonic curve P(w).

    References
    ----------
    .. [1] C. Zhao, J. Ren, H. Yu, D. Ma, "In-situ Mechanical Calibration for
       Vision-based Tactile Sensors", IEEE ICRA 2023,
       section V.A and Fig. 8.
    """
    w = check_array(depth_mm, "depth_mm", [("N",)], dtype=np.number, finite=True)
    p = check_array(force_n, "force_n", [w.shape], dtype=np.number, finite=True)
    w, p = w.astype(np.float64), p.astype(np.float64)
    for name, v in (("E_mpa", E_mpa), ("thickness_mm", thickness_mm), ("radius_mm", radius_mm)):
        if not (np.isfinite(v) and v > 0):
            raise InputError(f"{name} must be positive, got {v!r}")
    if not 0.0 <= nu <= 0.5:
        raise InputError(f"nu must lie in [0, 0.5], got {nu!r}")
    if np.any(w <= 0) or np.any(p <= 0):
        i = int(np.argmax((w <= 0) | (p <= 0)))
        raise InputError(f"press {i}: depth {w[i]:g} mm and force {p[i]:g} N must be positive")
    h = float(thickness_mm)
    pad = 20.0 * h if pad_radius_mm is None else float(pad_radius_mm)
    notes = []
    if pad_radius_mm is None:
        notes.append("pad radius not given: 20 h simulated (close to an infinite layer)")
    w_max = margin * float(w.max()) / h
    sweep = neo_hookean_indentation(radius_mm / h, nu, contact=contact, w_over_h_max=w_max,
                                    steps=steps, pad_radius_over_h=pad / h, **(mesh or {}))
    curve_w = np.concatenate([[0.0], sweep.w_over_h * h])
    curve_p = np.concatenate([[0.0], sweep.force * E_mpa * h * h])
    if not sweep.complete:
        notes.append(f"the FEM sweep stopped at w/h = {sweep.w_over_h[-1]:.3f} of the "
                     f"{w_max:.3f} asked for")
    sim = np.interp(p, curve_p, curve_w, right=np.nan)
    if np.any(np.isnan(sim)):
        notes.append(f"{int(np.isnan(sim).sum())} press(es) above the largest simulated "
                     f"force {curve_p[-1]:.4g} N: no simulated depth")
    return IndentationValidation(
        E_mpa=float(E_mpa), nu=float(nu), thickness_mm=h, radius_mm=float(radius_mm),
        pad_radius_mm=pad, contact=contact, depth_mm=w, force_n=p, simulated_depth_mm=sim,
        rel_error=sim / w - 1.0, curve_depth_mm=curve_w, curve_force_n=curve_p,
        notes=tuple(notes))
