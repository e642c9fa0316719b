"""Small-strain flat-punch FEM: kappa(nu, a/h) against Hayes 1972, convergence, timing.

Prints: dofs and seconds per solve; the mesh-convergence sequence at a/h = 0.8;
every entry of the Hayes table (ours, Hayes, % difference); convergence in mesh
and pad radius at a/h = 1.5 and 2.0; kappa against the pad radius; the
prototype's pad (a = 2.5, h = 3, R = 15 mm); the half-space limit; locking of a
displacement-only P2 model against the mixed one; bonded over frictionless.

Run: ``python benchmarks/bench_fem_linear.py`` (about 10 minutes on 2 cores).
"""

from __future__ import annotations

import time

import numpy as np
from skfem import Basis, BilinearForm, ElementTriP2, ElementVector, condense, solve
from skfem.helpers import ddot

from tactilevision.fem import LinearIndentationSolver, indentation_mesh
from tactilevision.fem._axisym import axisym_div, axisym_strain, ring_measure
from tactilevision.mechanics import HAYES_1972

NU3 = np.array([0.30, 0.45, 0.50])


def row(*cells: object) -> str:
    return "  ".join(f"{c:>10.5f}" if isinstance(c, float) else f"{c!s:>10}" for c in cells)


def section(title: str) -> None:
    print(f"\n== {title}")


def timing() -> None:
    section("timing, a/h = 0.8, default mesh (cell 0.125, 10 edge refinements, R/h 20)")
    t0 = time.perf_counter()
    s = LinearIndentationSolver(0.8)
    print(f"dofs {s.n_dofs}, assembly (mesh, A, B, C, ordering) "
          f"{time.perf_counter() - t0:.2f} s")
    for nu in (0.3, 0.45, 0.5):
        t0 = time.perf_counter()
        k = s.kappa(nu)
        print(f"nu {nu:.2f}: kappa {k:.5f}, solve {time.perf_counter() - t0:.2f} s")


LEVELS = ((0.5, 4), (0.25, 6), (0.125, 8), (0.125, 10), (0.0625, 12))


def convergence(a_over_h: float, levels=LEVELS, nus=NU3) -> np.ndarray:
    print(row("cell", "edge ref", "dofs", "s/solve", *(f"nu={n:.2f}" for n in nus),
              "max chg %"))
    last = None
    for cell, ref in levels:
        s = LinearIndentationSolver(a_over_h, cell=cell, edge_refinements=ref)
        t0 = time.perf_counter()
        k = s.kappa(nus)
        per = (time.perf_counter() - t0) / len(nus)
        chg = "" if last is None else f"{100 * np.max(np.abs(k / last - 1)):.4f}"
        print(row(cell, ref, s.n_dofs, f"{per:.2f}", *map(float, k), chg))
        last = k
    return last


def hayes_table() -> None:
    section("Hayes 1972 table (method.md): ours (default mesh, R/h 20), Hayes, % difference")
    print(row("a/h", "nu", "ours", "Hayes", "diff %"))
    worst = 0.0
    for ah, hayes in zip(HAYES_1972.a_over_h, HAYES_1972.values, strict=True):
        ours = LinearIndentationSolver(float(ah)).kappa(HAYES_1972.nu)
        for nu, k, h in zip(HAYES_1972.nu, ours, hayes, strict=True):
            d = 100 * (k / h - 1)
            worst = max(worst, abs(d)) if ah <= 1.0 else worst
            print(row(float(ah), float(nu), float(k), float(h), f"{d:+.2f}"))
    print(f"largest |difference| over a/h <= 1.0: {worst:.2f} %")


def pad_radius() -> None:
    section("kappa against the pad radius R/h (default mesh)")
    pads = (2.0, 3.0, 5.0, 10.0, 20.0, 40.0)
    print(row("a/h", "nu", *(f"R/h={p:g}" for p in pads)))
    for ah in (2.5 / 3, 1.0, 2.0):
        ks = np.array([LinearIndentationSolver(ah, pad_radius_over_h=p).kappa(NU3)
                       if p > ah + 0.25 else np.full(NU3.shape, np.nan) for p in pads])
        for j, nu in enumerate(NU3):
            print(row(ah, float(nu), *("-" if np.isnan(k) else float(k) for k in ks[:, j])))


def prototype() -> None:
    section("prototype pad: a = 2.5, h = 3, R = 15 mm (a/h 0.8333, R/h 5), default mesh")
    nus = np.array([0.3, 0.45, 0.49, 0.5])
    proto = np.array([2.185, 2.624, 2.888, 2.976])
    k = LinearIndentationSolver(2.5 / 3, pad_radius_over_h=5.0).kappa(nus)
    print(row("nu", "ours", "prototype", "diff %"))
    for n, a, b in zip(nus, k, proto, strict=True):
        print(row(float(n), float(a), float(b), f"{100 * (a / b - 1):+.3f}"))


def half_space() -> None:
    section("half-space limit (Sneddon kappa = 1): quadratic extrapolation to a/h = 0")
    ahs = np.array([0.05, 0.1, 0.2])
    nus = np.array([0.3, 0.5])
    ks = np.array([LinearIndentationSolver(a).kappa(nus) for a in ahs])
    print(row("a/h", *(f"nu={n:.2f}" for n in nus)))
    for a, k in zip(ahs, ks, strict=True):
        print(row(float(a), *map(float, k)))
    at0 = [np.polyval(np.polyfit(ahs, ks[:, j], 2), 0.0) for j in range(nus.size)]
    print(row("-> 0", *map(float, at0)))


@BilinearForm
def _elastic(u, v, w):
    r = w.x[0]
    return (2 * w.mu * ddot(axisym_strain(u, r), axisym_strain(v, r))
            + w.lam * axisym_div(u, r) * axisym_div(v, r)) * ring_measure(w)


def displacement_only_kappa(a_over_h: float, nu: float) -> float:
    """kappa from a displacement-only P2 model (locks as nu -> 0.5)."""
    m = indentation_mesh(a_over_h)
    b = Basis(m, ElementVector(ElementTriP2()), intorder=4)
    k = _elastic.assemble(b, mu=1 / (2 * (1 + nu)), lam=nu / ((1 + nu) * (1 - 2 * nu)))
    punch = b.get_dofs("punch").all("u^2")
    fixed = np.concatenate([b.get_dofs("bottom").all(), b.get_dofs("axis").all("u^1"), punch])
    x = np.zeros(b.N)
    x[punch] = -1.0
    x = solve(*condense(k, x=x, D=fixed))
    return float(-(k @ x)[punch].sum() * (1 - nu**2) / (2 * a_over_h))


def locking() -> None:
    section("locking at a/h = 0.8, default mesh: mixed P2/P1 against displacement-only P2")
    s = LinearIndentationSolver(0.8)
    print(row("nu", "mixed", "disp P2", "P2/mixed-1 %"))
    for nu in (0.3, 0.45, 0.49, 0.499, 0.4999, 0.5):
        km = s.kappa(nu)
        kd = displacement_only_kappa(0.8, nu) if nu < 0.5 else float("inf")
        print(row(nu, km, kd, f"{100 * (kd / km - 1):+.3f}"))


def bonded() -> None:
    section("bonded over frictionless punch, a/h = 0.8 (default mesh; bonded at two meshes)")
    nus = np.array([0.0, 0.3, 0.4, 0.45, 0.49, 0.5])
    kf = LinearIndentationSolver(0.8).kappa(nus)
    kb = LinearIndentationSolver(0.8, contact="bonded").kappa(nus)
    kb2 = LinearIndentationSolver(0.8, contact="bonded", cell=0.0625,
                                  edge_refinements=12).kappa(nus)
    print(row("nu", "frictionl.", "bonded", "bonded fine", "ratio"))
    for n, f, b, b2 in zip(nus, kf, kb, kb2, strict=True):
        print(row(float(n), float(f), float(b), float(b2), f"{b / f:.4f}"))


def main() -> None:
    t0 = time.perf_counter()
    timing()
    section("mesh convergence at a/h = 0.8 (R/h 20)")
    convergence(0.8)
    hayes_table()
    for ah in (1.5, 2.0):
        section(f"mesh convergence at a/h = {ah} (R/h 20), all nu of the table")
        convergence(ah, ((0.25, 6), (0.125, 10), (0.0625, 11)), HAYES_1972.nu)
    pad_radius()
    prototype()
    half_space()
    locking()
    bonded()
    print(f"\ntotal {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
