"""A ball's fit: its time beside the flat punch's, and the FEATS gel's error ladder.

Prints:

1. The time of ``fit_indenter`` on 50 presses of a ball (the sphere table,
   nu profiled) beside ``fit_indentation`` on 50 flat-punch presses in the same run.
2. The real FEATS gel (sample_frames/feats): every law x contact at nu = 0.5 on the
   pad of finite size (equal-area radius, and the inscribed one beside it), each with
   its E and its apparent E per press, then diagnose_indenter's ladder.
2b. Friction (``--friction``): the small-strain law with Coulomb friction mu between
   ball and gel (their model's 1.0, and 0.5, 0.2, 0.1) on the equal-area pad, E and
   the apparent E per press beside the tied and frictionless limits, and the FEM's force
   at w/h = 0.5 on two surface cells (mesh convergence of the node-wise friction).
2c. The dome (``--dome``): the FEATS gel's top is domed (0.06 mm below the apex at
   4 mm, 0.28 mm at 8 mm: a spherical cap of radius 114 mm through the second, 133 mm
   through the first); every law x contact on the equal-area pad with each dome beside
   the flat top, E and the apparent E per press.
3. The ladder on circles with a shared error (``--seeds N``, default 10): presses drawn
   from the small-strain law (nothing missing), depths read through contact circles
   off by a shared bias (0, -1, -1.5 px; the stated bound 1.5 px) and 0.5 px at random
   (``tests/test_ball_diagnose_noise.py``): how often an effect is named with the
   depths read as exact, and with the fit's noise model (the stated uncertainties and
   the shared error fitted within its bound), and the ladder's time.

Usage: python benchmarks/bench_ball.py [--figure docs/feats_ladder.png] [--seeds 10]
       [--friction] [--dome]
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path

import numpy as np

from tactilevision import InputError
from tactilevision.diagnosis import diagnose_indenter
from tactilevision.fem import sphere_indentation
from tactilevision.mechanics import Sphere, fem_force, fit_indentation, fit_indenter
from tactilevision.viz import indenter_figure

ROOT = Path(__file__).resolve().parents[1]


def timing() -> None:
    rng = np.random.default_rng(1)
    ball = Sphere(2.0)
    w = np.repeat(np.linspace(0.1, 0.9, 10), 5)
    P = ball.force(w, E_mpa=0.2, nu=0.48, thickness_mm=3.0, law="neo_hookean", contact="tied")
    P = P + 0.002 * rng.standard_normal(w.size)
    wf = np.repeat(np.linspace(0.15, 0.6, 10), 5)
    Pf = fem_force(0.2, 0.48, 2.5, 3.0, wf) + 0.002 * rng.standard_normal(wf.size)
    fit_indenter(w, P, ball, thickness_mm=3.0, contact="tied")       # tables loaded
    fit_indentation(wf, Pf, thickness_mm=3.0, radius_mm=2.5)
    t0 = time.perf_counter()
    for _ in range(3):
        fit = fit_indenter(w, P, ball, thickness_mm=3.0, contact="tied")
    t_ball = (time.perf_counter() - t0) / 3
    t0 = time.perf_counter()
    for _ in range(3):
        fit_indentation(wf, Pf, thickness_mm=3.0, radius_mm=2.5)
    t_flat = (time.perf_counter() - t0) / 3
    print(f"1. fit of 50 ball presses: {t_ball:.3f} s (E {fit.E_mpa:.4f}, nu {fit.nu:.3f} "
          f"identified {fit.nu_identified}); flat punch, 50 presses: {t_flat:.3f} s; ratio "
          f"{t_ball / t_flat:.1f}")


def feats(figure: Path | None) -> None:
    data = np.loadtxt(ROOT / "sample_frames" / "feats" / "force_depth.csv", delimiter=",",
                      skiprows=1)
    w, P = data[:, 0], data[:, 1]
    print("2. FEATS (R 7.5 mm, h 4 mm, nu 0.5): E by least squares, apparent E per press")
    for pad in (12.92, 10.375):
        ball = Sphere(7.5, pad_radius_mm=pad)
        for law in ("linear", "neo_hookean"):
            for contact in ("tied", "frictionless"):
                t0 = time.perf_counter()
                try:
                    f = fit_indenter(w, P, ball, thickness_mm=4.0, law=law, contact=contact)
                except InputError as exc:        # a pad sweep whose Newton fails: said so
                    print(f"   pad {pad:6.3f} mm {law:11s} {contact:12s} not computed: {exc}")
                    continue
                print(f"   pad {pad:6.3f} mm {law:11s} {contact:12s} E {f.E_mpa:.4f} MPa "
                      f"[{f.E_ci95_mpa[0]:.3f}, {f.E_ci95_mpa[1]:.3f}], rmse "
                      f"{f.rmse_n * 1e3:6.1f} mN, apparent E "
                      + " ".join(f"{v:.3f}" for v in f.apparent_E_mpa)
                      + f"  ({time.perf_counter() - t0:.0f} s)")
    d = diagnose_indenter(w, P, Sphere(7.5, pad_radius_mm=12.92), thickness_mm=4.0,
                          contact="tied")
    print("   " + d.message)
    if figure is not None:
        indenter_figure(d, figure, title="FEATS GelSight Mini gel (Helmut et al., "
                        "arXiv:2411.03315; MIT): R = 7.5 mm, h = 4 mm, pad 12.92 mm")
        print(f"   wrote {figure}")


def friction() -> None:
    data = np.loadtxt(ROOT / "sample_frames" / "feats" / "force_depth.csv", delimiter=",",
                      skiprows=1)
    w, P = data[:, 0], data[:, 1]
    print("2b. FEATS with Coulomb friction (small strain, nu 0.5, pad 12.92 mm)")
    for contact, mu in (("tied", None), ("coulomb", 1.0), ("coulomb", 0.5), ("coulomb", 0.2),
                        ("coulomb", 0.1), ("frictionless", None)):
        t0 = time.perf_counter()
        f = fit_indenter(w, P, Sphere(7.5, pad_radius_mm=12.92, friction=mu),
                         thickness_mm=4.0, law="linear", contact=contact, nu=0.5)
        print(f"   {contact:12s} mu {'-' if mu is None else f'{mu:.1f}':>3s} E {f.E_mpa:.4f} "
              f"MPa, rmse {f.rmse_n * 1e3:5.0f} mN, apparent E "
              + " ".join(f"{v:.3f}" for v in f.apparent_E_mpa)
              + f"  ({time.perf_counter() - t0:.0f} s)")
    for mu in (1.0, 0.2):
        forces = []
        for cell in (0.0625, 0.03125):
            res = sphere_indentation(1.875, 0.5, np.array([0.125, 0.5]), model="linear",
                                     contact="coulomb", friction=mu, pad_radius_over_h=3.23,
                                     surface_cell=cell, cache=False)
            forces.append(res.force[-1])
        print(f"   mesh: mu {mu:.1f}, P/(E h^2) at w/h 0.5 on surface cells h/16 and h/32: "
              f"{forces[0]:.5f}, {forces[1]:.5f} ({100 * (forces[0] / forces[1] - 1):+.2f} %)")


def dome() -> None:
    data = np.loadtxt(ROOT / "sample_frames" / "feats" / "force_depth.csv", delimiter=",",
                      skiprows=1)
    w, P = data[:, 0], data[:, 1]
    sag = {r: 0.28 if r == 8.0 else 0.06 for r in (8.0, 4.0)}
    domes = [None] + [(r * r + s * s) / (2 * s) for r, s in sag.items()]   # chord's sagitta
    print("2c. FEATS with the domed top (nu 0.5, pad 12.92 mm): E and apparent E per press")
    for law in ("linear", "neo_hookean"):
        for contact in ("tied", "frictionless"):
            for rd in domes:
                t0 = time.perf_counter()
                try:
                    f = fit_indenter(w, P, Sphere(7.5, pad_radius_mm=12.92, dome_radius_mm=rd),
                                     thickness_mm=4.0, law=law, contact=contact, nu=0.5)
                except InputError as exc:
                    print(f"   {law:11s} {contact:12s} dome {rd or 0:5.1f} mm not computed: "
                          f"{exc}")
                    continue
                name = "flat top  " if rd is None else f"dome {rd:5.1f}"
                print(f"   {law:11s} {contact:12s} {name} E {f.E_mpa:.4f} MPa, rmse "
                      f"{f.rmse_n * 1e3:5.0f} mN, apparent E "
                      + " ".join(f"{v:.3f}" for v in f.apparent_E_mpa)
                      + f"  ({time.perf_counter() - t0:.0f} s)")


def shared_circles(seeds: int) -> None:
    sys.path.insert(0, str(ROOT / "tests"))
    from test_ball_diagnose_noise import BALL, H, _circle_presses

    print(f"3. false alarms on {seeds} seeds of presses with nothing missing "
          "(circles' shared bias; stated bound 1.5 px, random 0.5 px):")
    for bias in (0.0, -1.0, -1.5):
        plain, noise, names, took, took_plain = 0, 0, {}, 0.0, 0.0
        for seed in range(seeds):
            w, P, sd, shared = _circle_presses(seed, bias)
            t = time.perf_counter()
            a = diagnose_indenter(w, P, BALL, thickness_mm=H, contact="frictionless")
            took_plain += time.perf_counter() - t
            t = time.perf_counter()
            b = diagnose_indenter(w, P, BALL, thickness_mm=H, contact="frictionless",
                                  depth_std_mm=sd, depth_shared_mm=shared)
            took += time.perf_counter() - t
            plain += a.missing_effects != ()
            noise += b.missing_effects != ()
            for e in a.missing_effects:
                names[e] = names.get(e, 0) + 1
        print(f"   bias {bias:+.1f} px: read as exact, an effect named on {plain} of {seeds} "
              f"{names or ''}; with the noise model on {noise} of {seeds} "
              f"(ladder {took / seeds:.2f} s per session of 24 presses; read as exact, same "
              f"run: {took_plain / seeds:.3f} s)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--figure", type=Path, help="write the FEATS ladder figure here")
    ap.add_argument("--no-feats", action="store_true")
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--friction", action="store_true", help="only part 2b (minutes)")
    ap.add_argument("--dome", action="store_true", help="only part 2c (minutes)")
    args = ap.parse_args()
    print(f"machine: {platform.machine()}, {platform.processor() or '?'}; "
          f"python {platform.python_version()}")
    if args.friction:
        friction()
        return
    if args.dome:
        dome()
        return
    timing()
    if not args.no_feats:
        feats(args.figure)
    shared_circles(args.seeds)


if __name__ == "__main__":
    main()
