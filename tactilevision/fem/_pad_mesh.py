r"""Mesh, assembly and static condensation of the 3D gel pad (see :mod:`._pad`).

The pad occupies [-Lx/2, Lx/2] x [-Ly/2, Ly/2] x [0, h] (mm) with the mesh's
z axis pointing *up*, out of the gel: the bottom z = 0 is bonded (u = 0), the
top z = h carries the contact. It is meshed with a structured grid of
(nx - 1) x (ny - 1) x layers hexahedra whose top vertices are the surface
nodes of :func:`~tactilevision.fem.pad_surface_stiffness`.

Weak form (E = 1 unless `young` says otherwise)
-----------------------------------------------
a(u, v) = int 2 mu eps(u) : eps(v) dV + int lambda div u div v dV,
mu = E / (2 (1 + nu)), lambda = E nu / ((1 + nu)(1 - 2 nu)).

'hex1' integrates both terms with 2 x 2 x 2 Gauss points, 'bbar' the first
with 2 x 2 x 2 and the lambda term with the single centre point (selective
reduced integration: on the pad's rectangular boxes div N at the centre is
the element mean of div N, so this is the mean-dilatation B-bar element),
'hex2' both with 3 x 3 x 3 points on 27-node triquadratic hexahedra.

Top surface of 'hex2'
---------------------
The top face of a 27-node element is a 9-node biquadratic quad. Its edge
and face nodes are tied to the bilinear interpolation of the vertices (the
matrix P), so the surface moves exactly as with 'hex1' / 'bbar' and the
vertex forces are the same hat-weighted integrals of the traction. Left
traction-free instead (``tie_surface=False``), the vertex forces become point
loads that dimple the surface between the vertices: 55 % too soft against
the closed form on a 27 x 20 grid (benchmarks/bench_fem_pad.py).

Static condensation
-------------------
With u = P v, v = [v_i, v_t] (v_t the public top-vertex dofs, uz into the
gel; v_i every other dof but the bonded base's and the tied top ones) and
R = P^T A P, equilibrium with no load on v_i gives the Schur complement

    K = R_tt - R_ti R_ii^{-1} R_it.

R_ii couples only neighbouring slices of dofs across the pad's longer axis
(a vertex plane and the mid-plane before it), so it is factorised by a dense
block-tridiagonal Cholesky (:class:`BlockTridiagonalCholesky`) and solved
for blocks of columns of R_it at once, all in BLAS-3 calls. On the default
40 x 30 x 3 mesh this takes 1.6 s against 49 s for SuperLU's
multi-right-hand-side solve (which is not blocked). Element matrices: all
elements of the structured mesh are translates, so scikit-fem assembles the
matrix of the first one and it is scattered to all (checked; see
:func:`assemble_translated`).
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Iterator

import numpy as np
import scipy.sparse as sp
from scipy.linalg import cholesky, solve_triangular
from scipy.linalg.blas import dtrsm
from scipy.sparse.linalg import splu
from skfem import (
    Basis,
    BilinearForm,
    CellBasis,
    ElementHex1,
    ElementHex2,
    ElementVector,
    MeshHex,
)
from skfem.helpers import ddot, div, sym_grad

from .._blas import openblas_thread_controls
from .._checks import InputError

__all__ = ["ELEMENTS", "BlockTridiagonalCholesky", "PadModel", "assemble_translated",
           "default_layers", "lame", "single_blas_thread"]

#: Element choices of :func:`~tactilevision.fem.pad_surface_stiffness`.
ELEMENTS = ("hex1", "bbar", "hex2")

#: Bytes of one block of right-hand sides of the Schur-complement solve.
_CHUNK_BYTES = 64 * 2**20


@BilinearForm
def _elasticity(u, v, w):
    """int 2 mu eps(u) : eps(v) + lambda div u div v dV (mu, lam from the parameters)."""
    return 2.0 * w.mu * ddot(sym_grad(u), sym_grad(v)) + w.lam * div(u) * div(v)


def assemble_translated(form: BilinearForm, basis: Basis, **params: float) -> sp.csr_matrix:
    """``form.assemble(basis, **params)``, fast when all elements are translates.

    The pad's structured mesh has one element shape: its matrix is assembled
    by scikit-fem on element 0 alone and scattered to every element (checked:
    each element's dof locations must be element 0's shifted by one vector,
    which also fixes the local dof order). Otherwise scikit-fem assembles all.
    """
    loc = basis.doflocs[:, basis.element_dofs]  # (3, Nbfun, nelems)
    shift = loc - loc[:, :, :1]
    scale = np.ptp(basis.mesh.p) if basis.mesh.p.size else 1.0
    if not np.all(np.abs(shift - shift[:, :1, :]) <= 1e-9 * scale):
        return sp.csr_matrix(form.assemble(basis, **params))
    one = CellBasis(basis.mesh, basis.elem, quadrature=basis.quadrature,
                    elements=np.array([0]))
    dofs = basis.element_dofs
    ke = form.assemble(one, **params).tocsr()[dofs[:, 0]][:, dofs[:, 0]].toarray()
    nb, ne = dofs.shape
    rows = np.broadcast_to(dofs[:, None, :], (nb, nb, ne)).ravel()
    cols = np.broadcast_to(dofs[None, :, :], (nb, nb, ne)).ravel()
    data = np.broadcast_to(ke[:, :, None], (nb, nb, ne)).ravel()
    return sp.csr_matrix(sp.coo_matrix((data, (rows, cols)), shape=(basis.N, basis.N)))


def lame(nu: float, young: float = 1.0) -> tuple[float, float]:
    """Lamé constants (mu, lambda) of (E, nu), in the units of E."""
    return young / (2.0 * (1.0 + nu)), young * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))


def default_layers(grid: tuple[int, int], size_mm: tuple[float, float],
                   thickness_mm: float) -> int:
    """Elements through the thickness that make them roughly cubic, at least 2."""
    spacing = 0.5 * (size_mm[0] / (grid[0] - 1) + size_mm[1] / (grid[1] - 1))
    return max(2, round(thickness_mm / spacing))


@contextlib.contextmanager
def single_blas_thread() -> Iterator[None]:
    """Run BLAS on one thread inside the block, restoring the previous count after.

    The condensation makes hundreds of BLAS calls on blocks of a few hundred
    rows; multithreaded, each costs 10 to 70 times more as soon as another
    process competes for a core (measured on 2 cores), and on an idle
    machine they gain little. Uses threadpoolctl if installed, else the
    loaded OpenBLAS libraries' own setters (Linux), else does nothing.
    """
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:
        threadpool_limits = None
    if threadpool_limits is not None:
        with threadpool_limits(1, user_api="blas"):
            yield
        return
    controls = [(setter, int(getter())) for setter, getter in openblas_thread_controls()]
    try:
        for setter, _ in controls:
            setter(1)
        yield
    finally:
        for setter, count in controls:
            setter(count)


class _Factorised:
    """Sparse LU of an SPD matrix: symmetric-mode SuperLU, COLAMD as fallback."""

    def __init__(self, a: sp.csc_matrix) -> None:
        probe = np.ones(a.shape[0])
        try:
            self.lu = splu(a, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                           options={"SymmetricMode": True})
            err = np.linalg.norm(a @ self.lu.solve(probe) - probe)
            if not err < 1e-8 * np.sqrt(len(probe)):
                raise RuntimeError("inaccurate symmetric-mode factorisation")
        except RuntimeError:
            self.lu = splu(a, permc_spec="COLAMD")

    def solve(self, b: np.ndarray) -> np.ndarray:
        return self.lu.solve(b)


class BlockTridiagonalCholesky:
    """Dense block Cholesky of a sparse SPD matrix that is block tridiagonal.

    Parameters
    ----------
    a : (N, N) sparse matrix
        Symmetric positive definite.
    block : (N,) int ndarray
        Block of each row; a row of block k may couple only to blocks k - 1,
        k and k + 1.

    Raises
    ------
    ValueError
        If `a` couples blocks further apart.
    numpy.linalg.LinAlgError
        If a pivot block is not positive definite.

    Notes
    -----
    With D_k, E_k = A[k, k], A[k, k - 1]: C_k = E_k L_{k-1}^{-T} and
    L_k L_k^T = D_k - C_k C_k^T. Each sweep costs about 3 s^2 flops per
    right-hand side and block of size s, all in BLAS-3 calls, far faster than
    SuperLU's solve with many right-hand sides for the thin pad.
    """

    def __init__(self, a: sp.spmatrix, block: np.ndarray) -> None:
        a = sp.csr_matrix(a)
        block = np.asarray(block, dtype=np.int64)
        coo = a.tocoo()
        if coo.nnz and np.abs(block[coo.row] - block[coo.col]).max() > 1:
            raise InputError("the matrix couples blocks that are not neighbours")
        #: Unknowns by block: block k is ``perm[bounds[k]:bounds[k + 1]]``.
        self.perm = np.argsort(block, kind="stable")
        self.blocks, counts = np.unique(block, return_counts=True)
        self.bounds = np.concatenate([[0], np.cumsum(counts)])
        self.n = a.shape[0]
        a = a[self.perm][:, self.perm].tocsr()
        self.lower: list[np.ndarray] = []  # L_k, Fortran order
        self.coupling: list[np.ndarray] = []  # C_k (empty for k = 0)
        for k in range(len(counts)):
            blk = slice(self.bounds[k], self.bounds[k + 1])
            d = a[blk, blk].toarray()
            c = np.zeros((counts[k], 0))
            if k > 0:
                e = a[blk, self.bounds[k - 1]:self.bounds[k]].toarray()
                # C_k = E_k L_{k-1}^{-T}  <=>  L_{k-1} C_k^T = E_k^T
                c = solve_triangular(self.lower[k - 1], e.T, lower=True,
                                     check_finite=False).T.copy()
                d -= c @ c.T
            self.lower.append(np.asfortranarray(cholesky(d, lower=True, check_finite=False)))
            self.coupling.append(c)

    def solve_permuted(self, w: np.ndarray, first_block: int = 0) -> np.ndarray:
        """Solve in place for a C-ordered (N, m) `w` in the order of `perm`.

        `w` must be zero in the blocks before `first_block`; it is overwritten
        with the solution and returned.
        """
        if not (w.dtype == np.float64 and w.flags.c_contiguous and w.ndim == 2):
            raise InputError("w must be a C-ordered 2D float64 array")
        nb = len(self.lower)
        rows = [slice(self.bounds[k], self.bounds[k + 1]) for k in range(nb)]
        # A C-ordered row block r is the Fortran-ordered r.T: solve r.T op(L) = r.T in place
        for k in range(first_block, nb):
            r = w[rows[k]]
            if k > first_block:
                r -= self.coupling[k] @ w[rows[k - 1]]
            dtrsm(1.0, self.lower[k], r.T, side=1, lower=1, trans_a=1, overwrite_b=1)
        for k in range(nb - 1, -1, -1):
            r = w[rows[k]]
            if k < nb - 1:
                r -= self.coupling[k + 1].T @ w[rows[k + 1]]
            dtrsm(1.0, self.lower[k], r.T, side=1, lower=1, trans_a=0, overwrite_b=1)
        return w

    def solve(self, b: np.ndarray) -> np.ndarray:
        """Solve A x = b for (N,) or (N, m) `b` (original order)."""
        b = np.asarray(b, dtype=np.float64)
        w = np.ascontiguousarray(b.reshape(self.n, -1)[self.perm])
        x = np.empty_like(w)
        x[self.perm] = self.solve_permuted(w)
        return x.reshape(b.shape)


class PadModel:
    """The full 3D pad model: mesh, stiffness, dof sets; condenses to the top.

    Parameters
    ----------
    grid, size_mm, thickness_mm, nu, layers, element
        As :func:`~tactilevision.fem.pad_surface_stiffness` (checked there;
        `layers` is resolved, an int).
    young : float, default 1.0
        Young's modulus (MPa); forces come out in N for lengths in mm.
    tie_surface : bool, default True
        For 'hex2': the top surface's edge and face nodes follow the bilinear
        interpolation of the vertices (True), or are condensed as
        traction-free (False), which turns the vertex forces into point loads
        (much too soft, see :func:`~tactilevision.fem.pad_surface_stiffness`).
        No effect on 'hex1' and 'bbar', whose top dofs are all vertices.

    Attributes
    ----------
    mesh : skfem.MeshHex
    basis : skfem.Basis
        Vector basis of the element (its own quadrature).
    A : (N, N) scipy.sparse.csr_matrix
        Unconstrained stiffness (mesh signs, z up), N/mm.
    P : (N, n_i + 3 n) scipy.sparse.csr_matrix
        Mesh dofs from the reduced unknowns: the condensed dofs `interior`
        (identity) then the public top-vertex dofs ``3 k + c`` of node
        ``k = iy * nx + ix`` (bilinear interpolation on the top, uz sign
        flipped); zero rows at the bonded bottom.
    top : (3 n,) int64 ndarray
        Mesh dof of public top dof ``3 k + c``.
    bottom, interior : int64 ndarrays
        Bonded dofs (z = 0) and the condensed ones (the rest of the mesh
        below the top surface, and with ``tie_surface=False`` its mid-side nodes).
    seconds : dict
        Wall time of 'assembly', and after :meth:`condense` of 'factorisation'
        and 'schur'.
    """

    def __init__(self, grid: tuple[int, int], size_mm: tuple[float, float],
                 thickness_mm: float, nu: float, layers: int, element: str,
                 young: float = 1.0, tie_surface: bool = True) -> None:
        t0 = time.perf_counter()
        nx, ny = grid
        lx, ly = size_mm
        self.x_mm = np.linspace(-0.5 * lx, 0.5 * lx, nx)
        self.y_mm = np.linspace(-0.5 * ly, 0.5 * ly, ny)
        z = np.linspace(0.0, thickness_mm, layers + 1)
        self.mesh = MeshHex.init_tensor(self.x_mm, self.y_mm, z)
        mu, lam = lame(nu, young)
        if element == "hex2":
            basis = Basis(self.mesh, ElementVector(ElementHex2()), intorder=5)  # 3x3x3
            parts = [(basis, _elasticity, {"mu": mu, "lam": lam})]
        else:
            basis = Basis(self.mesh, ElementVector(ElementHex1()), intorder=3)  # 2x2x2
            if element == "bbar":
                centre = (np.full((3, 1), 0.5), np.ones(1))  # reference cell [0, 1]^3
                parts = [(basis, _elasticity, {"mu": mu, "lam": 0.0}),
                         (Basis(self.mesh, basis.elem, quadrature=centre), _elasticity,
                          {"mu": 0.0, "lam": lam})]
            else:
                parts = [(basis, _elasticity, {"mu": mu, "lam": lam})]
        a = sum(assemble_translated(form, b, **params) for b, form, params in parts)
        self.basis, self.A = basis, sp.csr_matrix(a)
        self.A.sum_duplicates()

        comp = np.empty(basis.N, dtype=np.int64)
        for name in ("nodal_dofs", "edge_dofs", "facet_dofs", "interior_dofs"):
            dofs = getattr(basis, name)
            for c in range(dofs.shape[0]):
                comp[dofs[c]] = c
        loc = basis.doflocs
        tol = 1e-9 * max(lx, ly, thickness_mm)
        # grid coordinates of every dof, snapped to the vertex and mid-side positions
        fx = np.round(2.0 * (loc[0] - self.x_mm[0]) / (lx / (nx - 1))) / 2.0
        fy = np.round(2.0 * (loc[1] - self.y_mm[0]) / (ly / (ny - 1))) / 2.0
        on_top = np.abs(loc[2] - thickness_mm) < tol
        vertex = (fx == np.floor(fx)) & (fy == np.floor(fy))
        tied = on_top & (vertex | (tie_surface and element == "hex2"))
        self.bottom = np.flatnonzero(np.abs(loc[2]) < tol)
        self.interior = np.flatnonzero(~tied & (np.abs(loc[2]) >= tol))
        top_vertex = np.flatnonzero(on_top & vertex)
        public = (fy[top_vertex] * nx + fx[top_vertex]).astype(np.int64) * 3 + comp[top_vertex]
        self.top = np.empty(3 * nx * ny, dtype=np.int64)
        self.top[public] = top_vertex

        # P: interior dofs by identity, tied top dofs by bilinear interpolation
        rows, cols, vals = [self.interior], [np.arange(len(self.interior))], [np.ones(
            len(self.interior))]
        dofs = np.flatnonzero(tied)
        sign = np.where(comp[dofs] == 2, -1.0, 1.0)  # public uz points into the gel
        i0 = np.minimum(np.floor(fx[dofs]), nx - 2).astype(np.int64)
        j0 = np.minimum(np.floor(fy[dofs]), ny - 2).astype(np.int64)
        tx, ty = fx[dofs] - i0, fy[dofs] - j0
        for di, dj, w in ((0, 0, (1 - tx) * (1 - ty)), (1, 0, tx * (1 - ty)),
                          (0, 1, (1 - tx) * ty), (1, 1, tx * ty)):
            keep = w != 0
            node = (j0 + dj) * nx + i0 + di
            rows.append(dofs[keep])
            cols.append(len(self.interior) + 3 * node[keep] + comp[dofs][keep])
            vals.append((sign * w)[keep])
        self.P = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows),
                                                       np.concatenate(cols))),
                               shape=(basis.N, len(self.interior) + 3 * nx * ny))
        self.seconds = {"assembly": time.perf_counter() - t0}

    @property
    def n_dofs(self) -> int:
        """Mesh dofs, bonded ones included."""
        return int(self.basis.N)

    def slices(self) -> np.ndarray:
        """Slice index of each dof along the longer in-plane axis (block tridiagonal A)."""
        axis = 0 if len(self.x_mm) >= len(self.y_mm) else 1
        coords = self.x_mm if axis == 0 else self.y_mm
        step = (coords[-1] - coords[0]) / (len(coords) - 1)
        # vertex plane j and the mid-plane (hex2) just below it form slice j
        return np.ceil((self.basis.doflocs[axis] - coords[0]) / step - 1e-6).astype(np.int64)

    def _reduced(self) -> tuple[sp.csr_matrix, int]:
        """P^T A P and the number of condensed unknowns (ordered first)."""
        return sp.csr_matrix(self.P.T @ self.A @ self.P), len(self.interior)

    def condense(self) -> np.ndarray:
        """Schur complement on the top vertices, public signs: (3 n, 3 n) float64, N/mm."""
        with single_blas_thread():
            return self._condense()

    def _condense(self) -> np.ndarray:
        t0 = time.perf_counter()
        a, ni = self._reduced()
        chol = BlockTridiagonalCholesky(a[:ni, :ni], self.slices()[self.interior])
        t1 = time.perf_counter()
        a_it = a[:ni, ni:][chol.perm].tocsc()
        a_ti = a[ni:, :ni][:, chol.perm].tocsr()
        k = a[ni:, ni:].toarray()
        # right-hand sides by the slice of their top node: a block of them is zero
        # in the slices before its first one minus one, which the forward sweep skips
        col_slice = self.slices()[self.top]
        order = np.argsort(col_slice, kind="stable")
        width = max(64, min(len(order), _CHUNK_BYTES // (8 * max(1, ni))))
        for start in range(0, len(order), width):
            cols = order[start:start + width]
            first = int(np.searchsorted(chol.blocks, col_slice[cols].min() - 1))
            w = chol.solve_permuted(a_it[:, cols].toarray(order="C"), first_block=first)
            k[:, cols] -= a_ti @ w
        k += k.T
        k *= 0.5
        self.seconds["factorisation"] = t1 - t0
        self.seconds["schur"] = time.perf_counter() - t1
        return k

    def solve(self, u_top: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Full solve for imposed top displacements (public signs, mm).

        Parameters
        ----------
        u_top : (3 n,) float64 ndarray
            Public top-vertex displacements, mm.

        Returns
        -------
        x : (N,) float64 ndarray
            Nodal displacements of the mesh (mesh signs, z up), mm.
        residual : (N,) float64 ndarray
            A @ x (mesh signs), N: the external nodal forces; ~0 at `interior`,
            the loads on the top surface and the base's reactions at `bottom`.
        """
        a, ni = self._reduced()
        v = np.zeros(a.shape[0])
        v[ni:] = np.asarray(u_top, dtype=np.float64)
        v[:ni] = _Factorised(a[:ni, :ni].tocsc()).solve(-(a[:ni, ni:] @ v[ni:]))
        x = self.P @ v
        return x, self.A @ x
