"""The FEM force model (``method='fem'``, 40 x 30 nodes) against a finer pad and Hayes.

    python benchmarks/bench_forces_fem.py

(a) No inverse crime: the top surface of a finer 3D pad (80 x 60 x 8 B-bar hexahedra, twice
as fine in plane and through the thickness, a non-nested grid, assembled here with
scikit-fem: never the estimator's own condensed stiffness nor its mesh) under a known Hertz
pressure, read through the estimator on a 200 x 150 image at 0.2 mm/px (a 39.8 x 29.8 mm
sensed area, a 4 mm pad, E 0.2 MPa): the load a = 3 mm, 0.5 N at nu 0.45 and 0.49,
'field' and 'footprint' (the default threshold, 0.01 mm, the sink-in included; and the
loaded disc as the mask), and a = 2.5 mm at nu 0.45 with the disc, the disc grown by one
node spacing and the default threshold as the mask. Printed: each total against the load,
and the pressure's error at the nodes against the applied pressure's hat-weighted nodal
average (rms inside the disc, largest on the nodes it reaches, % of its peak).

(b) The footprint on the default grid (issue 21): a 427 x 320 image at 0.0806 mm/px (node
spacing 0.88 mm), a 3 mm layer bonded to its base, nu 0.48, 'footprint' contact on height
maps that are zero off the contact (a rigid indenter's profile, no sink-in): flat punches
of radius 1.5, 2.5 and 4 mm, 0.1 mm deep, against Hayes (1972) (kappa from
:func:`tactilevision.mechanics.kappa`), the spectral method's alongside; rigid spheres
(contact radius 1.4 to 4 mm) against the spectral method; each at three positions (the
image's centre and two off the nodes' symmetry). About a minute on this 2-core machine
with the stiffnesses cached, a few seconds more to build them.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.interpolate import RegularGridInterpolator
from skfem import (
    Basis,
    BilinearForm,
    ElementHex1,
    ElementVector,
    FacetBasis,
    LinearForm,
    MeshHex,
)
from skfem.helpers import ddot, div, sym_grad

from tactilevision.fem import ForceEstimator
from tactilevision.fem._pad_mesh import (
    BlockTridiagonalCholesky,
    assemble_translated,
    single_blas_thread,
)
from tactilevision.mechanics import kappa

# (a) the sensed area of benchmarks/bench_forces_accuracy.py: 39.8 x 29.8 mm, a 4 mm pad
HPX, WPX, DX, H, E = 150, 200, 0.2, 4.0, 0.2          # px, px, mm, mm, MPa
LX, LY = (WPX - 1) * DX, (HPX - 1) * DX
XC = np.arange(WPX) * DX - LX / 2                       # pixel x from the image centre, mm
YC = np.arange(HPX) * DX - LY / 2
RPX = np.hypot(XC[None, :], YC[:, None])               # pixel distance from the centre
P_HZ = 0.5                                              # the Hertz load's total, N

# (b) the default grid's case
GRID_SHAPE, GRID_DX, GRID_H, GRID_NU = (320, 427), 0.0806, 3.0, 0.48
#: positions of (b)'s contacts: px off the image's centre (x, y)
OFFSETS = ((0.0, 0.0), (5.5, 5.5), (3.0, 8.0))
PUNCHES = (1.5, 2.5, 4.0)                               # radius, mm (0.1 mm deep)
SPHERES = ((10.0, 0.3), (5.0, 0.2), (20.0, 0.4))        # radius, depth, mm


def hertz(p0: float, a: float):
    """The Hertz pressure (MPa) of peak `p0` on a disc of radius `a` (mm): p(x, y)."""
    return lambda x, y: p0 * np.sqrt(np.clip(1.0 - (x**2 + y**2) / a**2, 0.0, None))


@BilinearForm
def _elasticity(u, v, w):
    return 2.0 * w.mu * ddot(sym_grad(u), sym_grad(v)) + w.lam * div(u) * div(v)


def pad_forward(pressure, nu: float, cells=(40, 30), layers: int = 8):
    """Top-surface uz (mm, into the gel) of the pad under a normal pressure (MPa).

    A quarter of the LX x LY x H pad (the load is symmetric about both centre
    lines: ux = 0 on x = 0, uy = 0 on y = 0), bottom bonded, outer sides
    free; `cells` B-bar hexahedra in plane (80 x 60 over the whole pad) and
    `layers` through H. The load vector is the pressure's consistent nodal
    forces (12-point Gauss per facet). Returns (x, y, uz[iy, ix]) on the
    quarter's top vertices and the total load of the whole pad, N.
    """
    xs = np.linspace(0.0, LX / 2, cells[0] + 1)
    ys = np.linspace(0.0, LY / 2, cells[1] + 1)
    mesh = MeshHex.init_tensor(xs, ys, np.linspace(0.0, H, layers + 1))
    mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))
    full = Basis(mesh, ElementVector(ElementHex1()), intorder=3)          # 2 x 2 x 2
    centre = Basis(mesh, full.elem, quadrature=(np.full((3, 1), 0.5), np.ones(1)))
    A = sp.csr_matrix(assemble_translated(_elasticity, full, mu=mu, lam=0.0)
                      + assemble_translated(_elasticity, centre, mu=0.0, lam=lam))

    @LinearForm
    def load(v, w):
        return -pressure(w.x[0], w.x[1]) * v[2]         # the mesh's z points out of the gel

    top = mesh.facets_satisfying(lambda x: np.abs(x[2] - H) < 1e-9)
    f = load.assemble(FacetBasis(mesh, full.elem, facets=top, intorder=12))
    fixed = np.concatenate([full.get_dofs(lambda x: np.abs(x[2]) < 1e-9).all(),
                            full.get_dofs(lambda x: np.abs(x[0]) < 1e-9).all("u^1"),
                            full.get_dofs(lambda x: np.abs(x[1]) < 1e-9).all("u^2")])
    free = np.setdiff1d(np.arange(full.N), fixed)
    # block tridiagonal in the vertex planes across x: a dense block Cholesky, one thread
    planes = np.rint(full.doflocs[0, free] / (xs[1] - xs[0])).astype(np.int64)
    x = np.zeros(full.N)
    with single_blas_thread():
        x[free] = BlockTridiagonalCholesky(A[free][:, free], planes).solve(f[free])
    residual = np.linalg.norm(A[free] @ x - f[free])
    if residual >= 1e-10 * np.linalg.norm(f):
        raise RuntimeError(f"the finer pad's solve left a residual of {residual:.3g}")
    uz = -x[full.nodal_dofs[2]]
    loc = mesh.p
    top_nodes = np.abs(loc[2] - H) < 1e-9
    ix = np.rint(loc[0, top_nodes] / (xs[1] - xs[0])).astype(int)
    iy = np.rint(loc[1, top_nodes] / (ys[1] - ys[0])).astype(int)
    grid = np.full((len(ys), len(xs)), np.nan)
    grid[iy, ix] = uz[top_nodes]
    return xs, ys, grid, -4.0 * float(f.sum())


def on_image(xs, ys, grid):
    """The quarter's top surface, mirrored, at the image's pixel centres (bilinear: exact)."""
    interp = RegularGridInterpolator((ys, xs), grid)
    yy, xx = np.meshgrid(np.minimum(np.abs(YC), ys[-1]), np.minimum(np.abs(XC), xs[-1]),
                         indexing="ij")
    return interp(np.stack([yy, xx], axis=-1))


def hat_loads(x, y, pressure, sub: int = 10):
    """Exact nodal forces int p N_k dA of `pressure` on the bilinear node grid (x, y), N.

    Midpoint rule on cells `sub` times finer than the image's pixels (0.02 mm:
    the Hertz edge's square root costs < 1e-4 of the total).
    """
    step = DX / sub
    xq = np.arange(-LX / 2 - DX / 2 + step / 2, LX / 2 + DX / 2, step)
    yq = np.arange(-LY / 2 - DX / 2 + step / 2, LY / 2 + DX / 2, step)

    def hats(nodes, q):
        return np.maximum(0.0, 1.0 - np.abs(q[None, :] - nodes[:, None]) / (nodes[1] - nodes[0]))

    p = pressure(xq[None, :], yq[:, None])
    return hats(y, yq) @ p @ hats(x, xq).T * step * step


def finer_rows(cache_dir=None) -> list[dict]:
    """(a): one dict a reading, ``{"a", "nu", "reading", "total", "rms", "largest",
    "nodes"}``: the total's departure from the load, the pressure's rms inside the loaded
    disc and largest error on the nodes it reaches (both over the applied pressure's peak
    p0, hat-weighted at the nodes), the nodes in contact (None for 'field')."""
    out = []
    for a, nus in ((3.0, (0.45, 0.49)), (2.5, (0.45,))):
        pressure = hertz(3 * P_HZ / (2 * np.pi * a**2), a)
        for nu in nus:
            xs, ys, grid, load = pad_forward(pressure, nu)
            u = on_image(xs, ys, grid)
            kw = dict(thickness_mm=H, E_mpa=E, nu=nu, method="fem", grid=(40, 30),
                      cache_dir=cache_dir, threshold_mm=0.01)
            fp = ForceEstimator((HPX, WPX), DX, contact="footprint", **kw)
            x, y = fp.x_mm, fp.y_mm
            sx, sy = x[1] - x[0], y[1] - y[0]
            exact = hat_loads(x - LX / 2, y - LY / 2, pressure)        # N per node
            p_exact = exact / (sx * sy) * 1e3                            # kPa
            xr, yr = np.abs(x - LX / 2)[None, :], np.abs(y - LY / 2)[:, None]
            inside = np.hypot(xr, yr) < a
            touch = np.hypot(np.maximum(xr - sx, 0), np.maximum(yr - sy, 0)) < a
            readings = [("'footprint', the default threshold", fp, None),
                        ("'footprint', the loaded disc as the mask", fp, RPX <= a)]
            if a == 3.0:
                readings.insert(0, ("'field'", ForceEstimator((HPX, WPX), DX,
                                                              contact="field", **kw), None))
            else:
                readings.append(("'footprint', the disc grown by a node spacing", fp,
                                 RPX <= a + sx))
            for name, est, mask in readings:
                fm = est(u) if mask is None else est(u, contact_mask=mask)
                err = fm.pressure_kpa - p_exact
                out.append({"a": a, "nu": nu, "reading": name,
                            "total": float(fm.total_n[2]) / load - 1,
                            "rms": float(np.sqrt(np.mean(err[inside] ** 2)) / p_exact.max()),
                            "largest": float(np.abs(err[touch]).max() / p_exact.max()),
                            "nodes": None if est.contact == "field"
                            else int(fm.contact.sum())})
    return out


def _r(offset_px):
    Hp, Wp = GRID_SHAPE
    yy, xx = np.indices(GRID_SHAPE, dtype=np.float64)
    return np.hypot((xx - (Wp - 1) / 2 - offset_px[0]) * GRID_DX,
                    (yy - (Hp - 1) / 2 - offset_px[1]) * GRID_DX)


def grid_rows(cache_dir=None) -> dict[str, list[dict]]:
    """(b): ``{"punches": [{"a", "offset", "fem", "spectral"}] (totals over Hayes'),
    "spheres": [{"R", "depth", "a", "offset", "fem_over_spectral"}]}``."""
    kw = dict(thickness_mm=GRID_H, E_mpa=E, nu=GRID_NU, contact="footprint",
              threshold_mm=0.01)
    fem = ForceEstimator(GRID_SHAPE, GRID_DX, method="fem", cache_dir=cache_dir, **kw)
    spectral = ForceEstimator(GRID_SHAPE, GRID_DX, **kw)
    punches, spheres = [], []
    w = 0.1
    for a in PUNCHES:
        hayes = 2 * a * E * w * float(kappa(GRID_NU, a / GRID_H)) / (1 - GRID_NU**2)
        for off in OFFSETS:
            u = np.where(_r(off) <= a, w, 0.0)
            punches.append({"a": a, "offset": off, "fem": float(fem(u).total_n[2]) / hayes,
                            "spectral": float(spectral(u).total_n[2]) / hayes})
    for R, depth in SPHERES:
        for off in OFFSETS:
            u = np.maximum(depth - _r(off) ** 2 / (2 * R), 0.0)
            spheres.append({"R": R, "depth": depth, "a": float(np.sqrt(2 * R * depth)),
                            "offset": off, "fem_over_spectral":
                            float(fem(u).total_n[2] / spectral(u).total_n[2])})
    return {"punches": punches, "spheres": spheres}


def main() -> None:
    print("(a) the 40 x 30 FEM estimator on a finer pad's surface under a Hertz load "
          f"({P_HZ} N; 200 x 150 px at {DX} mm, h {H} mm)")
    print("a mm | nu | reading | total - load | pressure rms, largest (% of p0) | nodes")
    for r in finer_rows():
        print(f"{r['a']:g} | {r['nu']:g} | {r['reading']} | {100 * r['total']:+.2f} % | "
              f"{100 * r['rms']:.1f}, {100 * r['largest']:.1f} | "
              f"{'-' if r['nodes'] is None else r['nodes']}")
    g = grid_rows()
    print(f"\n(b) 'footprint' on the default grid: {GRID_SHAPE[1]} x {GRID_SHAPE[0]} px at "
          f"{GRID_DX} mm, h {GRID_H} mm, nu {GRID_NU}; positions (px off the centre) "
          + ", ".join(f"({x:g}, {y:g})" for x, y in OFFSETS))
    for a in PUNCHES:
        sub = [p for p in g["punches"] if p["a"] == a]
        print(f"flat punch a = {a:g} mm, 0.1 mm deep, over Hayes: FEM "
              + ", ".join(f"{p['fem']:.3f}" for p in sub) + "; spectral "
              + ", ".join(f"{p['spectral']:.3f}" for p in sub))
    for R, depth in SPHERES:
        sub = [s for s in g["spheres"] if (s["R"], s["depth"]) == (R, depth)]
        print(f"rigid sphere R = {R:g} mm, {depth:g} mm deep (a {sub[0]['a']:.2f} mm), FEM "
              "over spectral: " + ", ".join(f"{s['fem_over_spectral']:.3f}" for s in sub))


if __name__ == "__main__":
    main()
