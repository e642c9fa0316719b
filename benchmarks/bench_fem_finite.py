"""beta(nu, a/h) from the finite-strain Neo-Hookean indentation FEM, against the paper.

Prints, for a/h = 0.8 and 2.5/3: the small-strain limit against the linear
solver; secant and tangent beta for nu = 0.30 ... 0.499 with a bonded punch, a
frictionless punch in contact (gel cannot enter the punch) and the frictionless
prescribed-displacement punch of the linear problem (the prototype's model), on
two or three meshes; the physics that might close the gap to the paper's
relation (7) (pad radius 5, a rounded edge); how linear P/w is in w/h; the nu
our curves give for the paper's beta = 1.5071; dofs and seconds per sweep.

Run: ``python benchmarks/bench_fem_finite.py`` (about 15 to 25 minutes on two
cores; ``--quick``: the coarsest mesh only, a few minutes).
"""

from __future__ import annotations

import argparse
import math
import os
import pickle
import time
import warnings
from concurrent.futures import ProcessPoolExecutor

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np

from tactilevision.fem import linear_indentation, neo_hookean_indentation
from tactilevision.mechanics import PAPER_BETA_RELATION

NUS = (0.30, 0.40, 0.45, 0.48, 0.49, 0.499)
PROTOTYPE_SECANT = {0.30: 0.08, 0.40: 0.29, 0.45: 0.54, 0.48: 0.76, 0.49: 0.84}
PROTOTYPE_TANGENT = {0.30: 0.15, 0.40: 0.40, 0.45: 0.82, 0.48: 1.40, 0.49: 1.60}
MESHES = {"M1": (0.25, 4), "M2": (0.25, 6), "M3": (0.125, 8)}
MODELS = {"bonded": {"contact": "bonded"},
          "frictionless": {"contact": "frictionless"},
          "frictionless-PD": {"contact": "frictionless", "contact_search": False}}
PAPER_BETA = 5.2662 / 3.4943
A_PAPER = 2.5 / 3.0


def paper_beta(nu: float) -> float:
    rel = PAPER_BETA_RELATION
    return math.exp((nu - rel.intercept) / rel.slope)


def sweep(task: tuple) -> tuple:
    key, kwargs = task
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return key, neo_hookean_indentation(**kwargs)


def beta_upto(res, w_max: float = 0.1) -> float:
    """Secant beta over the depths <= w_max (the range every sweep reached)."""
    keep = res.w_over_h <= w_max + 1e-12
    if keep.sum() < 2:
        return float("nan")
    slope, icpt = np.polyfit(res.w_over_h[keep], res.kappa_n[keep], 1)
    return slope / icpt


def fmt(x: float, spec: str = ".3f") -> str:
    return "   -  " if not np.isfinite(x) else format(x, spec)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="mesh M1 only")
    parser.add_argument("--cache", help="pickle of the sweeps: read if it exists, else written")
    args = parser.parse_args()
    meshes = {"M1": MESHES["M1"]} if args.quick else MESHES
    t_start = time.perf_counter()

    print("Meshes (indentation_mesh): " + ", ".join(
        f"{k} = cell {c}, edge_refinements {e}" for k, (c, e) in meshes.items()))
    print("Material: Abaqus Neo-Hookean, C10 = E/(4(1+nu)), D1 = 6(1-2nu)/E, mixed P2/P1; "
          "pad radius 20 h unless stated; 10 depth steps to w/h = 0.2\n")

    # ------------------------------------------------------------ tasks
    tasks = []
    for ah in (0.8, A_PAPER):
        for model, opts in MODELS.items():
            for mesh, (cell, er) in meshes.items():
                if model != "bonded" and (mesh == "M3" or (ah != 0.8 and mesh != "M1")):
                    continue
                for nu in NUS:
                    tasks.append(((ah, model, mesh, nu), dict(
                        a_over_h=ah, nu=nu, cell=cell, edge_refinements=er, **opts)))
    variants = {
        "pad radius 20 (reference)": {},
        "pad radius 5 (paper's pad)": {"pad_radius_over_h": 5.0},
        "edge radius 0.02 h": {"edge_radius_over_h": 0.02},
        "20 depth steps": {"steps": 20},
    }
    var_mesh = "M1" if args.quick else "M2"
    for name, extra in variants.items():
        for model in MODELS:
            if name.startswith("edge") and model != "frictionless":
                continue
            cell, er = MESHES[var_mesh]
            tasks.append((("variant", name, model), dict(
                a_over_h=A_PAPER, nu=0.48, cell=cell, edge_refinements=er,
                **MODELS[model], **extra)))
    for mesh, (cell, er) in meshes.items():                  # kappa0 only
        for contact in ("frictionless", "bonded"):
            for nu in (0.30, 0.45, 0.499):
                tasks.append((("kappa0", mesh, contact, nu), dict(
                    a_over_h=0.8, nu=nu, contact=contact, cell=cell, edge_refinements=er,
                    w_over_h_max=1e-4, steps=1, contact_search=False)))
    tasks.sort(key=lambda t: -t[1]["edge_refinements"] / t[1]["cell"])  # big ones first
    if args.cache and os.path.exists(args.cache):
        with open(args.cache, "rb") as fh:
            results = pickle.load(fh)
    else:
        with ProcessPoolExecutor(max_workers=os.cpu_count()) as pool:
            results = dict(pool.map(sweep, tasks))
        if args.cache:
            with open(args.cache, "wb") as fh:
                pickle.dump(results, fh)

    # ------------------------------------------------ small-strain limit
    print("1. Small-strain limit: kappa0 (finite-strain solver, tangent at w = 0) and "
          "kappa_n at w/h = 1e-4 against linear_indentation on the same mesh, a/h = 0.8")
    print(f"{'mesh':4} {'contact':12} {'nu':>6} {'kappa0':>8} {'kappa_n':>8} {'linear':>8} "
          f"{'diff %':>7} {'dofs':>6} {'s lin':>6}")
    for mesh, (cell, er) in meshes.items():
        for contact in ("frictionless", "bonded"):
            for nu in (0.30, 0.45, 0.499):
                t0 = time.perf_counter()
                lin = linear_indentation(0.8, nu, contact=contact, cell=cell,
                                         edge_refinements=er).kappa
                t_lin = time.perf_counter() - t0
                res = results["kappa0", mesh, contact, nu]
                print(f"{mesh:4} {contact:12} {nu:6.3f} {res.kappa0:8.4f} {res.kappa_n[0]:8.4f} "
                      f"{lin:8.4f} {100 * (res.kappa0 / lin - 1):+7.3f} {res.n_dofs:6d} "
                      f"{t_lin:6.1f}")
    print()

    # ------------------------------------------------------- beta tables
    print("2. beta(nu): secant beta_s (fit P/w = c(1 + beta w/h), eq. 5, over the depths "
          "reached), tangent beta_t (dP/dw = c(1 + 2 beta_t w/h)), beta_s over w/h <= 0.1, "
          "R^2 of the P/w line, depth reached, min det F, largest penetration, dofs, seconds")
    header = (f"{'a/h':6} {'model':16} {'mesh':4} {'nu':>6} {'kappa0':>7} {'beta_s':>7} "
              f"{'beta_t':>7} {'b_s<=.1':>7} {'R^2':>7} {'w_max':>6} {'minJ':>6} "
              f"{'pen':>8} {'its':>4} {'dofs':>6} {'s':>6}")
    for ah in (0.8, A_PAPER):
        print(header)
        for model in MODELS:
            for mesh in meshes:
                for nu in NUS:
                    res = results.get((ah, model, mesh, nu))
                    if res is None:
                        continue
                    print(f"{ah:6.4f} {model:16} {mesh:4} {nu:6.3f} {res.kappa0:7.4f} "
                          f"{fmt(res.beta_secant):>7} {fmt(res.beta_tangent):>7} "
                          f"{fmt(beta_upto(res)):>7} {fmt(res.linearity_r2, '.4f'):>7} "
                          f"{res.w_over_h[-1] if len(res.w_over_h) else 0:6.3f} "
                          f"{res.min_jacobian.min(initial=1):6.3f} "
                          f"{res.penetration.max(initial=0):8.1e} "
                          f"{res.newton_iterations.sum():4d} {res.n_dofs:6d} {res.seconds:6.1f}")
        print()

    # ---------------------------------------------- against the paper
    best = "M3" if "M3" in meshes else "M1"
    fr_mesh = "M2" if "M2" in meshes else "M1"
    print(f"3. Against the paper's relation (7) at a/h = 0.8 (bonded: mesh {best}; "
          f"frictionless: {fr_mesh}; '*': the sweep stopped before w/h = 0.2)")
    print(f"{'nu':>6} {'paper(7)':>8} {'proto_s':>7} {'proto_t':>7} {'bond_s':>7} "
          f"{'bond_t':>7} {'2bond_t':>7} {'fric_s':>8} {'fric_t':>8} {'PD_s':>8} {'PD_t':>8}")
    for nu in NUS:
        b = results[0.8, "bonded", best, nu]
        f = results[0.8, "frictionless", fr_mesh, nu]
        p = results[0.8, "frictionless-PD", fr_mesh, nu]
        star = {id(r): ("*" if not r.complete else " ") for r in (b, f, p)}
        print(f"{nu:6.3f} {paper_beta(nu):8.3f} "
              f"{fmt(PROTOTYPE_SECANT.get(nu, np.nan)):>7} "
              f"{fmt(PROTOTYPE_TANGENT.get(nu, np.nan)):>7} "
              f"{fmt(b.beta_secant):>7} {fmt(b.beta_tangent):>7} "
              f"{fmt(2 * b.beta_tangent):>7} "
              f"{fmt(f.beta_secant)}{star[id(f)]} {fmt(f.beta_tangent)}{star[id(f)]} "
              f"{fmt(p.beta_secant)}{star[id(p)]} {fmt(p.beta_tangent)}{star[id(p)]}")
    print(f"\nThe paper's beta = 5.2662 / 3.4943 = {PAPER_BETA:.4f} gives nu = "
          f"{PAPER_BETA_RELATION.slope * math.log(PAPER_BETA) + PAPER_BETA_RELATION.intercept:.4f}"
          " by (7). Our curves at a/h = 2.5/3:")
    for model in MODELS:
        mesh = best if model == "bonded" else "M1"
        for label, attr, factor in (("secant", "beta_secant", 1.0),
                                    ("tangent", "beta_tangent", 1.0),
                                    ("tangent without the 2", "beta_tangent", 2.0)):
            betas = np.array([factor * getattr(results[A_PAPER, model, mesh, nu], attr)
                              for nu in NUS])
            ok = np.isfinite(betas)
            nus, bs = np.array(NUS)[ok], betas[ok]
            cross = [nus[i] + (PAPER_BETA - bs[i]) * (nus[i + 1] - nus[i]) / (bs[i + 1] - bs[i])
                     for i in range(len(bs) - 1)
                     if (bs[i] - PAPER_BETA) * (bs[i + 1] - PAPER_BETA) <= 0 and bs[i + 1] != bs[i]]
            span = (f"beta {bs.min():.3f} .. {bs.max():.3f} over nu "
                    f"{nus.min():.2f} .. {nus.max():.3f}")
            answer = ", ".join(f"{c:.4f}" for c in cross) if cross else "none"
            print(f"  {model:16} {mesh} {label:22}: {span}; nu for beta = 1.5071: {answer}")
    print()

    # ------------------------------------------------- physics variants
    print(f"4. What might close the gap: a/h = 2.5/3, nu = 0.48, mesh {var_mesh}")
    print(f"{'variant':28} {'model':16} {'kappa0':>7} {'beta_s':>7} {'beta_t':>7} "
          f"{'b_s<=.1':>7} {'R^2':>7} {'w_max':>6} {'minJ':>6} {'s':>6}")
    for name in variants:
        for model in MODELS:
            res = results.get(("variant", name, model))
            if res is None:
                continue
            print(f"{name:28} {model:16} {res.kappa0:7.4f} {fmt(res.beta_secant):>7} "
                  f"{fmt(res.beta_tangent):>7} {fmt(beta_upto(res)):>7} "
                  f"{fmt(res.linearity_r2, '.4f'):>7} {res.w_over_h[-1]:6.3f} "
                  f"{res.min_jacobian.min():6.3f} {res.seconds:6.1f}")
    print()

    # ------------------------------------------------------- linearity
    res = results[A_PAPER, "bonded", best, 0.48]
    slope, icpt = np.polyfit(res.w_over_h, res.kappa_n, 1)
    quad = np.polyfit(res.w_over_h, res.kappa_n, 2)
    print(f"5. Linearity of P/w in w/h: bonded, a/h = 2.5/3, nu = 0.48, mesh {best}; "
          f"line kappa_n = {icpt:.4f} (1 + {slope / icpt:.4f} w/h), R^2 = "
          f"{res.linearity_r2:.5f}; quadratic term {quad[0]:+.3f} (w/h)^2")
    print(f"{'w/h':>6} {'kappa_n':>8} {'line':>8} {'resid %':>8} {'dP/dw':>8} {'minJ':>6}")
    for w, k, t, j in zip(res.w_over_h, res.kappa_n, res.tangent_stiffness,
                          res.min_jacobian, strict=True):
        line = icpt + slope * w
        print(f"{w:6.3f} {k:8.4f} {line:8.4f} {100 * (k / line - 1):+8.3f} {t:8.4f} {j:6.3f}")
    print(f"\nTotal {len(tasks)} sweeps, wall time {time.perf_counter() - t_start:.0f} s "
          f"on {os.cpu_count()} processes")


if __name__ == "__main__":
    main()
