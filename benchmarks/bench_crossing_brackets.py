"""The crossing forces read as brackets against their midpoints' least squares, same tables.

    python benchmarks/bench_crossing_brackets.py [--tables 100]

Synthetic crossing forces as ``tests/test_crossings.py`` draws them: 5 indenters x 4
presses going round the indenters at fixed places on the pad, each crossing force
bracketed as the certification brackets it (a bracket 15.6 % of its reading wide, sd 4.5
%, holding the force at a uniform place). For each change (none, a step after the 10th
press, a steady softening over the session, a gradient along x), how many tables
``tactilevision.diagnosis.crossing_tests`` names it in (the brackets' likelihood ratio,
family-wise 1 %), against the scan it replaced on 2026-11-27: the brackets' midpoints
with sd width / sqrt(12), a weighted least-squares slope or step per test, family-wise 1 %
by the min-P over 10,000 draws of their joint normal null, a step preferred to a trend
along one column where its chi2 drops by more than 2 beyond the trend's. Counted as named:
the change's own kind (a step or a trend along press order or time;
``spatial_nonuniformity`` for the gradient); for nothing, any finding.

Also the milliseconds per ``crossing_tests`` call on each change's tables (the design's
null draws made once, before the rows: the first call's time is printed apart), beside a
same-run reference: one plain :func:`scipy.optimize.least_squares` fit of eq. (5) to 20
points (best of 20, at the start and at the end; the figure to compare across machines
is the ratio).
"""

from __future__ import annotations

import argparse
import itertools
import time

import numpy as np
from scipy.optimize import least_squares

from tactilevision.diagnosis import crossing_tests

SEM = 0.045
WIDTH = np.sqrt(12.0) * SEM
_DESIGN = np.random.default_rng(7)
X_MM, Y_MM = _DESIGN.uniform(-6.5, -1.3, 20), _DESIGN.uniform(-4, 4, 20)
IND = np.tile(np.arange(5), 4)
PRESS = np.arange(20.0)


def table(seed: int, scale: np.ndarray) -> dict[str, np.ndarray]:
    """One table: each crossing force P_g x scale, bracketed at a uniform place."""
    rng = np.random.default_rng(seed)
    p = np.array([0.3, 0.5, 0.7, 0.9, 1.1])[IND] * scale
    f = p / (1.0 + (rng.random(20) - 0.5) * WIDTH)
    return {"indenter": IND, "press": PRESS, "time_s": 3.0 * PRESS, "x_mm": X_MM,
            "y_mm": Y_MM, "force_w0_n": f, "force_w0_sem_n": SEM * f}


def _centred(v: np.ndarray, w: np.ndarray) -> np.ndarray:
    out = np.empty_like(v)
    for g in np.unique(IND):
        m = IND == g
        out[m] = v[m] - np.sum(w[m] * v[m]) / np.sum(w[m])
    return out


class Midpoints:
    """The midpoints' scan (the one replaced): built once for the design (its weights are
    the same for every table: the stated sd is 4.5 % of each reading)."""

    def __init__(self) -> None:
        self.w = np.full(20, 1.0 / SEM ** 2)
        cols = {"time_s": 3.0 * PRESS, "press": PRESS, "x_mm": X_MM, "y_mm": Y_MM}
        self.tests = []                    # (column, kind, shapes (K, 20))
        for col, z in cols.items():
            self.tests.append((col, "trend", [z]))
            if col in ("time_s", "press"):
                self.tests.append((col, "step", [(z > lo).astype(float) for lo, _ in
                                                 itertools.pairwise(np.unique(z))]))
        u = np.random.default_rng(20261126).standard_normal((10000, 20))
        self.dirs = [np.array([self._direction(z) for z in zs]) for _, _, zs in self.tests]
        null = np.stack([np.abs(u @ d.T).max(axis=1) for d in self.dirs], axis=1)
        self.srt = np.sort(null, axis=0)
        own = np.stack([(10000 - np.searchsorted(self.srt[:, j], null[:, j]) + 1) / 10001
                        for j in range(null.shape[1])], axis=1)
        self.least = np.sort(own.min(axis=1))

    def _direction(self, z: np.ndarray) -> np.ndarray:
        a = np.sqrt(self.w) * _centred(z, self.w)
        return a / np.linalg.norm(a)

    def found(self, cols: dict[str, np.ndarray]) -> tuple[str, str] | None:
        f = cols["force_w0_n"]
        scale = np.array([np.mean(f[IND == g]) for g in IND])
        r = _centred(f / scale - 1.0, self.w)
        zs = [np.abs(d @ (np.sqrt(self.w) * r)).max() for d in self.dirs]
        own = [(10000 - np.searchsorted(self.srt[:, j], z) + 1) / 10001
               for j, z in enumerate(zs)]
        fam = [(np.searchsorted(self.least, p, side="right") + 1) / 10001 for p in own]
        sig = sorted((p, -z, j) for j, (p, z) in enumerate(zip(fam, zs, strict=True))
                     if p < 0.01)
        if not sig:
            return None
        j = sig[0][2]
        col = self.tests[j][0]
        rival = [k for _, _, k in sig if self.tests[k][0] == col and k != j]
        if rival:
            js, jt = (j, rival[0]) if self.tests[j][1] == "step" else (rival[0], j)
            j = js if zs[js] ** 2 - zs[jt] ** 2 - 2.0 > 0 else jt
        return self.tests[j][0], self.tests[j][1]


def reference_fit() -> float:
    """Seconds for one least_squares fit of eq. (5) to 20 points (best of 20)."""
    rng = np.random.default_rng(0)
    w = np.linspace(0.15, 0.65, 20)
    p = 3.5 * w * (1 + 0.8 * w / 3.0) + rng.normal(0, 0.01, 20)
    best = np.inf
    for _ in range(20):
        t0 = time.perf_counter()
        least_squares(lambda x: x[0] * w * (1 + x[1] * w / 3.0) - p, [3.0, 1.0],
                      bounds=([0, -5], [np.inf, 20]), x_scale="jac")
        best = min(best, time.perf_counter() - t0)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--tables", type=int, default=100)
    n = ap.parse_args().tables
    mid = Midpoints()
    changes = [("nothing", np.ones(20), None),
               ("step after the 10th press, 12 %", np.where(PRESS >= 10, 0.88, 1.0), "step"),
               ("the same, 6 %", np.where(PRESS >= 10, 0.94, 1.0), "step"),
               ("steady softening, 20 % over the session", 1 - 0.2 * PRESS / 19, "trend"),
               ("the same, 10 %", 1 - 0.1 * PRESS / 19, "trend"),
               ("gradient along x, 4 %/mm", 1 + 0.04 * (X_MM + 4), "spatial"),
               ("the same, 2 %/mm", 1 + 0.02 * (X_MM + 4), "spatial")]
    ref = reference_fit()
    t0 = time.perf_counter()
    crossing_tests(table(10 ** 6, np.ones(20)))          # the design's null draws, once
    first = time.perf_counter() - t0
    print(f"reference: one least_squares fit of eq. (5), {ref * 1e3:.2f} ms; the first "
          f"crossing_tests call (the design's null draws) {first:.2f} s")
    print(f"{n} tables each | brackets named | midpoints named | ms / crossing_tests | "
          "/ reference")
    print("|---|---|---|---|---|")
    for label, scale, kind in changes:
        got, spent = [0, 0], 0.0
        for seed in range(n):
            cols = table(seed, scale)
            t0 = time.perf_counter()
            t = crossing_tests(cols).found
            spent += time.perf_counter() - t0
            ours = None if t is None else (t.column, t.kind)
            for i, f in enumerate((ours, mid.found(cols))):
                if kind is None:
                    got[i] += f is not None
                elif kind == "spatial":
                    got[i] += f is not None and f[0] in ("x_mm", "y_mm")
                else:
                    got[i] += f is not None and f[1] == kind and f[0] in ("press", "time_s")
        per = spent / n
        print(f"| {label} | {got[0]} | {got[1]} | {per * 1e3:.1f} | {per / ref:.0f} |")
    print(f"reference at the end {reference_fit() * 1e3:.2f} ms")


if __name__ == "__main__":
    main()
