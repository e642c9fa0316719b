"""Does ``plan`` predict how often ``fit_relaxation`` identifies g and tau?

For the paper's gauge block (``sample_frames/plan/paper_gauge_block.toml``: 50 presses,
1 s holds, a 1 kHz F/T of 12.5 mN per sample) and a few relaxations (g, tau) chosen so that
the predicted power spans 0 to 1, draws sessions of holds (each press's force ``P_i [(1 - g)
+ g phi(T_i / tau) exp(-t / tau)]`` at its FEM force, loaded over ``w / stage speed``, plus
white noise of the design's ``force_noise_n``), fits them with ``fit_relaxation`` and
counts how often it calls g and tau identified (``identified``), against
:func:`tactilevision.planning.relaxation_identifiability`'s power. The sessions use the
plan's own hold model and noise: this checks the power calculation, not the noise model
(a real F/T's noise is coloured).

Run: ``python benchmarks/bench_plan_relaxation.py [--sessions 40]``.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings

import numpy as np

from tactilevision.mechanics import fit_relaxation, ramp_factor
from tactilevision.planning import relaxation_identifiability
from tactilevision.planning._design import design_table, hold_lengths, read_design

CASES = ((0.004, 0.3), (0.006, 0.3), (0.008, 0.3), (0.01, 0.3), (0.012, 0.3), (0.016, 0.3),
         (0.02, 1.0), (0.05, 5.0))


def session(d, g: float, tau: float, rng: np.random.Generator):
    """(press, t, fz, ramp) of one drawn session of holds."""
    w, P = design_table(d)
    press, ts, fz, ramp = [], [], [], []
    for i, (wi, Pi, hold) in enumerate(zip(w, P, hold_lengths(d, w.size), strict=True)):
        n = round(hold * d.rate_hz)
        t = np.arange(n) / d.rate_hz
        T = wi / d.stage_speed_mm_s
        f = Pi * ((1 - g) + g * float(ramp_factor(T, tau)) * np.exp(-t / tau))
        press.append(np.full(n, i))
        ts.append(t)
        fz.append(f + d.force_noise_n * rng.standard_normal(n))
        ramp.append(np.full(n, T))
    return (np.concatenate(press), np.concatenate(ts), np.concatenate(fz),
            np.concatenate(ramp))


def rows(sessions: int, cases=CASES, design: str = "sample_frames/plan/paper_gauge_block.toml",
         *, echo: bool = False) -> list[dict]:
    """Per (g, tau) of `cases`: ``plan``'s noncentrality and power, and the share of
    `sessions` drawn sessions (seed 1) whose ``fit_relaxation`` calls g and tau identified."""
    d = read_design(design)
    out = []
    for g, tau in cases:
        r = relaxation_identifiability(d, g, tau)
        rng = np.random.default_rng(1)
        hits = 0
        for _ in range(sessions):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                fit = fit_relaxation(*session(d, g, tau, rng), n_boot=20)
            hits += bool(fit.identified)
        out.append({"g": g, "tau_s": tau, "noncentrality": float(r.noncentrality),
                    "predicted": float(r.power), "identified": hits / sessions,
                    "sessions": sessions})
        if echo:
            print(f"| {g:g} | {tau:g} | {r.noncentrality:.3g} | {100 * r.power:.0f} % | "
                  f"{100 * hits / sessions:.0f} % | {sessions} |", flush=True)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sessions", type=int, default=40)
    ap.add_argument("--design", default="sample_frames/plan/paper_gauge_block.toml")
    args = ap.parse_args(argv)
    print("| g | tau (s) | noncentrality | predicted | identified in | sessions |")
    print("|---|---|---|---|---|---|")
    t0 = time.perf_counter()
    rows(args.sessions, design=args.design, echo=True)
    print(f"{time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
