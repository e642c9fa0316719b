"""Gauge-block calibration sessions rendered by Taxim itself (an independent renderer).

    python benchmarks/taxim_gauge_session.py OUT_DIR [--presses N | --repeats K]
        [--fps F] [--seed S] [--no-shadow] [--taxim-contact-scale X]
        [--theta DEG] [--offset-mm R] [--direction-deg PHI] [--length-mm W]
        [--overshoot-mm LO HI] [--hold-s LO HI] [--mark-flank-deg DEG]
        [--approach-mm-s V] [--clock-offset-s T] [--force-rate-hz R]
        [--c-n-per-mm C] [--beta B] [--progress]

Writes a session folder in the project's public format (``session.toml``,
``reference.png``, ``frames/``, ``frames.csv``, ``forces.csv``,
``presses.csv``, ``truth.json``, ``README.md``, ``LICENSE``) whose frames are
drawn by Taxim's own renderer, ``taxim.Taxim(backend="jax").render(height_map,
press_depth=w)`` (Si and Yuan, RA-L 2022; PyPI ``taxim``), from the object
height map of the gauge block ("the bevel as a vernier"): five flat-ended
cylindrical indenters of radius 2.5 mm protruding w0 = 0.15 ... 0.60 mm beyond
the block's reference plane, and beside each a V ridge (the bevel) whose crest
lies w0 behind the indenter face, its flanks falling away at ``theta``.
Pressing an indenter to w = w0 + delta puts the crest delta into the gel; the
ridge's contact is the band |u| <= delta / tan(theta) along the bevel
direction, the vernier the depth certification reads.

Why no ``tactilevision`` code: these sessions test the project's depth
certification on frames that no project code drew, so the generator imports
only numpy, cv2, jax and taxim (plus the standard library, and tqdm for the
optional progress bar). Geometry, timing and forces are written out here from
their definitions; the image formation (gel deformation, shading, shadows) is
entirely Taxim's.

Taxim settings (see ``TAXIM_NOTES``): a flat gel (the shipped ``gelmap.npy``
replaced by a constant), ``contact_scale = 0`` (Taxim's default 0.4 drops
contacts shallower than 0.4 x the deepest one: the bevel would not show) and
shadows on. ``--no-shadow`` and ``--taxim-contact-scale 0.4`` give the
comparison variants; the press layout, timing and forces depend only on the
seed, so variants of one seed differ in their frames only.

Deterministic: the same arguments give the same files (JAX on CPU, its
kernels single-threaded: set before jax is first imported, see below).
"""

from __future__ import annotations

import argparse
import importlib.metadata
import json
import math
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

# Bit-reproducible renders: XLA's multi-threaded CPU kernels change Taxim's output
# by up to ~5 grey levels from one run to the next; single-threaded they do not
# (and are no slower on a few cores). Only effective if jax is not imported yet.
_DETERMINISTIC_XLA = "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"
if "jax" not in sys.modules and "xla_cpu_multi_thread_eigen" not in os.environ.get("XLA_FLAGS",
                                                                                     ""):
    os.environ["XLA_FLAGS"] = (os.environ.get("XLA_FLAGS", "") + " " + _DETERMINISTIC_XLA).strip()

import cv2  # noqa: E402
import jax  # noqa: E402, F401  (Taxim's jax backend; imported here so a missing jax fails early)
import numpy as np  # noqa: E402
import taxim  # noqa: E402

__all__ = ["DEPTHS_MM", "force_n", "gauge_height_map", "make_taxim_session",
           "press_positions_region"]

# ------------------------------------------------------------------ constants

DEPTHS_MM = (0.15, 0.30, 0.40, 0.50, 0.60)   # w0 of the five indenters
MM_PER_PX = 0.0295                            # Taxim's GelSight (params.json "pixmm")
SHAPE = (480, 640)                            # rows, columns
INDENTER_RADIUS_MM = 2.5
GEL_THICKNESS_MM = 3.0
GEL_RADIUS_MM = 9.4
RELIEF_MM = 1.0                               # relieved block: w0 + 1 mm, out of reach
# Force law, eq. 5 of the in-situ calibration paper: P(w) = c w (1 + beta w / h)
C_N_PER_MM = 3.51
BETA = 0.78
CLOCK_OFFSET_S = 0.137                        # t_force = t_frame + offset
FORCE_RATE_HZ = 1000
FORCE_NOISE_N = (1 / 40, 1 / 40, 1 / 80)      # sd on x, y, z
TANGENTIAL_FRACTION = 0.01                    # Fx = Fy = 0.01 P
CAMERA_NOISE_GREY = 1.5
JPEG_QUALITY = 90
# press timing (s)
WAIT_S = (1.5, 2.5)
APPROACH_S = 0.5
HOLD_S = 0.5
RELEASE_S = 0.25
PRE_ROLL_S = 0.2
# placement margins (mm)
FOOTPRINT_MARGIN_MM = 0.3
BAND_HALF_U_MM = 1.2
BAND_V_MARGIN_MM = 0.3
TAXIM_DEFAULT_CONTACT_SCALE = 0.4
# Measured with this generator's settings: a bevel band narrower than about this
# half-width (px) gets a 10-25 px wide slab of shadow colour beside it in Taxim's
# frames (its shadow caster); wider bands show clean edges at u = +-L.
NARROW_BAND_PX = 10.0

TAXIM_NOTES = """\
1. Flat gel. Taxim's calibration folder `taxim/calib/gelsight` is copied to a
   temporary folder and its `gelmap.npy` replaced by a constant array (the
   shipped map's maximum). The shipped gel map is a dome about 0.9 mm deep over
   the pad (0.57 mm lower 7.5 mm right of the centre than at the centre): the
   bevel beside an indenter would meet gel at a different height than the
   indenter face, while our mechanics and the gauge-block method assume a flat
   layer of uniform thickness. With the flat map, Taxim's contact is exactly
   where the object map, shifted by `press_depth`, lies below 0.
2. `contact_scale = 0` (`params={"simulator": {"contact_scale": 0.0}}`).
   Taxim keeps the object's shape only inside its contact mask, the pixels
   deeper than `contact_scale` x the deepest penetration; everything else is
   smoothed by its Gaussian pyramid (sigma about 35 px in all). With the
   default 0.4 the bevel contact (0 to 50 um deep, the indenter face 150 to
   650 um) is never in the mask: it is blurred away, and with it the shadow
   edge Taxim draws around the contact (measured on one press, delta = 40 um:
   with 0.4 the bevel region differs from the no-contact frame by at most
   7 grey levels, a smooth halo with no edge; with 0 the band's edges stand
   out at u = -L and +L, 18 and 42 grey levels averaged along the crest, up
   to 61). With 0 every contact pixel is in the mask.
3. Shadows on (Taxim's default `with_shadow=True`). Taxim's shading of a 5 deg
   flank is faint; the band shows mainly through the shadow Taxim casts from
   the contact boundary, so the vernier is readable only with shadows
   (without them the band differs from the no-contact frame by 5 to 10 grey
   levels, peaked about 5 px from the crest whatever its half-width).
   Known Taxim artefact: when the band's half-width is under about 10 px
   (delta < 0.026 mm at theta = 5 deg), Taxim's shadow caster paints a slab of
   shadow colour 10 to 25 px wide beside the band (wider than the band itself),
   at any position in the image; truth.json flags those presses
   (`taxim_narrow_band`). From about 10 px up the band's edges sit at u = +-L.
The no-contact frames (the reference and every frame before contact or after
release) are one render of a height map that stays out of the gel (no
`press_depth`), with the same settings. Note that a Taxim frame with contact
differs from the no-contact frame everywhere, not only near the contact: its
Gaussian pyramid spreads a tiny slope over the whole image and Taxim's shading
table looks up the slope's direction even when its magnitude rounds to zero
(median 2.6, up to 11 grey levels, noise-free, 3 mm and more from any
contact). XLA's CPU kernels run single-threaded (XLA_FLAGS, set before jax is
imported) so that the renders are bit-reproducible."""

TAXIM_MIT_LICENSE = """\
MIT License

Copyright (c) 2021 CMURoboTouch

Permission is hereby granted, free of charge, to any person obtaining a copy
of this software and associated documentation files (the "Software"), to deal
in the Software without restriction, including without limitation the rights
to use, copy, modify, merge, publish, distribute, sublicense, and/or sell
copies of the Software, and to permit persons to whom the Software is
furnished to do so, subject to the following conditions:

The above copyright notice and this permission notice shall be included in all
copies or substantial portions of the Software.

THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR
IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY,
FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO EVENT SHALL THE
AUTHORS OR COPYRIGHT HOLDERS BE LIABLE FOR ANY CLAIM, DAMAGES OR OTHER
LIABILITY, WHETHER IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM,
OUT OF OR IN CONNECTION WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE
SOFTWARE.
"""


# ------------------------------------------------------------------ geometry


def _pixel_grid_mm(shape=SHAPE, mm_per_px=MM_PER_PX):
    """x (along columns) and y (down the rows) of every pixel centre, mm from the image centre."""
    rows, cols = shape
    x = (np.arange(cols) - (cols - 1) / 2) * mm_per_px
    y = (np.arange(rows) - (rows - 1) / 2) * mm_per_px
    return np.meshgrid(x, y)


#: Width of the line of a mark (``--theta 0``), mm: the paper's bevel mark, a line on the
#: block's land with no flanks to read.
MARK_WIDTH_MM = 0.15


#: Half-width of the base of a drawn mark's ridge (``mark_flank_deg > 0``), mm: a small V
#: ridge whose crest lies at the land's level and whose flanks fall at the mark's flank
#: angle to this half-width, the block relieved beyond it.
MARK_RIDGE_HALF_MM = 0.5


def gauge_height_map(x_mm: float, y_mm: float, w0_mm: float, *, radius_mm=INDENTER_RADIUS_MM,
                     offset_mm=7.5, direction_deg=0.0, theta_deg=5.0, length_mm=3.0,
                     relief_mm=RELIEF_MM, shape=SHAPE, mm_per_px=MM_PER_PX,
                     mark_flank_deg=0.0) -> np.ndarray:
    """Taxim object height map (mm from the gel's highest point; smaller = closer to the camera).

    Indenter face 0 inside the circle of ``radius_mm`` about (x_mm, y_mm); the
    bevel's crest w0 on the line u = 0 (u along ``direction_deg`` measured from
    ``offset_mm``), |v| <= length/2; its flanks w0 + |u| tan(theta); the rest
    of the block w0 + relief. With ``theta_deg = 0`` a drawn mark: a line
    :data:`MARK_WIDTH_MM` wide at w0, or with ``mark_flank_deg > 0`` a V ridge
    w0 + |u| tan(mark_flank) for |u| <= :data:`MARK_RIDGE_HALF_MM`. Pixel
    centres are sampled (no anti-aliasing).
    """
    X, Y = _pixel_grid_mm(shape, mm_per_px)
    X = X - x_mm
    Y = Y - y_mm
    c, s = math.cos(math.radians(direction_deg)), math.sin(math.radians(direction_deg))
    u = X * c + Y * s - offset_mm
    v = -X * s + Y * c
    h = np.full(shape, w0_mm + relief_mm)
    if theta_deg > 0:
        ridge = w0_mm + np.abs(u) * math.tan(math.radians(theta_deg))
    elif mark_flank_deg > 0:
        # a drawn mark with flanks: a small V ridge, crest at the land's level, its contact
        # growing from nothing at w0 as a band |u| <= delta / tan(flank)
        ridge = np.where(np.abs(u) <= MARK_RIDGE_HALF_MM,
                         w0_mm + np.abs(u) * math.tan(math.radians(mark_flank_deg)),
                         w0_mm + relief_mm)
    else:
        # a mark, not a vernier: a line MARK_WIDTH_MM wide at the land's level (w0 behind
        # the indenter face), whose contact shows once the press passes w0
        ridge = np.where(np.abs(u) <= MARK_WIDTH_MM / 2, w0_mm, w0_mm + relief_mm)
    h = np.where(np.abs(v) <= length_mm / 2, np.minimum(h, ridge), h)
    h = np.where(X * X + Y * Y <= radius_mm * radius_mm, 0.0, h)
    return h.astype(np.float32)


def _placement_ok(x, y, *, offset_mm, direction_deg, length_mm, shape=SHAPE, mm_per_px=MM_PER_PX):
    """Whether a press at (x, y) keeps its footprint and bevel band (with margins) inside."""
    hx = (shape[1] - 1) / 2 * mm_per_px
    hy = (shape[0] - 1) / 2 * mm_per_px
    r = INDENTER_RADIUS_MM + FOOTPRINT_MARGIN_MM
    ok = (x - r >= -hx) & (x + r <= hx) & (y - r >= -hy) & (y + r <= hy)
    c, s = math.cos(math.radians(direction_deg)), math.sin(math.radians(direction_deg))
    bx, by = x + offset_mm * c, y + offset_mm * s
    hv = length_mm / 2 + BAND_V_MARGIN_MM
    for su in (-1, 1):
        for sv in (-1, 1):
            px = bx + su * BAND_HALF_U_MM * c - sv * hv * s
            py = by + su * BAND_HALF_U_MM * s + sv * hv * c
            ok = ok & (px >= -hx) & (px <= hx) & (py >= -hy) & (py <= hy)
    return ok


def press_positions_region(*, offset_mm=7.5, direction_deg=0.0, length_mm=3.0, shape=SHAPE,
                           mm_per_px=MM_PER_PX) -> dict:
    """The admissible press centres: bounding box (mm) and count of admissible pixel centres."""
    X, Y = _pixel_grid_mm(shape, mm_per_px)
    ok = _placement_ok(X, Y, offset_mm=offset_mm, direction_deg=direction_deg,
                       length_mm=length_mm, shape=shape, mm_per_px=mm_per_px)
    if not ok.any():
        return {"candidate_pixel_centres": 0}
    return {"candidate_pixel_centres": int(ok.sum()),
            "x_mm": [round(float(X[ok].min()), 4), round(float(X[ok].max()), 4)],
            "y_mm": [round(float(Y[ok].min()), 4), round(float(Y[ok].max()), 4)]}


def force_n(w_mm, c_n_per_mm=C_N_PER_MM, beta=BETA):
    """Normal force, eq. 5 of the in-situ calibration paper: P = c w (1 + beta w / h)."""
    w = np.maximum(np.asarray(w_mm, dtype=float), 0.0)
    return c_n_per_mm * w * (1.0 + beta * w / GEL_THICKNESS_MM)


def _depth(t, p) -> np.ndarray:
    """True indenter depth (mm) at camera time(s) t during press p (0 outside it)."""
    t = np.asarray(t, dtype=float)
    t0, t1, t2, t3 = p["t_start_s"], p["hold_from_s"], p["hold_to_s"], p["release_end_s"]
    wf = p["depth_mm"]
    w = np.zeros_like(t)
    w = np.where((t > t0) & (t < t1), wf * (t - t0) / (t1 - t0), w)
    w = np.where((t >= t1) & (t <= t2), wf, w)
    w = np.where((t > t2) & (t < t3), wf * (1.0 - (t - t2) / (t3 - t2)), w)
    return w


# ------------------------------------------------------------------ Taxim


def _flat_calib_folder(tmp: Path) -> Path:
    """Copy of Taxim's GelSight calibration with gelmap.npy replaced by its maximum (a flat gel)."""
    src = Path(taxim.__file__).parent / "calib" / "gelsight"
    dst = tmp / "gelsight_flat"
    shutil.copytree(src, dst)
    gel = np.load(src / "gelmap.npy")
    np.save(dst / "gelmap.npy", np.full_like(gel, gel.max()))
    return dst


def _license_text() -> str:
    """Taxim's MIT licence from the installed package's metadata (the embedded copy if absent)."""
    try:
        dist = importlib.metadata.distribution("taxim")
        for f in dist.files or ():
            if f.name.upper().startswith("LICENSE"):
                text = f.read_text()
                if text and "MIT" in text:
                    return text
    except (importlib.metadata.PackageNotFoundError, OSError):
        pass
    return TAXIM_MIT_LICENSE


def _taxim_version() -> str:
    try:
        return importlib.metadata.version("taxim")
    except importlib.metadata.PackageNotFoundError:
        return "unknown"


# ------------------------------------------------------------------ session


def _schedule(rng, rng_pos, n_presses, repeats, overshoot_mm, offset_mm, direction_deg,
              length_mm, hold_s=(HOLD_S, HOLD_S), rng_hold=None, approach_mm_s=None,
              law=(C_N_PER_MM, BETA)):
    """Chronological presses: indenter, overshoot, position and times (camera clock).

    Order, waits and overshoots come from ``rng``, positions from ``rng_pos``,
    hold lengths (uniform in ``hold_s``) from ``rng_hold``: sessions of one seed
    share their indenters, overshoots and timing whatever the bevel geometry, and
    a constant hold draws nothing. The approach lasts :data:`APPROACH_S`, or runs at
    ``approach_mm_s`` (the stage's speed, mm/s) where given.
    """
    k = len(DEPTHS_MM)
    if n_presses is None:
        n_presses = k * repeats
    order = np.repeat(np.arange(k), -(-n_presses // k))
    order = rng.permutation(order)[:n_presses]
    lo, hi = overshoot_mm
    hx = (SHAPE[1] - 1) / 2 * MM_PER_PX
    hy = (SHAPE[0] - 1) / 2 * MM_PER_PX
    presses, t_prev = [], 0.0
    for i, ind in enumerate(order):
        wait = float(rng.uniform(*WAIT_S))
        delta = round(float(rng.uniform(lo, hi)), 5)
        for _ in range(100000):
            x = round(float(rng_pos.uniform(-hx, hx)), 4)
            y = round(float(rng_pos.uniform(-hy, hy)), 4)
            if _placement_ok(x, y, offset_mm=offset_mm, direction_deg=direction_deg,
                             length_mm=length_mm):
                break
        else:
            raise ValueError("no press position keeps the footprint and the bevel band inside "
                             "the image: reduce --offset-mm or --length-mm")
        t0 = round(t_prev + wait, 4)
        hold = (float(hold_s[0]) if hold_s[0] == hold_s[1] or rng_hold is None
                else float(rng_hold.uniform(*hold_s)))
        w0 = DEPTHS_MM[int(ind)]
        depth = round(w0 + delta, 5)
        approach = APPROACH_S if approach_mm_s is None else depth / float(approach_mm_s)
        p = {"press": i, "indenter": int(ind), "w0_mm": w0, "overshoot_mm": delta,
             "depth_mm": depth, "force_n": round(float(force_n(depth, *law)), 6),
             "x_mm": x, "y_mm": y, "t_start_s": t0,
             "hold_from_s": round(t0 + approach, 4),
             "hold_to_s": round(t0 + approach + hold, 4),
             "release_end_s": round(t0 + approach + hold + RELEASE_S, 4),
             "wait_s": round(wait, 4)}
        presses.append(p)
        t_prev = p["release_end_s"]
    return presses


_TOML_COMMENTS = {
    "bevel_offset_mm": "distance from the indenter axis to the bevel's crest line, mm",
    "bevel_direction_deg": "direction from the axis to the bevel in the image: "
                           "0 = +x (right, along columns), 90 = +y (down the rows)",
    "bevel_angle_deg": "flank angle of the bevel ridge to the block land, degrees",
    "bevel_length_mm": "length of the crest line",
    "bulge_correction": "Taxim's gel does not bulge "
                        "(volume is not conserved in its deformation model)",
    "bevel_force_correction": "forces.csv holds the indenter's force alone "
                              "(eq. 5), not the bevel band's",
}


def _session_toml(offset_mm, direction_deg, theta_deg, length_mm,
                  force_rate_hz=FORCE_RATE_HZ) -> str:
    depths = ", ".join(f"{d:.2f}" for d in DEPTHS_MM)
    bevel = [("bevel_offset_mm", repr(float(offset_mm))),
             ("bevel_direction_deg", repr(float(direction_deg))),
             ("bevel_angle_deg", repr(float(theta_deg))),
             ("bevel_length_mm", repr(float(length_mm))),
             ("bulge_correction", "false"), ("bevel_force_correction", "false")]
    lines = ["[sensor]", 'name = "taxim-gelsight"', f"mm_per_px = {MM_PER_PX}",
             f"gel_thickness_mm = {GEL_THICKNESS_MM}", f"gel_radius_mm = {GEL_RADIUS_MM}", "",
             "[indenter]", f"radius_mm = {INDENTER_RADIUS_MM}", "",
             "[gauge_block]", f"depths_mm = [{depths}]"]
    lines += [f"{f'{k} = {v}':<32} # {_TOML_COMMENTS[k]}" for k, v in bevel]
    # the force window: 0.2 s of samples (200 at 1 kHz)
    lines += ["", "[force_sensor]", f"rate_hz = {force_rate_hz:g}",
              f"window_samples = {round(0.2 * force_rate_hz)}", ""]
    return "\n".join(lines)


def _holds(truth: dict) -> str:
    lo, hi = truth["hold_range_s"]
    return f"{lo:g} s" if lo == hi else f"{lo:g} to {hi:g} s (uniform)"


def _approach(truth: dict) -> str:
    a = truth["approach"]
    return f"in {a}" if a.endswith(" s") else f"at {a}"


def _mark_text(b: dict) -> str:
    if b["angle_deg"] > 0:
        return ""
    if b["mark_flank_deg"] > 0:
        return (f" (a drawn mark, `bevel_angle_deg = 0` in session.toml: a V ridge whose "
                f"flanks fall at {b['mark_flank_deg']:g} deg to |u| = {b['mark_ridge_half_mm']:g} "
                "mm)")
    return f" (a drawn mark: a line {MARK_WIDTH_MM:g} mm wide at the crest's level)"


def _session_readme(truth: dict, command: str) -> str:
    tx, b = truth["taxim"], truth["bevel"]
    n = len(truth["presses"])
    narrow = ", ".join(str(p["press"]) for p in truth["presses"] if p["taxim_narrow_band"])
    narrow = narrow or "none"
    return f"""# Gauge-block session rendered by Taxim (independent renderer)

A gauge-block calibration session ("the bevel as a vernier") whose frames were
rendered by Taxim's own renderer (`taxim.Taxim(backend="jax").render(height_map,
press_depth=w)`, PyPI `taxim` {tx['version']}; Taxim, CMURoboTouch / Si and Yuan,
RA-L 2022), not by any `tactilevision` code: the generator
`benchmarks/taxim_gauge_session.py` does not import `tactilevision`.

- **Gauge block**: five flat-ended cylindrical indenters, radius
  {truth['radius_mm']} mm, protruding w0 = 0.15, 0.30, 0.40, 0.50, 0.60 mm beyond the
  block's reference plane; beside each, {b['offset_mm']:g} mm from its axis in
  direction {b['direction_deg']:g} deg (0 = +x along the columns, 90 = +y down the rows),
  a V ridge whose crest ({b['length_mm']:g} mm long, perpendicular to that direction)
  lies w0 behind the face, flanks falling away at {b['angle_deg']:g} deg{_mark_text(b)}; the rest of
  the block is relieved {b['relief_mm']:g} mm. Pressed to w = w0 + delta, the ridge
  contact is the band |u| <= delta / tan(theta): its half-width is the vernier.
- **Presses** ({n}, chronological in `presses.csv`, centres in mm from the image
  centre, sub-pixel): shuffled indenters, idle 1.5 to 2.5 s, approach from
  w = 0 to w0 + delta {_approach(truth)}, hold {_holds(truth)}, release in 0.25 s; delta uniform in
  [{truth['overshoot_range_mm'][0]:g}, {truth['overshoot_range_mm'][1]:g}] mm.
- **Frames** (`frames/`, 640 x 480 JPEG quality {tx['jpeg_quality']}, {truth['fps']:g} frames/s
  from 0.2 s before each press to its release end, times on the camera clock in
  `frames.csv`): one Taxim render per frame at the true depth; frames with no
  contact reuse the no-contact render (`reference.png`, noise-free); every
  frame has fresh Gaussian camera noise of {tx['camera_noise_grey']:g} grey levels per channel.
- **Forces** (`forces.csv`, {truth['force_rate_hz']:g} Hz, on the F/T clock: t_force = t_frame +
  {truth['clock_offset_s']} s, not in `session.toml`): P(w) = c w (1 + beta w / h), eq. 5
  of the in-situ calibration paper, c = {truth['c_n_per_mm']} N/mm, beta = {truth['beta']},
  h = {truth['thickness_mm']} mm, following w(t); Fx = Fy = 0.01 P; noise 1/40, 1/40,
  1/80 N on x, y, z.
- **Truth** (`truth.json`): the force law, the clock offset, Taxim's settings,
  the bevel, and per press its indenter, overshoot, true depth during the hold,
  force, position and times.

## Taxim settings and why

This session: flat gel, contact_scale = {tx['contact_scale']:g}, shadows
{'on' if tx['with_shadow'] else 'off'}{'' if (tx['contact_scale'] == 0 and tx['with_shadow'])
                                       else ' (a comparison variant, not the reference settings)'}.

{TAXIM_NOTES}

Presses whose band half-width is under {b['taxim_narrow_band_px']:g} px here (Taxim's shadow slab,
`taxim_narrow_band` in truth.json): {narrow}.

## Regenerate

    {command}

(deterministic for a given seed; needs `taxim` and `jax`; about 1 to 2 s per
rendered frame on a CPU.)

## Licence

The images are Taxim's renders: its calibration data (shading polynomial,
no-contact background, shadow table) and code are MIT licensed, Copyright (c)
2021 CMURoboTouch (Taxim, CMURoboTouch / Si and Yuan, RA-L 2022); see
`LICENSE`.
"""


def make_taxim_session(folder, *, repeats: int = 2, presses: int | None = None, fps: float = 10.0,
                       seed: int = 0, shadow: bool = True, contact_scale: float = 0.0,
                       theta_deg: float = 5.0, offset_mm: float = 7.5,
                       direction_deg: float = 0.0, length_mm: float = 3.0,
                       overshoot_mm: tuple[float, float] = (0.0, 0.050),
                       hold_s: tuple[float, float] = (HOLD_S, HOLD_S),
                       mark_flank_deg: float = 0.0, approach_mm_s: float | None = None,
                       clock_offset_s: float = CLOCK_OFFSET_S,
                       force_rate_hz: float = FORCE_RATE_HZ,
                       c_n_per_mm: float = C_N_PER_MM, beta: float = BETA,
                       progress: bool = False, command: str | None = None,
                       timing: dict | None = None) -> dict:
    """Render a gauge-block session with Taxim into ``folder``; return its truth (truth.json).

    Parameters
    ----------
    folder : path
        Session folder to write (created; existing files of the same names are replaced).
    repeats, presses : int
        Presses per indenter, or the total number of presses (overrides ``repeats``).
    fps : float
        Camera rate; frames are kept from 0.2 s before each press to its release end.
    seed : int
        Layout, timing, forces and noise; the same seed gives the same session.
    shadow : bool
        Taxim's ``with_shadow`` (True: the setting the bevel needs).
    contact_scale : float
        Taxim's ``contact_scale`` (0: every contact pixel kept; Taxim's default is 0.4).
    theta_deg, offset_mm, direction_deg, length_mm : float
        Bevel flank angle, crest offset from the indenter axis, its direction in the
        image (0 = +x, 90 = +y) and the crest length.
    overshoot_mm : (lo, hi)
        Range of the uniform overshoot delta past w0.
    hold_s : (lo, hi)
        Range of the uniform hold length, s (default: every hold 0.5 s).
    mark_flank_deg : float
        With ``theta_deg = 0`` (a drawn mark, ``bevel_angle_deg = 0`` in session.toml):
        the flank angle of the mark's small V ridge (:data:`MARK_RIDGE_HALF_MM`), deg; 0:
        the flat line :data:`MARK_WIDTH_MM` wide.
    approach_mm_s : float or None
        The stage's approach speed, mm/s (None: every approach lasts :data:`APPROACH_S`).
    clock_offset_s : float
        t_force - t_frame, s (never written to session.toml).
    force_rate_hz : float
        The F/T log's rate, Hz (the force window is 0.2 s of its samples).
    c_n_per_mm, beta : float
        The force law's c and beta (eq. 5).
    progress : bool
        tqdm progress bar over the frames.
    command : str or None
        Regenerate command quoted in README.md (one is composed when None).
    timing : dict or None
        Filled with frames, renders, render_s (Taxim time) and first_render_s (with jit).

    Returns
    -------
    dict
        The content of truth.json.
    """
    folder = Path(folder)
    (folder / "frames").mkdir(parents=True, exist_ok=True)
    for old in (folder / "frames").glob("*.jpg"):
        old.unlink()
    # independent streams: order/timing/overshoot, positions, camera noise, force noise
    rng_layout = np.random.default_rng([seed, 0])
    rng_pos = np.random.default_rng([seed, 3])
    rng_cam = np.random.default_rng([seed, 1])
    rng_force = np.random.default_rng([seed, 2])
    rng_hold = np.random.default_rng([seed, 4])

    if theta_deg > 0 and mark_flank_deg:
        raise ValueError("mark_flank_deg is a drawn mark's (theta_deg = 0)")
    plist = _schedule(rng_layout, rng_pos, presses, repeats, tuple(overshoot_mm), offset_mm,
                      direction_deg, length_mm, tuple(hold_s), rng_hold, approach_mm_s,
                      (c_n_per_mm, beta))
    tan_t = math.tan(math.radians(theta_deg))
    for p in plist:
        if tan_t > 0:
            L = p["overshoot_mm"] / tan_t
        elif mark_flank_deg > 0:
            L = min(p["overshoot_mm"] / math.tan(math.radians(mark_flank_deg)),
                    MARK_RIDGE_HALF_MM)
        else:
            L = MARK_WIDTH_MM / 2
        p["bevel_half_width_mm"] = round(L, 5)
        p["bevel_half_width_px"] = round(L / MM_PER_PX, 3)
        p["taxim_narrow_band"] = bool(L / MM_PER_PX < NARROW_BAND_PX)

    # frame times: the camera clock ticks at k / fps; kept from 0.2 s before a press to its end
    frame_rows = []                     # (file, t, press index)
    eps = 1e-9
    for p in plist:
        k0 = math.ceil((p["t_start_s"] - PRE_ROLL_S) * fps - eps)
        k1 = math.floor(p["release_end_s"] * fps + eps)
        for k in range(k0, k1 + 1):
            frame_rows.append((f"{len(frame_rows):05d}.jpg", k / fps, p["press"]))

    timings = {"renders": 0, "render_s": 0.0}
    with tempfile.TemporaryDirectory(prefix="taxim_flat_") as tmp:
        calib = _flat_calib_folder(Path(tmp))
        sim = taxim.Taxim(calib_folder=calib, backend="jax",
                          params={"simulator": {"contact_scale": float(contact_scale)}})
        # no contact: an object map entirely beyond the gel, no press_depth
        t = time.perf_counter()
        ref = np.asarray(sim.render(np.full(SHAPE, 1.0, np.float32), with_shadow=shadow))
        timings["first_render_s"] = time.perf_counter() - t      # includes jit
        ref255 = ref.astype(np.float64) * 255.0
        cv2.imwrite(str(folder / "reference.png"),
                    np.clip(np.rint(ref255), 0, 255).astype(np.uint8)[..., ::-1])

        bar = None
        if progress:
            from tqdm import tqdm
            bar = tqdm(total=len(frame_rows), unit="frame", desc="taxim")
        hmaps = {}
        last = (None, None, None)       # (press, depth, image): a hold's frames share a render
        for name, tf, pi in frame_rows:
            p = plist[pi]
            w = float(_depth(tf, p))
            if w <= 0.0:
                img = ref255
            elif last[0] == pi and last[1] == w:
                img = last[2]
            else:
                if pi not in hmaps:
                    hmaps.clear()
                    hmaps[pi] = gauge_height_map(p["x_mm"], p["y_mm"], p["w0_mm"],
                                                 offset_mm=offset_mm, direction_deg=direction_deg,
                                                 theta_deg=theta_deg, length_mm=length_mm,
                                                 mark_flank_deg=mark_flank_deg)
                t = time.perf_counter()
                img = np.asarray(sim.render(hmaps[pi], with_shadow=shadow, press_depth=w))
                timings["render_s"] += time.perf_counter() - t
                timings["renders"] += 1
                img = img.astype(np.float64) * 255.0
                last = (pi, w, img)
            noisy = img + rng_cam.normal(0.0, CAMERA_NOISE_GREY, img.shape)
            out = np.clip(np.rint(noisy), 0, 255).astype(np.uint8)[..., ::-1]
            cv2.imwrite(str(folder / "frames" / name), out,
                        [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])
            if bar is not None:
                bar.update(1)
        if bar is not None:
            bar.close()

    with open(folder / "frames.csv", "w") as f:
        f.write("frame,t_s\n")
        for name, tf, _ in frame_rows:
            f.write(f"{name},{tf:.6f}\n")

    # forces: force_rate_hz on the F/T clock over the whole session
    t_end = plist[-1]["release_end_s"] + 0.5
    n = round(t_end * force_rate_hz) + 1
    t_cam = np.arange(n) / force_rate_hz
    w_all = np.zeros(n)
    for p in plist:
        w_all = np.maximum(w_all, _depth(t_cam, p))
    P = force_n(w_all, c_n_per_mm, beta)
    noise = rng_force.normal(0.0, 1.0, (n, 3)) * np.array(FORCE_NOISE_N)
    table = np.column_stack([t_cam + clock_offset_s,
                             TANGENTIAL_FRACTION * P + noise[:, 0],
                             TANGENTIAL_FRACTION * P + noise[:, 1],
                             P + noise[:, 2]])
    np.savetxt(folder / "forces.csv", table, fmt="%.4f", delimiter=",",
               header="t_s,fx_n,fy_n,fz_n", comments="")

    with open(folder / "presses.csv", "w") as f:
        f.write("press,indenter,x_mm,y_mm\n")
        for p in plist:
            f.write(f"{p['press']},{p['indenter']},{p['x_mm']:.4f},{p['y_mm']:.4f}\n")

    (folder / "session.toml").write_text(_session_toml(offset_mm, direction_deg, theta_deg,
                                                       length_mm, force_rate_hz))

    truth = {
        "c_n_per_mm": c_n_per_mm, "beta": beta, "thickness_mm": GEL_THICKNESS_MM,
        "radius_mm": INDENTER_RADIUS_MM, "clock_offset_s": clock_offset_s,
        "force_rate_hz": force_rate_hz,
        "approach": (f"{APPROACH_S} s" if approach_mm_s is None
                     else f"{approach_mm_s:g} mm/s"),
        "mm_per_px": MM_PER_PX, "seed": seed, "fps": fps,
        "overshoot_range_mm": [float(overshoot_mm[0]), float(overshoot_mm[1])],
        "hold_range_s": [float(hold_s[0]), float(hold_s[1])],
        "force_law": "P(w) = c w (1 + beta w / h), eq. 5 of the in-situ calibration paper; "
                     "Fx = Fy = 0.01 P; noise sd 1/40, 1/40, 1/80 N",
        "taxim": {"renderer": "taxim.Taxim(backend='jax').render(height_map, press_depth=w)",
                  "version": _taxim_version(), "calib": "taxim/calib/gelsight",
                  "flat_gel": True, "contact_scale": float(contact_scale),
                  "with_shadow": bool(shadow), "camera_noise_grey": CAMERA_NOISE_GREY,
                  "jpeg_quality": JPEG_QUALITY, "reference": "no-contact render, noise-free"},
        "bevel": {"offset_mm": offset_mm, "direction_deg": direction_deg,
                  "angle_deg": theta_deg, "length_mm": length_mm, "relief_mm": RELIEF_MM,
                  "mark_flank_deg": mark_flank_deg,
                  "mark_ridge_half_mm": MARK_RIDGE_HALF_MM if mark_flank_deg > 0 else None,
                  "half_width": "delta / tan(angle_deg), delta = overshoot_mm",
                  "taxim_narrow_band_px": NARROW_BAND_PX,
                  "taxim_narrow_band": "presses whose band half-width is under "
                                       "taxim_narrow_band_px: Taxim paints a 10-25 px "
                                       "shadow slab beside such a band"},
        "positions": press_positions_region(offset_mm=offset_mm, direction_deg=direction_deg,
                                            length_mm=length_mm),
        "presses": plist,
    }
    with open(folder / "truth.json", "w") as f:
        json.dump(truth, f, indent=1)
        f.write("\n")

    if command is None:
        args = [f"--presses {presses}" if presses is not None else f"--repeats {repeats}",
                f"--fps {fps:g}", f"--seed {seed}"]
        args += [] if shadow else ["--no-shadow"]
        args += [f"--taxim-contact-scale {contact_scale:g}"] if contact_scale != 0 else []
        for flag, value, default in (("--theta", theta_deg, 5.0), ("--offset-mm", offset_mm, 7.5),
                                     ("--direction-deg", direction_deg, 0.0),
                                     ("--length-mm", length_mm, 3.0)):
            args += [f"{flag} {value:g}"] if value != default else []
        if tuple(overshoot_mm) != (0.0, 0.050):
            args.append(f"--overshoot-mm {overshoot_mm[0]:g} {overshoot_mm[1]:g}")
        if tuple(hold_s) != (HOLD_S, HOLD_S):
            args.append(f"--hold-s {hold_s[0]:g} {hold_s[1]:g}")
        for flag, value, default in (("--mark-flank-deg", mark_flank_deg, 0.0),
                                     ("--approach-mm-s", approach_mm_s, None),
                                     ("--clock-offset-s", clock_offset_s, CLOCK_OFFSET_S),
                                     ("--force-rate-hz", force_rate_hz, FORCE_RATE_HZ),
                                     ("--c-n-per-mm", c_n_per_mm, C_N_PER_MM),
                                     ("--beta", beta, BETA)):
            args += [f"{flag} {value:g}"] if value != default else []
        command = f"python benchmarks/taxim_gauge_session.py {folder.as_posix()} " + " ".join(args)
    (folder / "README.md").write_text(_session_readme(truth, command))
    (folder / "LICENSE").write_text(
        "The frames and reference.png of this folder were rendered by Taxim (PyPI taxim "
        f"{_taxim_version()},\nhttps://github.com/TimSchneider42/taxim; original: Taxim, "
        "CMURoboTouch / Si and Yuan,\nRA-L 2022) with its GelSight calibration data. "
        "Their licence:\n\n" + _license_text())

    if timing is not None:
        timing.update(frames=len(frame_rows), **timings)
    return truth


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out_dir", type=Path)
    g = ap.add_mutually_exclusive_group()
    g.add_argument("--presses", type=int, default=None, help="total presses")
    g.add_argument("--repeats", type=int, default=2, help="presses per indenter (default 2)")
    ap.add_argument("--fps", type=float, default=10.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--no-shadow", action="store_true", help="Taxim with_shadow=False")
    ap.add_argument("--taxim-contact-scale", type=float, default=0.0,
                    help="Taxim's contact_scale (default 0; Taxim's own default is 0.4)")
    ap.add_argument("--theta", type=float, default=5.0,
                    help="bevel flank angle, deg (0: a mark, a line on the land, no vernier)")
    ap.add_argument("--offset-mm", type=float, default=7.5, help="axis to crest, mm")
    ap.add_argument("--direction-deg", type=float, default=0.0,
                    help="direction to the bevel: 0 = +x, 90 = +y")
    ap.add_argument("--length-mm", type=float, default=3.0, help="crest length, mm")
    ap.add_argument("--overshoot-mm", type=float, nargs=2, default=(0.0, 0.050),
                    metavar=("LO", "HI"))
    ap.add_argument("--hold-s", type=float, nargs=2, default=(HOLD_S, HOLD_S),
                    metavar=("LO", "HI"), help=f"hold lengths, uniform (default {HOLD_S} s)")
    ap.add_argument("--mark-flank-deg", type=float, default=0.0,
                    help="with --theta 0: the drawn mark's V ridge flank, deg (0: a flat line)")
    ap.add_argument("--approach-mm-s", type=float, default=None,
                    help=f"the stage's approach speed, mm/s (default: {APPROACH_S} s approaches)")
    ap.add_argument("--clock-offset-s", type=float, default=CLOCK_OFFSET_S,
                    help="t_force - t_frame, s (not in session.toml)")
    ap.add_argument("--force-rate-hz", type=float, default=FORCE_RATE_HZ)
    ap.add_argument("--c-n-per-mm", type=float, default=C_N_PER_MM, help="eq. 5's c")
    ap.add_argument("--beta", type=float, default=BETA, help="eq. 5's beta")
    ap.add_argument("--progress", action="store_true")
    a = ap.parse_args(argv)
    if (a.presses is not None and a.presses < 1) or a.repeats < 1:
        ap.error("--presses and --repeats must be positive")
    if a.fps <= 0 or not 0 <= a.theta < 90 or a.length_mm <= 0 or a.offset_mm < 0:
        ap.error("need fps > 0, 0 <= theta < 90 (0: a mark, no vernier), length > 0, "
                 "offset >= 0")
    if not 0 <= a.overshoot_mm[0] <= a.overshoot_mm[1]:
        ap.error("--overshoot-mm needs 0 <= LO <= HI")
    if not 0 < a.hold_s[0] <= a.hold_s[1]:
        ap.error("--hold-s needs 0 < LO <= HI")
    if a.mark_flank_deg and (a.theta != 0 or not 0 < a.mark_flank_deg < 45):
        ap.error("--mark-flank-deg needs --theta 0 and 0 < DEG < 45")
    if (a.approach_mm_s is not None and a.approach_mm_s <= 0) or a.force_rate_hz <= 0 \
            or a.c_n_per_mm <= 0:
        ap.error("--approach-mm-s, --force-rate-hz and --c-n-per-mm must be positive")
    t = time.perf_counter()
    tm: dict = {}
    truth = make_taxim_session(a.out_dir, repeats=a.repeats, presses=a.presses, fps=a.fps,
                               seed=a.seed, shadow=not a.no_shadow,
                               contact_scale=a.taxim_contact_scale, theta_deg=a.theta,
                               offset_mm=a.offset_mm, direction_deg=a.direction_deg,
                               length_mm=a.length_mm, overshoot_mm=tuple(a.overshoot_mm),
                               hold_s=tuple(a.hold_s), mark_flank_deg=a.mark_flank_deg,
                               approach_mm_s=a.approach_mm_s, clock_offset_s=a.clock_offset_s,
                               force_rate_hz=a.force_rate_hz, c_n_per_mm=a.c_n_per_mm,
                               beta=a.beta, progress=a.progress, timing=tm)
    per = tm["render_s"] / max(tm["renders"], 1)
    print(f"{a.out_dir}: {len(truth['presses'])} presses, {tm['frames']} frames, "
          f"{tm['renders']} Taxim renders, {per:.2f} s per render (first, with jit: "
          f"{tm['first_render_s']:.1f} s), {time.perf_counter() - t:.0f} s in all")


if __name__ == "__main__":
    main()
