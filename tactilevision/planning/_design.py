"""A calibration session's design: what ``plan`` reads and what a session of it writes.

A design is a ``session.toml`` (formats.md §1: gel thickness h, indenter radius a, the
gauge block's depths and bevel, the F/T window) plus a ``[plan]`` table of what a session
does not hold yet (:class:`Design`). Here: reading and checking it, writing it back
(:func:`design_toml`), each press's depth uncertainty (:func:`depth_uncertainty`), the
noise-free presses (:func:`design_table`) and the measurements table a session of it
will write (:func:`planned_columns`), and the catalogue effects that table cannot test
(:func:`untestable_in_table`).
"""

from __future__ import annotations

import difflib
import math
import tomllib
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .._checks import InputError, InputWarning
from ..diagnosis import ABSORBED_BY_MARK, untestable_reason
from ..io import KNOWN_KEYS, read_presses, warn_unknown_keys
from ..mechanics import EFFECT_SIZE_PARAMS, EFFECTS, MAX_W_OVER_H, fem_force

__all__ = [
    "BRACKET_PERIODS",
    "RESOLVED_PX",
    "VERNIER_EDGE_PX",
    "Design",
    "check_design",
    "depth_uncertainty",
    "design_table",
    "design_toml",
    "hold_lengths",
    "planned_columns",
    "press_indenters",
    "press_times",
    "read_design",
    "read_schedule",
    "readable_overshoot_um",
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
#: contact package's ``RESOLVED_PX`` (planning does not import contact; a test keeps the
#: two equal).
RESOLVED_PX = 10.0

#: The frame periods a drawn mark's crossing bracket spans on average, where a design
#: does not say (``[plan] bracket_periods``), as
#: :func:`~tactilevision.planning.measured_bracket_periods` reads a calibrated session (at
#: least 1). Over the 20 Taxim mark designs of report ``mark_sweep`` (seed 9973, drawn at
#: random over what labs use, shadows on and off) the brackets spanned 1.00 to 1.42
#: periods, mean 1.11 (``python benchmarks/bench_mark_sweep.py --seed 9973 --designs 20
#: --kinds mark-shadow mark-plain``, its "brackets" column); over designs 0 to 11 of seed
#: 10039 (``--seed 10039 --designs 12``) 1.00 to 1.70, mean 1.23, the widest without the
#: renderer's shadows; a generated 15 frames/s session (seed 8600) 1.13. 1.5 here, at or
#: above 30 of those 32 designs: a plan's crossing-force sizes err large rather than small
#: on a session it has not seen (1 and 2 periods in turn). Judged on designs drawn after it
#: was set: seed 10039's designs 12 to 19 (``--seed 10039 --first 12 --designs 8``) spanned
#: 1.02 to 1.22, 8 of 8 within it; report ``plan_crossings``.
BRACKET_PERIODS = 1.5

#: nu's physical range as this project's beta tables hold it: a sigma of nu beyond a

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
        frame's travel); the speed is not read where ``approach_s`` is given.
    approach_s : float or None
        The stage reaches each press's depth in this time, s, at constant speed (a move
        of fixed duration: its speed through w0 is ``(w0 + overshoot) / approach_s``, the
        overshoot the middle of ``overshoot_um``, so deeper indenters pass their mark
        faster); None: every press at ``stage_speed_mm_s`` (:func:`indenter_speeds`).
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
        Distinct press positions on the pad (a golden-angle spiral over a 5 mm disc, the
        presses going round them), where no `schedule` gives them.
    schedule : tuple of (int, float, float) or None
        The presses as the robot will command them (formats.md §1 ``presses.csv``), in
        the order pressed: each one's indenter (0-based, into ``depths_mm``) and its
        position x_mm, y_mm on the pad. Each indenter ``repeats`` times. None: the
        presses go round the indenters at the spiral's `positions`. A drawn mark's
        within-indenter effects are sized on it
        (:func:`~tactilevision.planning.crossing_effect_sizes`): on 20
        generated mark sessions at 15 frames/s (seeds 8200 to 8219 of
        ``benchmarks/bench_crossings.py``) the gradient their own crossing forces could
        name was 0.58 to 1.43 times the spiral's (each indenter's x spread 0.84 to 1.56
        mm sd against the spiral's 1.41) and 0.70 to 1.09 times their own schedule's.
    bracket_periods : float
        The frame periods of the stage's travel a drawn mark's crossing bracket spans on
        average, 1 to 4 (:data:`BRACKET_PERIODS` by default): its crossing forces'
        brackets are that many frames' travel times dP/dw wide
        (:func:`~tactilevision.planning.crossing_table`).
        :func:`~tactilevision.planning.design_from_calibration` measures it on the
        session's own brackets.
    unseen_share : float
        The share of presses whose mark the certification will not see (the stage
        stopping too little past w0 to show it), in [0, 0.5): a drawn mark's crossing
        forces are sized on sessions that lose each press with that probability
        (:func:`~tactilevision.planning.crossing_sessions`), and E's and nu's spread on
        the presses left. :func:`~tactilevision.planning.design_from_calibration`
        measures it (the presses ``calibrate`` rejected).
    detect : tuple of (str, float)
        Effect sizes the user wants to be able to see (``[plan.detect]``: a catalogue
        effect of :data:`EFFECT_SIZE_PARAMS` and its size in that table's unit):
        ``plan`` gives the share of sessions in which ``diagnose`` names each.
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
    approach_s: float | None = None
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
    schedule: tuple[tuple[int, float, float], ...] | None = None
    relaxation_g: float | None = None
    relaxation_tau_s: float | None = None
    detect: tuple[tuple[str, float], ...] = ()
    bracket_periods: float = BRACKET_PERIODS
    unseen_share: float = 0.0

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
        below 1, a nu outside (0, 0.5], a ``bracket_periods`` outside [1, 4] or an
        ``unseen_share`` outside [0, 0.5).
    """
    _check_block(d)
    _check_schedule(d)


def _check_block(d: Design) -> None:
    """The gel, indenter, depths, bevel, sensor and noise keys of a design."""
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
    if d.approach_s is not None:
        _positive(d.approach_s, "[plan] approach_s")
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
    periods = float(d.bracket_periods)
    if not 1.0 <= periods <= 4.0:
        raise InputError(f"[plan] bracket_periods must lie in [1, 4] (frame periods a mark's "
                         f"crossing bracket spans), got {d.bracket_periods!r}")
    if not 0.0 <= float(d.unseen_share) < 0.5:
        raise InputError(f"[plan] unseen_share must lie in [0, 0.5) (the share of presses "
                         f"whose mark is not seen), got {d.unseen_share!r}")


def _check_schedule(d: Design) -> None:
    """The days, positions, holds, waits, relaxation and detect keys of a design."""
    for key in ("days", "positions"):
        v = getattr(d, key)
        if isinstance(v, bool) or not isinstance(v, int | float) or int(v) != v or v < 1:
            raise InputError(f"[plan] {key} must be a positive integer, got {v!r}")
    _check_press_schedule(d)
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
    for item in d.detect:
        if not (isinstance(item, tuple | list) and len(item) == 2):
            raise InputError(f"[plan.detect] entries are effect = size, got {item!r}")
        name, size = item
        if name not in EFFECT_SIZE_PARAMS:
            raise InputError(f"[plan.detect] {name} is not an effect plan can size (known: "
                             f"{', '.join(EFFECT_SIZE_PARAMS)})")
        _positive(size, f"[plan.detect] {name}")


def _check_press_schedule(d: Design) -> None:
    """``[plan] schedule``: (indenter, x_mm, y_mm) per press, each indenter ``repeats``
    times (one sentence naming the press at fault)."""
    if d.schedule is None:
        return
    n_ind = len(d.depths_mm)
    if not isinstance(d.schedule, tuple | list) or not d.schedule:
        raise InputError(f"[plan] schedule must list the presses, got {d.schedule!r}")
    for k, item in enumerate(d.schedule):
        if not (isinstance(item, tuple | list) and len(item) == 3
                and all(_is_number(v) and math.isfinite(v) for v in item)):
            raise InputError(f"[plan] schedule: press {k} must be [indenter, x_mm, y_mm], "
                             f"three finite numbers, got {item!r}")
        if not float(item[0]).is_integer() or not 0 <= item[0] < n_ind:
            raise InputError(f"[plan] schedule: press {k}'s indenter {item[0]!r} is not one "
                             f"of [gauge_block] depths_mm (0 to {n_ind - 1})")
    counts = np.bincount([int(item[0]) for item in d.schedule], minlength=n_ind)
    off = np.flatnonzero(counts != int(d.repeats))
    if off.size:
        raise InputError(f"[plan] schedule presses indenter {off[0]} {counts[off[0]]} "
                         f"time(s), but [plan] repeats is {d.repeats}: each indenter is "
                         "pressed repeats times")


#: The type of every key a design reads (``'number'``: an int or float, never a
#: boolean; ``'integer'``; ``'numbers'``: a list of numbers; ``'text'``).
DESIGN_KEYS: dict[str, dict[str, str]] = {
    "sensor": {"gel_thickness_mm": "number", "mm_per_px": "number"},
    "indenter": {"radius_mm": "number"},
    "gauge_block": {"depths_mm": "numbers", "bevel_angle_deg": "number"},
    "force_sensor": {"rate_hz": "number", "window_samples": "integer", "window_at": "text"},
    "plan": {"repeats": "integer", "E_mpa": "number", "nu": "number",
             "frame_rate_hz": "number", "stage_speed_mm_s": "number",
             "approach_s": "number", "force_noise_n": "number", "force_zero_n": "number",
             "hold_s": "number",
             "depth_std_um": "number", "beta_table": "text", "overshoot_um": "numbers",
             "holds_s": "numbers", "waits_s": "numbers", "days": "integer",
             "positions": "integer", "schedule": "schedule", "relaxation_g": "number",
             "relaxation_tau_s": "number", "detect": "table", "bracket_periods": "number",
             "unseen_share": "number"},
}

_KIND_WORDS = {"number": "a number", "integer": "a whole number", "numbers": "a list of numbers",
               "text": "a string", "table": "a table",
               "schedule": "a presses.csv file name or a list of [indenter, x_mm, y_mm]"}


def _is_number(v: Any) -> bool:
    return not isinstance(v, bool) and isinstance(v, int | float)


def _typed(v: Any, kind: str) -> bool:
    if kind == "number":
        return _is_number(v)
    if kind == "integer":
        return _is_number(v) and float(v).is_integer()
    if kind == "numbers":
        return isinstance(v, list) and all(_is_number(x) for x in v)
    if kind == "schedule":
        return isinstance(v, str) or (isinstance(v, list) and all(
            isinstance(x, list) and all(_is_number(y) for y in x) for x in v))
    return isinstance(v, str) if kind == "text" else isinstance(v, dict)


def _check_keys(doc: dict, path: Path) -> None:
    """Every key a design reads has its type (one sentence naming file, table and key), and
    a ``[plan]`` key it does not know is refused; a table or key neither a design nor a
    session reads is warned, with the nearest known one (:class:`~tactilevision.InputWarning`,
    :func:`~tactilevision.io.warn_unknown_keys`)."""
    known = {table: (*KNOWN_KEYS.get(table, ()), *DESIGN_KEYS.get(table, {}))
             for table in (*KNOWN_KEYS, *DESIGN_KEYS)}
    for table, section in doc.items():
        if table not in known:
            continue
        if not isinstance(section, dict):
            raise InputError(f"{path}: [{table}] must be a table")
        for key, value in section.items():
            kind = DESIGN_KEYS.get(table, {}).get(key)
            if kind is not None and not _typed(value, kind):
                raise InputError(f"{path}: [{table}] {key} must be {_KIND_WORDS[kind]}, "
                                 f"got {value!r}")
            if table == "plan" and key not in known["plan"]:
                near = difflib.get_close_matches(key, list(known["plan"]), n=1)
                raise InputError(f"{path}: [plan] {key} is not a design key"
                                 + (f" (did you mean {near[0]}?)" if near else "")
                                 + f" (known: {', '.join(sorted(known['plan']))})")
    warn_unknown_keys(doc, path, known, unset="its default is used", skip=("plan",),
                      stacklevel=3)


def read_design(path: str | Path) -> Design:
    """Read a design file: a ``session.toml`` with a ``[plan]`` table.

    Parameters
    ----------
    path : str or Path
        The TOML file. Keys: ``[sensor] gel_thickness_mm, mm_per_px``, ``[indenter]
        radius_mm``, ``[gauge_block] depths_mm, bevel_angle_deg``, ``[force_sensor]
        rate_hz, window_samples, window_at``, ``[plan] repeats, E_mpa, nu,
        frame_rate_hz, stage_speed_mm_s or approach_s, force_noise_n, force_zero_n, hold_s,
        depth_std_um, beta_table, overshoot_um, holds_s, waits_s, days, positions,
        schedule, relaxation_g, relaxation_tau_s, bracket_periods, unseen_share`` and
        ``[plan.detect]``
        (effect = size;
        every ``[plan]`` key optional; :class:`Design` gives the defaults). ``schedule``
        is a list of ``[indenter, x_mm, y_mm]`` or the name of a ``presses.csv``
        (formats.md §1; relative to the design file's folder, its rows in ``press``
        order); without ``repeats`` it sets them.

    Returns
    -------
    design : Design

    Raises
    ------
    InputError
        A missing or unreadable file, TOML that does not parse, a missing required
        key, an unknown ``[plan]`` key, both ``stage_speed_mm_s`` and ``approach_s``
        (one says how the stage moves), a bad value (:func:`check_design`), or a
        ``schedule`` file :func:`~tactilevision.io.read_presses` refuses, each naming the
        file and the key (or the line).
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

    _check_keys(doc, path)
    plan = doc.get("plan", {})
    if "stage_speed_mm_s" in plan and "approach_s" in plan:
        raise InputError(f"{path}: [plan] gives both stage_speed_mm_s and approach_s: give "
                         "the stage's speed through w0 or its move's duration, not both")
    depths = need("gauge_block", "depths_mm")
    gauge = doc.get("gauge_block", {})
    sensor = doc.get("sensor", {})
    force = doc.get("force_sensor", {})
    kw: dict[str, Any] = dict(plan)
    if "detect" in kw:
        if not isinstance(kw["detect"], dict):
            raise InputError(f"{path}: [plan.detect] must be a table of effect = size")
        kw["detect"] = tuple(kw["detect"].items())
    for key in ("overshoot_um", "holds_s", "waits_s"):
        if key in kw and isinstance(kw[key], list):
            kw[key] = tuple(kw[key])
    if "schedule" in kw:
        if "positions" in kw:
            warnings.warn(f"{path}: [plan] positions is not read: [plan] schedule gives the "
                          "presses' places", InputWarning, stacklevel=2)
            del kw["positions"]
        kw["schedule"] = _read_schedule(kw["schedule"], path, len(depths))
        if "repeats" not in kw:
            counts = np.bincount([int(v[0]) for v in kw["schedule"]
                                  if v and _is_number(v[0]) and 0 <= v[0] < len(depths)])
            kw["repeats"] = int(counts.max()) if counts.size else 1
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


def _read_schedule(value: Any, path: Path, n_indenters: int
                   ) -> tuple[tuple[Any, ...], ...]:
    """``[plan] schedule`` as (indenter, x_mm, y_mm) per press: inline, or read from the
    ``presses.csv`` it names (relative to the design file), its rows in ``press``
    order."""
    if not isinstance(value, str):
        return tuple(tuple(v) for v in value)
    p = Path(value) if Path(value).is_absolute() else path.parent / value
    try:
        return read_schedule(p, n_indenters)
    except InputError as exc:
        raise InputError(f"{path}: [plan] schedule: {exc}") from None


def read_schedule(path: str | Path, n_indenters: int) -> tuple[tuple[int, float, float], ...]:
    """A ``presses.csv`` (formats.md §1) as a design's ``schedule``: each press's
    (indenter, x_mm, y_mm), in ``press`` order.

    Parameters
    ----------
    path : str or Path
    n_indenters : int
        The gauge block's indenters.

    Returns
    -------
    schedule : tuple of (int, float, float)

    Raises
    ------
    InputError
        As :func:`~tactilevision.io.read_presses`.
    """
    rows = read_presses(path, n_indenters)
    order = np.argsort(rows["press"], kind="stable")
    return tuple((int(rows["indenter"][k]), float(rows["x_mm"][k]), float(rows["y_mm"][k]))
                 for k in order)


def press_indenters(d: Design) -> np.ndarray:
    """(N,) int64 indenter (index into ``depths_mm``) of each planned press in turn: the
    ``schedule``'s, else each depth's ``repeats`` presses in turn."""
    if d.schedule is not None:
        return np.array([int(v[0]) for v in d.schedule], np.int64)
    return np.repeat(np.arange(len(d.depths_mm)), int(d.repeats))


def indenter_speeds(d: Design) -> np.ndarray:
    """(I,) float64 the stage's speed through each indenter's w0, mm/s.

    ``stage_speed_mm_s`` for every indenter; with ``approach_s`` (a move of fixed
    duration at constant speed to the press's depth) ``(w0 + o) / approach_s``, o the
    middle of ``overshoot_um`` (mm).
    """
    if d.approach_s is None:
        return np.full(len(d.depths_mm), float(d.stage_speed_mm_s))
    return _travel_mm(d) / float(d.approach_s)


def _travel_mm(d: Design) -> np.ndarray:
    """(I,) float64 each indenter's approach, mm: its w0 plus the middle of
    ``overshoot_um``."""
    over = 0.5e-3 * (float(d.overshoot_um[0]) + float(d.overshoot_um[1]))
    return np.asarray(d.depths_mm, np.float64) + over


def speed_words(d: Design) -> str:
    """The stage's speed through w0 in words (mm/s; the range over indenters with
    ``approach_s``)."""
    v = indenter_speeds(d)
    if d.approach_s is None:
        return f"{d.stage_speed_mm_s:g} mm/s"
    return f"{v.min():.3g} to {v.max():.3g} mm/s, each depth reached in {d.approach_s:g} s"


def readable_overshoot_um(d: Design) -> float:
    """How far past w0 the stage must stop for the design's vernier bands to be read, um:
    ``RESOLVED_PX x mm_per_px x tan(theta)`` (0 for a drawn mark)."""
    return RESOLVED_PX * d.mm_per_px * math.tan(math.radians(d.bevel_angle_deg)) * 1e3


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
    up to that much in every press (the bound given as ``depth_shared_um``). With
    ``approach_s`` the travel differs by indenter (:func:`indenter_speeds`): the sd is
    the root mean square over the planned presses, the bound the largest travel.
    ``depth_std_um`` overrides the random part.
    """
    if d.bevel_angle_deg > 0:
        o_r = readable_overshoot_um(d)
        read_sd = VERNIER_EDGE_PX * o_r / RESOLVED_PX
        lo, hi = (float(v) for v in d.overshoot_um)
        f = 1.0 if o_r <= lo else (0.0 if o_r >= hi else (hi - o_r) / (hi - lo))
        sd = math.sqrt(f * read_sd**2 + (1 - f) * o_r**2 / 12)
        shared, how = 0.0, (f"vernier at {d.bevel_angle_deg:g} deg: {100 * f:.0f} % of presses "
                            f"read ({VERNIER_EDGE_PX:g} px x {d.mm_per_px:g} mm/px x "
                            f"tan(theta) = {read_sd:.2f} um), the rest bounded to "
                            f"{o_r:.1f} um past w0")
    else:
        travel = indenter_speeds(d)[press_indenters(d)] / d.frame_rate_hz * 1e3
        rms = math.sqrt(float(np.mean(travel**2)))
        sd, shared = rms / math.sqrt(12.0), float(travel.max())
        what = (f"{rms:.1f} um" if d.approach_s is None else
                f"{travel.min():.1f} to {travel.max():.1f} um by indenter, rms {rms:.1f} um")
        how = (f"mark: one frame's travel {what} ({speed_words(d)}, "
               f"{d.frame_rate_hz:g} frames/s) / sqrt(12), shared up to one frame's travel")
    if d.depth_std_um is not None:
        sd, how = float(d.depth_std_um), "given ([plan] depth_std_um)"
    return sd, shared, how


def design_table(d: Design) -> tuple[np.ndarray, np.ndarray]:
    """The design's noise-free presses: depths w (mm) and the finite-strain FEM's forces
    P = 2 a E w kappa_n(nu, a/h, w/h) / (1 - nu^2) (N), ``repeats`` per depth, in the
    order of :func:`press_indenters`."""
    w = np.asarray(d.depths_mm, np.float64)[press_indenters(d)]
    return w, fem_force(d.E_mpa, d.nu, d.radius_mm, d.thickness_mm, w)


def hold_lengths(d: Design, n: int) -> np.ndarray:
    """(n,) hold length of each press in turn, s: ``holds_s`` cycled, else ``hold_s``,
    else 1 s."""
    holds = np.asarray(d.holds_s if d.holds_s is not None else
                       (d.hold_s if d.hold_s is not None else 1.0,), np.float64)
    return holds[np.arange(n) % holds.size]


def press_times(d: Design, indenters: np.ndarray) -> np.ndarray:
    """(N,) float64 each press's time, s, for presses on `indenters` (indices into
    ``depths_mm``) in that order: each press follows the last after its rest (``wait_s``,
    from the last release), its approach (``approach_s``, or the depth ``w0 + o`` at
    ``stage_speed_mm_s``, o the middle of ``overshoot_um``) and its hold. The stage's
    retreat is not counted (no key gives it): a session whose stage retreats slowly runs
    longer, and sees a change with time more easily, than planned."""
    ind = np.asarray(indenters, np.int64)
    n = ind.size
    approach = (_travel_mm(d) / indenter_speeds(d))[ind]
    waits = np.asarray(d.waits_s, np.float64)[np.arange(n) % len(d.waits_s)]
    return np.cumsum(waits + approach + hold_lengths(d, n))


def planned_columns(d: Design) -> dict[str, np.ndarray]:
    """The measurements table a session of the design will write, but its forces (formats.md
    §2 columns): each depth's ``repeats`` presses in turn (or the ``schedule``'s
    presses), the holds (``hold_s``: half the window with ``window_at = 'start'``, the
    hold less half the window with ``'end'``), the rests, the press times
    (:func:`press_times`), the days and
    the positions on the pad (the ``schedule``'s, else a spiral's); the
    tangential forces ``fx_n``, ``fy_n`` only as varying columns (an F/T sensor always
    records them).

    Returns
    -------
    columns : dict of str to (N,) float ndarray
    """
    w = np.asarray(d.depths_mm, np.float64)[press_indenters(d)]
    n = w.size
    i = np.arange(n)
    hold = hold_lengths(d, n)
    half = 0.5 * d.window_samples / d.rate_hz
    waits = np.asarray(d.waits_s, np.float64)[i % len(d.waits_s)]
    k = np.arange(d.positions)
    ang = 2.39996 * k                   # a golden-angle spiral over a 5 mm disc
    px, py = 5.0 * np.sqrt((k + 0.5) / d.positions) * np.cos(ang), 5.0 * np.sqrt(
        (k + 0.5) / d.positions) * np.sin(ang)
    x, y = px[i % d.positions], py[i % d.positions]
    if d.schedule is not None:
        x, y = (np.array([float(v[j]) for v in d.schedule]) for j in (1, 2))
    return {
        "press": i.astype(np.float64), "depth_mm": w,
        "hold_s": np.full(n, half) if d.window_at == "start" else hold - half,
        "wait_s": waits, "time_s": press_times(d, press_indenters(d)),
        "day": np.floor(i * d.days / n), "x_mm": x, "y_mm": y, "fx_n": np.cos(i),
        "fy_n": np.sin(i),
    }


#: Why a design with a mark (``bevel_angle_deg = 0``) cannot show a force effect that
#: varies between one indenter's presses.
MARK_ABSORBS = ("the mark rule reads each depth past w0 from the press's own force "
                "(w = w0 + (P - P(w0)) / (dP/dw)), so a change of the force between one "
                "indenter's presses is read as depth and absorbed; a vernier bevel "
                "(bevel_angle_deg > 0) certifies depth apart from the force")


def untestable_effects(d: Design) -> dict[str, str]:
    """The catalogue's effects ``diagnose`` could not test on a session of the design,
    and why (its column constant or missing in :func:`planned_columns`; the same test
    ``diagnose`` makes of a table; with a mark, the force effects its depth rule absorbs:
    :data:`MARK_ABSORBS`)."""
    out = untestable_in_table(planned_columns(d), window_at=d.window_at)
    if d.bevel_angle_deg == 0:
        # a mark: calibrate reads each depth past w0 from the press's own force, so an
        # effect that changes the force between one indenter's presses is read as depth
        # (diagnose says the same of such a table: tactilevision.diagnosis.ABSORBED_BY_MARK)
        for name in ABSORBED_BY_MARK:
            out.setdefault(name, MARK_ABSORBS)
    return out


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
        why = untestable_reason(name, columns)
        if why is not None:
            held = np.asarray(columns.get("hold_s", [np.nan]), np.float64)
            held = held[np.isfinite(held)]
            if name == "viscoelastic_relaxation" and window_at == "start" and \
                    held.size and np.ptp(held) == 0:
                # hold_s is the time from the hold's start to the window's middle: say so,
                # not "constant 0.1" beside a design whose holds last 1 s
                why = (f"every press's force window sits {float(held[0]):g} s into its hold "
                       "(hold_s, the time from the hold's start to the window's middle, "
                       "with the window at the hold's start), so relaxation cannot show: "
                       "vary it with window_at = 'end' and holds of different lengths")
            elif name == "aging":
                why += "; spread the presses over several days"
            elif name == "spatial_nonuniformity":
                why += "; press at several positions of the pad"
            out[name] = why
    return out


def design_toml(d: Design) -> str:
    """The design as a design file (``session.toml`` tables plus ``[plan]``), for
    :func:`read_design`."""
    def val(v: Any) -> str:
        if isinstance(v, tuple | list):
            return "[" + ", ".join(val(x) for x in v) + "]"
        if isinstance(v, str):
            return f'"{v}"'
        return repr(float(v)) if isinstance(v, float) else str(v)

    speed = "stage_speed_mm_s" if d.approach_s is None else "approach_s"
    plan_keys = ["repeats", "E_mpa", "nu", "frame_rate_hz", speed,
                 "force_noise_n", "force_zero_n", "hold_s", "depth_std_um", "beta_table",
                 "overshoot_um", "holds_s", "waits_s", "days", "positions", "relaxation_g",
                 "relaxation_tau_s", "bracket_periods", "unseen_share"]
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
        if v is not None and not (k == "positions" and d.schedule is not None):
            lines.append(f"{k} = {val(v)}")
    if d.schedule is not None:
        lines.append("schedule = [" + ", ".join(
            f"[{int(i)}, {val(float(x))}, {val(float(y))}]" for i, x, y in d.schedule) + "]")
    if d.detect:
        lines += ["", "[plan.detect]"] + [f"{k} = {val(float(v))}" for k, v in d.detect]
    return "\n".join(lines) + "\n"
