"""One input-check helper for shapes, dtypes and finiteness.

Every public function validates its arrays with :func:`check_array`, which
raises :class:`ShapeError` (a ``ValueError``) naming the argument and showing
the expected against the actual shape or dtype. Bad files and table rows raise
:class:`InputError`, whose message is the one plain sentence the command line
prints before exiting with status 2.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ._errors import InputError, InputWarning, ShapeError

__all__ = ["InputError", "InputWarning", "ShapeError", "check_array", "check_poisson",
           "check_positive", "check_presses"]


def _dims_match(expected: Sequence[int | str | None], shape: tuple[int, ...],
                bound: dict[str, int]) -> bool:
    if len(expected) != len(shape):
        return False
    for e, s in zip(expected, shape, strict=True):
        if e is None:
            continue
        if isinstance(e, str):
            if e in bound and bound[e] != s:
                return False
            bound[e] = s
        elif int(e) != s:
            return False
    return True


def _dtype_name(d: object) -> str:
    if isinstance(d, type) and issubclass(d, np.generic) and d.__name__ in _ABSTRACT:
        return _ABSTRACT[d.__name__]
    return np.dtype(d).name  # type: ignore[arg-type]


def _real_scalar(value: object, name: str, what: str) -> float:
    """`value` as a float when it is a real scalar (not bool, str or complex)."""
    if isinstance(value, bool | str | bytes | complex | np.complexfloating) or np.ndim(value):
        raise InputError(f"{name} must be {what}, got {value!r}")
    try:
        return float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise InputError(f"{name} must be {what}, got {value!r}") from None


def check_positive(value: object, name: str) -> float:
    """A positive, finite real scalar as a float.

    Raises
    ------
    InputError
        Naming `name`, for anything else (bool, string, complex, array,
        zero, negative, NaN, inf).
    """
    v = _real_scalar(value, name, "a positive number")
    if not (math.isfinite(v) and v > 0):
        raise InputError(f"{name} must be positive and finite, got {value!r}")
    return v


def check_poisson(value: object, name: str = "nu") -> float:
    """Poisson's ratio within [0, 0.5) as a float (compressible linear elasticity).

    Raises
    ------
    InputError
        Naming `name`, for a non-real value or one outside [0, 0.5).
    """
    v = _real_scalar(value, name, "a number within [0, 0.5)")
    if not 0.0 <= v < 0.5:
        raise InputError(f"{name} must be within [0, 0.5), got {value!r}")
    return v


_ABSTRACT = {"floating": "float", "integer": "integer", "number": "numeric",
             "unsignedinteger": "unsigned integer", "signedinteger": "signed integer"}


def check_array(
    x: object,
    name: str,
    shapes: Sequence[Sequence[int | str | None]],
    *,
    dtype: type | np.dtype | tuple | None = None,
    finite: bool = False,
) -> np.ndarray:
    """Check an array argument against allowed shapes, dtype and finiteness.

    Parameters
    ----------
    x : array_like
        The argument to check. It is converted with ``np.asarray`` (no copy
        when it already is an ndarray); it is never reshaped or recast.
    name : str
        Argument name, used in the error message.
    shapes : sequence of sequence of {int, str, None}
        Allowed shapes. An int fixes a dimension, ``None`` accepts any size,
        and a string names a dimension whose size must agree wherever the
        same string appears, e.g. ``[("H", "W", 3), ("N", "H", "W", 3)]``.
    dtype : numpy dtype, type or tuple of them, optional
        Allowed dtype(s), tested with ``np.issubdtype``.
    finite : bool, default False
        Require every element to be finite.

    Returns
    -------
    arr : ndarray
        ``np.asarray(x)``.

    Raises
    ------
    ShapeError
        When the shape, dtype or finiteness is wrong; the message names the
        argument and shows expected against actual.
    """
    arr = np.asarray(x)
    if not any(_dims_match(s, arr.shape, {}) for s in shapes):
        want = " or ".join("(" + ", ".join("?" if d is None else str(d) for d in s) + ")"
                           for s in shapes)
        raise ShapeError(f"{name} must have shape {want}, got {arr.shape}")
    if dtype is not None:
        allowed = dtype if isinstance(dtype, tuple) else (dtype,)
        if not any(np.issubdtype(arr.dtype, d) for d in allowed):
            names = " or ".join(_dtype_name(d) for d in allowed)
            raise ShapeError(f"{name} must have dtype {names}, got {arr.dtype}")
    if finite and not np.all(np.isfinite(arr)):
        bad = int(np.size(arr) - np.count_nonzero(np.isfinite(arr)))
        raise ShapeError(f"{name} must be finite, found {bad} NaN or infinite value(s)")
    return arr


def check_presses(depth_mm: object, force_n: object, thickness_mm: object
                  ) -> tuple[np.ndarray, np.ndarray, float]:
    """A table of presses checked: ``(w, P, h)``, depths and forces as (N,) float64
    arrays of one length with finite values, and the layer thickness positive.

    Raises
    ------
    ShapeError
        For arrays of other shapes or lengths.
    InputError
        For values that are not finite, or a thickness that is not positive.
    """
    w = check_array(depth_mm, "depth_mm", [("N",)], dtype=np.number, finite=True)
    P = check_array(force_n, "force_n", [(w.shape[0],)], dtype=np.number, finite=True)
    h = _real_scalar(thickness_mm, "thickness_mm", "a positive number")
    if not (math.isfinite(h) and h > 0):
        raise InputError(f"thickness_mm must be positive, got {thickness_mm!r}")
    return w.astype(np.float64), P.astype(np.float64), h
