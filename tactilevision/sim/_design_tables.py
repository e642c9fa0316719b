"""Measurements tables of a planned design, with one catalogue effect of a known size."""

from __future__ import annotations

import math

import numpy as np

from .._checks import InputError
from ..diagnosis import NOMINAL_TAU_S, TANGENTIAL_FRACTION
from ..mechanics import EFFECT_SIZE_PARAMS, make_effect
from ..planning import Design, depth_uncertainty, planned_columns
from ._tables import _fem_force

__all__ = ["design_measurement_table"]


def design_measurement_table(design: Design, effect: str | None = None, size: float = 0.0,
                             *, seed: int = 0) -> dict[str, np.ndarray]:
    """Draw the measurements table of one session of a design, with a catalogue effect.

    Parameters
    ----------
    design : Design
        The session's design (:class:`~tactilevision.planning.Design`).
    effect : str, optional
        A catalogue effect of ``EFFECT_SIZE_PARAMS`` (formats.md §5); None: none.
    size : float, default 0
        Its size in the parameter's own unit (mm, N, N/s, fraction, 1/day, 1/mm),
        along its first parameter; relaxation at tau 1 s (or the design's
        ``relaxation_tau_s``), recovery at 2 s.
    seed : int, default 0

    Returns
    -------
    columns : dict of str to (N,) float64 ndarray
        The columns of :func:`~tactilevision.planning.planned_columns` (formats.md §2)
        with ``force_n`` and the tangential ``fx_n``, ``fy_n`` drawn: each press goes to
        its depth w0 (a depth offset moves it to w0 + delta), its force is the
        finite-strain FEM's there, changed by the effect in the catalogue's exact form,
        plus F/T noise over the window (``force_noise_n / sqrt(window_samples)``); its
        certified depth ``depth_mm`` is w0 plus the design's random depth sd
        (``depth_uncertainty``); the tangential forces are 2 % of the normal force in a
        random direction, plus F/T noise.

    Raises
    ------
    InputError
        For an effect ``plan`` cannot size.

    Notes
    -----
    The noise is the plan's own model (white, Gaussian), and the effect the catalogue's
    form: these tables test ``diagnose``'s decisions and ``plan``'s replay of them, not
    the noise model or the effects' forms (``make_measurement_table`` draws forms that
    are not the catalogue's).
    """
    if effect is not None and effect not in EFFECT_SIZE_PARAMS:
        raise InputError(f"no planned size for effect {effect!r}: choose from "
                         f"{', '.join(EFFECT_SIZE_PARAMS)}")
    d = design
    rng = np.random.default_rng(seed)
    cols = planned_columns(d)
    w0 = cols["depth_mm"]
    n = w0.size
    w_cert = w0 + rng.normal(0, depth_uncertainty(d)[0] * 1e-3, n)
    data = {**cols, "_h": d.thickness_mm}
    eff, p = None, {}
    if effect is not None:
        eff = make_effect(effect)
        p = {q.name: 0.0 for q in eff.params}
        p[EFFECT_SIZE_PARAMS[effect][0]] = float(size)
        if effect in NOMINAL_TAU_S:
            p["tau_s"] = (d.relaxation_tau_s if effect == "viscoelastic_relaxation"
                          and d.relaxation_tau_s is not None else NOMINAL_TAU_S[effect])
    # the catalogue's depth offset: w_true = w + delta
    w_true = eff.apply(p, data, w0) if eff is not None and eff.kind == "depth" else w0
    P = _fem_force(d.E_mpa, d.nu, d.radius_mm, d.thickness_mm, w_true)
    fx = TANGENTIAL_FRACTION * P * rng.standard_normal(n)
    fy = TANGENTIAL_FRACTION * P * rng.standard_normal(n)
    data.update(fx_n=fx, fy_n=fy)
    if eff is not None and eff.kind == "stiffness":
        P = P * eff.apply(p, data, P)
    elif eff is not None and eff.kind == "force":
        P = eff.apply(p, data, P)
    s_P = d.force_noise_n / math.sqrt(d.window_samples)
    return {**cols, "depth_mm": w_cert, "force_n": P + rng.normal(0, s_P, n),
            "fx_n": fx + rng.normal(0, s_P, n), "fy_n": fy + rng.normal(0, s_P, n)}
