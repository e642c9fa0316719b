"""A ball's session folder drawn by closed forms: frames of a sphere pressed into a thick
gel and the F/T log of its force, with known depths and E.

The truth is not our FEM's: a rigid sphere on an elastic half-space, Sneddon's
solution (I. N. Sneddon, "The relation between load and penetration in the
axisymmetric Boussinesq problem for a punch of arbitrary profile", Int. J. Eng.
Sci. 3:47-57, 1965): at contact radius a, the depth w = (a / 2) ln((R + a) /
(R - a)) and the force P = E* / 2 ((a^2 + R^2) ln((R + a) / (R - a)) - 2 a R),
E* = E / (1 - nu^2); on a layer of thickness h the force times the bonded layer's
first-order term 1 + 1.133 sqrt(R w) / h (Dimitriadis et al., Biophys. J.
82:2798, 2002, eq. 12 to first order, nu = 0.5). The gel's surface is the ball's
cap inside a and Hertz's sink-in outside (K. L. Johnson, Contact Mechanics, 1985,
eq. 3.42), scaled to meet the cap at a; frames are shaded through a
:class:`ShadingTable` (the Taxim authors' real GelSight table by default).
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
from scipy.optimize import brentq
from tqdm import tqdm

from .._checks import InputError, check_positive
from ..io import STANDARD_GRAVITY
from ._render import ShadingTable, taxim_shading
from ._schedule import PressSchedule, depth_trajectory, ft_log, press_schedule

__all__ = ["make_ball_session", "make_dead_weight_session", "sneddon_sphere",
           "sneddon_sphere_radius", "sphere_press_surface"]


def sneddon_sphere(a_mm: np.ndarray, *, radius_mm: float, E_mpa: float, nu: float = 0.5,
                   thickness_mm: float = np.inf) -> tuple[np.ndarray, np.ndarray]:
    """Depth and force of a rigid sphere at contact radius a (Sneddon, 1965).

    Parameters
    ----------
    a_mm : (N,) array_like of float
        Contact radii, mm, 0 <= a < R.
    radius_mm : float
        The sphere's R, mm.
    E_mpa, nu : float
        The gel's Young's modulus (MPa) and Poisson's ratio.
    thickness_mm : float, default inf
        h of a bonded layer: the force times 1 + 1.133 sqrt(R w) / h (Dimitriadis et
        al. 2002, first order; for sqrt(R w) / h up to about 0.25).

    Returns
    -------
    depth_mm, force_n : (N,) float64 ndarray

    Raises
    ------
    InputError
        For a radius not in [0, R).
    """
    a = np.asarray(a_mm, np.float64)
    R = check_positive(radius_mm, "radius_mm")
    if np.any(~np.isfinite(a) | (a < 0) | (a >= R)):
        raise InputError(f"contact radii must lie in [0, R = {R:g}) mm")
    lg = np.log((R + a) / (R - a))
    w = 0.5 * a * lg
    P = 0.5 * E_mpa / (1.0 - nu * nu) * ((a * a + R * R) * lg - 2.0 * a * R)
    return w, P * (1.0 + 1.133 * np.sqrt(R * w) / thickness_mm)


def sneddon_sphere_radius(depth_mm: float, *, radius_mm: float) -> float:
    """The contact radius a at depth w of :func:`sneddon_sphere` (its inverse), mm."""
    if not depth_mm > 0:
        return 0.0
    return brentq(lambda a: float(sneddon_sphere(a, radius_mm=radius_mm, E_mpa=1.0)[0])
                  - depth_mm, 1e-12, radius_mm * (1 - 1e-12), xtol=1e-13)


def sphere_press_surface(shape: tuple[int, int], centre_px: tuple[float, float], a_mm: float, *,
                         radius_mm: float, mm_per_px: float) -> np.ndarray:
    """The gel's surface under a sphere at contact radius a, mm into the gel, (H, W) float64:
    the ball's cap inside a (at Sneddon's depth), Hertz's sink-in outside, scaled to meet
    the cap at a."""
    R = radius_mm
    rows, cols = np.indices(shape, dtype=np.float64)
    r = np.hypot(cols - centre_px[0], rows - centre_px[1]) * mm_per_px
    w = float(sneddon_sphere(a_mm, radius_mm=R, E_mpa=1.0)[0])
    edge = w - (R - np.sqrt(R * R - a_mm * a_mm))          # the cap's depth at r = a
    out = np.empty(shape)
    inside = r < a_mm
    out[inside] = w - (R - np.sqrt(R * R - r[inside] ** 2))
    ro = r[~inside]
    out[~inside] = edge * ((2 * a_mm * a_mm - ro ** 2) * np.arcsin(a_mm / ro)
                           + a_mm * np.sqrt(ro ** 2 - a_mm * a_mm)) / (np.pi * a_mm * a_mm / 2)
    return out


def make_ball_session(folder: str | Path, *, radius_mm: float = 2.0, E_mpa: float = 1.0,
                      thickness_mm: float = 100.0, pad_radius_mm: float = 1000.0,
                      contact_radii_mm: tuple[float, ...] = (0.6, 0.8, 1.0, 1.2),
                      repeats: int = 2, fps: float = 20.0, clock_offset_s: float = 0.05,
                      table: ShadingTable | None = None, reference: np.ndarray | None = None,
                      ft_bias_n: float = 0.0, seed: int = 3,
                      progress: bool = False) -> PressSchedule:
    """Write a ball's session folder (formats.md section 1, ``[indenter] shape = "sphere"``).

    Parameters
    ----------
    folder : str or Path
        Created; must not hold a session already.
    radius_mm, E_mpa, thickness_mm, pad_radius_mm : float
        The ball's R, the gel's E (nu = 0.5), h and the pad's radius, mm (a thick
        gel: Sneddon's half-space is the truth).
    contact_radii_mm : tuple of float
        The contact radius of each depth, mm.
    repeats : int, default 2
        Presses per depth (shuffled, at random positions within 2.5 mm of the centre).
    fps : float, default 20
        Frame rate; the F/T log is at 1 kHz with an ATI-class sensor's noise.
    clock_offset_s : float, default 0.05
        F/T clock minus camera clock (not written to session.toml: calibrate finds it).
    table, reference : optional
        The shading table and no-contact frame (default :func:`taxim_shading`).
    ft_bias_n : float, default 0.0
        A constant offset of the F/T's fz, N (a sensor tared with something else on it).
    seed : int, default 3
    progress : bool, default False

    Returns
    -------
    PressSchedule
        Each press's depth (``depth_mm``: the truth), position and times.

    Raises
    ------
    InputError
        For a folder that holds a session.toml already, or a contact radius not in (0, R).
    """
    folder = Path(folder)
    if (folder / "session.toml").exists():
        raise InputError(f"{folder} holds a session already")
    if table is None:
        table, reference = taxim_shading("gelsight")
    s = table.mm_per_px
    w_true, _ = sneddon_sphere(np.array(contact_radii_mm), radius_mm=radius_mm, E_mpa=E_mpa)
    if np.any(w_true <= 0):
        raise InputError("contact_radii_mm must be positive")
    sched = press_schedule(tuple(w_true), repeats=repeats, position_radius_mm=2.5,
                           wait_s=(0.5, 0.8), approach_s=0.3, hold_s=0.8, release_s=0.3,
                           start_s=0.5, seed=seed)
    duration = float(sched.t_start_s[-1] + 1.6)
    times = np.arange(0.0, duration, 1.0 / fps)
    depth, press = depth_trajectory(sched, times)
    rng = np.random.default_rng(seed)
    (folder / "frames").mkdir(parents=True, exist_ok=True)
    cx, cy = (table.shape[1] - 1) / 2, (table.shape[0] - 1) / 2
    rows = ["frame,t_s"]
    for i, (t, w, k) in enumerate(tqdm(list(zip(times, depth, press, strict=True)),
                                       desc="ball session", unit="frame", disable=not progress)):
        height = np.zeros(table.shape)
        if w > 0:
            height = sphere_press_surface(
                table.shape, (cx + sched.x_mm[k] / s, cy + sched.y_mm[k] / s),
                sneddon_sphere_radius(float(w), radius_mm=radius_mm), radius_mm=radius_mm,
                mm_per_px=s)
        name = f"{i:05d}.png"
        cv2.imwrite(str(folder / "frames" / name),
                    table.render(height, reference, noise_dn=2.0, rng=rng))
        rows.append(f"{name},{t:.6f}")
    cv2.imwrite(str(folder / "reference.png"), reference)
    (folder / "frames.csv").write_text("\n".join(rows) + "\n")

    def force(_: int, w: np.ndarray) -> np.ndarray:
        a = np.array([sneddon_sphere_radius(float(x), radius_mm=radius_mm) for x in w])
        return sneddon_sphere(a, radius_mm=radius_mm, E_mpa=E_mpa,
                              thickness_mm=thickness_mm)[1]

    t_ft, f = ft_log(sched, force, duration_s=duration, clock_offset_s=clock_offset_s,
                     bias_n=(0.0, 0.0, float(ft_bias_n)), seed=seed)
    np.savetxt(folder / "forces.csv", np.column_stack([t_ft, f]), delimiter=",", fmt="%.6f",
               header="t_s,fx_n,fy_n,fz_n", comments="")
    (folder / "session.toml").write_text(
        f'[sensor]\nname = "gelsight"\nmm_per_px = {s}\ngel_thickness_mm = {thickness_mm}\n'
        f'gel_radius_mm = {pad_radius_mm}\n\n[indenter]\nradius_mm = {radius_mm}\n'
        'shape = "sphere"\ncontact = "frictionless"\n\n[force_sensor]\nrate_hz = 1000\n'
        'window_samples = 200\n')
    return sched


def make_dead_weight_session(folder: str | Path, masses_kg: tuple[float, ...], *,
                             repeats: int = 3, radius_mm: float = 2.0, E_mpa: float = 1.0,
                             thickness_mm: float = 100.0, pad_radius_mm: float = 1000.0,
                             mass_std_kg: float = 1e-4, seed: int = 0) -> np.ndarray:
    """Write a dead-weight folder (:func:`tactilevision.io.read_dead_weights`): one frame of
    the ball at rest under each mass, its depth where Sneddon's force is m g.

    Parameters
    ----------
    folder : str or Path
        Created; must not hold a session already.
    masses_kg : tuple of float
        The masses on the gel, kg, > 0; each pressed `repeats` times at a random position.
    repeats : int, default 3
    radius_mm, E_mpa, thickness_mm, pad_radius_mm : float
        As :func:`make_ball_session` (nu = 0.5).
    mass_std_kg : float, default 1e-4
        The stated uncertainty of each mass (written to ``mass_std_kg``; the masses are
        exact).
    seed : int, default 0

    Returns
    -------
    depth_mm : (N,) float64 ndarray
        Each frame's true depth, in the order of ``weights.csv``.

    Raises
    ------
    InputError
        For a folder that holds a session already, or a mass the ball cannot carry
        within its equator.
    """
    folder = Path(folder)
    if (folder / "session.toml").exists():
        raise InputError(f"{folder} holds a session already")
    table, reference = taxim_shading("gelsight")
    s = table.mm_per_px
    rng = np.random.default_rng(seed)
    masses = np.repeat(np.asarray(masses_kg, np.float64), int(repeats))
    P = masses * STANDARD_GRAVITY

    def force_at(a: float) -> float:
        return float(sneddon_sphere(a, radius_mm=radius_mm, E_mpa=E_mpa,
                                    thickness_mm=thickness_mm)[1])

    top = 0.95 * radius_mm
    if np.any(masses <= 0) or np.any(P >= force_at(top)):
        most = force_at(top) / STANDARD_GRAVITY
        raise InputError(f"masses_kg must be positive and below {most:.4g} kg (the ball's "
                         "contact past 0.95 R)")
    (folder / "frames").mkdir(parents=True, exist_ok=True)
    depth = np.empty(masses.size)
    rows = ["frame,mass_kg,mass_std_kg"]
    for i, p in enumerate(P):
        a = brentq(lambda x, p=p: force_at(x) - p, 1e-9, top, xtol=1e-13)
        depth[i] = float(sneddon_sphere(a, radius_mm=radius_mm, E_mpa=E_mpa)[0])
        centre = (table.shape[1] / 2 + rng.uniform(-80, 80), table.shape[0] / 2
                  + rng.uniform(-60, 60))
        height = sphere_press_surface(table.shape, centre, a, radius_mm=radius_mm, mm_per_px=s)
        cv2.imwrite(str(folder / "frames" / f"{i:03d}.png"),
                    table.render(height, reference, noise_dn=2.0, rng=rng))
        rows.append(f"{i:03d}.png,{masses[i]:.6g},{mass_std_kg:.3g}")
    cv2.imwrite(str(folder / "reference.png"), reference)
    (folder / "weights.csv").write_text("\n".join(rows) + "\n")
    (folder / "session.toml").write_text(
        f'[sensor]\nname = "gelsight"\nmm_per_px = {s}\ngel_thickness_mm = {thickness_mm}\n'
        f'gel_radius_mm = {pad_radius_mm}\n\n[indenter]\nradius_mm = {radius_mm}\n'
        'shape = "sphere"\ncontact = "frictionless"\n')
    return depth
