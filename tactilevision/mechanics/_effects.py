"""Names of the effect catalogue (``formats.md`` §4) and what ``fit`` accepts.

The effects themselves (classes with parameters, composed into models) are
in :mod:`tactilevision.mechanics._catalogue`, and the names here are read from
it; the command line checks names here without building a model. Effects of your own
(:func:`~tactilevision.mechanics.register_effect`) are given as
``package.module:ClassName``: :func:`effect_names` imports and checks them
before any table is read.
"""

from __future__ import annotations

from collections.abc import Sequence

from .._checks import InputError
from ._catalogue import COLUMN_EFFECTS, EFFECTS, effect_name, is_registered

__all__ = ["EFFECT_NAMES", "EFFECT_SIZE_PARAMS", "FIT_EFFECTS", "check_fit_effects",
           "effect_names", "model_label"]

#: Catalogue names, part of the public contract (docs/formats.md §5): the classes of
#: :data:`~tactilevision.mechanics.EFFECTS` in their order, then
#: ``stiffness_trend:<column>``, ``stiffness_step:<column>`` and ``force_trend:<column>``,
#: which take any covariate column after the colon. Read from the catalogue itself, the
#: one place the effects are listed.
EFFECT_NAMES = tuple(EFFECTS) + tuple(f"{k}:<column>" for k in COLUMN_EFFECTS)

#: The catalogue's effects that take a column: ``<kind>:<column>``.
COLUMN_KINDS = tuple(COLUMN_EFFECTS)

#: Effects of the paper's base model, eq. (5), which
#: :func:`~tactilevision.mechanics.fit_indentation` fits.
FIT_EFFECTS = ("large_deformation",)


#: The parameter that sizes each catalogue effect in a plan and in what a table rules out
#: (``[plan.detect]``, :func:`~tactilevision.planning.effect_sensitivity`,
#: :func:`~tactilevision.diagnosis.table_sensitivity`), its display unit and the factor
#: from the parameter's own unit to it. Two-parameter effects are sized along their
#: first parameter, the second at zero (``force_drift``'s curvature, the y gradient,
#: ``ky``).
EFFECT_SIZE_PARAMS: dict[str, tuple[str, str, float]] = {
    "depth_offset": ("delta_mm", "um", 1e3),
    "force_offset": ("offset_n", "mN", 1e3),
    "force_drift": ("drift_n_per_s", "mN/s", 1e3),
    "viscoelastic_relaxation": ("g", "", 1.0),
    "incomplete_recovery": ("r", "", 1.0),
    "aging": ("k_per_day", "1/day", 1.0),
    "spatial_nonuniformity": ("gx_per_mm", "1/mm", 1.0),
    "force_crosstalk": ("kx", "", 1.0),
}

def _in_catalogue(name: str) -> bool:
    kind, colon, column = name.partition(":")
    if colon and kind in COLUMN_KINDS:
        return bool(column.strip())
    return name in EFFECT_NAMES


def effect_names(specs: Sequence[str]) -> tuple[str, ...]:
    """Check effect names and import specs; return the model's names, each once.

    Parameters
    ----------
    specs : sequence of str
        Catalogue names (formats.md §4), ``<kind>:<column>``, names registered
        by :func:`~tactilevision.mechanics.register_effect`, or import specs
        of effects of your own, ``package.module:ClassName`` or
        ``path/to/file.py:ClassName`` (imported and registered here, so a
        bad one is reported before any table is read).

    Returns
    -------
    names : tuple of str
        In the order given, each once: import specs replaced by their
        effects' names, ``<kind>: <column>`` written without the spaces.

    Raises
    ------
    InputError
        For an unknown name (the message lists the valid names),
        ``stiffness_trend:`` (or another column effect) without a column, or
        an import spec whose module or class is not found, whose class is
        not an ``Effect`` subclass or is invalid (bounds, name taken by the
        catalogue, ...): the message names the spec.
    """

    out: list[str] = []
    for spec in specs:
        kind, colon, column = spec.partition(":")
        if colon and kind in COLUMN_KINDS and not column.strip():
            raise InputError(f"{kind} needs a column: {kind}:<column>")
        if _in_catalogue(spec):
            name = f"{kind}:{column.strip()}" if colon else spec
        elif colon or is_registered(spec):
            name = effect_name(spec)
        else:
            raise InputError(
                f"unknown effect '{spec}'; valid names: {', '.join(EFFECT_NAMES)}, or "
                "package.module:ClassName for an Effect subclass of your own"
            )
        if name not in out:
            out.append(name)
    return tuple(out)


def check_fit_effects(names: Sequence[str]) -> tuple[str, ...]:
    """Check effect names requested of ``fit``; return the model's effect names.

    Parameters
    ----------
    names : sequence of str
        Catalogue names (formats.md §4), e.g. ``["incomplete_recovery"]``,
        names of registered effects, or import specs of effects of your own
        (``"my_effects:TemperatureStiffening"``, see :func:`effect_names`);
        ``large_deformation`` (the paper's base) is always in the model.

    Returns
    -------
    effects : tuple of str
        ``large_deformation`` then the other names in the order given, each
        once (import specs replaced by their registered names).

    Raises
    ------
    InputError
        For an unknown name (the message lists the valid names),
        ``stiffness_trend:`` (or another column effect) without a column, or
        an import spec that cannot be imported or names no valid effect (the
        message names the spec and what is wrong).
    """
    out = list(FIT_EFFECTS)
    for name in effect_names(names):
        if name not in out:
            out.append(name)
    return tuple(out)


def model_label(names: Sequence[str]) -> str:
    """How ``fit`` and ``diagnose`` name a model: the base law, then its effects.

    Parameters
    ----------
    names : sequence of str
        The model's effect names (``IndentationModel.names``), optionally
        preceded by ``'layer'`` (as ``Diagnosis.model``).

    Returns
    -------
    label : str
        ``'eq. (5) [layer + large_deformation]'`` for the paper's base, then
        ``' + <effect>'`` for each further effect; ``'layer'`` (eq. 2) for
        the small-strain base; ``'FEM law [layer + fem_law]'`` for the FEM's
        finite-strain base (``IndentationModel(base='fem')``).

    Examples
    --------
    >>> model_label(("large_deformation", "incomplete_recovery"))
    'eq. (5) [layer + large_deformation] + incomplete_recovery'
    >>> model_label(("layer", "force_offset"))
    'layer + force_offset'
    """
    rest = [n for n in names if n != "layer"]
    if rest[:1] == ["large_deformation"]:
        return " + ".join(["eq. (5) [layer + large_deformation]", *rest[1:]])
    if rest[:1] == ["fem_law"]:
        return " + ".join(["FEM law [layer + fem_law]", *rest[1:]])
    return " + ".join(["layer", *rest])
