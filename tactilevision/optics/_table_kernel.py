"""The first-order table lookup compiled by numba (the ``fast`` extra): one pass a pixel.

A gradient table's lookup (``GradientTable.gradients``) on a first-order table is a
chain of whole-image OpenCV and numpy operations (the colour coordinates, their cell, a
32-byte gather, a transpose into planes, six multiply-adds), each of which reads and
writes the whole frame. :func:`first_order_kernel` compiles the same arithmetic as one
loop over the pixels, which keeps a pixel's values in registers. On gs_sdk's GelSight
Mini network at 320 x 240 (order 1, 16 cells) the whole reconstruction took 1.36 to
1.42 times a DCT-II pair plus a gather with it, against 1.54 to 1.65 without it in the
same rounds, one thread, the angles to gs_sdk unchanged
(``benchmarks/bench_table_order.py``, three runs of two rounds, 2-core x86_64,
2026-11-27); its gradients were
bit-identical to the OpenCV path's on those six presses. The plane's multiply-adds are
fused (``fastmath={'contract'}``), as OpenCV's ``accumulateProduct`` fuses them; nothing
else is reordered.

numba is optional: without it (or with ``kernel='numpy'``) the OpenCV path runs. Its
cost is paid once per process, when a reconstructor of a first-order table is built:
importing numba (0.10 to 0.11 s) and reading the kernel back from numba's disk cache
(0.10 to 0.13 s), beside 0.51 to 0.54 s for importing ``tactilevision.optics`` in the
same three fresh processes; compiling it the first time on a machine took 0.48 s
(beside 0.54 s). 2-core x86_64, 2026-11-27.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from .._checks import InputError

__all__ = ["KERNELS", "check_kernel", "first_order_kernel"]

#: The ``kernel`` choices: 'auto' (numba where installed, else OpenCV and numpy),
#: 'numba' (required: an error without it), 'numpy' (the OpenCV and numpy path).
KERNELS = ("auto", "numba", "numpy")

_COMPILED: dict[str, Callable | None] = {}


def check_kernel(kernel: str) -> None:
    """Raise :class:`InputError` naming `kernel` unless it is one of :data:`KERNELS`."""
    if kernel not in KERNELS:
        raise InputError(f"kernel must be one of {', '.join(KERNELS)}, got {kernel!r}")


def _lookup(frame: np.ndarray, scale_map: np.ndarray, coef: np.ndarray, top: np.float32,
            bins: int, cell_offset: np.ndarray, slopes: np.ndarray, gx: np.ndarray,
            gy: np.ndarray) -> None:
    """gx, gy of a first-order table, pixel by pixel (compiled by numba; see
    :meth:`GradientTable.gradients`'s notes for the arithmetic)."""
    h, w = gx.shape
    n = h * w
    b2 = bins * bins
    f = frame.reshape(n * 3)
    s = scale_map.reshape(n * 3)
    cell = cell_offset.reshape(n)
    ox = gx.reshape(n)
    oy = gy.reshape(n)
    rows = slopes.reshape(slopes.shape[0] * 8)
    g0, g1, g2, o0, o1, o2 = coef[0], coef[1], coef[2], coef[3], coef[4], coef[5]
    zero = np.float32(0.0)
    for p in range(n):
        k = 3 * p
        # as cv2.multiply (float32 product), cv2.transform (1 / gain, offset), then
        # THRESH_TRUNC at top and THRESH_TOZERO
        q0 = min(max(np.float32(f[k]) * s[k] * g0 + o0, zero), top)
        q1 = min(max(np.float32(f[k + 1]) * s[k + 1] * g1 + o1, zero), top)
        q2 = min(max(np.float32(f[k + 2]) * s[k + 2] * g2 + o2, zero), top)
        r = 8 * (cell[p] + np.int32(q0) * b2 + np.int32(q1) * bins + np.int32(q2))
        ox[p] = rows[r] + rows[r + 2] * q0 + rows[r + 4] * q1 + rows[r + 6] * q2
        oy[p] = rows[r + 1] + rows[r + 3] * q0 + rows[r + 5] * q1 + rows[r + 7] * q2


def _signature(t: Any) -> Any:
    """The one signature compiled: the inputs read-only (the tables are shared, read-only
    arrays; ``GradientTable.gradients`` passes read-only views of the rest), C order;
    frame, scale map, (1 / gain, offset), top, bins, cell offsets, rows, then gx, gy."""
    def ro(dtype: Any, ndim: int) -> Any:
        return t.Array(dtype, ndim, "C", readonly=True)

    out = t.Array(t.float32, 2, "C")
    return t.void(ro(t.uint8, 3), ro(t.float32, 3), ro(t.float32, 1), t.float32, t.int64,
                  ro(t.int32, 2), ro(t.float32, 2), out, out)


def _compile(numba: Any) -> Callable:
    """The kernel compiled now, for :func:`_signature`'s types only (the caller makes them:
    never compiled on a frame), kept in numba's disk cache; compiled afresh each process
    where no cache folder can be written (numba finds none beside an installed package
    and none in the user's cache folder)."""
    options = dict(nogil=True, boundscheck=False, fastmath={"contract"})
    try:
        return numba.njit(_signature(numba.types), cache=True, **options)(_lookup)
    except RuntimeError:                 # "cannot cache function ...: no locator available"
        return numba.njit(_signature(numba.types), **options)(_lookup)


def first_order_kernel(kernel: str = "auto") -> Callable | None:
    """The compiled first-order lookup, or None where the OpenCV path is to run.

    Parameters
    ----------
    kernel : {'auto', 'numba', 'numpy'}, default 'auto'
        'auto': compiled where numba is installed (``pip install
        'tactilevision[fast]'``), else None; 'numba': compiled, numba required;
        'numpy': None.

    Returns
    -------
    callable or None
        ``f(frame, scale_map, coef, top, bins, cell_offset, slopes, gx, gy)``, writing
        gx and gy in place; compiled once per process (numba's disk cache keeps it
        between processes).

    Raises
    ------
    InputError
        For an unknown `kernel`, or 'numba' without numba installed.
    """
    check_kernel(kernel)
    if kernel == "numpy":
        return None
    if "numba" not in _COMPILED:
        try:
            import numba
        except ImportError:
            numba = None
        _COMPILED["numba"] = None if numba is None else _compile(numba)
    compiled = _COMPILED["numba"]
    if compiled is None and kernel == "numba":
        raise InputError("kernel='numba' needs numba, which is not installed: pip install "
                         "'tactilevision[fast]' (or kernel='auto' to run without it)")
    return compiled
