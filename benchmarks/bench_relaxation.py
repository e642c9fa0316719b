"""A viscoelastic gel end to end: session folder -> calibrate -> E_0 and E_inf.

    python benchmarks/bench_relaxation.py [--seeds 1000 1001 ...] [--presses-per-depth 4]
        [--hold-s 2.0] [--g 0.25] [--tau-s 0.7] [--keep DIR] [--json FILE]

Issue 23's relaxation target: "E_0 and E_inf within 5 % from the hold curves of
a 20-press session". For each seed, a session is simulated
(:func:`tactilevision.sim.make_session`: frames of the FEM gel surface through
Taxim's shading table, the F/T log of a gel that relaxes by Boltzmann
superposition with G(t)/G(0) = 1 - g (1 - exp(-t/tau)), 5 depths x
``--presses-per-depth`` presses held ``--hold-s`` s, the stage overshooting
w0 by 0 to 50 um as the sample session's does, seeds from 1000: the tests use
seeds below 1000). Then :func:`tactilevision.calibrate_session` runs three
ways:

- ``relaxation='off'``: the forces as measured (the window's mean over the
  first 0.2 s of the hold) and the clock synchronised on them;
- the default (``'auto'``): the holds fitted, the clock synchronised on the
  elastic force, each press's force taken back to the instant of loading;
  E is E_0, and E_inf = (1 - g) E_0 beside it;

and ``fit --holds`` on calibrate's own measurements.csv and holds.csv must
give the same E_0. Printed per seed: the clock offset found (truth 0.137 s),
g and tau, E (off), E_0 and E_inf against the truth (E_0 = ``E_mpa``, E_inf
= (1 - g) E_0), and whether each interval covers it; then the worst error.
The sessions take about a minute each to render on 2 cores.
"""

from __future__ import annotations

import argparse
import json
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from tactilevision import calibrate_session
from tactilevision.sim import SessionSpec, make_session


def one(seed: int, *, per_depth: int, hold_s: float, g: float, tau_s: float,
        keep: Path | None) -> dict:
    """Simulate, calibrate with and without the relaxation, return the numbers."""
    base = keep if keep is not None else Path(tempfile.mkdtemp(prefix="bench_relax_"))
    folder = base / f"relax_{seed}"
    if folder.exists():
        shutil.rmtree(folder)
    spec = SessionSpec(repeats=per_depth, hold_s=hold_s, relaxation_g=g, relaxation_tau_s=tau_s,
                       overshoot_mm=(0.0, 0.05), seed=seed)
    t0 = time.perf_counter()
    truth = make_session(folder, spec)
    t_render = time.perf_counter() - t0
    t0 = time.perf_counter()
    off = calibrate_session(folder, relaxation="off")
    t_off = time.perf_counter() - t0
    t0 = time.perf_counter()
    cal = calibrate_session(folder)
    t_auto = time.perf_counter() - t0
    e0, e_inf = truth["E_mpa"], (1 - g) * truth["E_mpa"]
    r = cal.relaxation
    m = cal.moduli or {}
    row = dict(seed=seed, presses=len(truth["presses"]),
               certified=len(cal.certification.presses),
               clock_off_s=off.certification.clock_offset_s,
               clock_auto_s=cal.certification.clock_offset_s,
               clock_true_s=truth["clock_offset_s"],
               g=r.g if r else float("nan"), g_ci=list(r.g_ci) if r else None,
               tau_s=r.tau_s if r else float("nan"),
               E_off=off.fit.E_mpa, E0=m.get("E0_mpa", float("nan")),
               E0_ci=list(m.get("E0_ci_mpa", (np.nan, np.nan))),
               E_inf=m.get("E_inf_mpa", float("nan")),
               E_inf_ci=list(m.get("E_inf_ci_mpa", (np.nan, np.nan))),
               nu_off=off.fit.nu, nu=cal.fit.nu, nu_true=truth["nu"],
               E0_true=e0, E_inf_true=e_inf, render_s=t_render, calibrate_off_s=t_off,
               calibrate_s=t_auto)
    # fit --holds on calibrate's own output repeats the default
    from tactilevision.cli import main

    out = folder / "out"
    if out.exists():
        shutil.rmtree(out)
    main(["calibrate", str(folder), "--out", str(out), "--no-report", "--no-progress",
          "--json", str(folder / "cal.json")])
    main(["fit", str(out / "measurements.csv"), "--holds", str(out / "holds.csv"),
          "--json", str(folder / "fit.json")])
    e = json.loads((folder / "fit.json").read_text())["E_mpa"]
    row["E0_fit_holds"] = float("nan") if e is None else e       # None: out of the table
    if keep is None:
        shutil.rmtree(base)
    return row


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1000, 1001, 1002])
    ap.add_argument("--presses-per-depth", type=int, default=4)
    ap.add_argument("--hold-s", type=float, default=2.0)
    ap.add_argument("--g", type=float, default=0.25)
    ap.add_argument("--tau-s", type=float, default=0.7)
    ap.add_argument("--keep", type=Path, help="keep the sessions under this folder")
    ap.add_argument("--json", type=Path)
    a = ap.parse_args(argv)
    rows = []
    print(f"g {a.g}, tau {a.tau_s} s, {5 * a.presses_per_depth} presses held {a.hold_s} s; "
          "E truth: E_0 0.2 MPa, E_inf (1 - g) E_0")
    print("| seed | certified | clock off / auto (true 0.137 s) | g [CI] | tau (s) | E, off (MPa) "
          "| E_0 [CI] | E_inf [CI] | E_0 err | E_inf err | fit --holds E_0 | nu off / auto |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for seed in a.seeds:
        r = one(seed, per_depth=a.presses_per_depth, hold_s=a.hold_s, g=a.g, tau_s=a.tau_s,
                keep=a.keep)
        rows.append(r)
        e0_err = r["E0"] / r["E0_true"] - 1
        einf_err = r["E_inf"] / r["E_inf_true"] - 1
        cov0 = r["E0_ci"][0] <= r["E0_true"] <= r["E0_ci"][1]
        covi = r["E_inf_ci"][0] <= r["E_inf_true"] <= r["E_inf_ci"][1]
        print(f"| {r['seed']} | {r['certified']}/{r['presses']} | {r['clock_off_s']:.4f} / "
              f"{r['clock_auto_s']:.4f} | {r['g']:.3f} [{r['g_ci'][0]:.3f}, {r['g_ci'][1]:.3f}] "
              f"| {r['tau_s']:.3f} | {r['E_off']:.4f} | {r['E0']:.4f} [{r['E0_ci'][0]:.4f}, "
              f"{r['E0_ci'][1]:.4f}] | {r['E_inf']:.4f} [{r['E_inf_ci'][0]:.4f}, "
              f"{r['E_inf_ci'][1]:.4f}] | {100 * e0_err:+.1f} %{'' if cov0 else ' (outside)'} "
              f"| {100 * einf_err:+.1f} %{'' if covi else ' (outside)'} | "
              f"{r['E0_fit_holds']:.4f} | {r['nu_off']:.3f} / {r['nu']:.3f} |", flush=True)
    def worst(key: str, true: str) -> str:
        err = np.array([abs(r[key] / r[true] - 1) for r in rows])
        ok = np.isfinite(err)
        txt = f"{100 * err[ok].max():.1f} %" if ok.any() else "-"
        return txt + (f" ({int((~ok).sum())} of {err.size} not computed: out of the beta "
                      "table or not resolved)" if (~ok).any() else "")

    print(f"worst |error|: E_0 {worst('E0', 'E0_true')}, E_inf {worst('E_inf', 'E_inf_true')}; "
          f"E with the relaxation off against E_0: {worst('E_off', 'E0_true')} "
          f"({len(rows)} sessions; render {np.mean([r['render_s'] for r in rows]):.0f} s, "
          f"calibrate {np.mean([r['calibrate_off_s'] for r in rows]):.1f} s off and "
          f"{np.mean([r['calibrate_s'] for r in rows]):.1f} s with it, per session)")
    if a.json:
        a.json.write_text(json.dumps(rows, indent=1, default=float) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
