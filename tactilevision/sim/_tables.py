"""Measurement tables with one hidden physical effect, for testing ``diagnose``.

Each table is a calibration campaign: a few sessions on different days, each
pressing a gauge block's indenters in shuffled order with realistic timing,
positions and room temperature, so every column of formats.md §2 is present
whatever the effect. The force comes from the finite-strain FEM
(:func:`~tactilevision.mechanics.kappa_n`, not eq. 5) and then one hidden
effect changes it. The hidden effects' functional forms are deliberately not
the catalogue's (:mod:`tactilevision.mechanics._catalogue`):

================================  ==============================================
hidden                            form in the generator
================================  ==============================================
``depth_offset``                  constant bevel-lag plus a per-indenter
                                  machining error (sd 0.2 um)
``force_offset``                  a tare error per session, scattered 3 %
                                  around a common bias
``force_drift``                   thermal: ``D (1 - exp(-t / T))`` after each
                                  tare plus a small random walk
``viscoelastic_relaxation``       two-term Prony series (tau and 8 tau)
``incomplete_recovery``           power-law recovery ``r (1 + t_wait / tau)^-1.5``
``aging``                         post-cure hardening ``A (1 - exp(-day / D))``
``spatial_nonuniformity``         a tilted pad: thickness ``h (1 + tx x + ty y)``,
                                  stiffness ``(h / h(x, y))^1.3``
``stiffness_step``                the gel damaged after one press: E falls by
                                  8 to 12 %, then by a further tenth of that
                                  over the next few presses (settling as
                                  ``1 - exp(-presses / 3)``)
``large_deformation``             the FEM's own finite-strain P(w) (for
                                  ``diagnose --base layer``)
``temperature`` (out of the       modulus ``exp(-k (T - 23 C))``: no named
catalogue)                        effect; shows along ``temperature_c``
``crosstalk``                     the F/T's Fz reads ``chi Fx``; shows along
                                  ``fx_n`` (the catalogue's ``force_crosstalk``)
================================  ==============================================

Two effects at once: ``hidden="incomplete_recovery+force_drift"``. The size
of an effect can be set as a signal-to-noise ratio (``snr``): the RMS over
the presses of the part of its force change that the base law cannot take
up, in units of the replicate noise.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from .._checks import InputError
from ..mechanics import fem_force as _fem_force

__all__ = ["HIDDEN_EFFECTS", "HiddenTable", "make_measurement_table"]

#: Hidden effects the generator knows: the catalogue's (formats.md §4; ``crosstalk`` is
#: its ``force_crosstalk``) and one outside it (``temperature``). Value: the covariate
#: column it shows along.
HIDDEN_EFFECTS = {
    "depth_offset": "depth_mm",
    "force_offset": "depth_mm",
    "force_drift": "time_s",
    "viscoelastic_relaxation": "hold_s",
    "incomplete_recovery": "wait_s",
    "aging": "day",
    "spatial_nonuniformity": "x_mm",
    "stiffness_step": "press",
    "large_deformation": "depth_mm",
    "temperature": "temperature_c",
    "crosstalk": "fx_n",
}


@dataclass(frozen=True)
class HiddenTable:
    """A generated measurements table and its truth.

    Attributes
    ----------
    columns : dict of str to (N,) float64 ndarray
        ``depth_mm``, ``force_n`` and every covariate of formats.md §2
        (``wait_s`` is NaN for the first press of each session).
    thickness_mm, radius_mm : float
        h and a.
    hidden : str or None
        The hidden effect (None: a null table).
    truth : dict
        ``E_mpa``, ``nu``, ``noise_n`` (F/T noise sd, N), ``depth_jitter_mm``
        (sd of the stage's depth repeatability), ``base``
        (``'layer'`` for a ``large_deformation`` table, else ``'paper'``),
        ``covariate`` (the column the effect shows along) and the effect's
        own parameters.
    """

    columns: dict[str, np.ndarray]
    thickness_mm: float
    radius_mm: float
    hidden: str | None
    truth: dict


def _hidden_names(hidden: str | None) -> tuple[str, ...]:
    if hidden is None:
        return ()
    names = tuple(n.strip() for n in hidden.split("+"))
    for n in names:
        if n not in HIDDEN_EFFECTS:
            raise InputError(f"unknown hidden effect {n!r}; known: {', '.join(HIDDEN_EFFECTS)} "
                             "(two at once: 'a+b')")
    if len(set(names)) != len(names):
        raise InputError(f"hidden effect {hidden!r} names an effect twice")
    if "large_deformation" in names and len(names) > 1:
        raise InputError("large_deformation (the base law itself) cannot be paired")
    return names


def make_measurement_table(hidden: str | None = None, seed: int = 0, *,
                           strength: float = 1.0, snr: float | None = None) -> HiddenTable:
    """A calibration campaign's measurements table with hidden effects.

    Parameters
    ----------
    hidden : str or None
        A key of :data:`HIDDEN_EFFECTS`, two joined by ``+`` (both hidden),
        or None for a null table (the FEM law and noise only).
    seed : int
        Everything (E, nu, h, a, depths, repeats, sessions, timing, noise,
        the effect's size) is drawn from it.
    strength : float, default 1.0
        Scales the hidden effects' sizes. At 1, additive effects (offset,
        drift, cross-talk) are 4 to 15 times the press-to-press force scatter,
        stiffness effects change P by 3 to 15 %.
    snr : float, optional
        Instead of `strength`: the size of the (single) hidden effect as a
        signal-to-noise ratio, ``truth["snr"]``: the RMS over the presses of
        its force change less the best fit of the base law to that change
        (``c w + c beta w^2 / h``), over
        the replicate noise ``truth["replicate_sd_n"]`` (the F/T noise and
        the stage's depth repeatability). Found by scaling the strength (the
        random draws do not depend on it), to 1 %.

    Returns
    -------
    HiddenTable

    Raises
    ------
    InputError
        For an unknown `hidden`, a pair with ``large_deformation``, or `snr`
        with two effects or none.

    Notes
    -----
    Drawn: E 0.1 to 0.4 MPa, nu 0.40 to 0.475, h 2 to 4 mm, a/h 0.85 to 1.5,
    4 to 6 depths evenly from 0.04 h to 0.19 h, 2 to 4 sessions on days
    0 to 90 with 3 to 6 repeats of each depth per session in shuffled order,
    hold 0.2 to 5 s, wait 0.3 to 30 s (log-uniform), press centres over a
    16 x 12 mm pad, temperature 23 C +- 1.5 C per day plus a slow swing
    within the session, tangential forces 2 % of P, F/T noise sd 1 to 3 mN and
    a depth repeatability of the stage of sd 0.5 to 1.5 um (times the local
    stiffness dP/dw).
    """
    names = _hidden_names(hidden)
    if snr is not None:
        return _at_snr(hidden, seed, float(snr))
    rng = np.random.default_rng(seed)
    E = float(rng.uniform(0.1, 0.4))
    nu = float(rng.uniform(0.40, 0.475))
    h = float(rng.uniform(2.0, 4.0))
    a = float(h * rng.uniform(0.85, 1.5))
    n_depth = int(rng.integers(4, 7))
    depths = np.round(np.linspace(0.04 * h, 0.19 * h, n_depth), 4)
    n_sessions = int(rng.integers(2, 5))
    days = np.concatenate([[0.0], np.sort(rng.uniform(1, 90, n_sessions - 1)).round()])
    noise = float(rng.uniform(0.001, 0.003))
    jitter = float(rng.uniform(0.0005, 0.0015))

    c = _campaign(rng, depths, days)
    w = c["depth_mm"]
    n = w.size
    session = c.pop("session").astype(int)
    truth: dict = {"E_mpa": E, "nu": nu, "noise_n": noise, "depth_jitter_mm": jitter,
                   "base": "paper",
                   "covariate": HIDDEN_EFFECTS.get(hidden) if len(names) == 1 else None,
                   "covariates": [HIDDEN_EFFECTS[k] for k in names], "strength": strength}

    def u(lo: float, hi: float) -> float:
        return float(rng.uniform(lo, hi)) * strength

    w_true = w.copy()
    if "depth_offset" in names:
        delta = u(0.008, 0.02) * rng.choice([-1, 1])
        step_err = rng.normal(0, 0.0002, n_depth)
        w_true = w + delta + step_err[c["indenter"].astype(int)]
        truth["delta_mm"] = delta
    P = _fem_force(E, nu, a, h, np.round(w_true, 9))
    P = _stiffness_effects(names, rng, u, c, P, truth)
    fx = P * rng.normal(0, 0.02, n)
    fy = P * rng.normal(0, 0.02, n)
    # additive effects are sized against the press-to-press scatter
    sd = math.hypot(noise, jitter * float(np.mean(P / w_true)))
    truth["replicate_sd_n"] = sd
    P, fx = _force_effects(names, rng, u, c, P, fx, truth, sd, n_sessions, session)
    # F/T noise plus the stage's depth repeatability (force = local stiffness x depth error)
    P = P + rng.normal(0, noise, n) + rng.normal(0, jitter, n) * np.gradient(
        _fem_force(E, nu, a, h, depths), depths)[c["indenter"].astype(int)]
    c["force_n"] = P
    c["fx_n"] = fx + rng.normal(0, noise, n)
    c["fy_n"] = fy + rng.normal(0, noise, n)
    c["force_std_n"] = np.abs(rng.normal(noise * 10, noise, n))
    order = ["press", "indenter", "depth_mm", "force_n", "force_std_n", "fx_n", "fy_n",
             "time_s", "hold_s", "wait_s", "x_mm", "y_mm", "day", "temperature_c"]
    return HiddenTable(columns={k: c[k] for k in order}, thickness_mm=h, radius_mm=a,
                       hidden=hidden, truth=truth)


def _campaign(rng: np.random.Generator, depths: np.ndarray, days: np.ndarray
              ) -> dict[str, np.ndarray]:
    """The presses of the sessions (one per day): shuffled depths, timing, positions and
    room temperature; every column but the forces, and ``session``."""
    n_depth = depths.size
    cols: dict[str, list] = {k: [] for k in (
        "press", "indenter", "depth_mm", "time_s", "hold_s", "wait_s", "x_mm", "y_mm", "day",
        "temperature_c", "session")}
    press = 0
    for s, day in enumerate(days):
        reps = int(rng.integers(3, 7))
        order = rng.permutation(np.repeat(np.arange(n_depth), reps))
        t = 0.0
        t_room = 23.0 + rng.normal(0, 1.5)
        swing, period = rng.uniform(0.3, 1.2), rng.uniform(600, 2400)
        phase = rng.uniform(0, 2 * math.pi)
        for j, k in enumerate(order):
            wait = math.exp(rng.uniform(math.log(0.3), math.log(30.0)))
            hold = float(rng.uniform(0.2, 5.0))
            if j:
                t += wait
            cols["press"].append(press)
            cols["indenter"].append(int(k))
            cols["depth_mm"].append(float(depths[k]))
            cols["time_s"].append(t)
            cols["hold_s"].append(hold)
            cols["wait_s"].append(wait if j else math.nan)
            cols["x_mm"].append(float(rng.uniform(-8, 8)))
            cols["y_mm"].append(float(rng.uniform(-6, 6)))
            cols["day"].append(float(day))
            cols["temperature_c"].append(t_room + swing * math.sin(2 * math.pi * t / period
                                                                   + phase)
                                         + rng.normal(0, 0.05))
            cols["session"].append(s)
            t += 0.5 + hold + 0.25     # approach, hold, release
            press += 1
    return {k: np.asarray(v, np.float64) for k, v in cols.items()}


def _stiffness_effects(names: tuple[str, ...], rng: np.random.Generator,
                       u: Callable[[float, float], float], c: Mapping[str, np.ndarray],
                       P: np.ndarray, truth: dict) -> np.ndarray:
    """The hidden effects that scale the force (the stiffness's); their sizes into `truth`."""
    n = P.size
    if "large_deformation" in names:
        truth["base"] = "layer"
    if "viscoelastic_relaxation" in names:
        g1, g2 = u(0.03, 0.06), u(0.02, 0.04)
        tau = float(rng.uniform(0.3, 1.0))
        t_h = c["hold_s"]
        P = P * (1 - g1 * (1 - np.exp(-t_h / tau)) - g2 * (1 - np.exp(-t_h / (8 * tau))))
        truth.update(g1=g1, g2=g2, tau_s=tau, tau2_s=8 * tau)
    if "incomplete_recovery" in names:
        r, tau = u(0.05, 0.12), float(rng.uniform(1.0, 4.0))
        wait = np.nan_to_num(c["wait_s"], nan=np.inf)
        P = P * (1 + r * (1 + wait / tau) ** -1.5)
        truth.update(r=r, tau_s=tau)
    if "aging" in names:
        A, D = u(0.06, 0.15) * rng.choice([-1, 1]), float(rng.uniform(30, 90))
        P = P * (1 + A * (1 - np.exp(-c["day"] / D)))
        truth.update(A=A, D_days=D)
    if "spatial_nonuniformity" in names:
        tx, ty = u(0.004, 0.01) * rng.choice([-1, 1]), u(0.0, 0.008) * rng.choice([-1, 1])
        P = P * (1 + tx * c["x_mm"] + ty * c["y_mm"]) ** -1.3
        truth.update(tilt_x_per_mm=tx, tilt_y_per_mm=ty)
    if "temperature" in names:
        k = u(0.03, 0.06)
        P = P * np.exp(-k * (c["temperature_c"] - 23.0))
        truth.update(k_per_c=k)
    if "stiffness_step" in names:
        d_step = u(0.08, 0.12)
        k_step = int(rng.integers(n // 4, 3 * n // 4))
        after = c["press"] > k_step
        later = np.where(after, 1 - np.exp(-(c["press"] - k_step) / 3.0), 0.0)
        P = P * (1 - d_step * after - 0.1 * d_step * later)
        truth.update(step=-d_step, step_settled=-1.1 * d_step, after_press=k_step)
    return P


def _force_effects(names: tuple[str, ...], rng: np.random.Generator,
                   u: Callable[[float, float], float], c: Mapping[str, np.ndarray],
                   P: np.ndarray, fx: np.ndarray, truth: dict, sd: float, n_sessions: int,
                   session: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The hidden effects that add a force, sized against the replicate scatter `sd`;
    returns the force and the tangential force fx (which cross-talk redraws)."""
    n = P.size
    if "force_offset" in names:
        b0 = u(6, 15) * sd * rng.choice([-1, 1])
        b = b0 * (1 + rng.normal(0, 0.03, n_sessions))
        P = P + b[session]
        truth.update(offset_n=b0)
    if "force_drift" in names:
        D = u(6, 15) * sd * rng.choice([-1, 1])
        T = float(rng.uniform(0.5, 2.0)) * float(np.max(c["time_s"]))
        walk = np.cumsum(rng.normal(0, 0.05 * abs(D) / math.sqrt(n), n))
        P = P + D * (1 - np.exp(-c["time_s"] / T)) + walk
        truth.update(D_n=D, T_s=T)
    if "crosstalk" in names:
        fx = P * rng.normal(0, 0.05, n)
        chi = u(4, 8) * sd / float(np.std(fx)) * rng.choice([-1, 1])
        P = P + chi * fx
        truth.update(chi=chi)
    return P, fx


def _signal_rms(hidden: str, seed: int, strength: float) -> tuple[float, HiddenTable]:
    """RMS of the hidden effect's force change the base law cannot take up, and the table."""
    t = make_measurement_table(hidden, seed, strength=strength)
    t0 = make_measurement_table(hidden, seed, strength=0.0)
    # the same draws (the strength scales sizes only), so the noise cancels
    delta = t.columns["force_n"] - t0.columns["force_n"]
    w = t.columns["depth_mm"]
    X = np.column_stack([w, w * w])          # eq. (5): c w + c beta w^2 / h
    coef, *_ = np.linalg.lstsq(X, delta, rcond=None)
    return float(np.sqrt(np.mean((delta - X @ coef) ** 2))), t


def _at_snr(hidden: str | None, seed: int, snr: float) -> HiddenTable:
    names = _hidden_names(hidden)
    if len(names) != 1:
        raise InputError("snr sizes one hidden effect; give strength for pairs and null tables")
    if not (math.isfinite(snr) and snr > 0):
        raise InputError(f"snr must be positive, got {snr!r}")
    if names[0] == "large_deformation":
        raise InputError("large_deformation is the law itself: its size is not a parameter")
    strength = 1.0
    for _ in range(6):
        rms, t = _signal_rms(names[0], seed, strength)
        got = rms / t.truth["replicate_sd_n"]
        if abs(got / snr - 1) < 0.01:
            break
        strength *= snr / max(got, 1e-12)
    t.truth["snr"] = got
    return t
