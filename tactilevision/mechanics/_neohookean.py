"""Neo-Hookean (Abaqus form) constants from small-strain E and nu."""

from __future__ import annotations

import numpy as np

from .._checks import InputError

__all__ = ["neo_hookean_constants"]


def neo_hookean_constants(E_mpa: float | np.ndarray,
                          nu: float | np.ndarray) -> tuple[float | np.ndarray,
                                                           float | np.ndarray]:
    """Abaqus Neo-Hookean constants C10 and D1 matching E and nu at small strain.

    Parameters
    ----------
    E_mpa : float or (...) array_like, MPa
        Young's modulus, positive.
    nu : float or (...) array_like, dimensionless
        Poisson's ratio, in (-1, 0.5]. Broadcast against `E_mpa`.

    Returns
    -------
    C10_mpa : float or (...) float64 ndarray, MPa
        ``E / (4 (1 + nu))``, half the initial shear modulus.
    D1_per_mpa : float or (...) float64 ndarray, 1/MPa
        ``6 (1 - 2 nu) / E``, twice the inverse initial bulk modulus
        (0 when incompressible).

    Raises
    ------
    ValueError
        When `E_mpa` is not positive or `nu` is outside (-1, 0.5].

    Notes
    -----
    The Abaqus Neo-Hookean energy is
    ``U = C10 (I1_bar - 3) + (J - 1)^2 / D1`` with initial shear modulus
    ``mu0 = 2 C10`` and bulk modulus ``K0 = 2 / D1``. Matching
    ``mu0 = E / (2 (1 + nu))`` and ``K0 = E / (3 (1 - 2 nu))`` gives the two
    formulas above, as used in section V.A of [1]_ (E = 0.1981 MPa,
    nu = 0.4797 -> C10 = 0.0335 MPa, D1 = 1.2297 1/MPa).

    References
    ----------
    .. [1] C. Zhao, J. Ren, H. Yu, D. Ma, "In-situ Mechanical Calibration for
       Vision-based Tactile Sensors", IEEE ICRA 2023,
       section V.A.
    .. [2] Abaqus Analysis User's Guide, "Hyperelastic behavior of rubberlike
       materials", Neo-Hookean form.

    Examples
    --------
    >>> from tactilevision.mechanics import neo_hookean_constants
    >>> C10, D1 = neo_hookean_constants(0.1981, 0.4797)
    >>> round(C10, 4), round(D1, 4)
    (0.0335, 1.2297)
    """
    E = np.asarray(E_mpa, dtype=np.float64)
    n = np.asarray(nu, dtype=np.float64)
    if not np.all(np.isfinite(E) & (E > 0)):
        raise InputError(f"E_mpa must be positive and finite, got {E_mpa!r}")
    if not np.all((n > -1) & (n <= 0.5)):
        raise InputError(f"nu must be in (-1, 0.5], got {nu!r}")
    C10 = E / (4.0 * (1.0 + n))
    D1 = 6.0 * (1.0 - 2.0 * n) / E
    if C10.ndim == 0:
        return float(C10), float(D1)
    return C10, D1
