"""Before the first press: what a calibration session's design will measure.

A design is a ``session.toml`` (formats.md §1: gel thickness h, indenter radius a, the
gauge block's depths and bevel, the F/T window) plus a ``[plan]`` table of what a session
does not hold yet: the expected E and nu, the repeats per depth, the camera's frame rate
and the stage's speed at the bevel (for a mark), the F/T noise and zero stability, and
the hold length. :func:`plan_session` predicts, without drawing a single session:

- each press's depth uncertainty, random and shared, from the bevel (a vernier's band
  half-width read to :data:`VERNIER_EDGE_PX` once it reaches :data:`RESOLVED_PX`, only
  bounded before) or the mark (one frame's travel);
- the standard deviations of E and nu that :func:`fit_indentation` will give over
  repeated sessions of this design: every press's force and depth noise propagated
  through the fit itself to eq. (5)'s line (its derivatives taken on the design's
  noise-free table, the finite-strain FEM's forces), then E and nu integrated over that
  line's spread by Gauss-Hermite quadrature; and the biases that the shared errors
  leave;
- whether nu is identified at all (a/h where the beta table cannot tell nu, or a
  sigma of nu as wide as the physical range).

``benchmarks/bench_plan.py`` checks the predicted sigmas against the scatter of the
fit over generated sessions of each design in a grid.
"""

from __future__ import annotations

import csv
import json
import math
import tomllib
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats

from .._checks import InputError
from ._catalogue import EFFECTS, make_effect
from ._diagnose import _usable, _why
from ._fem_tables import kappa_n
from ._fit import MAX_W_OVER_H, fit_indentation
from ._relaxation import (
    RELAX_ALPHA,
    TAU_HOLD_RATIO,
    TAU_MIN_HOLD_FRACTION,
    _blocks,
    _straight_decay,
    ramp_factor,
)

__all__ = [
    "VERNIER_EDGE_PX",
    "Design",
    "PlanPrediction",
    "design_from_calibration",
    "design_toml",
    "plan",
    "plan_session",
    "planned_columns",
    "read_design",
    "untestable_effects",
    "untestable_in_table",
]

#: The sd of a vernier band's half-width read, px: the sample session's certified depths
#: (``measurements.csv`` of ``tactilevision calibrate sample_frames/gelsight_session``,
#: 48 presses, scored against the session's ``truth.json``; 2026-11-25) lie -0.47 um off
#: on average with an sd of 1.8 um at a 5 deg bevel and 0.0295 mm/px:
#: 1.8e-3 / (tan 5 deg x 0.0295) = 0.70 px. One session's figure, on frames this
#: project drew.
VERNIER_EDGE_PX = 0.70

#: The band half-width, px, below which a vernier's band is only bounded, not read: the
#: contact package's ``RESOLVED_PX`` (mechanics does not import contact; a test keeps the
#: two equal).
RESOLVED_PX = 10.0

#: nu's physical range as this project's beta tables hold it: a sigma of nu beyond a
#: quarter of it leaves nu "not identified".
NU_RANGE = (0.30, 0.50)


@dataclass(frozen=True)
class Design:
    """A calibration session's design (formats.md §1 ``session.toml`` plus ``[plan]``).

    Attributes
    ----------
    thickness_mm, radius_mm : float
        Gel thickness h and indenter radius a, mm.
    depths_mm : tuple of float
        The gauge block's depths w0, mm.
    repeats : int
        Presses per depth.
    E_mpa, nu : float
        The expected Young's modulus (MPa) and Poisson's ratio.
    bevel_angle_deg : float
        Flank angle of the bevel ridge, deg; 0 for a mark.
    mm_per_px : float
        Image scale, mm per px (the vernier's resolution).
    frame_rate_hz, stage_speed_mm_s : float
        Camera rate and the stage's speed as it passes w0 (a mark's depth error is one
        frame's travel).
    force_noise_n : float
        sd of one F/T sample, N.
    window_samples : int
        F/T samples averaged per press.
    force_zero_n : float
        Zero stability of the F/T sensor: a force offset every press may share, N (a
        bound).
    hold_s : float or None
        Hold length per press, s (checked against the window).
    rate_hz : float
        F/T sample rate, Hz.
    depth_std_um : float or None
        Overrides the bevel's or the mark's random depth sd, um.
    beta_table : {'fem', 'paper'}
    overshoot_um : (float, float)
        How far past w0 the stage stops, um, uniform over this range (the vernier reads
        a band only past :data:`RESOLVED_PX` of half-width).
    holds_s : tuple of float or None
        The hold lengths the presses cycle through, s (None: ``hold_s`` for every press).
    window_at : {'start', 'end'}
        Where the F/T window sits in the hold (formats.md §1 ``[force_sensor]``).
    waits_s : tuple of float
        The rests between presses the session cycles through, s.
    days : int
        Calendar days (sessions) the presses are spread over.
    positions : int
        Distinct press positions on the pad.
    relaxation_g, relaxation_tau_s : float or None
        A relaxation to plan for (g in (0, 1), tau in s; both or neither):
        whether ``fit_relaxation`` identifies it from the planned holds
        (:func:`relaxation_identifiability`).
    """

    thickness_mm: float
    radius_mm: float
    depths_mm: tuple[float, ...]
    repeats: int = 10
    E_mpa: float = 0.2
    nu: float = 0.45
    bevel_angle_deg: float = 0.0
    mm_per_px: float = 0.0295
    frame_rate_hz: float = 30.0
    stage_speed_mm_s: float = 0.1
    force_noise_n: float = 0.0125
    window_samples: int = 200
    force_zero_n: float = 0.0
    hold_s: float | None = None
    rate_hz: float = 1000.0
    depth_std_um: float | None = None
    beta_table: str = "fem"
    overshoot_um: tuple[float, float] = (0.0, 50.0)
    holds_s: tuple[float, ...] | None = None
    window_at: str = "start"
    waits_s: tuple[float, ...] = (2.0,)
    days: int = 1
    positions: int = 10
    relaxation_g: float | None = None
    relaxation_tau_s: float | None = None

    def __post_init__(self) -> None:
        check_design(self)

    @property
    def a_over_h(self) -> float:
        """a/h."""
        return self.radius_mm / self.thickness_mm


def _positive(value: Any, key: str, *, allow_zero: bool = False) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{key} must be a number, got {value!r}") from None
    if not math.isfinite(v) or v < 0 or (v == 0 and not allow_zero):
        raise InputError(f"{key} must be {'non-negative' if allow_zero else 'positive'}, "
                         f"got {value!r}")
    return v


def check_design(d: Design) -> None:
    """Refuse a design that cannot be run, naming the key at fault (one sentence).

    Raises
    ------
    InputError
        A non-positive h or a, no depth or a depth beyond the gel (w0 >= h) or past
        the FEM beta table's reach (w/h > 0.23), fewer than two distinct depths, a bevel
        angle of 45 degrees or more, a window longer than the hold, a repeat count
        below 1, or a nu outside (0, 0.5].
    """
    h = _positive(d.thickness_mm, "[sensor] gel_thickness_mm")
    _positive(d.radius_mm, "[indenter] radius_mm")
    if len(d.depths_mm) == 0:
        raise InputError("[gauge_block] depths_mm lists no depth")
    for w in d.depths_mm:
        w = _positive(w, "[gauge_block] depths_mm")
        if w >= h:
            raise InputError(f"[gauge_block] depths_mm: {w:g} mm is beyond the gel "
                             f"({h:g} mm thick)")
        if w / h > 0.23:
            raise InputError(f"[gauge_block] depths_mm: {w:g} mm is w/h = {w / h:.3f}, past "
                             f"the FEM beta table's reach (0.23; the linear law (2) fails "
                             f"beyond {MAX_W_OVER_H:g})")
    if len(set(d.depths_mm)) < 2:
        raise InputError("[gauge_block] depths_mm needs at least two distinct depths to "
                         "fit eq. (5)")
    angle = _positive(d.bevel_angle_deg, "[gauge_block] bevel_angle_deg", allow_zero=True)
    if angle >= 45:
        raise InputError(f"[gauge_block] bevel_angle_deg {angle:g} is 45 degrees or more: "
                         "the flank would press the gel as the indenter does")
    if int(d.repeats) != d.repeats or d.repeats < 1:
        raise InputError(f"[plan] repeats must be a positive integer, got {d.repeats!r}")
    if int(d.window_samples) != d.window_samples or d.window_samples < 1:
        raise InputError("[force_sensor] window_samples must be a positive integer, got "
                         f"{d.window_samples!r}")
    rate = _positive(d.rate_hz, "[force_sensor] rate_hz")
    if d.hold_s is not None:
        hold = _positive(d.hold_s, "[plan] hold_s")
        if d.window_samples / rate > hold:
            raise InputError(f"[force_sensor] window_samples {d.window_samples} at "
                             f"{rate:g} Hz is {d.window_samples / rate:g} s, longer than "
                             f"the hold ([plan] hold_s = {hold:g} s)")
    _positive(d.E_mpa, "[plan] E_mpa")
    nu = float(d.nu)
    if not 0 < nu <= 0.5:
        raise InputError(f"[plan] nu must lie in (0, 0.5], got {d.nu!r}")
    _positive(d.mm_per_px, "[sensor] mm_per_px")
    _positive(d.frame_rate_hz, "[plan] frame_rate_hz")
    _positive(d.stage_speed_mm_s, "[plan] stage_speed_mm_s")
    _positive(d.force_noise_n, "[plan] force_noise_n", allow_zero=True)
    _positive(d.force_zero_n, "[plan] force_zero_n", allow_zero=True)
    if d.depth_std_um is not None:
        _positive(d.depth_std_um, "[plan] depth_std_um", allow_zero=True)
    try:
        lo_o, hi_o = (float(v) for v in d.overshoot_um)
    except (TypeError, ValueError):
        raise InputError(f"[plan] overshoot_um must be two numbers [low, high], um, got "
                         f"{d.overshoot_um!r}") from None
    if not (math.isfinite(lo_o) and math.isfinite(hi_o) and 0 <= lo_o <= hi_o):
        raise InputError(f"[plan] overshoot_um must be [low, high] with 0 <= low <= high, got "
                         f"{d.overshoot_um!r}")
    if d.window_at not in ("start", "end"):
        raise InputError(f"[force_sensor] window_at must be 'start' or 'end', got "
                         f"{d.window_at!r}")
    for key in ("days", "positions"):
        v = getattr(d, key)
        if isinstance(v, bool) or not isinstance(v, int | float) or int(v) != v or v < 1:
            raise InputError(f"[plan] {key} must be a positive integer, got {v!r}")
    for key in ("holds_s", "waits_s"):
        v = getattr(d, key)
        if v is None:
            continue
        if not isinstance(v, tuple | list) or not v:
            raise InputError(f"[plan] {key} must be a list of seconds, got {v!r}")
        for x in v:
            _positive(x, f"[plan] {key}", allow_zero=key == "waits_s")
        if key == "holds_s" and min(v) < d.window_samples / d.rate_hz:
            raise InputError(f"[plan] holds_s: a hold of {min(v):g} s is shorter than the "
                             f"window ({d.window_samples / d.rate_hz:g} s)")
    if d.beta_table not in ("fem", "paper"):
        raise InputError(f"[plan] beta_table must be 'fem' or 'paper', got {d.beta_table!r}")
    if (d.relaxation_g is None) != (d.relaxation_tau_s is None):
        raise InputError("[plan] relaxation_g and relaxation_tau_s go together: give both "
                         "or neither")
    if d.relaxation_g is not None:
        if not 0 < float(d.relaxation_g) < 1:
            raise InputError(f"[plan] relaxation_g must be in (0, 1), got {d.relaxation_g!r}")
        _positive(d.relaxation_tau_s, "[plan] relaxation_tau_s")


def read_design(path: str | Path) -> Design:
    """Read a design file: a ``session.toml`` with a ``[plan]`` table.

    Parameters
    ----------
    path : str or Path
        The TOML file. Keys: ``[sensor] gel_thickness_mm, mm_per_px``, ``[indenter]
        radius_mm``, ``[gauge_block] depths_mm, bevel_angle_deg``, ``[force_sensor]
        rate_hz, window_samples``, ``[plan] repeats, E_mpa, nu, frame_rate_hz,
        stage_speed_mm_s, force_noise_n, force_zero_n, hold_s, depth_std_um,
        beta_table`` (every ``[plan]`` key optional; :class:`Design` gives the
        defaults).

    Returns
    -------
    design : Design

    Raises
    ------
    InputError
        A missing or unreadable file, TOML that does not parse, a missing required
        key, an unknown ``[plan]`` key, or a bad value (:func:`check_design`), each
        naming the file and the key.
    """
    path = Path(path)
    try:
        doc = tomllib.loads(path.read_text())
    except FileNotFoundError:
        raise InputError(f"design file {path} does not exist") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"design file {path} cannot be read: {exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"design file {path} is not valid TOML: {exc}") from None

    def need(table: str, key: str) -> Any:
        try:
            return doc[table][key]
        except (KeyError, TypeError):
            raise InputError(f"{path}: [{table}] {key} is missing") from None

    for table in ("sensor", "indenter", "gauge_block", "force_sensor", "plan"):
        if not isinstance(doc.get(table, {}), dict):
            raise InputError(f"{path}: [{table}] must be a table")
    plan = doc.get("plan", {})
    known = {"repeats", "E_mpa", "nu", "frame_rate_hz", "stage_speed_mm_s", "force_noise_n",
             "force_zero_n", "hold_s", "depth_std_um", "beta_table", "overshoot_um",
             "holds_s", "waits_s", "days", "positions", "relaxation_g", "relaxation_tau_s"}
    unknown = sorted(set(plan) - known)
    if unknown:
        raise InputError(f"{path}: [plan] {unknown[0]} is not a design key (known: "
                         f"{', '.join(sorted(known))})")
    depths = need("gauge_block", "depths_mm")
    if not isinstance(depths, list):
        raise InputError(f"{path}: [gauge_block] depths_mm must be a list of depths, mm")
    gauge = doc.get("gauge_block", {})
    sensor = doc.get("sensor", {})
    force = doc.get("force_sensor", {})
    kw: dict[str, Any] = dict(plan)
    for key in ("overshoot_um", "holds_s", "waits_s"):
        if key in kw and isinstance(kw[key], list):
            kw[key] = tuple(kw[key])
    if isinstance(force.get("window_at"), str):
        kw["window_at"] = force["window_at"]
    try:
        return Design(thickness_mm=need("sensor", "gel_thickness_mm"),
                      radius_mm=need("indenter", "radius_mm"),
                      depths_mm=tuple(depths),
                      bevel_angle_deg=gauge.get("bevel_angle_deg", 0.0),
                      mm_per_px=sensor.get("mm_per_px", Design.mm_per_px),
                      rate_hz=force.get("rate_hz", Design.rate_hz),
                      window_samples=force.get("window_samples", Design.window_samples),
                      **kw)
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None


@dataclass
class PlanPrediction:
    """What a design will measure (:func:`plan_session`).

    Attributes
    ----------
    design : Design
    n_presses : int
    depth_std_um : float
        Random sd of each press's certified depth, um.
    depth_shared_um : float
        Bound of a depth error every press shares, um (a mark's lag: up to one frame's
        travel; 0 for a vernier).
    depth_source : str
        How the depth sd was predicted.
    force_std_n : float
        Random sd of each press's force (window mean), N.
    E_sigma_mpa, nu_sigma : float
        Predicted sd of E and nu over repeated sessions of the design (random parts).
    E_sigma_pct : float
        ``E_sigma_mpa`` as a percentage of E.
    E_nu_corr : float
        Correlation of E's and nu's errors.
    bias : dict of str to (float, float)
        (E error in %, nu error): ``'model'``, the fit of the noise-free table (the
        fit's own error on the FEM's forces); ``'noise'``, the mean over sessions
        less the truth (the noise through the fit's curvature); and each shared
        error at its bound, either way: ``'depth_shared'`` and
        ``'depth_shared_minus'`` (every depth off by the shared bound),
        ``'force_zero'`` and ``'force_zero_minus'`` (every force off by the zero
        bound). NaN where the fit finds no E or nu.
    nu_identified : bool
        False when the beta table cannot tell nu at this a/h, or sigma(nu) exceeds a
        quarter of nu's range (0.3 to 0.5).
    notes : list of str
        Why, in words.
    relaxation : RelaxationPlan or None
        With ``relaxation_g`` and ``relaxation_tau_s`` in the design: whether
        ``fit_relaxation`` identifies them (:func:`relaxation_identifiability`).
    untestable : dict of str to str
        The catalogue's effects (formats.md §5) that ``diagnose`` cannot test on a
        session of this design, and why (the column each needs is constant or missing
        in the design's table: :func:`planned_columns`).
    """

    design: Design
    n_presses: int
    depth_std_um: float
    depth_shared_um: float
    depth_source: str
    force_std_n: float
    E_sigma_mpa: float
    nu_sigma: float
    E_sigma_pct: float
    E_nu_corr: float
    bias: dict[str, tuple[float, float]]
    nu_identified: bool
    notes: list[str] = field(default_factory=list)
    untestable: dict[str, str] = field(default_factory=dict)
    relaxation: RelaxationPlan | None = None

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready dict (the ``plan --json`` output; NaN written as None)."""
        d = self.design
        return _no_nan({
            "design": {k: (list(v) if isinstance(v, tuple) else v)
                       for k, v in d.__dict__.items()} | {"a_over_h": d.a_over_h},
            "n_presses": self.n_presses,
            "depth_std_um": self.depth_std_um, "depth_shared_um": self.depth_shared_um,
            "depth_source": self.depth_source, "force_std_n": self.force_std_n,
            "E_sigma_mpa": self.E_sigma_mpa, "E_sigma_pct": self.E_sigma_pct,
            "nu_sigma": self.nu_sigma, "E_nu_corr": self.E_nu_corr,
            "bias": {k: {"E_pct": v[0], "nu": v[1]} for k, v in self.bias.items()},
            "nu_identified": self.nu_identified, "notes": list(self.notes),
            "untestable": dict(self.untestable),
            "relaxation": None if self.relaxation is None else dict(self.relaxation.__dict__),
        })


def _no_nan(obj: Any) -> Any:
    """`obj` with every non-finite float replaced by None (JSON has no NaN)."""
    if isinstance(obj, dict):
        return {k: _no_nan(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_no_nan(v) for v in obj]
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def depth_uncertainty(d: Design) -> tuple[float, float, str]:
    """Random sd and shared bound of a press's certified depth, um, and how.

    A vernier (``bevel_angle_deg > 0``) reads the band's half-width L, w = w0 + L
    tan(theta) (formats.md §1), to ``VERNIER_EDGE_PX`` px: ``sd_read = VERNIER_EDGE_PX
    x mm_per_px x tan(theta)``. A band is read only once L reaches ``RESOLVED_PX``
    (10 px), an overshoot of ``o_r = RESOLVED_PX x mm_per_px x tan(theta)``; below it the
    depth is only bounded to [w0, w0 + o_r] (sd ``o_r / sqrt 12``, the uniform bound's).
    With the overshoot uniform over ``overshoot_um``, a share f of presses is read and
    the sd per press is ``sqrt(f sd_read^2 + (1 - f) o_r^2 / 12)``. A mark is seen at the
    first frame past it: the depth past w0 is off by up to one frame's travel ``v / f``,
    uniformly (sd ``v / (f sqrt 12)``), and the clock that dates the crossing can share
    up to that much in every press (the bound given as ``depth_shared_um``).
    ``depth_std_um`` overrides the random part.
    """
    if d.bevel_angle_deg > 0:
        t = math.tan(math.radians(d.bevel_angle_deg)) * d.mm_per_px * 1e3   # um per px
        read_sd, o_r = VERNIER_EDGE_PX * t, RESOLVED_PX * t
        lo, hi = (float(v) for v in d.overshoot_um)
        f = 1.0 if o_r <= lo else (0.0 if o_r >= hi else (hi - o_r) / (hi - lo))
        sd = math.sqrt(f * read_sd**2 + (1 - f) * o_r**2 / 12)
        shared, how = 0.0, (f"vernier at {d.bevel_angle_deg:g} deg: {100 * f:.0f} % of presses "
                            f"read ({VERNIER_EDGE_PX:g} px x {d.mm_per_px:g} mm/px x "
                            f"tan(theta) = {read_sd:.2f} um), the rest bounded to "
                            f"{o_r:.1f} um past w0")
    else:
        travel = d.stage_speed_mm_s / d.frame_rate_hz * 1e3
        sd, shared = travel / math.sqrt(12.0), travel
        how = (f"mark: one frame's travel {travel:.1f} um ({d.stage_speed_mm_s:g} mm/s at "
               f"{d.frame_rate_hz:g} frames/s) / sqrt(12), shared up to one frame's travel")
    if d.depth_std_um is not None:
        sd, how = float(d.depth_std_um), "given ([plan] depth_std_um)"
    return sd, shared, how


def design_table(d: Design) -> tuple[np.ndarray, np.ndarray]:
    """The design's noise-free presses: depths w (mm) and the finite-strain FEM's forces
    P = 2 a E w kappa_n(nu, a/h, w/h) / (1 - nu^2) (N), ``repeats`` per depth."""
    w = np.repeat(np.asarray(d.depths_mm, np.float64), int(d.repeats))
    kn = {x: kappa_n(d.nu, d.a_over_h, x / d.thickness_mm) for x in set(d.depths_mm)}
    k = np.array([kn[x] for x in w])
    return w, 2 * d.radius_mm * d.E_mpa * w * k / (1 - d.nu**2)


def _fit(d: Design, w: np.ndarray, P: np.ndarray, u_mm: np.ndarray | None) -> np.ndarray:
    """(E, nu, c, c beta) of :func:`fit_indentation` on the presses (w, P)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        f = fit_indentation(w, P, thickness_mm=d.thickness_mm, radius_mm=d.radius_mm,
                            beta_table=d.beta_table, depth_std_mm=u_mm)
    return np.array([f.E_mpa, f.nu, f.c_n_per_mm, f.c_n_per_mm * f.beta])


#: Gauss-Hermite nodes per axis of the (c, c beta) quadrature.
QUADRATURE_NODES = 9


def hold_lengths(d: Design, n: int) -> np.ndarray:
    """(n,) hold length of each press in turn, s: ``holds_s`` cycled, else ``hold_s``,
    else 1 s."""
    holds = np.asarray(d.holds_s if d.holds_s is not None else
                       (d.hold_s if d.hold_s is not None else 1.0,), np.float64)
    return holds[np.arange(n) % holds.size]


def planned_columns(d: Design) -> dict[str, np.ndarray]:
    """The measurements table a session of the design will write, but its forces (formats.md
    §2 columns): each depth's ``repeats`` presses in turn, the holds (``hold_s``: half
    the window with ``window_at = 'start'``, the hold less half the window with
    ``'end'``), the rests, the press times, the days and the positions on the pad; the
    tangential forces ``fx_n``, ``fy_n`` only as varying columns (an F/T sensor always
    records them).

    Returns
    -------
    columns : dict of str to (N,) float ndarray
    """
    w = np.repeat(np.asarray(d.depths_mm, np.float64), int(d.repeats))
    n = w.size
    i = np.arange(n)
    hold = hold_lengths(d, n)
    half = 0.5 * d.window_samples / d.rate_hz
    waits = np.asarray(d.waits_s, np.float64)[i % len(d.waits_s)]
    k = np.arange(d.positions)
    ang = 2.39996 * k                   # a golden-angle spiral over a 5 mm disc
    px, py = 5.0 * np.sqrt((k + 0.5) / d.positions) * np.cos(ang), 5.0 * np.sqrt(
        (k + 0.5) / d.positions) * np.sin(ang)
    return {
        "press": i.astype(np.float64), "depth_mm": w,
        "hold_s": np.full(n, half) if d.window_at == "start" else hold - half,
        "wait_s": waits, "time_s": np.cumsum(waits + hold),
        "day": np.floor(i * d.days / n), "x_mm": px[i % d.positions],
        "y_mm": py[i % d.positions], "fx_n": np.cos(i), "fy_n": np.sin(i),
    }


def untestable_effects(d: Design) -> dict[str, str]:
    """The catalogue's effects ``diagnose`` could not test on a session of the design,
    and why (its column constant or missing in :func:`planned_columns`; the same test
    ``diagnose`` makes of a table)."""
    return untestable_in_table(planned_columns(d), window_at=d.window_at)


def untestable_in_table(columns: dict[str, np.ndarray], *, window_at: str | None = None
                        ) -> dict[str, str]:
    """The catalogue's effects ``diagnose`` cannot test on a measurements table, and why.

    Parameters
    ----------
    columns : dict of str to (N,) ndarray
        Columns of a measurements table (formats.md section 2), as ``calibrate``
        writes them or :func:`planned_columns` plans them.
    window_at : {'start', 'end'}, optional
        Where the force window sat in each hold (``[force_sensor] window_at``);
        'start' adds how to make relaxation testable.

    Returns
    -------
    why : dict of str to str
        Effect name to one sentence: the column it needs, constant or missing (the
        test ``diagnose`` makes before it tries an effect), and the change that would
        let a session test it.
    """
    out = {}
    for name in EFFECTS:
        if name == "large_deformation":
            continue
        if _usable(name, columns) is not None:
            why = _why(make_effect(name).columns, columns)
            if name == "viscoelastic_relaxation" and window_at == "start":
                why += ("; with the window at the hold's start every press's window sits "
                        "at the same time of its hold: vary it with window_at = 'end' and "
                        "holds of different lengths")
            elif name == "aging":
                why += "; spread the presses over several days"
            elif name == "spatial_nonuniformity":
                why += "; press at several positions of the pad"
            out[name] = why
    return out


@dataclass(frozen=True)
class RelaxationPlan:
    """Whether ``fit_relaxation`` can identify g and tau from a design's holds.

    Attributes
    ----------
    g, tau_s : float
        The relaxation assumed (fraction, s).
    power : float
        Probability that the holds' curvature test rejects a straight decay at
        ``RELAX_ALPHA`` (noncentral F, 1 and n - P - 2 degrees of freedom), 0
        when tau lies outside the span the holds resolve.
    span_ok : bool
        tau within ``TAU_MIN_HOLD_FRACTION`` of the shortest hold to
        ``TAU_HOLD_RATIO`` times the longest.
    noncentrality : float
        ``RSS_line / sigma_b^2``: the straight decay's misfit to the noise-free
        holds over the block means' noise variance.
    why : str
        One sentence.
    """

    g: float
    tau_s: float
    power: float
    span_ok: bool
    noncentrality: float
    why: str


def relaxation_identifiability(d: Design, g: float, tau_s: float, *,
                               points_per_press: int = 100) -> RelaxationPlan:
    """Can :func:`~tactilevision.mechanics.fit_relaxation` identify g and tau from the
    design's holds?

    Parameters
    ----------
    d : Design
    g : float
        Relaxing fraction of the gel's force, in (0, 1).
    tau_s : float
        Relaxation time, s, > 0.
    points_per_press : int, default 100
        As in ``fit_relaxation``: each hold is averaged in this many blocks.

    Returns
    -------
    RelaxationPlan

    Raises
    ------
    InputError
        For g outside (0, 1) or tau_s not positive.

    Notes
    -----
    ``fit_relaxation`` calls g and tau identified when a straight decay
    ``F_i = A_i (1 + r t)`` (tau -> infinity at fixed g / tau) is rejected
    against the fitted standard linear solid by an F test at ``RELAX_ALPHA``
    and tau lies in the span the holds resolve. The holds are planned without
    noise: each press's force ``F_i(t) = P_i [(1 - g) + g phi(T_i / tau)
    exp(-t / tau)]`` (P_i the FEM force at its depth, T_i its loading time
    ``w / stage_speed_mm_s``, phi :func:`ramp_factor`), sampled at ``rate_hz``
    over its hold and averaged in blocks as the fit does; ``force_noise_n`` per
    sample, white, gives the block means' variance sigma_b^2. The straight
    decay's least-squares misfit ``RSS_line`` to these noise-free holds over
    sigma_b^2 is the noncentrality of the test (the fitted model's own misfit is
    zero there), and the power is the noncentral F's tail beyond the test's
    critical value. The F/T noise of a real sensor is coloured: with fewer
    independent samples than assumed the power is lower.
    """
    if not 0 < g < 1:
        raise InputError(f"relaxation g must be in (0, 1), got {g!r}")
    tau = _positive(tau_s, "relaxation tau_s")
    w, P = design_table(d)
    hold = hold_lengths(d, w.size)
    ramp = w / d.stage_speed_mm_s
    curves, var_b = [], []
    for Pi, Ti, Hi in zip(P, ramp, hold, strict=True):
        n = max(round(Hi * d.rate_hz), 5)
        t = np.arange(n) / d.rate_hz
        f = Pi * ((1 - g) + g * float(ramp_factor(Ti, tau)) * np.exp(-t / tau))
        tb, fb = _blocks(t, f, points_per_press)          # as fit_relaxation averages
        curves.append((tb, fb, float(Ti)))
        var_b.append(np.full(tb.size, d.force_noise_n**2 / max(1, -(-n // points_per_press))))
    var_b = np.concatenate(var_b)
    s2 = float(np.mean(var_b))
    n_pts = var_b.size
    dof = max(n_pts - len(curves) - 2, 1)
    _, rss_line = _straight_decay(curves)
    lam = rss_line / s2
    shortest, longest = float(hold.min()), float(hold.max())
    span_ok = TAU_MIN_HOLD_FRACTION * shortest <= tau <= TAU_HOLD_RATIO * longest
    crit = float(stats.f.isf(RELAX_ALPHA, 1, dof))
    power = float(stats.ncf.sf(crit, 1, dof, lam)) if span_ok else 0.0
    if not span_ok:
        why = (f"tau = {tau:g} s lies outside the span the holds resolve "
               f"({TAU_MIN_HOLD_FRACTION:g} of the shortest hold to {TAU_HOLD_RATIO:g} times the "
               f"longest: {TAU_MIN_HOLD_FRACTION * shortest:.3g} to "
               f"{TAU_HOLD_RATIO * longest:.3g} s): fit_relaxation will not identify g and tau; "
               + ("longer holds would" if tau > TAU_HOLD_RATIO * longest else
                  "a faster F/T window at the hold's start would"))
    else:
        why = (f"fit_relaxation identifies g = {g:g} and tau = {tau:g} s in {100 * power:.0f} % "
               f"of sessions (its curvature test at p < {RELAX_ALPHA:g}; noncentrality "
               f"{lam:.3g})" + ("" if power >= 0.95 else
                                ": longer holds, more presses or a quieter F/T would raise it"))
    return RelaxationPlan(g=float(g), tau_s=tau, power=power, span_ok=bool(span_ok),
                          noncentrality=float(lam), why=why)


def _line_covariance(d: Design, w: np.ndarray, P: np.ndarray, u: np.ndarray | None,
                     s_P: float, s_w: float) -> np.ndarray:
    """Covariance (2, 2) of the fit's intercept c and slope c beta (linear in the presses'
    P/w) from independent force noise `s_P` and depth noise `s_w` per press, by central
    differences of the fit in every press's force and depth."""
    n = w.size
    J_P = np.empty((2, n))
    J_w = np.empty((2, n))
    for i in range(n):
        for J, arr, step in ((J_P, P, 1e-4 * P[i]), (J_w, w, 1e-4 * w[i])):
            hi, lo = arr.copy(), arr.copy()
            hi[i] += step
            lo[i] -= step
            args_hi = (w, hi) if arr is P else (hi, P)
            args_lo = (w, lo) if arr is P else (lo, P)
            J[:, i] = (_fit(d, *args_hi, u)[2:] - _fit(d, *args_lo, u)[2:]) / (2 * step)
    return s_P**2 * J_P @ J_P.T + s_w**2 * J_w @ J_w.T


def _quadrature(d: Design, w: np.ndarray, P: np.ndarray, u: np.ndarray | None,
                cov_cs: np.ndarray) -> tuple[np.ndarray, float, float, float, float]:
    """Mean (E, nu), sd of E and nu, their correlation and the weight of the spread where
    the fit gives none, over the Gaussian of (c, c beta) with covariance `cov_cs`.

    E and nu are not linear in (c, c beta): nu(beta) bends and the table clips it. Gauss-
    Hermite quadrature, each node fitted as a table whose P/w is moved by that node's
    line (which moves the fit's line by exactly as much, its residuals unchanged)."""
    x = w / d.thickness_mm
    t, wt = np.polynomial.hermite_e.hermegauss(QUADRATURE_NODES)     # probabilists'
    wt = wt / wt.sum()
    L = np.linalg.cholesky(cov_cs + 1e-30 * np.eye(2))
    vals, weights = [], []
    for i, ti in enumerate(t):
        for j, tj in enumerate(t):
            dc, ds = L @ np.array([ti, tj])
            vals.append(_fit(d, w, P + w * (dc + ds * x), u)[:2])
            weights.append(wt[i] * wt[j])
    vals, weights = np.array(vals), np.array(weights)
    ok = np.isfinite(vals).all(axis=1)
    out_of_table = float(weights[~ok].sum())
    if not ok.any():
        nan = math.nan
        return np.full(2, nan), nan, nan, nan, 1.0
    wk = weights[ok] / weights[ok].sum()
    mean = wk @ vals[ok]
    dev = vals[ok] - mean
    cov = (dev * wk[:, None]).T @ dev
    sE, snu = (float(math.sqrt(max(v, 0.0))) for v in np.diag(cov))
    corr = float(cov[0, 1] / (sE * snu)) if sE > 0 and snu > 0 else 0.0
    return mean, sE, snu, corr, out_of_table


def _biases(d: Design, w: np.ndarray, P: np.ndarray, u: np.ndarray | None,
            base: np.ndarray, mean: np.ndarray, shared_um: float
            ) -> dict[str, tuple[float, float]]:
    """(E error %, nu error) of the noise-free fit, of the mean over sessions, and of each
    shared error at its bound, either way (:attr:`PlanPrediction.bias`)."""
    def err(est: np.ndarray) -> tuple[float, float]:
        return (float(100 * (est[0] / d.E_mpa - 1)), float(est[1] - d.nu))

    bias = {"model": err(base[:2]), "noise": err(mean)}
    if shared_um > 0:
        bias["depth_shared"] = err(_fit(d, w + shared_um * 1e-3, P, u)[:2])
        bias["depth_shared_minus"] = err(_fit(d, w - shared_um * 1e-3, P, u)[:2])
    if d.force_zero_n > 0:
        bias["force_zero"] = err(_fit(d, w, P + d.force_zero_n, u)[:2])
        bias["force_zero_minus"] = err(_fit(d, w, P - d.force_zero_n, u)[:2])
    return bias


def plan_session(design: Design) -> PlanPrediction:
    """Predict what a calibration session of this design will measure.

    Parameters
    ----------
    design : Design

    Returns
    -------
    prediction : PlanPrediction

    Notes
    -----
    The fit is :func:`fit_indentation` on each press's (w, P), with each press's
    depth sd given (errors in both variables), as ``calibrate`` fits. Its intercept c
    and slope c beta are linear in the presses' P/w: their covariance is propagated
    from independent force noise s_P (the F/T sample sd over sqrt(window)) and depth
    noise s_w per press through central differences of the fit in every press's force
    (step 1e-4 P) and depth (step 1e-4 w) on the design's noise-free table
    (:func:`design_table`). E and nu are not linear in (c, c beta), and the beta table
    clips nu: their mean, sds and correlation are integrated over that Gaussian by
    Gauss-Hermite quadrature (:data:`QUADRATURE_NODES` per axis), each node a fit of
    the table moved by the node's line. The shared errors are fitted at their bounds,
    either way.

    Where the fit refuses the design's noise-free table (a/h outside the kappa table,
    or a bonded punch at an a/h where beta does not increase with nu), the sds are NaN,
    ``nu_identified`` is False and the note says why.
    """
    d = design
    w, P = design_table(d)
    sd_um, shared_um, how = depth_uncertainty(d)
    s_w = sd_um * 1e-3
    s_P = d.force_noise_n / math.sqrt(d.window_samples)
    u = np.full(w.size, s_w) if s_w > 0 else None
    notes: list[str] = []
    untest = untestable_effects(d)
    relax = (None if d.relaxation_g is None else
             relaxation_identifiability(d, float(d.relaxation_g), float(d.relaxation_tau_s)))
    try:
        base = _fit(d, w, P, u)
    except InputError as exc:       # the tables cannot fit this a/h: nothing to predict
        why = str(exc)
    else:
        why = None if np.isfinite(base[:2]).all() else (
            f"the fit of the design's own noise-free presses finds no E or nu: their beta lies "
            f"outside the FEM beta table at a/h = {d.a_over_h:.2f}")
    if why is not None:
        nan = math.nan
        return PlanPrediction(d, w.size, sd_um, shared_um, how, s_P, nan, nan, nan, nan, {},
                              False, [f"nu is not identified by this design: {why}"],
                              untest, relax)
    n = w.size
    cov_cs = _line_covariance(d, w, P, u, s_P, s_w)
    mean, sE, snu, corr, out_of_table = _quadrature(d, w, P, u, cov_cs)
    if not np.isfinite(mean).all():
        nan = math.nan
        return PlanPrediction(d, n, sd_um, shared_um, how, s_P, nan, nan, nan, nan, {}, False,
                              ["nu is not identified by this design: beta falls outside the "
                               "FEM beta table over the whole predicted spread"], untest, relax)
    if out_of_table > 0.01:
        notes.append(f"beta falls outside the beta table in {100 * out_of_table:.0f} % of "
                     "sessions of this design (E and nu not computed there); the sds are "
                     "over the others")

    bias = _biases(d, w, P, u, base, mean, shared_um)
    beyond = [k for k, v in bias.items() if not np.isfinite(v).all()]
    if beyond:
        notes.append(f"{', '.join(beyond)}: the fit finds no E or nu there (beta beyond the "
                     "beta table): that shared error would leave nu undetermined")
    pinned = snu < 1e-6 < sE
    identified = bool(np.isfinite(base).all() and snu <= 0.25 * (NU_RANGE[1] - NU_RANGE[0])
                      and out_of_table <= 0.05 and not pinned)
    if pinned:
        notes.append(f"nu is not identified: the fit puts it at {mean[1]:.3f} whatever the "
                     f"presses (the beta table cannot tell nu at a/h = {d.a_over_h:.2f}); E's "
                     "sd is at that nu, and its bias is nu's")
    elif not identified and snu > 0.25 * (NU_RANGE[1] - NU_RANGE[0]):
        notes.append(f"nu is not identified: its predicted sd {snu:.3f} exceeds a quarter of "
                     f"its range {NU_RANGE[0]:g} to {NU_RANGE[1]:g}")
    elif not identified:
        notes.append("nu is not identified: beta falls outside the beta table in more than "
                     "5 % of sessions")
    return PlanPrediction(d, n, sd_um, shared_um, how, s_P, sE, snu, 100 * sE / d.E_mpa,
                          corr, bias, identified, notes, untest, relax)


def plan(design: Design | str | Path) -> PlanPrediction:
    """What a calibration session of this design will measure (``tactilevision plan``).

    Parameters
    ----------
    design : Design, or str or Path of a design file (:func:`read_design`)

    Returns
    -------
    prediction : PlanPrediction

    Raises
    ------
    InputError
        For a bad design file or design (naming the key), or a design whose a/h the
        tables cannot fit.

    Examples
    --------
    >>> from tactilevision.mechanics import Design
    >>> p = plan(Design(thickness_mm=3.0, radius_mm=2.5,
    ...                 depths_mm=(0.15, 0.3, 0.4, 0.5, 0.6), bevel_angle_deg=5.0,
    ...                 overshoot_um=(30.0, 60.0)))
    >>> round(p.depth_std_um, 2)
    1.81
    """
    return plan_session(design if isinstance(design, Design) else read_design(design))


def design_toml(d: Design) -> str:
    """The design as a design file (``session.toml`` tables plus ``[plan]``), for
    :func:`read_design`."""
    def val(v: Any) -> str:
        if isinstance(v, tuple | list):
            return "[" + ", ".join(val(x) for x in v) + "]"
        if isinstance(v, str):
            return f'"{v}"'
        return repr(float(v)) if isinstance(v, float) else str(v)

    plan_keys = ["repeats", "E_mpa", "nu", "frame_rate_hz", "stage_speed_mm_s",
                 "force_noise_n", "force_zero_n", "hold_s", "depth_std_um", "beta_table",
                 "overshoot_um", "holds_s", "waits_s", "days", "positions", "relaxation_g",
                 "relaxation_tau_s"]
    lines = ["[sensor]", f"gel_thickness_mm = {val(d.thickness_mm)}",
             f"mm_per_px = {val(d.mm_per_px)}", "", "[indenter]",
             f"radius_mm = {val(d.radius_mm)}", "", "[gauge_block]",
             f"depths_mm = {val(tuple(d.depths_mm))}",
             f"bevel_angle_deg = {val(d.bevel_angle_deg)}", "", "[force_sensor]",
             f"rate_hz = {val(d.rate_hz)}", f"window_samples = {int(d.window_samples)}",
             f"window_at = {val(d.window_at)}", "",
             "[plan]"]
    for k in plan_keys:
        v = getattr(d, k)
        if v is not None:
            lines.append(f"{k} = {val(v)}")
    return "\n".join(lines) + "\n"


def design_from_calibration(folder: str | Path, session: str | Path | None = None
                            ) -> Design:
    """The design of a session that ``calibrate`` has run, to plan the next one from.

    Parameters
    ----------
    folder : str or Path
        The calibration folder (``fit.json``, ``measurements.csv``).
    session : str or Path, optional
        The session folder it calibrated (its ``session.toml`` gives the image scale,
        the bevel, the F/T window and its ``frames.csv`` the frame rate). Default: the
        one ``fit.json`` names, where it exists.

    Returns
    -------
    design : Design
        h and a, E and nu as fitted; the gauge block's depths w0 (each press's depth
        less its overshoot); the repeats per depth (presses over depths, rounded); the
        overshoot range the presses had, um; the F/T sample sd (median of
        ``force_std_n``); the zero's stability (the drift ``calibrate`` measured plus two
        of its standard errors). What the folders do not hold keeps :class:`Design`'s
        default.

    Raises
    ------
    InputError
        A folder without ``fit.json`` or ``measurements.csv``, or a fit without E and nu.
    """
    folder = Path(folder)
    try:
        fit = json.loads((folder / "fit.json").read_text())
        with open(folder / "measurements.csv", newline="") as fh:
            rows = list(csv.DictReader(fh))
    except FileNotFoundError as exc:
        raise InputError(f"{folder} is not a calibration folder: {exc.filename} is "
                         "missing") from None
    except (OSError, ValueError) as exc:
        raise InputError(f"{folder}: cannot read the calibration ({exc})") from None
    E, nu = fit.get("E_mpa"), fit.get("nu")
    if not (isinstance(E, int | float) and isinstance(nu, int | float)
            and math.isfinite(E) and math.isfinite(nu)):
        raise InputError(f"{folder}/fit.json has no E and nu to plan from")

    def col(name: str) -> np.ndarray:
        return np.array([float(r[name]) if r.get(name) not in (None, "") else np.nan
                         for r in rows])

    depth, over = col("depth_mm"), col("overshoot_mm")
    w0 = np.round(np.where(np.isfinite(over), depth - over, depth), 4)
    depths = tuple(float(v) for v in np.unique(w0[np.isfinite(w0)]))
    kw: dict[str, Any] = dict(
        thickness_mm=float(fit["thickness_mm"]), radius_mm=float(fit["radius_mm"]),
        depths_mm=depths, repeats=max(1, round(len(rows) / max(len(depths), 1))),
        E_mpa=float(E), nu=min(float(nu), 0.5))
    if np.isfinite(over).any():
        kw["overshoot_um"] = (max(0.0, float(np.nanmin(over)) * 1e3),
                              max(0.0, float(np.nanmax(over)) * 1e3))
    f_sd = col("force_std_n") if rows and "force_std_n" in rows[0] else np.array([])
    if np.isfinite(f_sd).any():
        kw["force_noise_n"] = float(np.nanmedian(f_sd))
    waits = col("wait_s") if rows and "wait_s" in rows[0] else np.array([])
    if np.isfinite(waits).any():
        kw["waits_s"] = tuple(round(float(v), 3) for v in waits[np.isfinite(waits)])
    relax = fit.get("relaxation")
    if isinstance(relax, dict) and relax.get("resolved") and 0 < float(relax.get("g") or 0) < 1:
        kw["relaxation_g"] = float(relax["g"])      # the relaxation it found, to plan for
        kw["relaxation_tau_s"] = float(relax["tau_s"])
    zero = fit.get("ft_zero")
    if isinstance(zero, dict) and isinstance(zero.get("drift_n"), int | float):
        kw["force_zero_n"] = abs(float(zero["drift_n"])) + 2 * float(zero.get("drift_se_n")
                                                                      or 0.0)
    where = Path(session) if session is not None else (
        Path(fit["session"]) if isinstance(fit.get("session"), str) else None)
    if where is not None and (where / "session.toml").is_file():
        try:
            doc = tomllib.loads((where / "session.toml").read_text())
        except (OSError, tomllib.TOMLDecodeError) as exc:
            raise InputError(f"{where / 'session.toml'}: {exc}") from None
        sensor, gauge = doc.get("sensor", {}), doc.get("gauge_block", {})
        force = doc.get("force_sensor", {})
        for key, table, name in (("mm_per_px", sensor, "mm_per_px"),
                                 ("bevel_angle_deg", gauge, "bevel_angle_deg"),
                                 ("rate_hz", force, "rate_hz"),
                                 ("window_samples", force, "window_samples")):
            if isinstance(table, dict) and isinstance(table.get(name), int | float):
                kw[key] = table[name]
        if force.get("window_at") in ("start", "end"):
            kw["window_at"] = force["window_at"]
        hold = col("hold_s")
        if kw.get("window_at") == "end" and np.isfinite(hold).all() and hold.size:
            half = 0.5 * kw.get("window_samples", 200) / kw.get("rate_hz", 1000.0)
            kw["holds_s"] = tuple(round(float(v) + half, 3) for v in hold)  # in press order
        frames = where / "frames.csv"
        if frames.is_file():
            with open(frames, newline="") as fh:
                t = np.array([float(r["t_s"]) for r in csv.DictReader(fh) if r.get("t_s")])
            dt = np.diff(np.sort(t))
            if dt.size and np.median(dt) > 0:
                kw["frame_rate_hz"] = float(1.0 / np.median(dt))
    return Design(**kw)
