"""How much do sessions of one design differ from the one ``plan`` sizes?

``plan`` sizes the changes a drawn mark's crossing forces can name on one table: the
design's presses, every one certified, their brackets spanning 1 or 2 frame periods
spread evenly to the design's mean (``[plan] bracket_periods``). A real session draws
which presses span two periods, and loses presses whose mark never shows. This takes a
calibration's design (``tactilevision.planning.design_from_calibration``), draws
``--draws`` sessions of it (each press two periods with probability ``periods - 1``,
lost with probability ``--lost``), and prints the sizes the crossing tests name on each
(``tactilevision.diagnosis.crossing_sizes``) over the planned table's: their median,
90th percentile and largest.

    python benchmarks/bench_bracket_spread.py CALIBRATION_DIR [--session DIR]
        [--periods P] [--lost Q] [--draws N] [--seed S]
"""

from __future__ import annotations

import argparse
import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from tactilevision.diagnosis import crossing_sizes
from tactilevision.planning import (
    crossing_table,
    design_from_calibration,
    press_bracket_periods,
)

NAMES = ("spatial_nonuniformity", "stiffness_trend:time_s", "stiffness_step:press")


def drawn_sizes(design, draws: int, lost: float, seed: int) -> np.ndarray:
    """(draws, 3) sizes named on drawn sessions over the planned table's (NAMES' order)."""
    table = crossing_table(design)
    one = crossing_table(replace(design, bracket_periods=1.0, force_noise_n=0.0))
    unit = one["force_w0_sem_n"]                      # one period's bracket, as an sd
    even = press_bracket_periods(design.bracket_periods, unit.size)
    base = crossing_sizes(table)
    rng = np.random.default_rng(seed)
    share = design.bracket_periods - math.floor(design.bracket_periods)
    out = []
    for _ in range(draws):
        periods = math.floor(design.bracket_periods) + (rng.random(unit.size) < share)
        keep = rng.random(unit.size) >= lost
        drawn = {**table, "force_w0_sem_n": table["force_w0_sem_n"] + unit * (periods - even)}
        got = crossing_sizes({k: v[keep] for k, v in drawn.items()})
        out.append([got[n] / base[n] for n in NAMES])
    return np.array(out)


def add_design_arguments(ap: argparse.ArgumentParser) -> None:
    """A calibration's design on the command line: the folder, its ``--session`` and
    ``--periods`` (the brackets' mean frame periods instead of its own)."""
    ap.add_argument("calibration", type=Path)
    ap.add_argument("--session", type=Path)
    ap.add_argument("--periods", type=float, help="plan with this bracket_periods instead "
                    "of the calibration's own")


def design_of(a: argparse.Namespace):
    """The design :func:`add_design_arguments`' arguments name."""
    design = design_from_calibration(a.calibration, a.session)
    return design if a.periods is None else replace(design, bracket_periods=a.periods)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_design_arguments(ap)
    ap.add_argument("--lost", type=float, default=0.0, help="each press lost with this "
                    "probability")
    ap.add_argument("--draws", type=int, default=20)
    ap.add_argument("--seed", type=int, default=5)
    a = ap.parse_args(argv)
    design = design_of(a)
    r = drawn_sizes(design, a.draws, a.lost, a.seed)
    print(f"design: {len(design.depths_mm)} depths x {design.repeats}, brackets of "
          f"{design.bracket_periods:.3g} periods, presses lost with probability {a.lost:g}; "
          f"{a.draws} drawn sessions, sizes named over the planned table's:")
    for j, name in enumerate(NAMES):
        print(f"  {name:24s} median {np.median(r[:, j]):.2f}, 90th percentile "
              f"{np.percentile(r[:, j], 90):.2f}, largest {r[:, j].max():.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
