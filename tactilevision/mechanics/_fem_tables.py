"""Read the project's FEM tables (``models/kappa_fem.npz``, ``models/beta_fem.npz``).

Built by ``tactilevision fem tables`` (:mod:`tactilevision.fem._tables`); read
here with numpy alone, once per process.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np
from scipy.interpolate import PchipInterpolator, PPoly

from .._assets import asset_dir
from .._checks import InputError
from ._kappa_table import KappaTable

__all__ = ["TABLE_EXTRAPOLATION", "TabulatedBetaRelation", "fem_beta_relation", "fem_force",
           "fem_kappa_table", "fem_table_meta", "kappa_n", "kappa_n_grid"]

#: The FEM's kappa_n(w/h) is read (PCHIP) up to this factor beyond the table's deepest w/h
#: (0.2): a press pushed past the gauge block's w0 = 0.2 h by a stage overshoot (a vernier
#: session with 50 um past 0.6 mm on a 3 mm gel reaches 0.217 h). kappa_n is smooth and
#: nearly linear in w/h there.
TABLE_EXTRAPOLATION = 1.15


@lru_cache(maxsize=4)
def _load(name: str) -> dict:
    path = asset_dir("models") / name
    if not path.is_file():
        raise InputError(f"the FEM table {path} is missing: rebuild it with "
                         "'tactilevision fem tables'")
    with np.load(path, allow_pickle=False) as z:
        data = {k: z[k] for k in z.files}
    data["meta"] = json.loads(data["meta"].tobytes().decode())
    data["path"] = str(path)
    return data


def fem_table_meta(name: str = "kappa_fem.npz") -> dict:
    """Provenance record of a stored FEM table.

    Parameters
    ----------
    name : str, default 'kappa_fem.npz'
        File name of the table in the package's ``models`` folder (as
        written by ``tactilevision fem tables``).

    Returns
    -------
    meta : dict
        The record stored with the table: the command that built it, the
        mesh, the library versions and the date (a copy).

    Raises
    ------
    InputError
        If the table is missing (naming the path and the command that builds it).
    """
    return dict(_load(name)["meta"])


@lru_cache(maxsize=4)
def fem_kappa_table(contact: str = "frictionless") -> KappaTable:
    """The FEM kappa(nu, a/h) table for one punch condition.

    Parameters
    ----------
    contact : {'frictionless', 'bonded'}, default 'frictionless'

    Returns
    -------
    table : KappaTable

    Raises
    ------
    InputError
        If the table file is missing or lacks the contact.
    """
    data = _load("kappa_fem.npz")
    contacts = [str(c) for c in data["contacts"]]
    if contact not in contacts:
        raise InputError(f"contact must be one of {contacts}, got {contact!r}")
    meta = data["meta"]
    return KappaTable(
        a_over_h=data["a_over_h"].astype(np.float64),
        nu=data["nu"].astype(np.float64),
        values=np.ascontiguousarray(data["kappa"][contacts.index(contact)], np.float64),
        source=(f"tactilevision FEM, {contact} punch, small strain ({meta['solver']}; mesh "
                f"{meta['mesh']}; built {meta.get('created', '?')} by "
                f"'{meta.get('command', '?')}')"),
        doi="",
    )


@dataclass(frozen=True)
class TabulatedBetaRelation:
    """beta(nu) of the FEM table at one a/h and punch condition, and its inverse.

    The same interface as :class:`BetaRelation` (the paper's relation), so the
    fit uses either.

    Attributes
    ----------
    a_over_h : float
    contact : str
    definition : {'secant', 'tangent'}
    nu_grid, beta_grid : (N,) float64 ndarray
        beta at the table's nu, interpolated in a/h (PCHIP per nu column).
    source : str
    kappa_line_grid : (N,) float64 ndarray or None
        With press depths given: the intercept of the FEM's kappa_n line
        fitted at them (see :meth:`kappa_line`).
    """

    a_over_h: float
    contact: str
    definition: str
    nu_grid: np.ndarray
    beta_grid: np.ndarray
    source: str
    kappa_line_grid: np.ndarray | None = None

    def kappa_line(self, nu: float) -> float:
        """Intercept of the FEM's kappa_n line at the given depths, at `nu` (PCHIP).

        Only with ``w_over_h`` (:func:`fem_beta_relation`): eq. (4) then reads
        c = 2 a E kappa_line / (1 - nu^2) with the same straight line as beta,
        instead of the small-strain kappa (they differ by the curvature of
        P/w, under 1%).
        """
        return float(self._kappa_line_pchip(nu))

    def dkappa_line_dnu(self, nu: float) -> float:
        """d kappa_line / d nu at `nu`."""
        return float(self._kappa_line_pchip.derivative()(nu))

    # the interpolants, built once per relation (a fit reads them many times)
    @cached_property
    def _kappa_line_pchip(self) -> PchipInterpolator:
        return PchipInterpolator(self.nu_grid, self.kappa_line_grid)

    @cached_property
    def _beta_pchip(self) -> PchipInterpolator:
        return PchipInterpolator(self.nu_grid, self.beta_grid)

    @cached_property
    def _inverse_pchip(self) -> PchipInterpolator:
        first, last = self.branch
        if last == first:
            raise InputError(
                f"the FEM beta ({self.definition}, {self.contact} punch) does not rise with "
                f"nu at a/h = {self.a_over_h:.4g}: nu cannot be recovered from beta there")
        sel = slice(first, last + 1)
        return PchipInterpolator(self.beta_grid[sel], self.nu_grid[sel])

    @property
    def branch(self) -> tuple[int, int]:
        """First and last index of the branch on which nu is recovered from beta.

        ``beta_grid[first:last + 1]`` increases strictly and ends at the
        largest beta of the table. A bonded punch stiffens *less* as nu grows
        at small a/h, and near a/h = 0.8 beta peaks below nu = 0.5: beta then
        tells nu apart only on this rising branch; above its top nu is
        ambiguous or unreachable.
        """
        last = int(np.argmax(self.beta_grid))
        first = last
        while first > 0 and self.beta_grid[first - 1] < self.beta_grid[first]:
            first -= 1
        return first, last

    @property
    def nu_forward_min(self) -> float:
        """Smallest tabulated nu (the range of :meth:`beta`)."""
        return float(self.nu_grid[0])

    @property
    def nu_forward_max(self) -> float:
        """Just above the largest tabulated nu (the range of :meth:`beta`, closed)."""
        return float(np.nextafter(self.nu_grid[-1], 1.0))

    @property
    def nu_min(self) -> float:
        """Smallest nu of the invertible branch (the range of :meth:`nu`)."""
        return float(self.nu_grid[self.branch[0]])

    @property
    def nu_max(self) -> float:
        """Just above the largest nu of the branch (the range is closed, unlike eq. 7's)."""
        return float(np.nextafter(self.nu_grid[self.branch[1]], 1.0))

    @property
    def beta_min(self) -> float:
        """beta at :attr:`nu_min`."""
        return float(self.beta_grid[self.branch[0]])

    @property
    def beta_max(self) -> float:
        """Just above the largest beta of the branch (and of the table)."""
        return float(np.nextafter(self.beta_grid[self.branch[1]], np.inf))

    def _inverse(self):
        return self._inverse_pchip

    def beta(self, nu: float | np.ndarray) -> float | np.ndarray:
        """beta at `nu` (PCHIP in nu over the whole table; no range check)."""
        out = self._beta_pchip(np.asarray(nu, np.float64))
        return float(out) if out.ndim == 0 else out

    def nu(self, beta: float | np.ndarray) -> float | np.ndarray:
        """nu at `beta` (PCHIP of the inverse on the increasing branch; no range check)."""
        out = self._inverse()(np.asarray(beta, np.float64))
        return float(out) if out.ndim == 0 else out

    def dnu_dbeta(self, beta: float) -> float:
        """Slope d nu / d beta of the inverse at `beta`."""
        return float(self._inverse().derivative()(beta))

    def range_text(self) -> str:
        """The invertible range as one phrase, for messages."""
        first, last = self.branch
        return (f"beta in [{self.beta_grid[first]:.4f}, {self.beta_grid[last]:.4f}], i.e. nu "
                f"in [{self.nu_grid[first]:.3f}, {self.nu_grid[last]:.3f}] ({self.contact} punch, "
                f"{self.definition} beta, a/h = {self.a_over_h:.4g})")


@lru_cache(maxsize=64)
def fem_beta_relation(a_over_h: float, *, contact: str = "bonded",
                      definition: str = "secant",
                      w_over_h: tuple[float, ...] | None = None,
                      weights: tuple[float, ...] | None = None) -> TabulatedBetaRelation:
    """The FEM beta(nu) at one a/h, for the fit and for :func:`beta`.

    Parameters
    ----------
    a_over_h : float
        Within the table's a/h range.
    contact : str, default 'bonded'
        A punch condition of the table (it holds 'bonded' only).
    definition : {'secant', 'tangent'}, default 'secant'
        'secant': beta of the straight-line fit of P/w against w/h over
        w/h = 0.02 ... 0.2, the paper's procedure (eq. 5); 'tangent': beta_t
        of dP/dw = c_t (1 + 2 beta_t w/h).
    w_over_h : tuple of float, optional
        The depths of a set of presses (w/h, repeats included, each within
        (0, w/h max of the table]). Given, the secant beta is the one eq. (5)
        fitted at exactly these depths would give on the FEM's kappa_n(w/h)
        (interpolated by PCHIP through kappa0 at w = 0 and the stored
        depths), so a measurement and the table are read alike: P/w is not
        exactly straight (up to 1.1% off its line), and at a/h = 1.2,
        nu = 0.47 the secant beta over w/h 0.06 to 0.2 is 3% above the one
        over 0.02 to 0.2. Secant definition only.
    weights : tuple of float, optional
        With `w_over_h`: the weight (1 / variance of P/w, any common scale)
        of each press in the line of eq. (5), so that a weighted fit and the
        table are read alike. Default: equal weights.

    Returns
    -------
    relation : TabulatedBetaRelation

    Raises
    ------
    InputError
        For a missing table, an a/h outside it, an unknown contact or
        definition, or a table with incomplete sweeps at this a/h.
    """
    data = _load("beta_fem.npz")
    contacts = [str(c) for c in data["contacts"]]
    if contact not in contacts:
        raise InputError(f"contact must be one of {contacts}, got {contact!r}")
    if definition not in ("secant", "tangent"):
        raise InputError(f"definition must be 'secant' or 'tangent', got {definition!r}")
    ah = data["a_over_h"]
    if not ah[0] <= a_over_h <= ah[-1]:
        raise InputError(f"a_over_h = {a_over_h:g} is outside the FEM beta table range "
                         f"[{ah[0]:g}, {ah[-1]:g}]")
    c = contacts.index(contact)
    values = data[f"beta_{definition}"][c]  # (A, N)
    if not np.all(np.isfinite(values)):
        raise InputError(f"the FEM beta table {data['path']} has incomplete sweeps for the "
                         f"{contact} punch: rebuild it")
    if w_over_h is None:
        row = np.array([float(PchipInterpolator(ah, values[:, j])(a_over_h))
                        for j in range(values.shape[1])])
    else:
        if definition != "secant":
            raise InputError("w_over_h applies to the secant beta only")
        x = np.asarray(w_over_h, np.float64)
        wt = np.concatenate([[0.0], data["w_over_h"]])
        top = TABLE_EXTRAPOLATION * wt[-1]
        if x.ndim != 1 or x.size < 2 or np.ptp(x) <= 0 or not np.all((x > 0) & (x <= top + 1e-12)):
            raise InputError(f"w_over_h must hold two distinct depths or more within "
                             f"(0, {top:g}], got {w_over_h!r}")
        k_at = _kappa_n_along_w(float(a_over_h), c)(x)               # (N, n)
        if weights is None:
            wt_fit = None
        else:
            wt_fit = np.asarray(weights, np.float64)
            if wt_fit.shape != x.shape or not np.all(np.isfinite(wt_fit) & (wt_fit > 0)):
                raise InputError(f"weights must hold one finite positive weight per depth, "
                                 f"got {weights!r}")
            wt_fit = np.sqrt(wt_fit / wt_fit.max())  # polyfit weighs residuals by w
        slope, icpt = np.polyfit(x, k_at.T, 1, w=wt_fit)
        row = slope / icpt
    line = None if w_over_h is None else np.asarray(icpt, np.float64)
    meta = data["meta"]
    return TabulatedBetaRelation(
        a_over_h=float(a_over_h), contact=contact, definition=definition,
        nu_grid=data["nu"].astype(np.float64), beta_grid=row, kappa_line_grid=line,
        source=(f"tactilevision FEM, finite-strain Neo-Hookean, {contact} punch, {definition} "
                f"beta (mesh {meta['mesh']}; built {meta.get('created', '?')})"))


@lru_cache(maxsize=64)
def _kappa_n_along_w(a_over_h: float, contact_index: int) -> PchipInterpolator:
    """kappa_n of the FEM table at one a/h (PCHIP across a/h), as a PCHIP along w/h
    through kappa0 at 0 and the stored depths: (N,) per w/h, one per nu of the table."""
    data = _load("beta_fem.npz")
    wt = np.concatenate([[0.0], data["w_over_h"]])
    kn = np.concatenate([data["kappa0"][contact_index][..., None],
                         data["kappa_n"][contact_index]], axis=-1)
    kn_ah = PchipInterpolator(data["a_over_h"], kn, axis=0)(a_over_h)     # (N, K + 1)
    return PchipInterpolator(wt, kn_ah, axis=1)


def _window(x: np.ndarray, x0: float) -> slice:
    """The nodes of a PCHIP through `x` that decide its value at `x0`.

    PCHIP's value in the interval [x_k, x_k+1] that holds x0 is the cubic through the values
    and slopes at nodes k and k+1; an interior node's slope is read from its two secants
    (nodes k-1 to k+2), an end node's from the first or last three nodes. The interpolant
    through this window alone gives the same numbers, from the same operations on the same
    values (tests/test_mechanics_tables.py), at a fraction of the cost where there are many
    columns (a ramp's 600 depths x 14 x 14 nodes)."""
    n = x.size
    k = min(max(int(np.searchsorted(x, x0, side="right")) - 1, 0), n - 2)
    lo, hi = max(k - 1, 0), min(k + 3, n)
    if lo == 0:
        hi = max(hi, min(3, n))
    if hi == n:
        lo = min(lo, max(n - 3, 0))
    return slice(lo, hi)


def _kappa_n_at(data: dict, along_w: PchipInterpolator, nu: float, a_over_h: float,
                w_over_h: np.ndarray) -> np.ndarray:
    """kappa_n at one nu and a/h, at each of `w_over_h` (M,): PCHIP along w/h, nu, then a/h,
    each on the window of nodes that decides the next step's value (:func:`_window`)."""
    a_sl, n_sl = _window(data["a_over_h"], a_over_h), _window(data["nu"], nu)
    part = PPoly.construct_fast(along_w.c[:, :, a_sl, n_sl], along_w.x,
                                along_w.extrapolate)
    k_w = np.moveaxis(part(w_over_h), 0, -1)                                # (A', N', M)
    k_nu = PchipInterpolator(data["nu"][n_sl], k_w, axis=1)(nu)             # (A', M)
    return PchipInterpolator(data["a_over_h"][a_sl], k_nu, axis=0)(a_over_h)  # (M,)


@lru_cache(maxsize=8)
def _kappa_n_along_w_all(contact: str) -> PchipInterpolator:
    """The whole table's kappa_n as a PCHIP along w/h (through kappa0 at 0 and the stored
    depths), (A, N) per w/h: the first step of :func:`kappa_n`, the same for every query,
    built once (building it was a third of a call, and the planner calls it thousands of
    times). Read-only: a caller must not change its arrays."""
    _, wt, kn = _kappa_n_nodes(np.asarray(0.4), np.asarray(1.0), np.asarray(0.0), contact)
    return PchipInterpolator(wt, kn, axis=2)


def kappa_n(nu: float | np.ndarray, a_over_h: float | np.ndarray,
            w_over_h: float | np.ndarray, *, contact: str = "bonded") -> float | np.ndarray:
    """Finite-strain layer factor kappa_n(nu, a/h, w/h) of eq. (1), from the FEM table.

    Parameters
    ----------
    nu, a_over_h, w_over_h : float or (...) array_like
        Broadcast together. nu and a/h within the table (0.30 to 0.499, 0.2
        to 2.0); w/h within [0, 0.2] (0 gives the small-strain limit kappa0).
    contact : str, default 'bonded'
        A punch condition of the table (it holds 'bonded' only).

    Returns
    -------
    kappa_n : float or (...) float64 ndarray
        ``P (1 - nu^2) / (2 a E w)`` of the compressible Neo-Hookean layer,
        so that ``P = 2 a E w kappa_n / (1 - nu^2)`` (N with E in MPa and
        lengths in mm).

    Raises
    ------
    InputError
        (a ``ValueError``) outside the table, or for an unknown contact.

    Notes
    -----
    PCHIP along w/h (through kappa0 at w = 0 and the ten stored depths), then
    along nu, then along a/h: exact at the table's nodes.

    References
    ----------
    .. [1] C. Zhao, J. Ren, H. Yu, D. Ma, "In-situ Mechanical Calibration for
       Vision-based Tactile Sensors", IEEE ICRA 2023,
       eq. (1)-(2); the table: ``models/beta_fem.npz`` (``tactilevision fem
       tables --what beta``).
    """
    n, r, x = np.broadcast_arrays(*(np.asarray(v, np.float64) for v in (nu, a_over_h, w_over_h)))
    data, _, _ = _kappa_n_nodes(n, r, x, contact)
    along_w = _kappa_n_along_w_all(contact)
    if n.size > 1 and np.all(n == n.flat[0]) and np.all(r == r.flat[0]):
        # one nu and a/h (a ramp's or a table's depths): each depth's column is interpolated
        # on its own, so all depths at once give the same numbers as the loop below
        return _kappa_n_at(data, along_w, float(n.flat[0]), float(r.flat[0]),
                           x.ravel()).reshape(n.shape)
    out = np.empty(n.shape)
    for idx in np.ndindex(n.shape):
        out[idx] = _kappa_n_at(data, along_w, float(n[idx]), float(r[idx]),
                               np.atleast_1d(x[idx]))[0]
    return float(out) if out.ndim == 0 else out


def kappa_n_nu_range(contact: str = "bonded") -> tuple[float, float]:
    """The Poisson's ratios the finite-strain table of :func:`kappa_n` holds.

    Parameters
    ----------
    contact : str, default 'bonded'
        A punch condition of the table.

    Returns
    -------
    nu_min, nu_max : float
        The table's first and last nu (0.30 and 0.499): :func:`kappa_n` and
        :func:`fem_force` refuse a nu outside them.

    Raises
    ------
    InputError
        If the table is missing, or for an unknown contact.
    """
    data = _load("beta_fem.npz")
    contacts = [str(c) for c in data["contacts"]]
    if contact not in contacts:
        raise InputError(f"contact must be one of {contacts}, got {contact!r}")
    return float(data["nu"][0]), float(data["nu"][-1])


def fem_force(E_mpa: float, nu: float, radius_mm: float, thickness_mm: float,
              depth_mm: float | np.ndarray) -> np.ndarray:
    """Force of a flat punch pressed into the bonded layer, from the finite-strain FEM.

    P = 2 a E w kappa_n(nu, a/h, w/h) / (1 - nu^2), eq. (1) with :func:`kappa_n`.

    Parameters
    ----------
    E_mpa, nu : float
        Young's modulus (MPa) and Poisson's ratio.
    radius_mm, thickness_mm : float
        Indenter radius a and layer thickness h, mm.
    depth_mm : float or (N,) array_like
        Indentation depths w, mm (w/h up to the table's reach, :func:`kappa_n`).

    Returns
    -------
    P : float64 ndarray, shape of `depth_mm`
        Forces, N.
    """
    w = np.asarray(depth_mm, np.float64)
    k = np.asarray(kappa_n(nu, radius_mm / thickness_mm, w / thickness_mm), np.float64)
    return 2 * radius_mm * E_mpa * w * k / (1 - nu**2)


def kappa_n_grid(nu: np.ndarray, a_over_h: float, w_over_h: np.ndarray, *,
                 contact: str = "bonded") -> np.ndarray:
    """:func:`kappa_n` on a grid of nu x w/h at one a/h, at once.

    The same interpolation as :func:`kappa_n` (PCHIP along w/h, then nu, then
    a/h), each step done for the whole grid: three interpolants instead of
    three per point.

    Parameters
    ----------
    nu : (M,) array_like
    a_over_h : float
    w_over_h : (K,) array_like
        Within the ranges of :func:`kappa_n`.
    contact : str, default 'bonded'

    Returns
    -------
    kappa_n : (M, K) float64 ndarray

    Raises
    ------
    InputError
        As :func:`kappa_n`.
    """
    nu = np.atleast_1d(np.asarray(nu, np.float64))
    x = np.atleast_1d(np.asarray(w_over_h, np.float64))
    data, wt, kn = _kappa_n_nodes(nu, np.asarray(float(a_over_h)), x, contact)
    k_w = PchipInterpolator(wt, kn, axis=2)(x)                                # (A, N, K)
    k_nu = PchipInterpolator(data["nu"], k_w, axis=1)(nu)                     # (A, M, K)
    return np.asarray(PchipInterpolator(data["a_over_h"], k_nu, axis=0)(float(a_over_h)),
                      np.float64)


def _kappa_n_nodes(nu: np.ndarray, a_over_h: np.ndarray, w_over_h: np.ndarray, contact: str
                   ) -> tuple[dict, np.ndarray, np.ndarray]:
    """Check a query of :func:`kappa_n` against the table's ranges; return the table, its
    w/h nodes (0 first) and kappa_n at them, shape (A, N, K+1), kappa0 first."""
    data = _load("beta_fem.npz")
    contacts = [str(c) for c in data["contacts"]]
    if contact not in contacts:
        raise InputError(f"contact must be one of {contacts}, got {contact!r}")
    wt = np.concatenate([[0.0], data["w_over_h"]])
    for name, v, lo, hi in (("nu", nu, data["nu"][0], data["nu"][-1]),
                            ("a_over_h", a_over_h, data["a_over_h"][0], data["a_over_h"][-1]),
                            ("w_over_h", w_over_h, 0.0, TABLE_EXTRAPOLATION * wt[-1])):
        bad = ~((v >= lo) & (v <= hi))
        if np.any(bad):
            raise InputError(f"{name} = {float(np.asarray(v)[bad].ravel()[0]):g} is outside "
                             f"the FEM kappa_n table range [{lo:g}, {hi:g}]")
    c = contacts.index(contact)
    kn = np.concatenate([data["kappa0"][c][..., None], data["kappa_n"][c]], axis=-1)
    return data, wt, kn
