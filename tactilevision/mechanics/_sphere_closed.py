"""Closed forms of a rigid sphere on an elastic layer: Hertz and Dimitriadis' layer correction.

Below the sphere table's smallest R/h (a thick gel, the Hertz limit) the force
of a ball is the half-space's (Hertz) times the thin-layer correction of
Dimitriadis et al. (2002), whose variable chi = sqrt(R w) / h is the contact
radius over the thickness. Both assume a paraboloidal tip, small strain and a
frictionless contact between ball and gel; Dimitriadis' two variants differ in
how the *layer* meets its rigid base:

- ``'bonded'`` (the layer glued to the base, the case of every table of this
  package): their eq. for a bonded sample, at nu = 0.5 eq. (12),
  1 + 1.133 chi + 1.283 chi^2 + 0.769 chi^3 + 0.0975 chi^4;
- ``'sliding'`` (the layer free to slide on the base; their "not bonded"):
  eq. (11) at nu = 0.5, 1 + 0.884 chi + 0.781 chi^2 + 0.386 chi^3
  + 0.0048 chi^4.

For any nu the series is eq. (9)-(10) of the paper, with alpha_0, beta_0
of its eq. for each case::

    1 - 2 a0/pi chi + 4 a0^2/pi^2 chi^2 - 8/pi^3 (a0^3 + 4 pi^2/15 b0) chi^3
      + 16 a0/pi^4 (a0^3 + 3 pi^2/5 b0) chi^4

    bonded:  a0 = -(1.2876 - 1.4678 nu + 1.3442 nu^2) / (1 - nu)
             b0 =  (0.6387 - 1.0277 nu + 1.5164 nu^2) / (1 - nu)
    sliding: a0 = -0.347 (3 - 2 nu) / (1 - nu)
             b0 =  0.056 (5 - 2 nu) / (1 - nu)

Checked against the paper's printed nu = 0.5 series: the general form gives
1.1329, 1.2834, 0.7695, -0.0975 (bonded) and 0.8836, 0.7808, 0.3857, 0.0048
(sliding), every printed digit of eq. (11) and (12) save one sign: eq. (12)
prints +0.0975 chi^4. The general form is kept (it and eq. (11) agree on that
term's sign; one misprint explains the difference, where the other reading
needs two). At the chi the sphere table's seam asks for (at most 0.39) the
two signs differ by 0.0975 chi^4 <= 0.22 % of P.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from .._checks import InputError

__all__ = ["DIMITRIADIS_BASES", "DIMITRIADIS_CHI_MAX", "dimitriadis_coefficients",
           "dimitriadis_force_ratio", "sneddon_sphere_ratios"]

#: The layer's condition at its rigid base for which Dimitriadis et al. give a series.
DIMITRIADIS_BASES = ("bonded", "sliding")
#: Largest chi = sqrt(R w)/h the series is used to (Dimitriadis et al. 2002 fitted their
#: alpha_0, beta_0 for chi up to about 1 and show the series within a few % of their
#: numerical solution there); the sphere table's seam never asks for more than 0.39.
DIMITRIADIS_CHI_MAX = 1.0


def dimitriadis_coefficients(nu: float, base: str = "bonded") -> np.ndarray:
    """The five coefficients of Dimitriadis' series in chi, for one nu.

    Parameters
    ----------
    nu : float
        Poisson's ratio of the layer, 0 <= nu <= 0.5.
    base : {'bonded', 'sliding'}, default 'bonded'
        The layer bonded to its rigid base, or free to slide on it.

    Returns
    -------
    (5,) float64 ndarray
        c_0 .. c_4, c_0 = 1: P / P_Hertz = sum_k c_k chi^k.

    Raises
    ------
    InputError
        For nu outside [0, 0.5] or an unknown base.

    Notes
    -----
    E. K. Dimitriadis, F. Horkay, J. Maresca, B. Kachar and R. S. Chadwick,
    "Determination of elastic moduli of thin layers of soft material using
    the atomic force microscope", Biophys. J. 82 (2002) 2798-2810: the
    series of eq. (9)-(10) with their alpha_0, beta_0 for a bonded and a
    non-bonded sample; at nu = 0.5 eq. (12) (bonded) and eq. (11) (not
    bonded). The bonded chi^4 term at nu = 0.5 is -0.0975 where eq. (12)
    prints +0.0975 (module docstring).
    """
    if base not in DIMITRIADIS_BASES:
        raise InputError(f"base must be one of {DIMITRIADIS_BASES}, got {base!r}")
    v = float(nu)
    if not 0.0 <= v <= 0.5:
        raise InputError(f"nu = {v:.4g}: Dimitriadis' layer correction is for 0 <= nu <= 0.5")
    if base == "bonded":
        a0 = -(1.2876 - 1.4678 * v + 1.3442 * v**2) / (1.0 - v)
        b0 = (0.6387 - 1.0277 * v + 1.5164 * v**2) / (1.0 - v)
    else:
        a0 = -0.347 * (3.0 - 2.0 * v) / (1.0 - v)
        b0 = 0.056 * (5.0 - 2.0 * v) / (1.0 - v)
    pi = np.pi
    return np.array([
        1.0,
        -2.0 * a0 / pi,
        4.0 * a0**2 / pi**2,
        -8.0 / pi**3 * (a0**3 + 4.0 * pi**2 / 15.0 * b0),
        16.0 * a0 / pi**4 * (a0**3 + 3.0 * pi**2 / 5.0 * b0),
    ])


def dimitriadis_force_ratio(chi: np.ndarray, nu: float, base: str = "bonded") -> np.ndarray:
    """P / P_Hertz of a rigid paraboloid on an elastic layer of finite thickness.

    P_Hertz = 4/3 E / (1 - nu^2) R^(1/2) w^(3/2) (K. L. Johnson, Contact
    Mechanics, 1985, eq. 4.22-4.23, a rigid sphere); the layer's correction
    is Dimitriadis et al. (2002), eq. (9)-(12) (:func:`dimitriadis_coefficients`).
    Small strain, frictionless contact between ball and layer.

    Parameters
    ----------
    chi : array_like of float
        sqrt(R w) / h, >= 0 and at most :data:`DIMITRIADIS_CHI_MAX` (1).
    nu : float
        0 <= nu <= 0.5.
    base : {'bonded', 'sliding'}, default 'bonded'
        The layer bonded to its rigid base (this package's layer), or free to
        slide on it.

    Returns
    -------
    float64 ndarray, shape of `chi`
        1 at chi = 0 (Hertz's half-space).

    Raises
    ------
    InputError
        For chi negative, not finite or past :data:`DIMITRIADIS_CHI_MAX`,
        nu outside [0, 0.5], or an unknown base.

    Examples
    --------
    >>> round(float(dimitriadis_force_ratio(0.5, 0.5)), 4)   # eq. (12) at chi = 0.5
    1.9774
    """
    x = np.asarray(chi, np.float64)
    if not np.all(np.isfinite(x)) or np.any(x < 0) or np.any(x > DIMITRIADIS_CHI_MAX):
        bad = float(x.ravel()[np.argmax(~np.isfinite(x.ravel()) | (x.ravel() < 0)
                                         | (x.ravel() > DIMITRIADIS_CHI_MAX))])
        raise InputError(f"chi = sqrt(R w)/h = {bad:.4g} is outside Dimitriadis' 0 to "
                         f"{DIMITRIADIS_CHI_MAX:g}")
    c = dimitriadis_coefficients(nu, base)
    return c[0] + x * (c[1] + x * (c[2] + x * (c[3] + x * c[4])))


def sneddon_sphere_ratios(w_over_r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Force and contact radius of a rigid *sphere* (not Hertz's paraboloid) on a half-space.

    I. N. Sneddon, Int. J. Engng Sci. 3 (1965) 47-57, the spherical punch:
    w = a/2 ln((R + a)/(R - a)) and P = E/(1 - nu^2) [(a^2 + R^2)/2
    ln((R + a)/(R - a)) - a R] (frictionless, small strain); as ratios to
    Hertz's P_Hertz = 4/3 E/(1 - nu^2) R^(1/2) w^(3/2) and sqrt(R w)
    (Johnson, Contact Mechanics, 1985, eq. 4.22-4.23), both 1 at w = 0 and
    0.990, 0.983 at w/R = 0.1 (0.940, 0.900 at 0.6).

    Parameters
    ----------
    w_over_r : array_like of float
        Depth over the ball's radius, 0 <= w/R <= 5.

    Returns
    -------
    force_ratio, contact_ratio : float64 ndarray, shape of `w_over_r`
        P / P_Hertz and a / sqrt(R w).

    Raises
    ------
    InputError
        For w/R negative, not finite or above 5.
    """
    s = np.asarray(w_over_r, np.float64)
    if not np.all(np.isfinite(s)) or np.any(s < 0) or np.any(s > 5.0):
        raise InputError(f"w/R must be within 0 to 5, got {s.min():.4g} to {s.max():.4g}")
    force, contact = np.ones(s.shape), np.ones(s.shape)
    for i in np.ndindex(s.shape):
        w = float(s[i])
        if w < 1e-10:               # the series' first terms: 1 - w/R (...) vanish below
            continue
        x = brentq(lambda x, w=w: 0.5 * x * np.log1p(2 * x / (1 - x)) - w, 0.0, 1 - 1e-15,
                   xtol=1e-15, rtol=1e-14)            # a / R
        log = np.log1p(2 * x / (1 - x))
        force[i] = 0.5 * ((x**2 + 1) * log - 2 * x) / (4.0 / 3.0 * w**1.5)
        contact[i] = x / np.sqrt(w)
    return force, contact
