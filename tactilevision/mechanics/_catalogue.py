"""The effect catalogue (formats.md §5): effects as small classes, and their registry.

Each effect (in the manner of lmfit's composable models) gives its parameters
with bounds and units, the columns it needs, and how it changes the depth the
law sees or the force it predicts. Adding an effect to the catalogue is one new
class in :data:`EFFECTS`; effects of one's own are registered
(:func:`register_effect`) or named by an import spec
(``package.module:ClassName``). The fitting engine that composes them into a
model is :mod:`tactilevision.mechanics._model`.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import math
import os
import sys
from collections.abc import Mapping
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from .._checks import InputError
from ._fem_tables import kappa_n_grid


@dataclass(frozen=True)
class Param:
    """One model parameter.

    Attributes
    ----------
    name : str
    value : float
        Starting value.
    lower, upper : float
        Bounds.
    unit : str
    """

    name: str
    value: float
    lower: float = -math.inf
    upper: float = math.inf
    unit: str = ""


class Effect:
    """Base class of a catalogue effect.

    Subclasses set :attr:`name`, :attr:`params`, :attr:`columns` and
    :attr:`kind` (``'depth'``, ``'stiffness'`` or ``'force'``) and implement
    :meth:`apply`; the docstring gives the physics and its source.
    """

    name: str = ""
    params: tuple[Param, ...] = ()
    columns: tuple[str, ...] = ()
    kind: str = "stiffness"

    def apply(self, p: Mapping[str, float], data: Mapping[str, np.ndarray],
              value: np.ndarray) -> np.ndarray:
        """Return the changed depth (``kind='depth'``), stiffness factor
        (``'stiffness'``, multiplies P) or force (``'force'``)."""
        raise NotImplementedError

    def profile(self, data: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
        """Parameters found by search rather than by gradient, and their candidate values.

        :meth:`IndentationModel.fit` fits the model at every candidate value
        (the other parameters free) and keeps the best: for parameters on
        which the force does not depend smoothly (a change point). Default:
        none.
        """
        return {}

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


class LargeDeformation(Effect):
    """Finite-strain stiffening, P/w = c (1 + beta w / h) (paper, eq. 5).

    Part of the base model ``'paper'``; an effect of ``base='layer'``.
    """

    name = "large_deformation"
    params = (Param("beta", 1.0, -5.0, 20.0, ""),)
    columns = ("depth_mm",)

    def apply(self, p, data, value):
        return 1.0 + p["beta"] * data["depth_mm"] / data["_h"]


class DepthOffset(Effect):
    """A constant error in the certified depth, w_true = w + delta (bevel-onset
    lag, block height error). Shows along depth: P/w curves at small w."""

    name = "depth_offset"
    params = (Param("delta_mm", 0.0, -0.05, 0.05, "mm"),)
    columns = ("depth_mm",)
    kind = "depth"

    def apply(self, p, data, value):
        return value + p["delta_mm"]


class ForceOffset(Effect):
    """A constant force-sensor bias (bad tare), P + b."""

    name = "force_offset"
    params = (Param("offset_n", 0.0, -1.0, 1.0, "N"),)
    columns = ("depth_mm",)
    kind = "force"

    def apply(self, p, data, value):
        return value + p["offset_n"]


class ForceDrift(Effect):
    """A force-sensor bias growing within a session from zero at the tare,
    P + d t + q t^2 (t = time_s, the time since the session start, when the
    F/T sensor is tared). Thermal drift of strain-gauge sensors settles
    roughly as D (1 - exp(-t / T)) (e.g. ATI, F/T Transducer Manual,
    "temperature compensation"); d t + q t^2 is its second-order expansion,
    which also covers a steady ramp (q = 0). The straight line alone left
    residuals along time_s on generated thermal drifts and moved E by up to
    12 % (``benchmarks/bench_diagnose.py``)."""

    name = "force_drift"
    params = (Param("drift_n_per_s", 0.0, -1.0, 1.0, "N/s"),
              Param("curvature_n_per_s2", 0.0, -1e-2, 1e-2, "N/s^2"))
    columns = ("time_s",)
    kind = "force"

    def apply(self, p, data, value):
        t = data["time_s"]
        return value + p["drift_n_per_s"] * t + p["curvature_n_per_s2"] * t * t


class ForceCrosstalk(Effect):
    """F/T cross-talk: the sensor's fz reads part of the tangential forces,
    P + kx fx + ky fy. A six-axis sensor turns its gauges' strains into forces
    through a calibration matrix; an error in it, or a sensor mounted askew,
    couples fx and fy into fz. fx_n and fy_n are read here as the sensor's
    conditions, not scanned as covariates (they are responses: a press's
    tangential force grows with its normal force)."""

    name = "force_crosstalk"
    params = (Param("kx", 0.0, -1.0, 1.0, ""), Param("ky", 0.0, -1.0, 1.0, ""))
    columns = ("fx_n", "fy_n")
    kind = "force"

    def apply(self, p, data, value):
        return value + p["kx"] * data["fx_n"] + p["ky"] * data["fy_n"]


class ViscoelasticRelaxation(Effect):
    """Force relaxing while the depth is held: a standard linear solid,
    P (1 - g (1 - exp(-t_hold / tau))) (e.g. Lakes, Viscoelastic Materials, 2009, ch. 2)."""

    name = "viscoelastic_relaxation"
    params = (Param("g", 0.05, 0.0, 0.9, ""), Param("tau_s", 1.0, 1e-3, 1e3, "s"))
    columns = ("hold_s",)

    def apply(self, p, data, value):
        return 1.0 - p["g"] * (1.0 - np.exp(-data["hold_s"] / p["tau_s"]))


class IncompleteRecovery(Effect):
    """The gel still recovering from the previous press: stiffer after a short
    rest, P (1 + r exp(-t_wait / tau)) (method.md: too short a wait makes the
    next press stiffer)."""

    name = "incomplete_recovery"
    params = (Param("r", 0.05, 0.0, 2.0, ""), Param("tau_s", 2.0, 1e-2, 1e4, "s"))
    columns = ("wait_s",)

    def apply(self, p, data, value):
        w = np.nan_to_num(data["wait_s"], nan=np.inf)
        return 1.0 + p["r"] * np.exp(-w / p["tau_s"])


class Aging(Effect):
    """Stiffness changing over calendar time, P (1 + k day) (silicone aging:
    Ito, Hirai and Ohki, IEEE TDEI 27(3), 2020)."""

    name = "aging"
    params = (Param("k_per_day", 0.0, -0.1, 0.1, "1/day"),)
    columns = ("day",)

    def apply(self, p, data, value):
        return 1.0 + p["k_per_day"] * data["day"]


class SpatialNonuniformity(Effect):
    """Stiffness varying over the gel surface, P (1 + gx x + gy y) (x, y from
    the gel centre; the paper presses at different positions for this)."""

    name = "spatial_nonuniformity"
    params = (Param("gx_per_mm", 0.0, -0.2, 0.2, "1/mm"),
              Param("gy_per_mm", 0.0, -0.2, 0.2, "1/mm"))
    columns = ("x_mm", "y_mm")

    def apply(self, p, data, value):
        return 1.0 + p["gx_per_mm"] * data["x_mm"] + p["gy_per_mm"] * data["y_mm"]


class _ColumnEffect(Effect):
    """An effect along a column named after a colon: ``<kind>:<column>``.

    Subclasses set :attr:`prefix` and implement :meth:`_params` (the
    parameters, whose units may name the column).
    """

    prefix = ""

    def __init__(self, column: str) -> None:
        if not column:
            raise InputError(f"{self.prefix} needs a column: {self.prefix}:<column>")
        self.column = column
        self.name = f"{self.prefix}:{column}"
        self.params = self._params(column)
        self.columns = (column,)

    def _params(self, column: str) -> tuple[Param, ...]:
        raise NotImplementedError

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.column!r})"


class StiffnessTrend(_ColumnEffect):
    """A generic stiffness change along any covariate column, P exp(k x)
    (1 + k x for small k; the reference value of x is absorbed by c, so no
    data-dependent centring is needed and cross-validation folds predict
    consistently): offered when residuals carry structure along a column
    that no named effect explains."""

    kind = "stiffness"
    prefix = "stiffness_trend"

    def _params(self, column: str) -> tuple[Param, ...]:
        return (Param("k", 0.0, -10.0, 10.0, f"1/({column} unit)"),)

    def apply(self, p, data, value):
        return np.exp(p["k"] * data[self.column])


class StiffnessStep(_ColumnEffect):
    """A sudden change of stiffness at an unknown value of a column, P (1 + s [x > x0]).

    A change point: the gel damaged or re-seated after some press
    (``stiffness_step:press``), between sessions (``stiffness_step:day``) or
    at some time (``stiffness_step:time_s``). It scales P(w), so its force
    change grows with depth, where a force-sensor bias (``force_drift``,
    ``force_offset``) adds the same force at every depth: that is what tells
    them apart. ``s`` is the relative change (-0.1: 10 % softer after);
    ``at`` (x0), in the column's unit, is found by search over the midpoints
    between the column's sorted values that leave at least
    :attr:`min_side` presses on each side (:meth:`IndentationModel.fit`
    tries 16 evenly spaced, then every midpoint next to the best); its
    standard error is not given, and it counts twice in the BIC (a search
    over K places gains about 2 ln K by chance). c is the stiffness before
    the step.
    """

    kind = "stiffness"
    prefix = "stiffness_step"
    #: Fewest presses on each side of the change point.
    min_side = 3

    def _params(self, column: str) -> tuple[Param, ...]:
        return (Param("s", 0.0, -0.9, 3.0, ""),
                Param("at", 0.0, -math.inf, math.inf, f"{column} unit"))

    def apply(self, p, data, value):
        # a press exactly at the change point (a held-out press in cross-validation, the
        # place being the midpoint of its neighbours) is as likely on either side
        x = data[self.column]
        return 1.0 + p["s"] * np.where(x > p["at"], 1.0, np.where(x == p["at"], 0.5, 0.0))

    def profile(self, data):
        x = np.sort(np.asarray(data[self.column], np.float64))
        n = x.size
        k = self.min_side
        if n < 2 * k:
            return {"at": np.array([])}
        # change points between x[i - 1] and x[i] with i presses at or below
        i = np.arange(k, n - k + 1)
        i = i[x[i - 1] < x[i]]
        return {"at": 0.5 * (x[i - 1] + x[i])}


class ForceTrend(_ColumnEffect):
    """A force-sensor bias along any covariate column, P + k x (zero where x is 0).

    The additive counterpart of :class:`StiffnessTrend`: offered when a
    column's residual structure is a force added at every depth rather than
    a stiffness change (one that grows with depth).
    """

    kind = "force"
    prefix = "force_trend"

    def _params(self, column: str) -> tuple[Param, ...]:
        return (Param("k_n", 0.0, -100.0, 100.0, f"N/({column} unit)"),)

    def apply(self, p, data, value):
        return value + p["k_n"] * data[self.column]


class LawCurvature(Effect):
    """Curvature of P/w against w/h beyond eq. (5): P (1 + gamma (w/h)^2).

    Not a physical effect of the catalogue but the known limit of the base
    law: the FEM's finite-strain P/w is not exactly linear in w/h (its
    misfit to eq. 5 is about 0.1 % of the deepest press's force, which
    repeatable presses resolve). :func:`~tactilevision.diagnosis.diagnose`
    uses it as the alternative a depth effect must beat, so that the law's
    own curvature is not reported as a depth or force offset.
    """

    name = "law_curvature"
    params = (Param("gamma", 0.0, -50.0, 50.0, ""),)
    columns = ("depth_mm",)

    def apply(self, p, data, value):
        x = data["depth_mm"] / data["_h"]
        return 1.0 + p["gamma"] * x * x


#: nu and w/h grids of :class:`FemLaw`'s table of kappa_n ratios (the FEM table's nu
#: range; w/h to its reach, 0.2 x ``TABLE_EXTRAPOLATION``).
_FEM_NU = np.linspace(0.30, 0.499, 61)
_FEM_X = np.linspace(0.0, 0.229, 93)


@lru_cache(maxsize=64)
def _fem_ratio_table(a_over_h: float) -> np.ndarray:
    """kappa_n(nu, a/h, w/h) / kappa_n(nu, a/h, 0) on ``_FEM_NU`` x ``_FEM_X``."""
    k = kappa_n_grid(_FEM_NU, a_over_h, _FEM_X)
    return k / k[:, :1]


class FemLaw(Effect):
    """The FEM's finite-strain stiffening: P = c w kappa_n(nu, a/h, w/h) / kappa_0.

    The base law of ``IndentationModel(base='fem')``: the compressible
    Neo-Hookean layer's P(w) from the project's FEM table
    (:func:`~tactilevision.mechanics.kappa_n`, ``models/beta_fem.npz``)
    instead of eq. (5)'s straight line in P/w, with c = 2 a E kappa_0 /
    (1 - nu^2) (eq. 1-2) and nu the shape's parameter (0.30 to 0.499, the
    table's range). Its curvature is the FEM's, so eq. (5)'s own misfit
    (:class:`LawCurvature`) is not in the comparison. Needs a/h (the model's
    ``a_over_h``) and w/h within the table (up to 0.23).
    """

    name = "fem_law"
    params = (Param("nu", 0.45, float(_FEM_NU[0]), float(_FEM_NU[-1]), ""),)
    columns = ("depth_mm",)

    def apply(self, p, data, value):
        # a depth effect may push a shallow press below zero: the law starts at w = 0
        x = np.maximum(np.asarray(data["depth_mm"], np.float64) / data["_h"], 0.0)
        if np.any(x > _FEM_X[-1]):
            raise InputError(f"fem_law: w/h reaches {float(x.max()):.3f}, beyond the FEM "
                             f"table's {_FEM_X[-1]:.2f}")
        table = _fem_ratio_table(round(float(data["_a_over_h"]), 9))
        # bilinear between nodes 0.0033 apart in nu and 0.0025 in w/h (the ratio is smooth)
        nu = float(np.clip(p["nu"], _FEM_NU[0], _FEM_NU[-1]))
        j = int(np.clip(np.searchsorted(_FEM_NU, nu) - 1, 0, _FEM_NU.size - 2))
        t = (nu - _FEM_NU[j]) / (_FEM_NU[j + 1] - _FEM_NU[j])
        row = (1 - t) * table[j] + t * table[j + 1]
        return np.interp(x, _FEM_X, row)


#: The catalogue: name -> effect class (formats.md §4, names are the contract).
EFFECTS: dict[str, type[Effect]] = {
    c.name: c for c in (LargeDeformation, DepthOffset, ForceOffset, ForceDrift,
                        ViscoelasticRelaxation, IncompleteRecovery, Aging,
                        SpatialNonuniformity, ForceCrosstalk)
}


#: Effects that take a column after a colon: ``<kind>:<column>``.
COLUMN_EFFECTS: dict[str, type[Effect]] = {
    "stiffness_trend": StiffnessTrend,
    "stiffness_step": StiffnessStep,
    "force_trend": ForceTrend,
}



def make_effect(name: str | Effect | type[Effect]) -> Effect:
    """An effect by its name: the catalogue's, a column effect's or a user effect's.

    Parameters
    ----------
    name : str, Effect or Effect subclass
        A catalogue name (:data:`EFFECTS`, ``law_curvature``),
        ``<kind>:<column>`` of :data:`COLUMN_EFFECTS`
        (``stiffness_trend:temperature_c``), the name of an effect registered
        by :func:`register_effect`, or an import spec of a user effect,
        ``'package.module:ClassName'`` or ``'path/to/file.py:ClassName'``
        (imported, registered, then made; a module not found on
        :data:`sys.path` is looked for in the current working directory). An
        :class:`Effect` subclass or instance is registered and returned.

    Returns
    -------
    effect : Effect

    Raises
    ------
    InputError
        For a name neither in the catalogue nor registered (the message lists
        the valid names), a column effect without its column, or an import
        spec that cannot be imported or names no valid effect (the message
        names the spec and what is wrong).

    Examples
    --------
    >>> make_effect("aging").params
    (Param(name='k_per_day', value=0.0, lower=-0.1, upper=0.1, unit='1/day'),)
    >>> make_effect("stiffness_trend:temperature_c").columns
    ('temperature_c',)
    """
    if not isinstance(name, str):
        return _USER_EFFECTS[_register(name)]
    kind, colon, column = name.partition(":")
    if colon and kind in COLUMN_EFFECTS:
        return COLUMN_EFFECTS[kind](column.strip())
    if name == LawCurvature.name:
        return LawCurvature()
    if name == FemLaw.name:
        return FemLaw()
    if name in EFFECTS:
        return EFFECTS[name]()
    if name in _USER_EFFECTS:
        return _USER_EFFECTS[name]
    if colon:
        return _USER_EFFECTS[_register(_import_effect(name), f"effect '{name}'")]
    valid = [*EFFECTS, *(k + ":<column>" for k in COLUMN_EFFECTS), *_USER_EFFECTS]
    raise InputError(f"unknown effect '{name}'; valid names: {', '.join(valid)}, or "
                     "package.module:ClassName for an Effect subclass of your own")


# ----------------------------------------------------------------- user effects

#: Effects registered by :func:`register_effect` (process-wide): name -> the effect.
_USER_EFFECTS: dict[str, Effect] = {}

#: Kinds of effect, in the order they act (:meth:`IndentationModel.predict`).
_KINDS = ("depth", "stiffness", "force")

#: Modules loaded from a file path (``path/to/file.py:ClassName``): resolved path -> name.
_FILE_MODULES: dict[str, str] = {}


def _bad_token(text: str) -> str | None:
    """What makes `text` unfit for an effect or parameter name (None: nothing)."""
    if not text:
        return "is empty"
    for ch, what in ((",", "a comma"), (":", "a colon"), (".", "a dot")):
        if ch in text:
            return f"holds {what}"
    if any(ch.isspace() for ch in text):
        return "holds white space"
    return None


def _check_effect(effect: Effect, label: str) -> str:
    """Validate a user effect; return its name. `label` names it in the messages."""
    name = getattr(effect, "name", None)
    if not isinstance(name, str):
        raise InputError(f"{label}: its name must be a str, got {name!r}")
    bad = _bad_token(name)
    if bad is not None:
        raise InputError(f"{label}: its name {name!r} {bad} (names are written in "
                         "comma-separated lists, parameters as <effect>.<param>)")
    if name in EFFECTS or name in COLUMN_EFFECTS or name == LawCurvature.name:
        raise InputError(f"{label}: its name '{name}' is taken by the catalogue; give it "
                         "another name")
    params = getattr(effect, "params", None)
    if not isinstance(params, tuple | list) or not all(isinstance(q, Param) for q in params):
        raise InputError(f"{label}: params must be a tuple of "
                         f"tactilevision.mechanics.Param, got {params!r}")
    seen: set[str] = set()
    for q in params:
        bad = _bad_token(q.name) if isinstance(q.name, str) else "is not a str"
        if bad is not None:
            raise InputError(f"{label}: parameter name {q.name!r} {bad}")
        if q.name in seen:
            raise InputError(f"{label}: parameter {q.name} appears twice")
        seen.add(q.name)
        try:
            lo, hi, v = float(q.lower), float(q.upper), float(q.value)
        except (TypeError, ValueError):
            raise InputError(f"{label}: parameter {q.name} has a value or bound that is not "
                             f"a number ({q.value!r}, {q.lower!r}, {q.upper!r})") from None
        if not lo < hi:
            raise InputError(f"{label}: parameter {q.name} needs lower < upper, got bounds "
                             f"[{lo:g}, {hi:g}]")
        if not (math.isfinite(v) and lo <= v <= hi):
            raise InputError(f"{label}: the start value {v:g} of parameter {q.name} is not "
                             f"a finite number within its bounds [{lo:g}, {hi:g}]")
    columns = getattr(effect, "columns", None)
    if (not isinstance(columns, tuple | list) or not columns
            or not all(isinstance(c, str) and c for c in columns)):
        raise InputError(f"{label}: columns must be a non-empty tuple of column names (str), "
                         f"got {columns!r}")
    for c in columns:
        if c == "force_n" or c.startswith("_"):
            raise InputError(f"{label}: it cannot read the column {c!r} (the force is what "
                             "the model predicts; names starting with '_' are internal: "
                             "data['_h'] is given to apply anyway)")
    if getattr(effect, "kind", None) not in _KINDS:
        raise InputError(f"{label}: kind must be one of {', '.join(_KINDS)}, got "
                         f"{getattr(effect, 'kind', None)!r}")
    if type(effect).apply is Effect.apply:
        raise InputError(f"{label}: it does not implement apply(p, data, value)")
    return name


def _same_class(a: type, b: type) -> bool:
    """`a` and `b` are one class, or one class defined again (a notebook cell run twice)."""
    return a is b or (a.__module__, a.__qualname__) == (b.__module__, b.__qualname__)


def register_effect(effect: type[Effect] | Effect) -> str:
    """Register an effect of your own so that models, ``fit`` and ``diagnose`` take its name.

    An effect is a subclass of :class:`Effect` with a :attr:`~Effect.name`,
    its :attr:`~Effect.params` (:class:`Param`: start value, bounds, unit),
    the :attr:`~Effect.columns` of the measurements table it reads, its
    :attr:`~Effect.kind` and the physics in :meth:`~Effect.apply`. Models
    (:class:`IndentationModel`), :func:`fit_model` and :func:`diagnose` take
    the class, an instance, the registered name or an import spec
    ``'package.module:ClassName'`` (registered on first use); so does the
    command line's ``--effects``. The registry lasts as long as the process.

    Parameters
    ----------
    effect : Effect subclass or Effect instance
        A class is made without arguments; an instance (e.g. one configured by
        its constructor) is used as it is.

    Returns
    -------
    name : str
        The effect's name, the model's currency: parameters are reported as
        ``<name>.<param>``.

    Raises
    ------
    InputError
        For something not an :class:`Effect` subclass or instance; a class
        that cannot be made without arguments; a name that is empty, holds a
        comma, colon, dot or white space, or is taken by the catalogue
        (:data:`EFFECTS`, the column effects, ``law_curvature``) or by another
        registered class; params not a tuple of :class:`Param`, a parameter
        with lower >= upper or a start value outside its bounds; no columns
        (or ``force_n``); a kind not ``'depth'``, ``'stiffness'`` or
        ``'force'``; :meth:`~Effect.apply` not implemented. Registering the
        same class (or the same class defined again) under its name again
        replaces the earlier registration.

    Examples
    --------
    >>> import numpy as np
    >>> from tactilevision.mechanics import Effect, IndentationModel, Param, register_effect
    >>> class Humidity(Effect):
    ...     '''Stiffness falling with relative humidity, P (1 - s (RH - 40 %)).'''
    ...     name = "humidity"
    ...     params = (Param("s_per_pct", 0.0, -0.05, 0.05, "1/%"),)
    ...     columns = ("humidity_pct",)
    ...     kind = "stiffness"
    ...     def apply(self, p, data, value):
    ...         return 1.0 - p["s_per_pct"] * (data["humidity_pct"] - 40.0)
    >>> register_effect(Humidity)
    'humidity'
    >>> IndentationModel(effects=(Humidity,)).param_names()
    ('c_n_per_mm', 'large_deformation.beta', 'humidity.s_per_pct')
    """
    return _register(effect)


def _register(effect: type[Effect] | Effect, label: str | None = None) -> str:
    """:func:`register_effect`; `label` names the effect in the messages (default: its class)."""
    if isinstance(effect, type):
        label = label or f"effect class {effect.__module__}.{effect.__qualname__}"
        if not issubclass(effect, Effect):
            raise InputError(f"{label} is not a subclass of tactilevision.mechanics.Effect")
        try:
            inst = effect()
        except Exception as exc:
            raise InputError(f"{label} cannot be made without arguments ({type(exc).__name__}: "
                             f"{exc}); register an instance instead") from None
    elif isinstance(effect, Effect):
        inst = effect
        label = label or f"effect {type(effect).__module__}.{type(effect).__qualname__}"
    else:
        raise InputError(f"{effect!r} is not an Effect: a subclass of "
                         "tactilevision.mechanics.Effect (or an instance of one) is needed")
    name = _check_effect(inst, label)
    old = _USER_EFFECTS.get(name)
    if old is not None and not _same_class(type(old), type(inst)):
        raise InputError(f"{label}: the effect name '{name}' is taken by "
                         f"{type(old).__module__}.{type(old).__qualname__}; give it another "
                         "name")
    _USER_EFFECTS[name] = inst
    return name


def is_registered(name: str) -> bool:
    """Whether `name` is the name of an effect registered by :func:`register_effect`.

    Parameters
    ----------
    name : str

    Returns
    -------
    bool
    """
    return name in _USER_EFFECTS


def _import_module(modname: str, spec: str) -> object:
    """Import `modname` (then from the working directory); InputError naming `spec`."""
    if modname.endswith(".py") or "/" in modname or os.sep in modname:
        path = Path(modname).expanduser().resolve()
        if not path.is_file():
            raise InputError(f"effect '{spec}': no such file {path}")
        key = str(path)
        if key in _FILE_MODULES and _FILE_MODULES[key] in sys.modules:
            return sys.modules[_FILE_MODULES[key]]
        stem = "".join(ch if ch.isalnum() else "_" for ch in path.stem)
        name = f"tactilevision_user_{stem}_{hashlib.sha1(key.encode()).hexdigest()[:8]}"
        mspec = importlib.util.spec_from_file_location(name, path)
        if mspec is None or mspec.loader is None:
            raise InputError(f"effect '{spec}': {path} cannot be imported as a Python module")
        module = importlib.util.module_from_spec(mspec)
        sys.modules[name] = module
        try:
            mspec.loader.exec_module(module)
        except Exception as exc:
            del sys.modules[name]
            raise InputError(f"effect '{spec}': importing {path} failed: "
                             f"{type(exc).__name__}: {exc}") from None
        _FILE_MODULES[key] = name
        return module
    if not all(part.isidentifier() for part in modname.split(".")):
        raise InputError(f"effect '{spec}': {modname!r} is not a module name; an effect of "
                         "your own is given as package.module:ClassName or "
                         "path/to/file.py:ClassName")

    def attempt():
        try:
            return importlib.import_module(modname)
        except ModuleNotFoundError as exc:
            if exc.name is not None and (modname == exc.name
                                         or modname.startswith(exc.name + ".")):
                return None       # the module itself (not one it imports) is not there
            raise InputError(f"effect '{spec}': importing {modname} failed: "
                             f"{type(exc).__name__}: {exc}") from None
        except Exception as exc:
            raise InputError(f"effect '{spec}': importing {modname} failed: "
                             f"{type(exc).__name__}: {exc}") from None

    module = attempt()
    if module is None:
        cwd = os.getcwd()
        importlib.invalidate_caches()
        sys.path.insert(0, cwd)
        try:
            module = attempt()
        finally:
            sys.path.remove(cwd)
    if module is None:
        raise InputError(f"effect '{spec}': no module named {modname} on the Python path or "
                         f"in the working directory {cwd}")
    return module


def _import_effect(spec: str) -> type[Effect] | Effect:
    """The effect an import spec ``'package.module:ClassName'`` names (not yet registered)."""
    modname, _, attr = spec.strip().rpartition(":")
    modname, attr = modname.strip(), attr.strip()
    if not modname or not attr:
        raise InputError(f"effect '{spec}': an effect of your own is given as "
                         "package.module:ClassName or path/to/file.py:ClassName")
    module = _import_module(modname, spec)
    obj = module
    for part in attr.split("."):
        if not hasattr(obj, part):
            raise InputError(f"effect '{spec}': {modname} has no attribute {attr}")
        obj = getattr(obj, part)
    if isinstance(obj, type):
        if not issubclass(obj, Effect):
            raise InputError(f"effect '{spec}': {attr} is not a subclass of "
                             "tactilevision.mechanics.Effect")
    elif not isinstance(obj, Effect):
        raise InputError(f"effect '{spec}': {attr} is not an Effect subclass "
                         f"(tactilevision.mechanics.Effect) but of type {type(obj).__name__}")
    return obj


def effect_name(effect: str | Effect | type[Effect]) -> str:
    """The name a model holds for `effect`, checked (user effects and specs registered).

    Parameters
    ----------
    effect : str, Effect or Effect subclass
        As :func:`make_effect`.

    Returns
    -------
    name : str
        ``stiffness_trend:<column>`` without spaces around the column; the
        registered name of a user effect or import spec.

    Raises
    ------
    InputError
        As :func:`make_effect`.
    """
    return make_effect(effect).name
