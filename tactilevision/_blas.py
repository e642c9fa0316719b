"""BLAS thread counts: the loaded OpenBLAS libraries' own setters (Linux).

Shared by the FEM's condensation and the live pipeline; no other imports from
the package (bottom layer, beside ``_checks`` and ``_cache``).
"""

from __future__ import annotations

import ctypes

__all__ = ["openblas_thread_controls"]


def openblas_thread_controls() -> list[tuple[object, object]]:
    """(set, get) num-threads functions of the OpenBLAS libraries loaded (Linux)."""
    try:
        with open("/proc/self/maps") as maps:
            paths = sorted({line.split()[-1] for line in maps
                            if "openblas" in line.lower() and ".so" in line})
    except OSError:
        return []
    controls = []
    for path in paths:
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        for name in ("scipy_openblas_{}_num_threads64_", "scipy_openblas_{}_num_threads",
                     "openblas_{}_num_threads64_", "openblas_{}_num_threads"):
            setter = getattr(lib, name.format("set"), None)
            getter = getattr(lib, name.format("get"), None)
            if setter is not None and getter is not None:
                getter.restype = ctypes.c_int
                controls.append((setter, getter))
                break
    return controls
