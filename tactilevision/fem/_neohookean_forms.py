r"""Compressible Neo-Hookean solid (Abaqus form), axisymmetric, mixed u-p forms.

Kinematics
----------
A torsion-free axisymmetric motion x = X + u(R, Z) has, in the order
(r, z, theta), the deformation gradient

    F = [[1 + d_R u_r,  d_Z u_r,      0          ],
         [d_R u_z,      1 + d_Z u_z,  0          ],
         [0,            0,            1 + u_r / R]],

so it is carried by five numbers, f = (F_rr, F_rz, F_zr, F_zz, F_tt), and
J = det F = (F_rr F_zz - F_rz F_zr) F_tt. A test displacement v varies f by
B v = (d_R v_r, d_Z v_r, d_R v_z, d_Z v_z, v_r / R) (total Lagrangian: all
derivatives are in the reference configuration, so B is built once).

Energy
------
Abaqus's compressible Neo-Hookean law [1]_,

    W = C10 (I1bar - 3) + (J - 1)^2 / D1,  I1bar = J^(-2/3) f . f,

with C10 = mu / 2 and D1 = 2 / K, is written as the stationary point in p of

    Pi(u, p) = int [ W_iso(f) + p (J - 1) - p^2 / (2 K) ] dV,   dV = 2 pi R dR dZ,

(d Pi / dp = 0 gives p = K (J - 1), and putting it back returns W), with
W_iso = C10 (J^(-2/3) f . f - 3). p is the hydrostatic Cauchy stress (tension
positive). At K -> infinity the last term vanishes and J = 1 is imposed
exactly, which Taylor-Hood P2 (u) / P1 (p) triangles do without locking.

Residual (first variation)
--------------------------

    R_u(v) = int (S + p g) . B v dV,        R_p(q) = int q (J - 1 - p / K) dV,

with g = dJ/df = (F_zz F_tt, -F_zr F_tt, -F_rz F_tt, F_rr F_tt,
F_rr F_zz - F_rz F_zr) and the first Piola-Kirchhoff stress of W_iso,

    S = dW_iso/df = C10 [2 J^(-2/3) f - (2/3) J^(-5/3) I1 g],   I1 = f . f.

Linearisation (second variation, consistent tangent)
-----------------------------------------------------

    K_uu(du, v) = int B v . (A + p H) B du dV,
    K_up(dp, v) = int dp g . B v dV,   K_pp(dp, q) = -int q dp / K dV,

    A = d^2 W_iso / df^2 = C10 [ 2 J^(-2/3) 1 - (4/3) J^(-5/3) (f g^T + g f^T)
                                 + (10/9) J^(-8/3) I1 g g^T - (2/3) J^(-5/3) I1 H ],

where H = d^2 J / df^2 is symmetric with the nonzero entries
H[rr,zz] = F_tt, H[rz,zr] = -F_tt, H[rr,tt] = F_zz, H[zz,tt] = F_rr,
H[rz,tt] = -F_zr, H[zr,tt] = -F_rz. At f = (1, 0, 0, 1, 1) the tangent reduces
to the small-strain isotropic elasticity with shear modulus 2 C10 = mu.

Strain stiffening (an extension, for testing the material law)
-------------------------------------------------------------
With ``c20 > 0`` the isochoric energy is Yeoh's [2]_ second-order
W_iso = C10 (I1bar - 3) + C20 (I1bar - 3)^2, so that with W1 = dW/dI1bar =
C10 + 2 C20 (I1bar - 3) and W11 = 2 C20 the stress and tangent become
S = W1 dI1bar/df and A = W1 d^2 I1bar/df^2 + W11 (dI1bar/df)(dI1bar/df)^T
(the Neo-Hookean expressions above with C10 = 1, scaled and completed).
C20 = 0 is the Abaqus Neo-Hookean law exactly.

The forms are evaluated with the B-matrix of each element (einsum over the
quadrature points) and scattered once per Newton iteration; the 2 pi of the
measure is left out here and put back into the reaction force.

References
----------
.. [1] Abaqus Analysis User's Guide, section 22.5.1 "Hyperelastic behavior of
   rubberlike materials", Neo-Hookean form U = C10 (I1bar - 3) + (J - 1)^2 / D1.
.. [2] O. H. Yeoh, "Some forms of the strain energy function for rubber",
   Rubber Chem. Technol. 66(5):754-771, 1993. doi:10.5254/1.3538343
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from skfem import Basis, ElementTriP1, ElementTriP2, ElementVector, MeshTri

__all__ = ["AxisymmetricNeoHookean", "cauchy_stress", "iso_energy", "iso_stress",
           "iso_tangent", "jacobian"]

_IDENTITY = np.array([1.0, 0.0, 0.0, 1.0, 1.0])  # f of the undeformed state


def jacobian(f: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """J = det F, g = dJ/df and H = d^2 J / df^2.

    Parameters
    ----------
    f : (5, ...) float64 ndarray
        (F_rr, F_rz, F_zr, F_zz, F_tt), dimensionless.

    Returns
    -------
    J : (...) float64 ndarray
    g : (5, ...) float64 ndarray
    H : (5, 5, ...) float64 ndarray, symmetric
    """
    frr, frz, fzr, fzz, ftt = f
    det2 = frr * fzz - frz * fzr
    g = np.stack([fzz * ftt, -fzr * ftt, -frz * ftt, frr * ftt, det2])
    H = np.zeros((5, 5, *f.shape[1:]))
    for (i, j), val in {(0, 3): ftt, (1, 2): -ftt, (0, 4): fzz, (3, 4): frr,
                        (1, 4): -fzr, (2, 4): -frz}.items():
        H[i, j] = H[j, i] = val
    return det2 * ftt, g, H


def iso_energy(f: np.ndarray, c10: float) -> np.ndarray:
    """W_iso = C10 (J^(-2/3) f . f - 3), energy per reference volume (units of C10)."""
    J = jacobian(f)[0]
    return c10 * (J ** (-2.0 / 3.0) * np.sum(f * f, axis=0) - 3.0)


def iso_stress(f: np.ndarray, c10: float) -> np.ndarray:
    """S = dW_iso/df, the isochoric first Piola-Kirchhoff stress, shape (5, ...)."""
    J, g, _ = jacobian(f)
    i1 = np.sum(f * f, axis=0)
    return c10 * (2.0 * J ** (-2.0 / 3.0) * f - (2.0 / 3.0) * J ** (-5.0 / 3.0) * i1 * g)


def iso_tangent(f: np.ndarray, c10: float) -> np.ndarray:
    """A = d^2 W_iso / df^2, shape (5, 5, ...), symmetric (see the module docstring)."""
    J, g, H = jacobian(f)
    i1 = np.sum(f * f, axis=0)
    j23, j53, j83 = J ** (-2.0 / 3.0), J ** (-5.0 / 3.0), J ** (-8.0 / 3.0)
    fg = f[:, None] * g[None, :]
    eye = np.eye(5).reshape((5, 5) + (1,) * (f.ndim - 1))
    return c10 * (2.0 * j23 * eye - (4.0 / 3.0) * j53 * (fg + np.swapaxes(fg, 0, 1))
                  + (10.0 / 9.0) * j83 * i1 * g[:, None] * g[None, :]
                  - (2.0 / 3.0) * j53 * i1 * H)


def cauchy_stress(f: np.ndarray, c10: float, d1: float) -> np.ndarray:
    """Cauchy stress of the Abaqus Neo-Hookean law from the mixed form's stress.

    sigma = (S + p g) F^T / J with p = 2 (J - 1) / D1, the pressure that makes
    the mixed form stationary.

    Parameters
    ----------
    f : (5, ...) float64 ndarray
    c10, d1 : float
        Abaqus constants (units of stress, 1 / stress).

    Returns
    -------
    sigma : (3, 3, ...) float64 ndarray
        Components in the order (r, z, theta), units of C10.
    """
    J, g, _ = jacobian(f)
    P = iso_stress(f, c10) + 2.0 * (J - 1.0) / d1 * g
    Pm = np.zeros((3, 3, *f.shape[1:]))
    Fm = np.zeros_like(Pm)
    for k, (i, j) in enumerate([(0, 0), (0, 1), (1, 0), (1, 1), (2, 2)]):
        Pm[i, j], Fm[i, j] = P[k], f[k]
    return np.einsum("ik...,jk...->ij...", Pm, Fm) / J


class AxisymmetricNeoHookean:
    """Residual and consistent tangent of the mixed u-p Neo-Hookean forms on a mesh.

    Parameters
    ----------
    mesh : skfem.MeshTri
        (R, Z) half-section in the reference configuration, R >= 0.
    c10 : float
        Abaqus C10 = mu / 2, units of stress.
    bulk : float
        K = 2 / D1 (``np.inf`` for an incompressible solid).
    intorder : int, default 4
        Quadrature order.
    c20 : float, default 0.0
        Yeoh's second coefficient (strain stiffening; see the module
        docstring), units of stress, >= 0. 0: Neo-Hookean.

    Attributes
    ----------
    ubasis, pbasis : skfem.CellBasis
        Taylor-Hood P2 vector (u_r, u_z) and P1 pressure bases.
    n_u, n_dofs : int
        Displacement dofs; all dofs ``x = [u, p]``.
    """

    def __init__(self, mesh: MeshTri, c10: float, bulk: float, *, intorder: int = 4,
                 c20: float = 0.0) -> None:
        self.c10, self.inv_bulk, self.c20 = float(c10), 1.0 / float(bulk), float(c20)
        self.ubasis = Basis(mesh, ElementVector(ElementTriP2()), intorder=intorder)
        self.pbasis = self.ubasis.with_element(ElementTriP1())
        ub, pb = self.ubasis, self.pbasis
        self.n_u = ub.N
        self.n_dofs = ub.N + pb.N
        radius = np.asarray(ub.global_coordinates())[0]               # (E, Q)
        self.dv = ub.dx * radius                                        # R dR dZ
        blocks = []
        for phi in ub.basis:                                            # 12 local dofs
            gr, val = phi[0].grad, np.asarray(phi[0])
            blocks.append(np.stack([gr[0, 0], gr[0, 1], gr[1, 0], gr[1, 1], val[0] / radius]))
        self.B = np.stack(blocks, axis=1)                               # (5, 12, E, Q)
        self.Np = np.stack([np.asarray(phi[0]) for phi in pb.basis])   # (3, E, Q)
        self.udofs = ub.element_dofs                                    # (12, E)
        self.pdofs = pb.element_dofs + ub.N                             # (3, E)
        dofs = np.concatenate([self.udofs, self.pdofs])                 # (15, E)
        self._rows = np.broadcast_to(dofs[:, None, :], (15, 15, dofs.shape[1])).ravel()
        self._cols = np.broadcast_to(dofs[None, :, :], (15, 15, dofs.shape[1])).ravel()
        # the tangent's sparsity, once: each element entry's slot in the CSR data (the
        # duplicates summed by bincount), and B with the points leading for batched products
        lin = self._rows.astype(np.int64) * self.n_dofs + self._cols
        uniq, self._slot = np.unique(lin, return_inverse=True)
        self._indices = (uniq % self.n_dofs).astype(np.int32)
        self._indptr = np.searchsorted(uniq // self.n_dofs,
                                       np.arange(self.n_dofs + 1)).astype(np.int32)
        self._Bt = np.ascontiguousarray(self.B.transpose(2, 3, 0, 1))  # (E, Q, 5, 12)

    def fields(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """f (5, E, Q) and p (E, Q) at the quadrature points for dofs `x`."""
        f = _IDENTITY[:, None, None] + np.einsum("kien,ie->ken", self.B, x[self.udofs])
        p = np.einsum("jen,je->en", self.Np, x[self.pdofs])
        return f, p

    def _w1(self, f: np.ndarray) -> tuple[np.ndarray | float, np.ndarray | float]:
        """W1 = dW_iso/dI1bar and W11 (Neo-Hookean: C10 and 0)."""
        if self.c20 == 0.0:
            return self.c10, 0.0
        i1bar = jacobian(f)[0] ** (-2.0 / 3.0) * np.sum(f * f, axis=0)
        return self.c10 + 2.0 * self.c20 * (i1bar - 3.0), 2.0 * self.c20

    def iso_stress(self, f: np.ndarray) -> np.ndarray:
        """S = dW_iso/df at the quadrature points, (5, E, Q)."""
        w1, _ = self._w1(f)
        return iso_stress(f, 1.0) * w1

    def iso_tangent(self, f: np.ndarray) -> np.ndarray:
        """A = d^2 W_iso/df^2 at the quadrature points, (5, 5, E, Q)."""
        w1, w11 = self._w1(f)
        out = iso_tangent(f, 1.0) * w1
        if self.c20 != 0.0:
            d = iso_stress(f, 1.0)
            out = out + w11 * d[:, None] * d[None, :]
        return out

    def min_jacobian(self, x: np.ndarray) -> float:
        """Smallest J = det F over all quadrature points."""
        return float(jacobian(self.fields(x)[0])[0].min())

    def residual(self, x: np.ndarray) -> np.ndarray:
        """[R_u, R_p] (n_dofs,), without the factor 2 pi."""
        f, p = self.fields(x)
        J, g, _ = jacobian(f)
        stress = (self.iso_stress(f) + p * g) * self.dv
        ru = np.einsum("kien,ken->ie", self.B, stress)
        rp = np.einsum("jen,en->je", self.Np, (J - 1.0 - p * self.inv_bulk) * self.dv)
        out = np.zeros(self.n_dofs)
        np.add.at(out, self.udofs, ru)
        np.add.at(out, self.pdofs, rp)
        return out

    def tangent(self, x: np.ndarray) -> sp.csr_matrix:
        """Consistent tangent [[K_uu, K_up], [K_pu, K_pp]] (n_dofs, n_dofs), symmetric."""
        f, p = self.fields(x)
        _, g, H = jacobian(f)
        D = (self.iso_tangent(f) + p * H) * self.dv
        DB = np.ascontiguousarray(D.transpose(2, 3, 0, 1)) @ self._Bt  # (E, Q, 5, 12)
        kuu = np.einsum("eqki,eqkj->ije", self._Bt, DB, optimize=True)  # (12, 12, E)
        kup = np.einsum("kien,ken,jen->ije", self.B, g * self.dv, self.Np)  # (12, 3, E)
        kpp = -self.inv_bulk * np.einsum("ien,jen,en->ije", self.Np, self.Np, self.dv)
        ke = np.concatenate([np.concatenate([kuu, kup], axis=1),
                             np.concatenate([np.swapaxes(kup, 0, 1), kpp], axis=1)], axis=0)
        data = np.bincount(self._slot, weights=ke.ravel(), minlength=self._indices.size)
        return sp.csr_matrix((data, self._indices, self._indptr),
                             shape=(self.n_dofs, self.n_dofs))
