"""An offset's power need not grow with its size: ``diagnose`` itself against the replay.

Beside a force or depth offset the law's curvature, P (1 + gamma (w/h)^2), has two
minima; ``diagnose``'s fit descends from gamma = 0 and can reach the one that mimics the
offset. On the paper's gauge block (a force offset) and on
``bench_plan_effects.py``'s design 2 (a depth offset), draws sessions at a few sizes
(``tactilevision.sim.design_measurement_table``), runs ``diagnose`` (defaults) on each
and prints the share that names the offset (on the ladder or as an equivalent) beside
``effect_power``'s replayed share.

Run: ``python benchmarks/bench_plan_dip.py [--sessions 30]`` (a few minutes).
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

from bench_plan_effects import designs

from tactilevision.diagnosis import diagnose
from tactilevision.planning import effect_power, read_design
from tactilevision.sim import design_measurement_table

PAPER = Path(__file__).resolve().parents[1] / "sample_frames" / "plan" / "paper_gauge_block.toml"

#: (label, design, effect, sizes in the plan's display unit: mN or um)
CASES = (("paper's block", lambda: read_design(PAPER), "force_offset", (50.8, 70.0, 80.8)),
         ("bench_plan_effects design 2", lambda: designs()[2], "depth_offset",
          (10.8, 19.0, 22.3)))


def named(d, effect: str, size_param: float, seed: int) -> bool:
    cols = design_measurement_table(d, effect, size_param, seed=seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = diagnose(cols, thickness_mm=d.thickness_mm, radius_mm=d.radius_mm)
    return effect in [s.added for s in r.ladder if s.added] + list(r.equivalent_effects)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sessions", type=int, default=30)
    args = ap.parse_args(argv)
    for label, make, effect, sizes in CASES:
        d = make()
        for size in sizes:
            share = sum(named(d, effect, size * 1e-3, seed) for seed in range(args.sessions))
            print(f"{label}: {effect} {size:g} {'mN' if effect == 'force_offset' else 'um'}: "
                  f"diagnose names it in {100 * share / args.sessions:.0f} % of "
                  f"{args.sessions} sessions; replayed {100 * effect_power(d, effect, size):.0f} %",
                  flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
