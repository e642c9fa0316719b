"""``plan``'s smallest effect sizes found in 95 % of sessions against ``diagnose`` itself.

For each of six designs (:func:`designs`: a/h 0.6 to 1.5, 4 to 8 depths, 3 to 6
repeats, vernier or mark; holds, rests, days and positions varied so that the
catalogue's effects can be tested), ``effect_sensitivity`` predicts for every
catalogue effect the size ``diagnose`` names in 95 % of sessions. This benchmark then
draws sessions of the design with the effect at 1/1.3, 1 and 1.3 times that size
(``tactilevision.sim.design_measurement_table``) and runs ``diagnose`` (defaults) on
each:

- forces from the finite-strain FEM at each press's true depth, so eq. (5)'s own
  misfit is in every table;
- the effect applied in the catalogue's own exact (not linearized) form
  (relaxation at tau 1 s, recovery at 2 s);
- F/T noise over the window on each force, each press's certified depth off its true
  depth by the design's random depth sd, tangential forces 2 % of the normal force in a
  random direction plus F/T noise.

An effect counts as found when ``diagnose`` puts it on its ladder or lists it as
equivalent to the effect it names (``bench_diagnose_power``'s rule). Prints per design
and effect the predicted size, the share found at each of the three sizes, and the
achieved 95 % size (interpolated: probit of the share against log size) over the
predicted; the target is within a factor 1.3.

The drawn sessions use the plan's own noise model (white, Gaussian) and the catalogue's
forms, so this checks the replay of ``diagnose``'s rule, not the noise model.

Then the replayed power (``effect_power``) at each drawn size against the share
``diagnose`` named (the issue's target: within 10 points).

Run: ``python benchmarks/bench_plan_effects.py [--sessions 40] [--jobs 2]
[--designs 0 1 ...] [--json PATH] [--figure PATH]``, or ``--from-json PATH`` to
summarize (and draw) a previous run.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
import warnings
from multiprocessing import Pool

os.environ.setdefault("OMP_NUM_THREADS", "1")

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from scipy import stats

from tactilevision import InputError
from tactilevision.diagnosis import diagnose
from tactilevision.planning import Design, effect_power, effect_sensitivity
from tactilevision.sim import design_measurement_table

FACTORS = (1 / 1.3, 1.0, 1.3)


def designs() -> list[Design]:
    """Six designs: a/h, depths, repeats and the depth method vary; each varies holds
    (window at the hold's end), rests, days and positions."""
    common = dict(window_at="end", force_noise_n=0.0125, window_samples=200)
    return [
        Design(thickness_mm=3.0, radius_mm=2.5, depths_mm=(0.15, 0.3, 0.4, 0.5, 0.6),
               repeats=6, bevel_angle_deg=5.0, overshoot_um=(30.0, 60.0),
               holds_s=(0.5, 2.0, 5.0), waits_s=(1.0, 3.0, 10.0), days=3, positions=6,
               **common),
        Design(thickness_mm=2.0, radius_mm=3.0, depths_mm=(0.1, 0.15, 0.2, 0.25, 0.3, 0.35),
               repeats=4, bevel_angle_deg=3.0, overshoot_um=(30.0, 90.0),
               holds_s=(1.0, 4.0), waits_s=(0.5, 5.0), days=2, positions=8, **common),
        Design(thickness_mm=4.0, radius_mm=2.4, depths_mm=(0.2, 0.4, 0.6, 0.75),
               repeats=6, frame_rate_hz=90.0, stage_speed_mm_s=0.1,
               holds_s=(0.5, 1.0, 3.0), waits_s=(2.0, 6.0), days=4, positions=10, **common),
        Design(thickness_mm=3.0, radius_mm=3.0,
               depths_mm=tuple(np.round(np.linspace(0.12, 0.57, 8), 3)), repeats=3,
               bevel_angle_deg=3.0, overshoot_um=(0.0, 50.0), holds_s=(0.3, 1.0, 3.0, 8.0),
               waits_s=(1.0, 2.0, 4.0, 8.0), days=2, positions=5, **common),
        Design(thickness_mm=2.5, radius_mm=3.75, depths_mm=(0.1, 0.2, 0.3, 0.4, 0.45),
               repeats=5, frame_rate_hz=30.0, stage_speed_mm_s=0.05,
               holds_s=(1.0, 2.0, 6.0), waits_s=(1.0, 10.0), days=3, positions=4, **common),
        Design(thickness_mm=3.0, radius_mm=2.0, depths_mm=(0.15, 0.25, 0.35, 0.45, 0.55),
               repeats=4, bevel_angle_deg=5.0, overshoot_um=(30.0, 60.0),
               holds_s=(0.5, 5.0), waits_s=(1.0, 4.0, 12.0), days=2, positions=6,
               force_noise_n=0.02, E_mpa=0.3, nu=0.47, window_at="end", window_samples=100),
    ]


def found(args: tuple) -> bool | None:
    """diagnose names the effect in the drawn session (None: the session cannot be drawn,
    a depth past the FEM table)."""
    i, name, size, seed = args
    d = designs()[i]
    try:
        cols = design_measurement_table(d, name, size, seed=seed)
    except InputError:
        return None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = diagnose(cols, thickness_mm=d.thickness_mm, radius_mm=d.radius_mm)
    named = [s.added for s in r.ladder if s.added] + list(r.equivalent_effects)
    return name in named


def achieved_ratio(factors: np.ndarray, shares: np.ndarray, n: int) -> float:
    """The achieved 95 % size over the predicted: probit of the share (clipped half a
    session from 0 and 1) against log size, the line through the points, at 0.95."""
    p = np.clip(shares, 0.5 / n, 1 - 0.5 / n)
    z = stats.norm.ppf(p)
    slope, icpt = np.polyfit(np.log(factors), z, 1)
    if slope <= 0:
        return math.nan
    return float(math.exp((stats.norm.ppf(0.95) - icpt) / slope))


def run(sessions: int = 40, jobs: int = 2, which: list[int] | None = None,
        effects: list[str] | None = None, json_path: str | None = None,
        show=print) -> list[dict]:
    """Draw `sessions` tables of each design (:func:`designs`, those in `which`) with each
    effect (those in `effects`) at each of :data:`FACTORS` times its predicted size, run
    diagnose on each on `jobs` processes, and return per (design, effect) the shares found
    and the achieved 95 % size over the predicted (:func:`achieved_ratio`); progress lines
    go to `show`; `json_path` is rewritten after every effect (a stop loses nothing)."""
    ds = designs()
    results: list[dict] = []
    with Pool(jobs) as pool:
        for i in which if which is not None else range(len(ds)):
            d = ds[i]
            t0 = time.perf_counter()
            pred = effect_sensitivity(d)
            t_plan = time.perf_counter() - t0
            how = (f"vernier {d.bevel_angle_deg:g} deg" if d.bevel_angle_deg
                   else f"mark {d.frame_rate_hz:g} frames/s")
            show(f"design {i}: a/h {d.a_over_h:.2f}, {len(d.depths_mm)} depths x "
                 f"{d.repeats}, {how}; sizes predicted in {t_plan:.2f} s")
            for name, s in pred.items():
                if effects and name not in effects:
                    continue
                if not math.isfinite(s.size_param):
                    show(f"  {name:24s} {s.why}")
                    continue
                jobs_ = [(i, name, f * s.size_param, 10_000 * i + 100 * k + j)
                         for k, f in enumerate(FACTORS) for j in range(sessions)]
                t1 = time.perf_counter()
                raw = pool.map(found, jobs_)
                if any(r is None for r in raw):
                    show(f"  {name:24s} predicted {s.size:9.4g} {s.unit:6s} not drawn: 1.3 "
                         "times it takes a press past the FEM table")
                    continue
                hits = np.array(raw, bool).reshape(len(FACTORS), sessions)
                shares = hits.mean(axis=1)
                ratio = achieved_ratio(np.array(FACTORS), shares, sessions)
                ok = 1 / 1.3 <= ratio <= 1.3 if math.isfinite(ratio) else False
                show(f"  {name:24s} predicted {s.size:9.4g} {s.unit:6s} found "
                     + " / ".join(f"{100 * v:3.0f} %" for v in shares)
                     + f" at x{FACTORS[0]:.2f}/x1/x{FACTORS[2]:.1f};  achieved/predicted "
                     f"{ratio:5.2f} {'ok' if ok else 'OUT'}  ({time.perf_counter() - t1:.0f} s)")
                results.append(dict(design=i, effect=name, predicted=s.size, unit=s.unit,
                                    predicted_param=s.size_param, snr=s.snr,
                                    shares=shares.tolist(), ratio=ratio, within=bool(ok),
                                    sessions=sessions, factors=list(FACTORS)))
                if json_path:
                    with open(json_path, "w") as fh:
                        json.dump(results, fh, indent=1)
    return results


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sessions", type=int, default=40)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--designs", type=int, nargs="*", default=None)
    ap.add_argument("--effects", nargs="*", default=None)
    ap.add_argument("--json", default=None)
    ap.add_argument("--from-json", default=None,
                    help="no sessions: read a previous run's JSON and print its summary")
    ap.add_argument("--figure", default=None,
                    help="draw achieved against predicted (with --from-json or after the run)")
    a = ap.parse_args(argv)
    if a.from_json:
        with open(a.from_json) as fh:
            results = json.load(fh)
        report(results, a.figure)
        return 0
    t_all = time.perf_counter()
    results = run(a.sessions, a.jobs, a.designs, a.effects, a.json,
                  show=lambda line: print(line, flush=True))
    print(f"{time.perf_counter() - t_all:.0f} s in all")
    report(results, a.figure)
    return 0


def report(results: list[dict], figure: str | None) -> None:
    """The summary: pairs within a factor 1.3, effects within it on how many designs, and
    the replayed power at each drawn size against the share diagnose named (``effect_power``
    at 2000 draws); ``figure``: both, drawn."""
    ds = designs()
    n_ok = sum(r["within"] for r in results)
    print(f"within a factor 1.3: {n_ok} of {len(results)} (design, effect) pairs")
    by_effect: dict[str, list[bool]] = {}
    for r in results:
        by_effect.setdefault(r["effect"], []).append(r["within"])
    for name, oks in by_effect.items():
        print(f"  {name:24s} within on {sum(oks)} of {len(oks)} designs")
    pred, got, where, n_s = [], [], [], []
    for r in results:
        for f, share in zip(r["factors"], r["shares"], strict=True):
            pred.append(effect_power(ds[r["design"]], r["effect"], f * r["predicted"]))
            got.append(share)
            where.append((r["design"], r["effect"], f))
            n_s.append(r["sessions"])
    pred, got, n_s = np.array(pred), np.array(got), np.array(n_s)
    close = np.abs(pred - got) <= 0.10
    # the share's own sampling sd over the sessions drawn, at the replayed power
    sd = np.sqrt(np.clip(pred * (1 - pred), 0.0025, None) / n_s)
    print(f"replayed power within 10 points of diagnose's share: {close.sum()} of {close.size} "
          f"(design, effect, size) points; median |difference| "
          f"{100 * np.median(np.abs(pred - got)):.0f} points; within 10 points or 2 sd of the "
          f"share's sampling error: {int(np.sum(close | (np.abs(pred - got) <= 2 * sd)))}")
    for k in np.flatnonzero(~close):
        i, name, f = where[k]
        print(f"  off by more than 10 points: design {i} {name} x{f:.2f}: replayed "
              f"{100 * pred[k]:.0f} %, diagnose {100 * got[k]:.0f} % of {n_s[k]} sessions "
              f"(sd {100 * sd[k]:.0f} points)")
    if figure:
        _figure(results, pred, got, figure)


def _figure(results: list[dict], pred: np.ndarray, got: np.ndarray, path: str) -> None:
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    names = list(dict.fromkeys(r["effect"] for r in results))
    for k in sorted({r["design"] for r in results}):
        rows = [r for r in results if r["design"] == k]
        ax1.plot([names.index(r["effect"]) + 0.08 * (k - 2.5) for r in rows],
                 [r["ratio"] for r in rows], "o", label=f"design {k}")
    ax1.axhspan(1 / 1.3, 1.3, color="0.9", zorder=0)
    ax1.axhline(1.0, color="0.5", lw=0.8)
    ax1.set_xticks(range(len(names)), [n.replace("_", " ") for n in names], rotation=35,
                   ha="right", fontsize=8)
    ax1.set_ylabel("achieved / predicted 95 % size")
    ax1.set_title("smallest size diagnose names in 95 % of sessions")
    ax1.legend(fontsize=7, ncol=2)
    ax2.plot(100 * pred, 100 * got, "o", ms=4, alpha=0.7)
    ax2.plot([0, 100], [0, 100], color="0.3", lw=0.8)
    ax2.fill_between([0, 100], [-10, 90], [10, 110], color="0.9", zorder=0)
    ax2.set_xlim(0, 102)
    ax2.set_ylim(0, 102)
    ax2.set_xlabel("plan's replayed power (%)")
    ax2.set_ylabel("share diagnose named (%)")
    ax2.set_title("at 1/1.3, 1 and 1.3 times the predicted size")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"figure: {path}")


if __name__ == "__main__":
    sys.exit(main())
