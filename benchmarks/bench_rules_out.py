"""What a "nothing missing" verdict rules out, checked: an effect of 1.5 times the stated
size is named.

    python benchmarks/bench_rules_out.py [--seeds 10] [--factor 1.5]

For each seed, the generator's null table (``tactilevision.sim.make_measurement_table``:
the finite-strain FEM law and its noise, nothing hidden) is diagnosed; its verdict names
nothing and states, per catalogue effect, the smallest size this very table would have
named (``Diagnosis.rules_out``, the plan's replay on the measured presses). Then the same
seed's table is drawn again with one effect hidden at `factor` times that size (the
generator's draws do not depend on the effect's strength, so presses, design and noise are
the same) and diagnosed: the effect is *named* when it is the missing effect or listed as
equivalent to it (the replay's rule). Effects whose generator parameter is the catalogue's
own: depth_offset (delta_mm), force_offset (offset_n), force_crosstalk (kx = chi). And a
stiffness changing over the session, hidden by scaling the null table's forces in the
catalogue's own parametrisation: a softening ``exp(-k (t - mean t))``
(``stiffness_trend:time_s``, named also as the offered trend of an unexplained
``time_s``) and a step ``1 - s [press > median]`` (``stiffness_step:press``).
Printed: per effect, the share of seeds that named it, and the sizes; the time of a
null diagnosis with its replay beside the same diagnosis without it (same run).
"""

from __future__ import annotations

import argparse
import platform
import time
import warnings

import numpy as np

from tactilevision.diagnosis import diagnose
from tactilevision.sim import make_measurement_table

#: catalogue effect -> (generator's hidden name, its truth key of the same parameter)
EFFECTS = {"depth_offset": ("depth_offset", "delta_mm"),
           "force_offset": ("force_offset", "offset_n"),
           "force_crosstalk": ("crosstalk", "chi")}
#: a stiffness changing over the session: its force factor at size x
COLUMN = {"stiffness_trend:time_s": lambda c, x: np.exp(-x * (c["time_s"] - c["time_s"].mean())),
          "stiffness_step:press": lambda c, x: 1 - x * (c["press"] > np.median(c["press"]))}


def _diag(t, columns=None):
    """diagnose of the table `t` (or of `columns` in its place, with its h and a)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return diagnose(t.columns if columns is None else columns,
                        thickness_mm=t.thickness_mm, radius_mm=t.radius_mm)


def _said(seed: int, eff: str, ruled, factor: float, d, echo: bool = True) -> bool:
    """Whether `d` names `eff` (its verdict, an equivalent or the offered trend), printed."""
    hit = eff in (d.missing_effect, *d.equivalent_effects, d.offered_effect)
    if echo:
        print(f"seed {seed}: {eff} ruled out above {ruled.size:.3g} {ruled.unit}; hidden at "
              f"{factor:g} x: {'named' if hit else 'missed'} (verdict {d.missing_effect}, "
              f"equivalent {list(d.equivalent_effects)}, offered {d.offered_effect})")
    return hit


def run(seeds: int, factor: float = 1.5, *, echo: bool = False) -> dict:
    """Seeds 0 to `seeds` - 1: each null table's verdict and what it rules out, then each
    effect hidden at `factor` times that size. Returns ``named`` and ``tried`` (per effect),
    ``null_alarms`` (seeds whose null table named something), and the null diagnoses'
    times with and without the replay (``took``, ``bare``, s)."""
    named = {k: 0 for k in (*EFFECTS, *COLUMN)}
    tried = {k: 0 for k in (*EFFECTS, *COLUMN)}
    took, bare, alarms = [], [], []
    for seed in range(seeds):
        null = make_measurement_table(None, seed)
        t0 = time.perf_counter()
        d0 = _diag(null)
        took.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            diagnose(null.columns, thickness_mm=null.thickness_mm, radius_mm=null.radius_mm,
                     rules_out=False)
        bare.append(time.perf_counter() - t0)
        if d0.missing_effect or d0.unexplained_covariate:
            alarms.append(seed)
            if echo:
                print(f"seed {seed}: the null table named "
                      f"{d0.missing_effect or d0.offered_effect}")
            continue
        for eff in (*EFFECTS, *COLUMN):
            size = d0.rules_out[eff].size_param
            if not 0 < size < float("inf"):
                continue
            x = factor * size
            if eff in EFFECTS:
                hidden, key = EFFECTS[eff]
                unit = make_measurement_table(hidden, seed).truth[key]
                d = _diag(make_measurement_table(hidden, seed, strength=x / unit))
            else:
                c = null.columns
                d = _diag(null, {**c, "force_n": c["force_n"] * COLUMN[eff](c, x)})
            tried[eff] += 1
            named[eff] += _said(seed, eff, d0.rules_out[eff], factor, d, echo)
    return dict(named=named, tried=tried, null_alarms=alarms, took=took, bare=bare)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--factor", type=float, default=1.5)
    args = ap.parse_args()
    print(f"machine: {platform.machine()}, python {platform.python_version()}; "
          f"{args.seeds} seeds, effects at {args.factor:g} x the size ruled out")
    got = run(args.seeds, args.factor, echo=True)
    for eff in (*EFFECTS, *COLUMN):
        print(f"{eff}: named in {got['named'][eff]} of {got['tried'][eff]}")
    med = float(np.median(got["took"]))
    ref = float(np.median(got["bare"]))
    print(f"diagnose of a null table with its replay: median {med:.2f} s; the same tables "
          f"without it (rules_out=False, same run): {ref:.2f} s; ratio {med / ref:.1f}")


if __name__ == "__main__":
    main()
