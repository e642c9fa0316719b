"""Names of the effect catalogue (``formats.md`` §4) and what ``fit`` accepts.

The effects themselves (classes with parameters, composed into models) are
in :mod:`tactilevision.mechanics._model`; the names live here so that the
command line can check them without building a model.
"""

from __future__ import annotations

from collections.abc import Sequence

from .._checks import InputError

__all__ = ["EFFECT_NAMES", "FIT_EFFECTS", "check_fit_effects"]

#: Catalogue names, part of the public contract (docs/formats.md §5);
#: ``stiffness_trend:<column>``, ``stiffness_step:<column>`` and ``force_trend:<column>``
#: take any covariate column after the colon.
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
    "stiffness_step:<column>",
    "force_trend:<column>",
)

#: The catalogue's effects that take a column: ``<kind>:<column>``.
COLUMN_KINDS = ("stiffness_trend", "stiffness_step", "force_trend")

#: Effects of the paper's base model, eq. (5), which
#: :func:`~tactilevision.mechanics.fit_indentation` fits.
FIT_EFFECTS = ("large_deformation",)


def _in_catalogue(name: str) -> bool:
    kind, colon, column = name.partition(":")
    if colon and kind in COLUMN_KINDS:
        return bool(column.strip())
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
        ``stiffness_trend:`` (or another column effect) without a column.
    """
    out = list(FIT_EFFECTS)
    for name in names:
        if not _in_catalogue(name):
            kind = name.partition(":")[0]
            if name.endswith(":") and kind in COLUMN_KINDS:
                raise InputError(f"{kind} needs a column: {kind}:<column>")
            raise InputError(
                f"unknown effect '{name}'; valid names: {', '.join(EFFECT_NAMES)}"
            )
        if name not in out:
            out.append(name)
    return tuple(out)
