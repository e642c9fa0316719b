"""The failures real recordings showed, drawn with their right answers, and how often the
library gives that answer.

    python benchmarks/bench_failures.py [--seeds 20] [--first-seed 0] [--cases ...]

Each case draws data whose right answer is known, runs the library's own call, and
scores the answer by a stated rule:

- ``ramp_wrong_law``: an Instron ramp of a flat punch (P linear in depth after a flat
  approach, 0.2 mN noise) fitted as a ball. Right: refused because the law cannot
  follow the curve (never "starts in contact"), or fitted with a warning that names the
  misfit.
- ``repeat_ramps``: two ramps of one specimen to 0.5 and 1.0 mm of a gel that stiffens
  more than the Neo-Hookean law (a Mooney-Rivlin-like extra term), fitted as a flat
  punch. Right: each E's interval holds the other's E (same specimen), or the fit
  warns of the misfit.
- ``specimens``: 6 specimens whose E scatter 15 % about 0.2 MPa, 20 presses each.
  Right: the batch's interval holds 0.2 MPa (a miss is silent where the pool does not
  say the specimens disagree).
- ``feats_shift``: four FEATS-like presses (the FEATS geometry: R 7.5 mm, h 4 mm, pad
  12.92 mm; the linear law, tied, E 0.414 MPa, 20 mN of F/T noise) with every depth
  shifted by +-0.05 mm. Right: fitted (not refused), ``diagnose`` names the depth offset
  within 15 um of the shift, and E within 5 %.

Every answer given without a warning is also checked: its interval must hold the
truth (``silent_miss`` counts those that do not).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np

from tactilevision import InputError
from tactilevision.diagnosis import diagnose_indenter
from tactilevision.mechanics import (
    FlatPunch,
    Sphere,
    fit_indentation,
    fit_indenter,
    fit_ramp,
    pool_specimens,
)

ROOT = Path(__file__).resolve().parents[1]


def ramp_wrong_law(seed: int) -> tuple[bool, bool]:
    """(right, silent miss) of a flat punch's ramp fitted as a ball."""
    rng = np.random.default_rng(seed)
    z = np.linspace(-0.3, 1.0, 651)
    k = 0.3 + 0.3 * rng.random()                          # N/mm
    P = 0.01 + k * np.clip(z, 0, None) + 2e-4 * rng.standard_normal(z.size)
    try:
        f = fit_ramp(z, P, Sphere(2.5), thickness_mm=5.0, law="linear")
    except InputError as exc:
        return "cannot follow this curve" in str(exc), False
    warned = f.indenter_fit.misfit is not None and f.indenter_fit.misfit.warning is not None
    return warned, not warned


def _stiffer_than_nh(w: np.ndarray, E: float, h: float) -> np.ndarray:
    """A gel stiffening faster than the Neo-Hookean flat punch: its force times
    (1 + 2 (w/h)^2)."""
    P = FlatPunch(2.0).force(w, E_mpa=E, nu=0.49, thickness_mm=h, law="neo_hookean")
    return P * (1 + 2.0 * (w / h) ** 2)


def repeat_ramps(seed: int) -> tuple[bool, bool]:
    """(right, silent miss) of two ramps of one specimen to different depths."""
    rng = np.random.default_rng(seed)
    h, E = 5.0, 0.05 * (1 + 0.2 * rng.random())
    fits = []
    for deep in (0.5, 1.0):
        z = np.linspace(-0.2, deep, 600)
        P = np.zeros(z.size)
        P[z > 0] = _stiffer_than_nh(z[z > 0], E, h)
        P += 0.005 + 2e-4 * rng.standard_normal(z.size)
        fits.append(fit_ramp(z, P, FlatPunch(2.0), thickness_mm=h, law="neo_hookean",
                             nu=0.49))
    a, b = fits
    overlap = (a.E_ci95_mpa[0] <= b.E_mpa <= a.E_ci95_mpa[1]
               and b.E_ci95_mpa[0] <= a.E_mpa <= b.E_ci95_mpa[1])
    warned = all(f.indenter_fit.misfit is not None and f.indenter_fit.misfit.warning
                 for f in fits)
    return overlap or warned, not (overlap or warned)


def specimens(seed: int) -> tuple[bool, bool]:
    """(right, silent miss) of a batch of 6 specimens with a 15 % spread."""
    rng = np.random.default_rng(seed)
    w = np.repeat([0.15, 0.30, 0.40, 0.50, 0.60], 4)
    fits = []
    for E in 0.2 * np.exp(0.15 * rng.standard_normal(6)):
        P = FlatPunch(2.5).force(w, E_mpa=E, nu=0.45, thickness_mm=3.0, law="neo_hookean")
        fits.append(fit_indentation(w, P + 0.005 * rng.standard_normal(w.size),
                                    thickness_mm=3.0, radius_mm=2.5))
    p = pool_specimens([str(i) for i in range(6)], [f.E_mpa for f in fits],
                       [f.E_ci95_mpa for f in fits])
    held = p.E_batch_ci95_mpa[0] <= 0.2 <= p.E_batch_ci95_mpa[1]
    return held, not held and not p.disagree


FEATS_BALL = Sphere(7.5, pad_radius_mm=12.92)
FEATS_DEPTHS = np.array([0.5, 1.0, 1.5, 2.0])


def feats_shift(seed: int) -> tuple[bool, bool]:
    """(right, silent miss) of FEATS-like presses with the depths shifted 0.05 mm."""
    rng = np.random.default_rng(seed)
    shift = 0.05 if seed % 2 else -0.05
    P = FEATS_BALL.force(FEATS_DEPTHS, E_mpa=0.414, nu=0.5, thickness_mm=4.0, law="linear",
                         contact="tied") + 0.02 * rng.standard_normal(4)
    w = FEATS_DEPTHS + shift
    fit = fit_indenter(w, P, FEATS_BALL, thickness_mm=4.0, law="linear", contact="tied")
    d = diagnose_indenter(w, P, FEATS_BALL, thickness_mm=4.0, contact="tied")
    last = d.ladder[-1]
    right = ("depth_offset" in d.missing_effects and abs(last.depth_offset_mm + shift) < 0.015
             and abs(last.E_mpa / 0.414 - 1) < 0.05)
    warned = fit.misfit is not None and fit.misfit.warning is not None
    silent = not warned and not fit.E_ci95_mpa[0] <= 0.414 <= fit.E_ci95_mpa[1]
    return right, silent


CASES: dict[str, Callable[[int], tuple[bool, bool]]] = {
    "ramp_wrong_law": ramp_wrong_law, "repeat_ramps": repeat_ramps, "specimens": specimens,
    "feats_shift": feats_shift}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--cases", nargs="+", choices=sorted(CASES), default=list(CASES))
    args = ap.parse_args(argv)
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    print(f"seeds {seeds.start} to {seeds.stop - 1}")
    for name in args.cases:
        scores = [CASES[name](s) for s in seeds]
        right = sum(r for r, _ in scores)
        silent = sum(m for _, m in scores)
        print(f"  {name:16s} right {right:2d} of {len(scores)}; answers without a warning "
              f"whose interval misses the truth: {silent}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
