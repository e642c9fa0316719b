"""Write a whole simulated calibration session folder, with its truth.

A session as a real rig would record it (formats.md section 1): the gauge
block pressed ``repeats`` times per indenter at shuffled gel positions, each
press approaching at constant speed until the land meets the gel (the bevel
shows), holding, and releasing; frames rendered from the FEM gel surface
through Taxim's fitted shading on the sensor's real reference frame, with
camera noise; an F/T log at ``rate_hz`` on its own clock with ATI-class
noise. ``truth.json`` holds E, nu, the clock offset and every press's true
depth and force. Deterministic for a seed.

The camera keeps frames from ``lead_s`` before each press to its release
(the recorder idles between presses), at ``fps``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from pathlib import Path

import cv2
import numpy as np
from scipy.interpolate import PchipInterpolator
from tqdm import tqdm

from .._checks import InputError
from ..contact import BevelGeometry, bevel_force, land_contact_depth
from ..fem import PressProfile, press_profile
from ._block import GaugeBlock, press_surface
from ._render import ShadingTable, taxim_shading
from ._schedule import PressSchedule, depth_trajectory, ft_log, press_schedule

__all__ = ["SessionSpec", "make_session"]


@dataclass(frozen=True)
class SessionSpec:
    """Everything that defines a simulated session (units in the names).

    Attributes
    ----------
    E_mpa, nu : float
        The gel's true Young's modulus and Poisson's ratio.
    thickness_mm : float
        Layer thickness h.
    block : GaugeBlock
    repeats : int
        Presses per indenter.
    fps : float
        Camera frame rate.
    rate_hz : float
        F/T sampling rate.
    clock_offset_s : float
        True t_force - t_frame.
    config_clock_offset_s : float or None
        What ``session.toml`` states (None: the key is left out, the offset
        must be estimated; a wrong value tests the check).
    window_samples : int
    noise_dn : float
        Camera noise, grey levels per channel.
    force_noise_n : (3,) float
        F/T noise sd (fx, fy, fz), N.
    approach_s, release_s, lead_s : float
    hold_s : float or (float, float)
        Each press's hold, s, or the range of a uniform draw per press.
    wait_s : (float, float)
        Range of the rest between presses.
    overshoot_mm : (float, float)
        The stage stops this far past w0 (uniform; default 0: an exact
        stage). With the machined bevel (``block.bevel_angle_deg > 0``)
        certification measures it; with the legacy drawn mark it is an
        unseen depth error (0.25 um at every press already moves the fitted
        nu by about 0.01).
    x_range_mm, y_range_mm : (float, float)
        Press centres, relative to the image centre (x along columns, y down
        the rows).
    misaligned : tuple of int
        Presses (chronological index) pressed with a tilt: tangential force
        ``misaligned_fraction`` of Fz.
    edge_presses : tuple of int
        Presses placed so the footprint is cut by the edge of the sensed area.
    recovery_r, recovery_tau_s : float
        A hidden incomplete recovery of the gel (default none): each press
        is stiffer by the factor ``1 + r (1 + t_wait / tau)^-1.5`` (a power
        law, deliberately not the catalogue's exponential), t_wait the rest
        since the previous release; the first press is rested.
    relaxation_g, relaxation_tau_s : float
        A hidden viscoelastic gel (default none, g = 0): the F/T log reads
        the elastic force's history through G(t) / G(0) = 1 - g (1 -
        exp(-t / tau)) (:func:`~tactilevision.sim.ft_log`). E_mpa is then
        the instantaneous modulus E_0; the relaxed one is (1 - g) E_0.
        Give long holds (`hold_s`) to see it relax.
    softening : float
        A gel softening over the session (default 0): its stiffness falls
        linearly by this fraction from the first press's start to the last
        press's end, and does not recover between presses (the F/T log's
        elastic force times ``1 - softening (t - t_first) / (t_last -
        t_first)``). ``E_mpa`` is the gel's at the first press.
    ft_zero_n, ft_drift_n : float
        The F/T's zero on fz (default 0): a constant (e.g. a gauge block's
        weight on a sensor tared before the block was mounted) and a linear
        drift over the log, N; every sample reads it, between presses too.
    ft_seed : int or None
        Seed of the F/T log's noise and tangential directions (default
        ``seed + 1``): variants of one schedule with other noise.
    jpeg_quality : int
    sensor_name : str
        ``[sensor] name`` of session.toml ('gelsight' picks the shipped
        photometric calibration for the report's height maps).
    seed : int
    window_at : {'start', 'end'}
        ``[force_sensor] window_at`` of session.toml: the force window from
        the hold's start (default) or ending at its end.
    """

    E_mpa: float = 0.20
    nu: float = 0.48
    thickness_mm: float = 3.0
    block: GaugeBlock = field(default_factory=GaugeBlock)
    repeats: int = 10
    fps: float = 10.0
    rate_hz: float = 1000.0
    clock_offset_s: float = 0.137
    config_clock_offset_s: float | None = None
    window_samples: int = 200
    noise_dn: float = 2.0
    force_noise_n: tuple[float, float, float] = (1 / 40, 1 / 40, 1 / 80)
    approach_s: float = 0.5
    hold_s: float | tuple[float, float] = 0.5
    release_s: float = 0.25
    lead_s: float = 0.2
    wait_s: tuple[float, float] = (1.5, 2.5)
    overshoot_mm: tuple[float, float] = (0.0, 0.0)
    x_range_mm: tuple[float, float] = (-6.5, -1.3)
    y_range_mm: tuple[float, float] = (-4.0, 4.0)
    misaligned: tuple[int, ...] = ()
    misaligned_fraction: float = 0.3
    edge_presses: tuple[int, ...] = ()
    recovery_r: float = 0.0
    recovery_tau_s: float = 2.0
    relaxation_g: float = 0.0
    relaxation_tau_s: float = 1.0
    softening: float = 0.0
    ft_zero_n: float = 0.0
    ft_drift_n: float = 0.0
    ft_seed: int | None = None
    jpeg_quality: int = 75
    sensor_name: str = "gelsight"
    seed: int = 0
    window_at: str = "start"


def _positions(spec: SessionSpec, n: int, rng: np.random.Generator, half_mm: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
    x = rng.uniform(*spec.x_range_mm, n)
    y = rng.uniform(*spec.y_range_mm, n)
    for i in spec.edge_presses:
        if not 0 <= i < n:
            raise InputError(f"edge press {i} is not a press (0 to {n - 1})")
        x[i] = -(half_mm[0] - 0.6 * spec.block.radius_mm)   # footprint crosses the left edge
    return x, y


def make_session(folder: str | Path, spec: SessionSpec | None = None, *,
                 shading: tuple[ShadingTable, np.ndarray] | None = None,
                 profile: PressProfile | None = None, progress: bool = False,
                 frames: bool = True) -> dict:
    """Simulate a gauge-block calibration session and write it to `folder`.

    Parameters
    ----------
    folder : str or Path
        Created (must not exist, or be empty).
    spec : SessionSpec, optional
        Default: the sample session's settings.
    shading : (ShadingTable, reference), optional
        Renderer and real reference frame; default Taxim's GelSight table
        (:func:`taxim_shading`, needs the ``taxim`` package).
    profile : PressProfile, optional
        FEM surface profiles at ``spec.nu`` (computed when not given, about
        10 s).
    progress : bool, default False
        Show a progress bar while rendering.
    frames : bool, default True
        Render and write the frames. False writes everything else (the
        F/T log, ``frames.csv``, ``truth.json``, ...) but leaves ``frames/``
        empty: the frames depend on the depths and nu only, so a session of
        the same seed, block, nu and schedule rendered once lends them to
        variants of its force log (other E, relaxation, softening, F/T
        zero); ``frames/`` is then not made.

    Returns
    -------
    truth : dict
        What ``truth.json`` holds.

    Raises
    ------
    InputError
        For a non-empty `folder` or inconsistent settings.
    """
    spec = spec or SessionSpec()
    out = Path(folder)
    if out.exists() and any(out.iterdir()):
        raise InputError(f"{out} is not empty: give a new folder for the session")
    table, reference = shading if shading is not None else taxim_shading()
    shape = table.shape
    s = table.mm_per_px
    h = spec.thickness_mm
    a = spec.block.radius_mm
    prof = profile if profile is not None else press_profile(
        a / h, spec.nu,
        w_over_h_max=max(0.22, (max(spec.block.depths_mm) + spec.overshoot_mm[1]) / h * 1.05))
    rng = np.random.default_rng(spec.seed)

    depths = np.asarray(spec.block.depths_mm, np.float64)
    if spec.block.land == "bulge" and not spec.block.vernier:
        w_c = np.array([land_contact_depth(w / h, prof) * h for w in depths])
    else:
        w_c = depths.copy()
    sched = press_schedule(tuple(depths), repeats=spec.repeats, wait_s=spec.wait_s,
                           approach_s=spec.approach_s, hold_s=spec.hold_s,
                           release_s=spec.release_s, start_s=1.0, seed=spec.seed)
    n = sched.n_presses
    half = np.array([(shape[1] - 1) / 2 * s, (shape[0] - 1) / 2 * s])
    x, y = _positions(spec, n, rng, half)
    true_depth = w_c[sched.indenter] + rng.uniform(*spec.overshoot_mm, n)
    sched = replace(sched, depth_mm=true_depth, x_mm=x, y_mm=y)
    forces = _PressForces(spec, prof, sched)

    out.mkdir(parents=True, exist_ok=True)
    if frames:
        (out / "frames").mkdir()
    cv2.imwrite(str(out / "reference.png"), reference)
    _write_frames(out, spec, sched, prof, table, reference, rng, frames=frames,
                  progress=progress)
    tang = _write_forces(out, spec, sched, forces)
    with open(out / "presses.csv", "w") as f:
        f.write("press,indenter,x_mm,y_mm\n")
        for i in range(n):
            f.write(f"{i},{int(sched.indenter[i])},{x[i]:.3f},{y[i]:.3f}\n")
    _write_toml(out, spec, s, table.shape, half)
    truth = _truth(spec, sched, w_c, forces.force_of_depth, tang, s, prof,
                   forces.bevel_force_of_depth)
    (out / "truth.json").write_text(json.dumps(truth, indent=1) + "\n")
    return truth


class _PressForces:
    """The forces of a session's presses against depth: the indenter's (from the FEM
    profile, with incomplete recovery) and the bevel band's, which the F/T reads too."""

    def __init__(self, spec: SessionSpec, prof: PressProfile, sched: PressSchedule) -> None:
        self.spec, self.prof, self.sched = spec, prof, sched
        self.h = h = spec.thickness_mm
        self.eh2 = spec.E_mpa * h * h
        # P / (E h^2) against w / h, built once
        self.p_of_w = PchipInterpolator(prof.w_over_h, prof.force)
        n = sched.n_presses
        self.recovery = np.ones(n)
        if spec.recovery_r:
            self.recovery[1:] += (spec.recovery_r
                                  * (1 + sched.wait_s[1:] / spec.recovery_tau_s) ** -1.5)

    def force_of_depth(self, i: int, d: np.ndarray) -> np.ndarray:
        """The indenter's force at depth d (what the fit is after)."""
        return self.eh2 * self.p_of_w(np.asarray(d) / self.h) * self.recovery[i]

    def bevel_force_of_depth(self, i: int, d: np.ndarray) -> np.ndarray:
        """What the bevel's band presses at depth d (the F/T sensor reads it too)."""
        spec, h = self.spec, self.h
        b = spec.block
        d = np.asarray(d, np.float64)
        if not b.vernier:
            return np.zeros_like(d)
        bulge = -self.prof.depth_at_many(d / h, b.bevel_offset_mm / h) * h
        closure = d - b.depths_mm[int(self.sched.indenter[i])] + bulge
        geom = BevelGeometry(offset_mm=b.bevel_offset_mm, direction_deg=b.bevel_direction_deg,
                             angle_deg=b.bevel_angle_deg, length_mm=b.bevel_length_mm)
        return bevel_force(np.where(d > 0, closure, 0.0), geom, thickness_mm=h,
                           E_mpa=spec.E_mpa, nu=spec.nu)

    def ft_force_of_depth(self, i: int, d: np.ndarray) -> np.ndarray:
        """What the F/T sensor reads at depth d: the indenter's and the bevel's force."""
        return self.force_of_depth(i, d) + self.bevel_force_of_depth(i, d)


def _write_frames(out: Path, spec: SessionSpec, sched: PressSchedule, prof: PressProfile,
                  table: ShadingTable, reference: np.ndarray, rng: np.random.Generator, *,
                  frames: bool, progress: bool) -> None:
    """Render the frames (from lead_s before each press to its release) into
    ``out/frames`` (unless not `frames`) and list them in ``frames.csv``."""
    shape, s, h = table.shape, table.mm_per_px, spec.thickness_mm
    x, y = sched.x_mm, sched.y_mm
    dt = 1.0 / spec.fps
    grid = np.arange(0.0, float(sched.t_end_s[-1]) + 1.0, dt)
    keep = np.zeros(grid.shape, bool)
    for t0, t1 in zip(sched.t_start_s, sched.t_end_s, strict=True):
        keep |= (grid >= t0 - spec.lead_s) & (grid <= t1 + dt)
    t_frames = grid[keep]
    d_frames, p_frames = depth_trajectory(sched, t_frames)
    names = []
    it = range(t_frames.size)
    if progress:

        it = tqdm(it, desc="rendering", unit="frame", mininterval=1.0)
    for k in it:
        name = f"{k:05d}.jpg"
        names.append(name)
        if not frames:
            continue
        i = int(p_frames[k])
        if i < 0 or d_frames[k] <= 0:
            z = np.zeros(shape, np.float32)
        else:
            c = (x[i] / s + (shape[1] - 1) / 2, y[i] / s + (shape[0] - 1) / 2)
            z, _ = press_surface(prof, spec.block, indenter=int(sched.indenter[i]),
                                 depth_mm=float(d_frames[k]), centre_px=c, shape=shape,
                                 mm_per_px=s, thickness_mm=h)
        img = table.render(z, reference, noise_dn=spec.noise_dn, rng=rng)
        cv2.imwrite(str(out / "frames" / name), img,
                    [cv2.IMWRITE_JPEG_QUALITY, int(spec.jpeg_quality)])
    with open(out / "frames.csv", "w") as f:
        f.write("frame,t_s\n")
        for name, t in zip(names, t_frames, strict=True):
            f.write(f"{name},{t:.6f}\n")


def _write_forces(out: Path, spec: SessionSpec, sched: PressSchedule, forces: _PressForces
                  ) -> np.ndarray:
    """Write the F/T log ``forces.csv``; returns each press's tangential force fraction."""
    n = sched.n_presses
    tang = np.full(n, 0.01)
    for i in spec.misaligned:
        if not 0 <= i < n:
            raise InputError(f"misaligned press {i} is not a press (0 to {n - 1})")
        tang[i] = spec.misaligned_fraction
    stiffness = None
    if spec.softening:
        t_a, t_b = float(sched.t_start_s[0]), float(sched.t_end_s[-1])

        def stiffness(t: np.ndarray) -> np.ndarray:
            return 1.0 - spec.softening * np.clip((t - t_a) / (t_b - t_a), 0.0, 1.0)

    t_f, f_ft = ft_log(sched, forces.ft_force_of_depth,
                       duration_s=float(sched.t_end_s[-1]) + 1.0,
                       rate_hz=spec.rate_hz, clock_offset_s=spec.clock_offset_s,
                       noise_n=spec.force_noise_n, tangential_fraction=tang,
                       relaxation=(spec.relaxation_g, spec.relaxation_tau_s),
                       stiffness=stiffness, bias_n=(0.0, 0.0, spec.ft_zero_n),
                       drift_n=spec.ft_drift_n,
                       seed=spec.seed + 1 if spec.ft_seed is None else spec.ft_seed)
    with open(out / "forces.csv", "w") as f:
        f.write("t_s,fx_n,fy_n,fz_n\n")
        np.savetxt(f, np.column_stack([t_f, f_ft]), fmt=["%.4f", "%.4f", "%.4f", "%.4f"],
                   delimiter=",")
    return tang


def _write_toml(out: Path, spec: SessionSpec, s: float, shape: tuple[int, int],
                half: np.ndarray) -> None:
    b = spec.block
    lines = [
        "[sensor]", f'name = "{spec.sensor_name}"', f"mm_per_px = {s}",
        f"gel_thickness_mm = {spec.thickness_mm}",
        f"gel_radius_mm = {float(half.max()):.3f}", "",
        "[indenter]", f"radius_mm = {b.radius_mm}", "",
        "[gauge_block]", "depths_mm = [" + ", ".join(f"{d:g}" for d in b.depths_mm) + "]",
        f"bevel_offset_mm = {b.bevel_offset_mm}",
        f"bevel_direction_deg = {b.bevel_direction_deg}",
        f"bevel_angle_deg = {b.bevel_angle_deg}",
        f"bevel_length_mm = {b.bevel_length_mm}", "",
        "[force_sensor]", f"rate_hz = {spec.rate_hz:g}", f"window_samples = {spec.window_samples}",
    ]
    if spec.window_at != "start":
        lines.append(f'window_at = "{spec.window_at}"')
    if spec.config_clock_offset_s is not None:
        lines.append(f"clock_offset_s = {spec.config_clock_offset_s}")
    (out / "session.toml").write_text("\n".join(lines) + "\n")


def _truth(spec: SessionSpec, sched: PressSchedule, w_c: np.ndarray, force_of_depth,
           tang: np.ndarray, s: float, prof: PressProfile, bevel_force_of_depth) -> dict:
    n = sched.n_presses
    presses = []
    for i in range(n):
        k = int(sched.indenter[i])
        presses.append({
            "press": i, "indenter": k, "w0_mm": spec.block.depths_mm[k],
            "depth_mm": round(float(sched.depth_mm[i]), 7),
            "overshoot_mm": round(float(sched.depth_mm[i] - spec.block.depths_mm[k]), 7),
            "bevel_reach_mm": [round(v, 7) for v in _bevel_reach(spec, prof, float(
                sched.depth_mm[i] - spec.block.depths_mm[k]), float(sched.depth_mm[i]))],
            "force_n": round(float(force_of_depth(i, np.array([sched.depth_mm[i]]))[0]), 7),
            "bevel_force_n": round(float(bevel_force_of_depth(
                i, np.array([sched.depth_mm[i]]))[0]), 7),
            "x_mm": round(float(sched.x_mm[i]), 4), "y_mm": round(float(sched.y_mm[i]), 4),
            "t_start_s": round(float(sched.t_start_s[i]), 6),
            "hold_from_s": round(float(sched.t_start_s[i] + sched.approach_s[i]), 6),
            "hold_to_s": round(float(sched.t_start_s[i] + sched.approach_s[i]
                                     + sched.hold_s[i]), 6),
            "wait_s": round(float(sched.wait_s[i]), 6),
            "tangential_fraction": float(tang[i]),
            "misaligned": i in spec.misaligned, "edge": i in spec.edge_presses,
        })
    return {
        "E_mpa": spec.E_mpa, "nu": spec.nu, "thickness_mm": spec.thickness_mm,
        "radius_mm": spec.block.radius_mm, "clock_offset_s": spec.clock_offset_s,
        "mm_per_px": s, "seed": spec.seed,
        "recovery_r": spec.recovery_r, "recovery_tau_s": spec.recovery_tau_s,
        "relaxation_g": spec.relaxation_g, "relaxation_tau_s": spec.relaxation_tau_s,
        "softening": spec.softening, "ft_zero_n": spec.ft_zero_n,
        "ft_drift_n": spec.ft_drift_n,
        "land_contact_depth_mm": [round(float(v), 7) for v in w_c],
        "land": spec.block.land,
        "bevel": {"offset_mm": spec.block.bevel_offset_mm,
                  "direction_deg": spec.block.bevel_direction_deg,
                  "angle_deg": spec.block.bevel_angle_deg,
                  "length_mm": spec.block.bevel_length_mm},
        "note": ("depth_mm is the true indentation while the force window is taken: the depth "
                 "at which the land meets the gel (w0 for the 'ideal' land, less for 'bulge'), "
                 "plus the stage's overshoot; force_n is the FEM force there (a bonded "
                 "Neo-Hookean layer), the indenter's alone, for an elastic gel (with "
                 "relaxation_g > 0 it is the instantaneous force, from which the F/T log "
                 "relaxes); the F/T log adds bevel_force_n, what "
                 "the bevel's band presses (tactilevision.contact.bevel_force); "
                 "overshoot_mm = depth_mm - w0; bevel_reach_mm: how far the "
                 "gel meets the bevel's flanks from the crest, towards and away from the indenter "
                 "(on the crest's middle; 0 when it does not touch)"),
        "presses": presses,
    }


def _bevel_reach(spec: SessionSpec, prof: PressProfile, overshoot_mm: float,
                 depth_mm: float) -> tuple[float, float]:
    """How far the gel meets the ridge's flanks from the crest, inwards and outwards, mm.

    On the crest's middle line: the flank ``overshoot - |u| tan(theta)`` meets
    the FEM surface ``z(r_b + u)`` (positive into the gel) where they cross;
    0 when the crest does not reach the gel or the block has no ridge.
    """
    b = spec.block
    if not b.vernier:
        return 0.0, 0.0
    h = spec.thickness_mm
    tan = np.tan(np.deg2rad(b.bevel_angle_deg))
    out = []
    for sign in (-1.0, 1.0):
        u = np.linspace(0.0, (overshoot_mm + 0.2 * depth_mm) / tan + 0.05, 4001)
        gap = overshoot_mm - u * tan - prof.depth_at(depth_mm / h, (b.bevel_offset_mm + sign * u)
                                                     / h) * h
        if gap[0] <= 0:
            out.append(0.0)
            continue
        k = int(np.argmax(gap <= 0))
        out.append(float(np.interp(0.0, [gap[k], gap[k - 1]], [u[k], u[k - 1]])) if k else
                   float(u[-1]))
    return out[0], out[1]
