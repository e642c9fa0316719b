"""A session's presses in time: the robot's schedule, depth against time, the F/T log.

The paper's procedure (method.md, "Measurement procedure"): ten presses per
indenter at different gel positions, in shuffled order, with waits between
them. Each press approaches at constant speed, holds, and releases. The F/T
sensor samples at ``rate_hz`` on its own clock (``t_force = t_frame +
clock_offset_s``) with the noise of an ATI-class sensor (about 1/80 N on z).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.signal import lfilter

from .._checks import InputError

__all__ = ["PressSchedule", "depth_trajectory", "ft_log", "press_schedule"]


@dataclass(frozen=True)
class PressSchedule:
    """What the robot commanded, press by press (times on the camera clock).

    Attributes
    ----------
    indenter : (P,) int64 ndarray
        Indenter index (into the gauge block's depths).
    depth_mm : (P,) float64 ndarray
        Depth reached at the end of the approach, mm.
    x_mm, y_mm : (P,) float64 ndarray
        Press centre on the gel, from the gel centre, mm.
    t_start_s : (P,) float64 ndarray
        First contact, s.
    approach_s, hold_s, release_s : (P,) float64 ndarray
        Durations of the ramp down, the hold at depth and the ramp up, s.
    wait_s : (P,) float64 ndarray
        Rest since the previous release (the first: since the session start).
    """

    indenter: np.ndarray
    depth_mm: np.ndarray
    x_mm: np.ndarray
    y_mm: np.ndarray
    t_start_s: np.ndarray
    approach_s: np.ndarray
    hold_s: np.ndarray
    release_s: np.ndarray
    wait_s: np.ndarray

    @property
    def t_end_s(self) -> np.ndarray:
        """End of each release, s."""
        return self.t_start_s + self.approach_s + self.hold_s + self.release_s

    @property
    def n_presses(self) -> int:
        """Number of presses."""
        return int(self.indenter.size)


def press_schedule(depths_mm: tuple[float, ...], *, repeats: int = 10,
                   position_radius_mm: float = 5.0, wait_s: tuple[float, float] = (3.0, 5.0),
                   approach_s: float = 0.5, hold_s: float | tuple[float, float] = 1.5,
                   release_s: float = 0.5, start_s: float = 1.0, seed: int = 0) -> PressSchedule:
    """A shuffled schedule: `repeats` presses per indenter at random gel positions.

    Parameters
    ----------
    depths_mm : sequence of float
        Depth of each indenter, mm (the gauge block's w0).
    repeats : int, default 10
    position_radius_mm : float, default 5.0
        Press centres are uniform in a disc of this radius about the gel
        centre.
    wait_s : (float, float), default (3.0, 5.0)
        Range of the uniform rest between presses, s.
    approach_s, release_s : float
        Durations of each press's loading and unloading, s.
    hold_s : float or (float, float)
        Duration of each press's hold, s, or the range of a uniform draw per
        press (holds of different lengths).
    start_s : float, default 1.0
        Time of the first contact, s.
    seed : int, default 0
        For the order, positions and waits (deterministic).

    Returns
    -------
    PressSchedule

    Raises
    ------
    InputError
        For empty or non-positive depths, repeats < 1, non-positive
        durations, or a wait range that is not increasing and non-negative.
    """
    d = np.asarray(depths_mm, np.float64)
    if d.ndim != 1 or d.size == 0 or not np.all(np.isfinite(d) & (d > 0)):
        raise InputError(f"depths_mm must be positive numbers, got {depths_mm!r}")
    if isinstance(repeats, bool) or int(repeats) != repeats or repeats < 1:
        raise InputError(f"repeats must be a positive integer, got {repeats!r}")
    hold_range = isinstance(hold_s, tuple | list)
    if hold_range and (len(hold_s) != 2 or not 0 < hold_s[0] <= hold_s[1]):
        raise InputError(f"hold_s must be a positive number or (low, high) with "
                         f"0 < low <= high, got {hold_s!r}")
    for name, v in (("approach_s", approach_s), ("hold_s", hold_s[0] if hold_range else hold_s),
                    ("release_s", release_s), ("position_radius_mm", position_radius_mm)):
        if not (np.isfinite(v) and v > 0):
            raise InputError(f"{name} must be positive, got {v!r}")
    if not (0 <= wait_s[0] <= wait_s[1]):
        raise InputError(f"wait_s must be (low, high) with 0 <= low <= high, got {wait_s!r}")
    rng = np.random.default_rng(seed)
    indenter = rng.permutation(np.repeat(np.arange(d.size), int(repeats)))
    n = indenter.size
    rad = position_radius_mm * np.sqrt(rng.uniform(0, 1, n))
    ang = rng.uniform(0, 2 * np.pi, n)
    waits = rng.uniform(wait_s[0], wait_s[1], n)
    waits[0] = start_s
    full = np.full(n, 1.0)
    # drawn last, so that a fixed hold leaves the other draws as they were
    holds = rng.uniform(hold_s[0], hold_s[1], n) if hold_range else hold_s * full
    dur = approach_s + holds + release_s
    t_start = np.cumsum(waits) + np.concatenate([[0.0], np.cumsum(dur)[:-1]])
    return PressSchedule(indenter=indenter.astype(np.int64), depth_mm=d[indenter],
                         x_mm=rad * np.cos(ang), y_mm=rad * np.sin(ang), t_start_s=t_start,
                         approach_s=approach_s * full, hold_s=holds,
                         release_s=release_s * full, wait_s=waits)


def depth_trajectory(schedule: PressSchedule, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Indentation depth at times `t_s` (camera clock) and which press it belongs to.

    Parameters
    ----------
    schedule : PressSchedule
    t_s : (N,) array_like of float

    Returns
    -------
    depth_mm : (N,) float64 ndarray
        0 between presses; linear ramps, flat hold.
    press : (N,) int64 ndarray
        Press index, -1 between presses.
    """
    t = np.asarray(t_s, np.float64)
    depth = np.zeros_like(t)
    press = np.full(t.shape, -1, np.int64)
    s = schedule
    for i in range(s.n_presses):
        u = t - s.t_start_s[i]
        on = (u >= 0) & (t <= s.t_end_s[i])
        if not on.any():
            continue
        up = np.clip(u[on] / s.approach_s[i], 0, 1)
        down = np.clip((s.t_end_s[i] - t[on]) / s.release_s[i], 0, 1)
        depth[on] = s.depth_mm[i] * np.minimum(up, down)
        press[on] = i
    return depth, press


def ft_log(schedule: PressSchedule, force_of_depth: Callable[[int, np.ndarray], np.ndarray], *,
           duration_s: float, rate_hz: float = 1000.0, clock_offset_s: float = 0.0,
           noise_n: tuple[float, float, float] = (1 / 40, 1 / 40, 1 / 80),
           tangential_fraction: float | np.ndarray = 0.01,
           bias_n: tuple[float, float, float] = (0, 0, 0),
           relaxation: tuple[float, float] = (0.0, 1.0),
           stiffness: Callable[[np.ndarray], np.ndarray] | None = None,
           drift_n: float = 0.0,
           seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Sample the F/T log of a schedule on the sensor's own clock.

    Parameters
    ----------
    schedule : PressSchedule
    force_of_depth : callable (press index, depth_mm array) -> force_n array
        Normal force of a press at a depth (e.g. the FEM's P(w)).
    duration_s : float
        Log length on the camera clock, s (samples from 0 to it, shifted).
    rate_hz : float, default 1000.0
    clock_offset_s : float, default 0.0
        t_force - t_frame, s.
    noise_n : (3,) float
        Gaussian noise sd of fx, fy, fz, N (ATI Nano17 class: about 1/40,
        1/40, 1/80 N).
    tangential_fraction : float or (P,) array_like of float, default 0.01
        Tangential force as a fraction of fz, in a random direction per
        press (a well-aligned press); larger for a misaligned one. One value
        for all presses or one per press.
    bias_n : (3,) float
        Constant offset of each channel, N.
    relaxation : (g, tau_s), default (0, 1)
        A viscoelastic gel: the force is the elastic force's history through
        the relaxation function G(t) / G(0) = 1 - g (1 - exp(-t / tau_s)) (a
        standard linear solid, one Prony term), by Boltzmann superposition:
        ``F(t) = (1 - g) P(t) + g int exp(-(t - s) / tau) dP(s)``, P the
        elastic force of `force_of_depth` (quasi-linear viscoelasticity, Fung
        1993, *Biomechanics*, ch. 7). g = 0: elastic.
    stiffness : callable (t_s array, camera clock) -> factor array, optional
        The gel's stiffness against the session's time, relative: the elastic
        force at each sample is multiplied by it (a gel softening or
        stiffening over the session, which does not recover between
        presses). Default: constant.
    drift_n : float, default 0.0
        The F/T's zero drifting linearly on fz by this much from the first
        sample to the last, N (on top of ``bias_n``).
    seed : int, default 0

    Returns
    -------
    t_s : (M,) float64 ndarray
        Sample times on the F/T clock, s.
    forces_n : (M, 3) float64 ndarray
        (fx, fy, fz), fz positive into the gel.
    """
    if not (np.isfinite(rate_hz) and rate_hz > 0):
        raise InputError(f"rate_hz must be positive, got {rate_hz!r}")
    g, tau = (float(v) for v in relaxation)
    if not (0.0 <= g < 1.0 and np.isfinite(tau) and tau > 0):
        raise InputError(f"relaxation must be (g, tau_s) with 0 <= g < 1 and tau_s > 0, got "
                         f"{relaxation!r}")
    rng = np.random.default_rng(seed)
    t_cam = np.arange(0.0, duration_s, 1.0 / rate_hz)
    depth, press = depth_trajectory(schedule, t_cam)
    fz = np.zeros_like(t_cam)
    for i in np.unique(press[press >= 0]):
        sel = press == i
        fz[sel] = force_of_depth(int(i), depth[sel])
    if stiffness is not None:
        fz = fz * np.asarray(stiffness(t_cam), np.float64)
    if g > 0:
        # q_n = a q_(n-1) + (P_n - P_(n-1)): the Prony term's memory, exact for a step per sample
        a = np.exp(-1.0 / (rate_hz * tau))
        q = lfilter([1.0], [1.0, -a], np.diff(fz, prepend=0.0))
        fz = (1.0 - g) * fz + g * q
    ang = rng.uniform(0, 2 * np.pi, schedule.n_presses)
    tf = np.broadcast_to(np.asarray(tangential_fraction, np.float64), (schedule.n_presses,))
    frac = np.where(press >= 0, tf[np.maximum(press, 0)], 0.0)
    fx = fz * frac * np.cos(ang[np.maximum(press, 0)])
    fy = fz * frac * np.sin(ang[np.maximum(press, 0)])
    forces = np.stack([fx, fy, fz], axis=1) + np.asarray(bias_n, np.float64)
    if drift_n:
        forces[:, 2] += drift_n * (t_cam - t_cam[0]) / max(float(t_cam[-1] - t_cam[0]), 1e-12)
    forces = forces + rng.normal(0, 1, forces.shape) * np.asarray(noise_n, np.float64)
    return t_cam + clock_offset_s, forces
