"""The crossing-force tests on synthetic tables, at the full number of tables.

    python benchmarks/bench_crossing_tables.py [--only NAME ...] [--per-seed]

``tests/test_crossings.py`` checks how often :func:`tactilevision.diagnosis.crossing_tests`
names a change on tables of 5 indenters x 4 presses whose crossing forces are bracketed as
the certification brackets them (its ``_crossings``: the same generator, imported from the
test file so that both draw the same tables). The suite runs the first tables of each
sweep; this script runs the sweeps at the sizes they were written with (issue 86: the
suite's time) and prints each count beside the bound it was written to meet, exiting 1 if
one misses:

- ``null``: nothing changes, 200 tables: alarms at most 6 (the family-wise 1 %), the scan's
  least p-value under 0.2 in 13 to 27 % of tables, the scatter's p-value 0.35 to 0.65 on
  average;
- ``step``: E falls 12 % after the 10th press, 100 tables: a step named along press or
  time in at least 84, found or listed as equivalent in at least 96, its size within 3 se
  in at least 80;
- ``trend``: E falls 20 % steadily, 100 tables: a trend named in at least 88, named or
  equivalent in at least 95;
- ``gradient``: 4 %/mm along x, 100 tables: spatial_nonuniformity named in at least 90;
- ``sizes``: :func:`~tactilevision.diagnosis.crossing_sizes`, 40 tables per shape and
  size: at the size said named in 34 to 40, at 1.5 times in 38 to 40, at half in at
  most 30;
- ``places``: :func:`~tactilevision.diagnosis.crossing_step_places`, 30 tables per size:
  the largest place's size named in at least 26, the half-way size there in at most 22.

``--per-seed`` prints each table's outcome (1 named, 0 not), so a smaller sweep's count
can be read off the first tables.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from test_crossings import _crossings

from tactilevision.diagnosis import (
    crossing_sizes,
    crossing_step_places,
    crossing_tests,
)


def _null() -> tuple[list[str], bool]:
    scans = [crossing_tests(_crossings(s, lambda p, x: np.ones(20))) for s in range(200)]
    alarms = [int(scan.found is not None) for scan in scans]
    least = float(np.mean([scan.tests[0].p_value < 0.2 for scan in scans]))
    chi = float(np.mean([scan.p_scatter for scan in scans]))
    ok = sum(alarms) <= 6 and 0.13 < least < 0.27 and 0.35 < chi < 0.65
    return [f"alarms {sum(alarms)} of 200 (<= 6)", f"least p < 0.2 in {least:.1%} (13-27 %)",
            f"mean scatter p {chi:.3f} (0.35-0.65)", f"per seed alarms {alarms}"], ok


def _step() -> tuple[list[str], bool]:
    named, either, held = [], [], []
    for seed in range(100):
        scan = crossing_tests(_crossings(seed, lambda p, x: np.where(p >= 10, 0.88, 1.0)))
        steps = [t for t in (scan.found, *scan.equivalent) if t is not None
                 and t.kind == "step" and t.column in ("press", "time_s")]
        either.append(int(bool(steps)))
        n = int(bool(steps) and steps[0] is scan.found)
        named.append(n)
        held.append(int(n and abs(steps[0].size - (0.88 - 1)) < 3 * steps[0].se))
    ok = sum(named) >= 84 and sum(either) >= 96 and sum(held) >= 80
    return [f"named {sum(named)} (>= 84), either {sum(either)} (>= 96), size held "
            f"{sum(held)} (>= 80) of 100", f"per seed named {named}", f"either {either}",
            f"held {held}"], ok


def _trend() -> tuple[list[str], bool]:
    found, either = [], []
    for seed in range(100):
        scan = crossing_tests(_crossings(seed, lambda p, x: 1 - 0.2 * p / 19))
        trends = [t for t in (scan.found, *scan.equivalent) if t is not None
                  and t.kind == "trend" and t.column in ("press", "time_s")]
        either.append(int(bool(trends)))
        found.append(int(bool(trends) and trends[0] is scan.found))
    ok = sum(found) >= 88 and sum(either) >= 95
    return [f"named {sum(found)} (>= 88), either {sum(either)} (>= 95) of 100",
            f"per seed named {found}", f"either {either}"], ok


def _gradient() -> tuple[list[str], bool]:
    hits = [int(getattr(crossing_tests(_crossings(s, lambda p, x: 1 + 0.04 * (x + 4))).found,
                        "effect", None) == "spatial_nonuniformity") for s in range(100)]
    return [f"named {sum(hits)} of 100 (>= 90)", f"per seed {hits}"], sum(hits) >= 90


def _sizes() -> tuple[list[str], bool]:
    sizes = crossing_sizes(_crossings(0, lambda p, x: np.ones(20)))
    shapes = {"stiffness_step:press": lambda d: lambda p, x: np.where(p > 9.5, 1 + d, 1.0),
              "stiffness_trend:time_s": lambda d: lambda p, x: np.exp(d * 3.0 * p),
              "spatial_nonuniformity": lambda d: lambda p, x: 1 + d * x}
    lines, ok = [], True
    for name, shape in shapes.items():
        for k, least, most in ((0.5, 0, 30), (1.0, 34, 40), (1.5, 38, 40)):
            hits = []
            for seed in range(40):
                t = crossing_tests(_crossings(100 + seed, shape(k * sizes[name]))).found
                hits.append(int(t is not None and (t.effect == name if name.startswith(
                    "spatial") else t.column in ("press", "time_s"))))
            ok &= least <= sum(hits) <= most
            lines.append(f"{name} at {k} x {sizes[name]:.4g}: named {sum(hits)} of 40 "
                         f"({least} to {most}); per seed {hits}")
    return lines, ok


def _places() -> tuple[list[str], bool]:
    null = _crossings(0, lambda p, x: np.ones(20))
    half = crossing_sizes(null)["stiffness_step:press"]
    places = dict(crossing_step_places(null))
    after, worst = max(places.items(), key=lambda p: p[1])

    def named(size: float) -> list[int]:
        return [int(getattr(crossing_tests(_crossings(100 + seed, lambda p, x: np.where(
            p > after, 1 + size, 1.0))).found, "column", None) in ("press", "time_s"))
            for seed in range(30)]

    at_worst, at_half = named(worst), named(half)
    return [f"after press {after:g}: its size {worst:.4g} named {sum(at_worst)} of 30 (>= 26), "
            f"the half-way size {half:.4g} {sum(at_half)} (<= 22)",
            f"per seed at its size {at_worst}", f"at the half-way size {at_half}"], \
        sum(at_worst) >= 26 and sum(at_half) <= 22


SWEEPS = {"null": _null, "step": _step, "trend": _trend, "gradient": _gradient,
          "sizes": _sizes, "places": _places}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="+", choices=sorted(SWEEPS), default=list(SWEEPS))
    ap.add_argument("--per-seed", action="store_true")
    args = ap.parse_args()
    failed = []
    for name in args.only:
        t0 = time.process_time()
        lines, ok = SWEEPS[name]()
        shown = [ln for ln in lines if args.per_seed or ("per seed" not in ln
                 and not ln.startswith(("either [", "held [", "at the half-way size [")))]
        if not args.per_seed:
            shown = [ln.split("; per seed")[0] for ln in shown]
        print(f"{name}: {'ok' if ok else 'MISSED'} ({time.process_time() - t0:.0f} s CPU)")
        for ln in shown:
            print(f"    {ln}")
        if not ok:
            failed.append(name)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
