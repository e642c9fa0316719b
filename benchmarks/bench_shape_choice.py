"""Does the crossing scan name a step as a step and a softening as a trend?

Along time and press order the crossing scan tests a stiffness step and a steady change
(a trend); where both are significant, Cox's test of separate families chooses between
them, and where both explain the brackets, the other is listed as equivalent. This takes a
calibration's design (``tactilevision.planning.design_from_calibration``), draws
``--draws`` tables of its crossing forces (``tactilevision.planning.crossing_table``: each
press's crossing at a uniform place in its bracket) with a step of ``--step`` after press
number ``--after`` (the stiffness falling, as a damaged gel), and as many with a softening
of ``--softening`` over the session (linear in the press's time, as
``bench_loop.py``'s), runs ``tactilevision.diagnosis.crossing_tests`` on each and counts
how it reads them: the change named in its shape, named in the other shape with its own
listed as equivalent, named in the other shape alone (the wrong shape), another column, or
nothing; with the shapes told apart by Cox's test at 1 % (the library's level) and at 5 %
(the rule before 2026-11-28), from the same scans.

    python benchmarks/bench_shape_choice.py CALIBRATION_DIR [--session DIR]
        [--periods P] [--step S] [--after A] [--softening T] [--draws N] [--seed K]

On 251's design (a Taxim mark session with the renderer's shadows; brackets of 1.58 frame
periods, the other shadowed sessions' mean), 200 tables each, 2026-11-28 (the step and
softening are the sizes ``plan`` gave that design then): the step of 6.64 % after the 10th
press named a step in 166, a trend with the step equivalent in 26, a trend alone in 3 and
nothing in 5; the softening of 10.8 % a trend in 178, a step with the trend equivalent in
15, nothing in 7. At 5 % (the rule before that day), the same scans: the trend alone for
the step in 14 (the step equivalent in 15), a step alone for the softening in 5 (the
trend equivalent in 10).
"""

from __future__ import annotations

import argparse
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np

from tactilevision.diagnosis import crossing_tests
from tactilevision.planning import crossing_table

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_bracket_spread import add_design_arguments, design_of

#: A bracket's edges jittered by this share of its width (the scan's own null model:
#: ``BRACKET_SOFTNESS`` of ``tactilevision.diagnosis``'s brackets).
SOFTNESS = 0.02


#: The levels Cox's test is read at: the library's (1 %) and the rule before 2026-11-28.
LEVELS = (0.01, 0.05)


def shape_read(scan, kind: str, alpha: float) -> str:
    """How a scan reads a change of the shape `kind` (``'step'`` or ``'trend'``), the
    shapes told apart at `alpha`."""
    found, equivalent = (None, ()) if scan is None else scan.shapes_at(alpha)
    if found is None:
        return "nothing"
    if found.column not in ("time_s", "press"):
        return "another column"
    if found.kind == kind:
        return "its shape"
    if any(e.kind == kind for e in equivalent):
        return "the other, its own equivalent"
    return "the other alone"


def shape_counts(design, kind: str, size: float, after: float, draws: int, seed: int
                 ) -> dict[float, Counter]:
    """How `draws` tables of `design` with a change of `kind` and `size` are read, at each
    of :data:`LEVELS`."""
    table = crossing_table(design)
    f, se = table["force_w0_n"], table["force_w0_sem_n"]
    if kind == "step":
        change = 1.0 - size * (table["press"] > after)
    else:
        t = table["time_s"]
        change = 1.0 - size * (t - t.min()) / np.ptp(t)
    width = np.sqrt(12.0) * se / f
    rng = np.random.default_rng(seed)
    # each crossing at a uniform place in its bracket, the edges jittered: the midpoints
    u = rng.random((draws, width.size))
    mid = 1.0 + (0.5 - u) * width + rng.standard_normal((draws, width.size)) * SOFTNESS * width
    out = {a: Counter() for a in LEVELS}
    for i in range(draws):
        scan = crossing_tests({**table, "force_w0_n": mid[i] * change * f})
        for a in LEVELS:
            out[a][shape_read(scan, kind, a)] += 1
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_design_arguments(ap)
    ap.add_argument("--step", type=float, default=0.0664, help="relative stiffness step")
    ap.add_argument("--after", type=float, default=9.5, help="the step falls after this "
                    "press number")
    ap.add_argument("--softening", type=float, default=0.108, help="relative softening "
                    "over the session")
    ap.add_argument("--draws", type=int, default=200)
    ap.add_argument("--seed", type=int, default=11, help="the step's tables' seed (the "
                    "softening's: one more)")
    a = ap.parse_args(argv)
    design = design_of(a)
    print(f"design: {len(design.depths_mm)} depths x {design.repeats}, brackets of "
          f"{design.bracket_periods:.3g} periods; {a.draws} tables each")
    for k, (kind, size) in enumerate((("step", a.step), ("trend", a.softening))):
        t0 = time.perf_counter()
        got = shape_counts(design, kind, size, a.after, a.draws, a.seed + k)
        what = (f"step of {100 * size:.3g} % after press {a.after:g}" if kind == "step"
                else f"softening of {100 * size:.3g} % over the session")
        print(f"  {what} ({time.perf_counter() - t0:.0f} s):")
        for level in LEVELS:
            print(f"    shapes told apart at {100 * level:g} %: "
                  + ", ".join(f"{v} {n}" for n, v in sorted(got[level].items())))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
