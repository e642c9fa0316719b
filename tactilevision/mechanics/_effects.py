"""Names of the effect catalogue (``formats.md`` §4) and what ``fit`` accepts.

The effects themselves (classes with parameters, composed into models) are
in :mod:`tactilevision.mechanics._model`; the names live here so that the
command line can check them without building a model.
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

#: Effects of the paper's base model, eq. (5), which
#: :func:`~tactilevision.mechanics.fit_indentation` fits.
FIT_EFFECTS = ("large_deformation",)


def _in_catalogue(name: str) -> bool:
    if name.startswith("stiffness_trend:"):
        return bool(name.partition(":")[2].strip())
    return name in EFFECT_NAMES


def check_fit_effects(names: Sequence[str]) -> tuple[str, ...]:
    """Check effect names requested of ``fit``; return the model's effect names.

    Parameters
    ----------
    names : sequence of str
        Catalogue names (formats.md §4), e.g. ``["incomplete_recovery"]``;
        ``large_deformation`` (the paper's base) is always in the model.

    Returns
    -------
    effects : tuple of str
        ``large_deformation`` then the other names in the order given, each
        once.

    Raises
    ------
    InputError
        For an unknown name (the message lists the valid names) or
        ``stiffness_trend:`` without a column.
    """
    out = list(FIT_EFFECTS)
    for name in names:
        if not _in_catalogue(name):
            if name.startswith("stiffness_trend:"):
                raise InputError("stiffness_trend needs a column: stiffness_trend:<column>")
            raise InputError(
                f"unknown effect '{name}'; valid names: {', '.join(EFFECT_NAMES)}"
            )
        if name not in out:
            out.append(name)
    return tuple(out)
