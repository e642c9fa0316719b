"""Seconds per ``diagnose`` call on the tables the tests use, beside a same-run reference.

    python benchmarks/bench_diagnose_speed.py [SEEDS] [KIND,KIND,...]

Diagnoses ``make_measurement_table(kind, seed)`` for every kind of
:data:`tactilevision.sim.HIDDEN_EFFECTS` and None (``null``), seeds 0 to
SEEDS - 1 (default 4, the tests' seeds), at each table's ``truth["base"]``,
and prints the seconds per call by kind and in all. The machine's speed (and
what else runs on it) moves those figures, so the same run also times a
reference: one plain :func:`scipy.optimize.least_squares` fit of eq. (5)
(``P = c w (1 + beta w / h)``, method 'trf', bounds, ``x_scale='jac'``,
'2-point' Jacobian: the kind of solve diagnose makes a few hundred of) on
the first table, and the ratio "diagnose / reference" is the figure to
compare across machines and commits.
"""

from __future__ import annotations

import sys
import time
import warnings

import numpy as np
from scipy.optimize import least_squares

from tactilevision.diagnosis import diagnose
from tactilevision.sim import HIDDEN_EFFECTS, make_measurement_table


def reference_fit(t) -> float:
    """Seconds for one least_squares fit of eq. (5) to the table (best of 20)."""
    w, P, h = t.columns["depth_mm"], t.columns["force_n"], t.thickness_mm

    def resid(x: np.ndarray) -> np.ndarray:
        return x[0] * w * (1 + x[1] * w / h) - P

    best = np.inf
    for _ in range(20):
        t0 = time.perf_counter()
        least_squares(resid, [float(np.median(P / w)), 1.0], bounds=([0, -5], [np.inf, 20]),
                      x_scale="jac", method="trf")
        best = min(best, time.perf_counter() - t0)
    return best


def main() -> None:
    n_seeds = int(sys.argv[1]) if len(sys.argv) > 1 else 4
    kinds: list[str | None] = [None, *HIDDEN_EFFECTS]
    if len(sys.argv) > 2:
        kinds = [None if k == "null" else k for k in sys.argv[2].split(",")]
    warnings.simplefilter("ignore")
    ref = reference_fit(make_measurement_table(kinds[0], 0))
    total, calls = 0.0, 0
    print(f"reference: one least_squares fit of eq. (5): {ref * 1e3:.2f} ms")
    print(f"{'kind':26s} {'s / diagnose':>12s} {'/ reference':>12s}")
    for kind in kinds:
        spent = 0.0
        for seed in range(n_seeds):
            t = make_measurement_table(kind, seed)
            t0 = time.perf_counter()
            diagnose(t.columns, thickness_mm=t.thickness_mm, radius_mm=t.radius_mm,
                     base=t.truth["base"])
            spent += time.perf_counter() - t0
        total += spent
        calls += n_seeds
        per = spent / n_seeds
        print(f"{kind or 'null':26s} {per:12.3f} {per / ref:12.0f}")
    ref_end = reference_fit(make_measurement_table(kinds[0], 0))
    per = total / calls
    print(f"{'all':26s} {per:12.3f} {per / ref:12.0f}   ({calls} calls, {total:.1f} s; "
          f"reference at the end {ref_end * 1e3:.2f} ms)")


if __name__ == "__main__":
    main()
