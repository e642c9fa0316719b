"""Names of the effect catalogue (``formats.md`` §4) and what ``fit`` accepts.

The effects themselves (classes with parameter hints, composed into models)
arrive with ``diagnose`` in a later issue; until then only the names are
known here so that ``fit --effects`` can say which it supports.
"""

from __future__ import annotations

from collections.abc import Sequence

from .._checks import InputError

__all__ = ["EFFECT_NAMES", "FIT_EFFECTS", "check_fit_effects"]

#: Catalogue names, part of the public contract (formats.md §4);
#: ``stiffness_trend:<column>`` takes any covariate column after the colon.
EFFECT_NAMES = (
    "large_deformation",
    "depth_offset",
    "force_offset",
    "force_drift",
    "viscoelastic_relaxation",
    "incomplete_recovery",
    "aging",
    "spatial_nonuniformity",
    "stiffness_trend:<column>",
)

#: Effects :func:`~tactilevision.mechanics.fit_indentation` fits: the base
#: model of the paper, eq. (5), already holds ``large_deformation``.
FIT_EFFECTS = ("large_deformation",)


def _in_catalogue(name: str) -> bool:
    if name.startswith("stiffness_trend:"):
        return bool(name.partition(":")[2].strip())
    return name in EFFECT_NAMES


def check_fit_effects(names: Sequence[str]) -> tuple[str, ...]:
    """Check effect names requested of ``fit``; return the effects fitted.

    Parameters
    ----------
    names : sequence of str
        Catalogue names (formats.md §4), e.g. ``["large_deformation"]``.

    Returns
    -------
    effects : tuple of str
        ``FIT_EFFECTS``: the base model, which all accepted requests reduce to.

    Raises
    ------
    InputError
        For a catalogue effect that ``fit`` does not fit yet (the catalogue
        arrives with ``diagnose`` in a later issue), or for an unknown name
        (the message lists the valid names).
    """
    for name in names:
        if name in FIT_EFFECTS:
            continue
        if _in_catalogue(name):
            raise InputError(
                f"effect '{name}' is in the catalogue, but fitting it arrives with "
                f"`diagnose` in a later issue; `fit` supports: {', '.join(FIT_EFFECTS)}"
            )
        raise InputError(
            f"unknown effect '{name}'; valid names: {', '.join(EFFECT_NAMES)}"
        )
    return FIT_EFFECTS
