"""Accuracy of ``ForceEstimator`` against models other than its own, printed.

    python benchmarks/bench_forces_accuracy.py

- Flat punch (a = 2.5 mm, h = 3 mm, nu = 0.45, frictionless): the spectral
  'footprint' total and the fraction of the force inside radius rho against
  the axisymmetric P2/P1 FEM's punch reactions (0.05 mm pixels); the same
  FEM's whole surface field through 'field' (0.06 mm pixels).
- Hertz (R = 5 mm, 0.08 mm deep, nu = 0.45): total over Hertz's and the rms
  of the pressure's shape against the ellipse, for pads 10 and 40 mm thick.
- Side conditions: a 3 mm Gaussian bump and a 10 mm sphere press on a
  40 x 30 mm, 4 mm pad, FEM (40 x 30 B-bar nodes, free sides) over spectral
  (infinite layer), 'field' and 'footprint', nu = 0.45 and 0.49.
"""

from __future__ import annotations

import tempfile

import numpy as np

from tactilevision.fem import ForceEstimator, LinearIndentationSolver


def radius(shape, dx):
    yy, xx = np.indices(shape, dtype=np.float64)
    return np.hypot(xx - (shape[1] - 1) / 2, yy - (shape[0] - 1) / 2) * dx


def punch_rows() -> dict:
    """The flat punch: the spectral 'footprint' total and the share of the force inside
    rho a against the axisymmetric FEM's punch reactions, and the FEM's surface field
    through 'field': ``{"P_fem", "P_footprint", "inside": [(rho, spectral, fem)],
    "P_field", "off_footprint"}`` (N; shares; the largest |pressure| off the footprint
    over the mean contact pressure)."""
    A, H, NU, E, W = 2.5, 3.0, 0.45, 0.2, 0.05
    s = LinearIndentationSolver(A / H, contact="frictionless")
    x, res = s.solve(NU)
    dp = s.ubasis.get_dofs("punch").all("u^2")
    df = s.ubasis.get_dofs("free").all("u^2")
    rp, fp = s.ubasis.doflocs[0, dp] * H, -res[dp] * E * H * W
    P = float(fp.sum())
    r = radius((360, 360), 0.05)
    fm = ForceEstimator((360, 360), 0.05, thickness_mm=H, E_mpa=E, nu=NU, contact="footprint",
                        threshold_mm=W / 2)(np.where(r <= A, W, 0.0))
    fz = fm.forces_n[..., 2]
    inside = [(rho, float(fz[r <= rho * A].sum() / fz.sum()),
               float(fp[rp <= rho * A].sum() / P)) for rho in (0.3, 0.5, 0.7, 0.8, 0.9, 0.95)]
    dofs = np.concatenate([dp, df])
    rr = s.ubasis.doflocs[0, dofs] * H
    o = np.argsort(rr)
    r2 = radius((480, 480), 0.06)
    u = np.interp(r2, rr[o], -x[dofs][o] * W)
    f2 = ForceEstimator((480, 480), 0.06, thickness_mm=H, E_mpa=E, nu=NU, contact="field")(u)
    out = np.abs(f2.pressure_kpa[r2 > A + 0.5]).max() / (P / (np.pi * A**2) * 1e3)
    return {"P_fem": P, "P_footprint": float(fm.total_n[2]), "inside": inside,
            "P_field": float(f2.total_n[2]), "off_footprint": float(out)}


def punch() -> None:
    r = punch_rows()
    P = r["P_fem"]
    print(f"flat punch: FEM P = {P:.5f} N; spectral footprint {r['P_footprint']:.5f} N "
          f"({r['P_footprint'] / P - 1:+.2%})")
    for rho, spectral, fem in r["inside"]:
        print(f"  force inside {rho:.2f} a: spectral {spectral:.4f}, FEM {fem:.4f}")
    print(f"  the FEM's surface field, 'field': {r['P_field']:.5f} N "
          f"({r['P_field'] / P - 1:+.2%}); largest |pressure| off the footprint "
          f"{r['off_footprint']:.1%} of the mean contact pressure")


def hertz_rows() -> list[tuple[float, float, float, float]]:
    """Hertz's sphere (R = 5 mm, 0.08 mm deep) on pads 10 and 40 mm thick: ``[(h, a,
    total / Hertz, rms of the pressure's departure from the scaled ellipse / p0)]``."""
    R, delta, nu, E = 5.0, 0.08, 0.45, 0.2
    a = np.sqrt(R * delta)
    P = 4 / 3 * E / (1 - nu**2) * np.sqrt(R) * delta**1.5
    p0 = 3 * P / (2 * np.pi * a**2) * 1e3
    dx, n = 0.04, 64
    r = radius((n, n), dx)
    u = np.maximum(delta - r**2 / (2 * R), 0.0)
    rows = []
    for h, pad in ((10.0, 10.0), (40.0, 20.0)):
        fm = ForceEstimator((n, n), dx, thickness_mm=h, E_mpa=E, nu=nu, contact="footprint",
                            threshold_mm=1e-6, pad_mm=pad)(u)
        ratio = float(fm.total_n[2] / P)
        ins = r < 0.9 * a
        shape = fm.pressure_kpa[ins] - ratio * p0 * np.sqrt(1 - (r[ins] / a) ** 2)
        rows.append((h, float(a), ratio, float(np.sqrt(np.mean(shape**2)) / p0)))
    return rows


def hertz() -> None:
    for h, a, ratio, rms in hertz_rows():
        print(f"Hertz a = {a:.3f} mm on h = {h:g} mm: total / Hertz {ratio:.4f}, shape rms "
              f"{rms:.2%} of p0")


def sides() -> None:
    H, W, dx, h = 150, 200, 0.2, 4.0
    r = radius((H, W), dx)
    cases = {"3 mm Gaussian bump, 'field'": (0.1 * np.exp(-(r / 3.0) ** 2 / 2), "field"),
             "R 10 mm sphere 0.3 mm deep, 'footprint'": (np.maximum(0.3 - r**2 / 20, 0),
                                                        "footprint")}
    with tempfile.TemporaryDirectory() as cache:
        for name, (u, contact) in cases.items():
            for nu in (0.45, 0.49):
                kw = dict(thickness_mm=h, E_mpa=0.2, nu=nu, contact=contact, threshold_mm=1e-6)
                sp = ForceEstimator((H, W), dx, **kw)(u).total_n[2]
                fe = ForceEstimator((H, W), dx, method="fem", cache_dir=cache, **kw)(u).total_n[2]
                print(f"{name}, nu {nu}: FEM {fe:.4f} N, spectral {sp:.4f} N, ratio "
                      f"{fe / sp:.3f}")


if __name__ == "__main__":
    punch()
    hertz()
    sides()
