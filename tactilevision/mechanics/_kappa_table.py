"""The container of a tabulated layer factor kappa(nu, a/h), :class:`KappaTable`.

Its own module, below both :mod:`._kappa` (the Hayes table, the interpolation
rule) and :mod:`._fem_tables` (the FEM table), which both build or read one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["KappaTable"]


@dataclass(frozen=True)
class KappaTable:
    """A tabulated kappa(nu, a/h) with its provenance.

    Attributes
    ----------
    a_over_h : (M,) float64 ndarray, dimensionless
        Indenter radius over layer thickness, strictly increasing.
    nu : (K,) float64 ndarray, dimensionless
        Poisson's ratios, strictly increasing.
    values : (M, K) float64 ndarray, dimensionless
        ``values[i, j] = kappa(nu[j], a_over_h[i])``.
    source : str
        Author, year, journal and table the values come from.
    doi : str
        DOI of the source.
    """

    a_over_h: np.ndarray
    nu: np.ndarray
    values: np.ndarray
    source: str
    doi: str

    def __post_init__(self) -> None:
        for arr in (self.a_over_h, self.nu, self.values):
            arr.setflags(write=False)
