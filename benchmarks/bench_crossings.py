"""Within-indenter effects on drawn-mark sessions, found through the crossing forces.

    python benchmarks/bench_crossings.py [--seeds 20] [--first-seed 8000] [--fps 15]
        [--at-rules-out K | --at-plan K]

Each seed is a session of the project's generator (:func:`tactilevision.sim.make_session`:
a drawn mark, ``bevel_angle_deg = 0``, 5 depths x 4 presses, the stage overshooting w0 by 5
to 60 um), its F/T log written anew for each kind by ``benchmarks/bench_loop.py``'s
``write_forces`` (eq. 5 with the paper's beta, Hayes' kappa; E 0.20 MPa, nu 0.48): nothing,
a spatial gradient (10 % per 10 mm along x), a softening (10 % over the session) and a
stiffness step (10 % after the 10th press). Each is calibrated by the mark rule and
diagnosed (``diagnose(..., depth_rule='mark')``); printed per kind: how often the verdict
is right (nothing; ``spatial_nonuniformity``; a stiffness trend or step along time or
press order; a step; named, or listed among the verdict's equivalent effects, as
``bench_loop.py`` counts it, and how often named itself, before 2026-11-28 the only
count), and how often the crossing forces found it (issue 53's target: at
least 90 % of sessions for the within-indenter effects, no false alarm on the null).

``--at-rules-out K`` puts each effect at K times what that session's own null table's
crossing forces rule out; ``--at-plan K`` at K times what ``plan`` says the session's
design can see (:func:`tactilevision.planning.crossing_effect_sizes` on the
:class:`~tactilevision.planning.Design` the session follows: its block, repeats, frame
rate, F/T noise and window, its approach time (``approach_s``: the generator reaches
every press's depth in the same time, so each indenter passes its mark at its own speed;
before 2026-11-27's second change, the median speed for all), its overshoot range and
its ``presses.csv`` as the schedule: each press's indenter and position, in order; with
``--spiral``, its press count as positions round a spiral, as before 2026-11-27), and
prints both sizes per seed.

    python benchmarks/bench_crossings.py [--seeds 20] [--first-seed S] --at-plan K [--spiral]
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from tactilevision import InputError
from tactilevision.diagnosis import crossing_tests, diagnose
from tactilevision.io import read_measurements
from tactilevision.pipeline import calibrate_session, write_calibration
from tactilevision.planning import Design, crossing_effect_sizes, read_schedule
from tactilevision.sim import GaugeBlock, SessionSpec, make_session

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_loop import rules_out_sizes, write_forces

KINDS = ("null", "spatial", "softening", "damage")


def right(kind: str, verdict: str | None, equivalent: tuple[str, ...] = ()) -> bool:
    """Whether the verdict names the kind hidden, or lists it as `equivalent` (a step for a
    damage, a trend or step along time or press order for a softening), as
    ``bench_loop.py``'s ``score`` counts it."""
    if kind == "null":
        return verdict is None
    if kind == "spatial":
        return verdict == "spatial_nonuniformity"
    said = [e for e in (verdict, *equivalent) if e]
    if kind == "softening":
        return any(e.startswith("stiffness_") and e.endswith((":time_s", ":press"))
                   for e in said)
    return any(e.startswith("stiffness_step:") for e in said)


def plan_sizes(spec: SessionSpec, truth: dict, k: float, folder: Path | None = None
               ) -> dict[str, float]:
    """`k` times what ``plan`` says the session's design lets the crossing forces name in
    95 % of sessions, in the kinds' parameters (as :func:`bench_loop.rules_out_sizes`);
    with the session `folder`, its ``presses.csv`` (what the robot was to command, written
    before any frame) as the design's schedule."""
    presses = truth["presses"]
    approach = float(np.median([p["hold_from_s"] - p["t_start_s"] for p in presses]))
    over = [p["overshoot_mm"] for p in presses]
    design = Design(thickness_mm=spec.thickness_mm, radius_mm=spec.block.radius_mm,
                    depths_mm=tuple(spec.block.depths_mm), repeats=spec.repeats,
                    E_mpa=spec.E_mpa, nu=spec.nu, bevel_angle_deg=0.0,
                    mm_per_px=truth["mm_per_px"], frame_rate_hz=spec.fps,
                    approach_s=approach, force_noise_n=spec.force_noise_n[2],
                    window_samples=spec.window_samples, rate_hz=spec.rate_hz,
                    hold_s=float(np.mean(spec.hold_s)),
                    overshoot_um=(1e3 * min(over), 1e3 * max(over)),
                    waits_s=(float(np.mean(spec.wait_s)),), positions=len(presses),
                    schedule=None if folder is None else read_schedule(
                        folder / "presses.csv", len(spec.block.depths_mm)))
    got = {name: s.size_param for name, s in crossing_effect_sizes(design).items()}
    last = max(p["t_start_s"] for p in presses)
    return {"spatial": k * got["spatial_nonuniformity"],
            "softening": k * got["stiffness_trend:time_s"] * last,
            "damage": k * got["stiffness_step:press"]}


def one(work: Path, seed: int, fps: float, at_rules_out: float | None = None,
        at_plan: float | None = None, spiral: bool = False, kinds: tuple[str, ...] = KINDS,
        step_after: float | None = None, record: dict | None = None
        ) -> dict[str, tuple[str | None, str | None, tuple[str, ...]]]:
    """The verdict, the crossings' finding and the verdict's equivalent effects of each
    kind on one generated session (with
    `at_rules_out`, each kind at that many times what the null table's crossing forces
    rule out: :func:`bench_loop.rules_out_sizes`; with `step_after`, the damage's step
    after that press number, sized at its place). `record`: a dict that receives the
    sizes, ``"plan"`` (with `at_plan`) and ``"own"`` (what the null table's crossing forces
    rule out, times the same factor), each by kind."""
    folder = work / "s"
    spec = SessionSpec(E_mpa=0.2, nu=0.48, block=GaugeBlock(bevel_angle_deg=0.0), repeats=4,
                       fps=fps, overshoot_mm=(0.005, 0.06), seed=seed)
    make_session(folder, spec)
    truth = json.loads((folder / "truth.json").read_text())
    for p in truth["presses"]:                 # the schedule write_forces reads
        p["release_end_s"] = p["hold_to_s"] + spec.release_s
    (folder / "truth.json").write_text(json.dumps(truth))
    out, sizes = {}, {}
    if at_plan is not None:
        sizes = plan_sizes(spec, truth, at_plan, None if spiral else folder)
    for kind in kinds:
        write_forces(folder, work / kind, kind, seed=seed, size=sizes.get(kind),
                     step_after=9.5 if step_after is None else step_after)
        try:
            cal = calibrate_session(work / kind)
        except InputError as exc:       # e.g. a press past the FEM table: counted wrong
            out[kind] = (f"calibrate refused ({exc})", None, ())
            if kind == "null" and at_rules_out is not None:      # nothing to size from
                return {k: (f"not run: the null {out[kind][0]}", None, ()) for k in kinds}
            continue
        write_calibration(cal, work / f"{kind}_cal")
        t = read_measurements(work / f"{kind}_cal" / "measurements.csv")
        scan = crossing_tests(t.columns)
        try:
            d = diagnose({**t.columns, "depth_mm": t.depth_mm, "force_n": t.force_n},
                         thickness_mm=t.thickness_mm, radius_mm=t.radius_mm,
                         depth_rule="mark", rules_out=False)
            verdict, equivalent = d.missing_effect or d.offered_effect, d.equivalent_effects
        except InputError as exc:
            verdict, equivalent = f"diagnose refused ({exc})", ()
        out[kind] = (verdict, None if scan is None or scan.found is None
                     else scan.found.effect, tuple(equivalent))
        if kind == "null" and (at_rules_out is not None or at_plan is not None):
            own = rules_out_sizes(folder, work / "null_cal" / "measurements.csv",
                                  at_rules_out or at_plan, step_after)
            if at_plan is None:
                sizes = own
            if record is not None:
                record["own"] = dict(own)
                if at_plan is not None:
                    record["plan"] = dict(sizes)
            print(f"seed {seed} sizes (gradient /mm, fall over the session, step): "
                  + ("plan " + ", ".join(f"{sizes[k]:.4f}" for k in KINDS[1:]) + "; "
                     if at_plan is not None else "")
                  + "the null table's own " + ", ".join(f"{own[k]:.4f}" for k in KINDS[1:]),
                  flush=True)
    return out


def at_plan_sessions(seeds: int, first_seed: int, at_plan: float = 1.0, fps: float = 15.0
                     ) -> list[dict]:
    """Each seed's session with every kind at `at_plan` times the sizes ``plan`` gives its
    design (:func:`one`): ``[{"seed", "right": {kind: (verdict right, named itself,
    crossings right)}, "plan", "own"}]``."""
    rows = []
    for seed in range(first_seed, first_seed + seeds):
        work = Path(tempfile.mkdtemp(prefix="bench_crossings_"))
        record: dict = {}
        try:
            res = one(work, seed, fps, at_plan=at_plan, record=record)
        finally:
            shutil.rmtree(work, ignore_errors=True)
        rows.append({"seed": seed, "plan": record.get("plan", {}), "own": record.get("own", {}),
                     "right": {k: (right(k, v, eq), right(k, v), right(k, c))
                               for k, (v, c, eq) in res.items()}})
    return rows


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--first-seed", type=int, default=8000)
    ap.add_argument("--fps", type=float, default=15.0)
    ap.add_argument("--at-rules-out", type=float, metavar="K",
                    help="each kind at K times what its session's null table's crossing "
                         "forces rule out (default: the fixed sizes above)")
    ap.add_argument("--at-plan", type=float, metavar="K",
                    help="each kind at K times what plan says the session's design can see")
    ap.add_argument("--kinds", nargs="+", default=list(KINDS), choices=KINDS,
                    help="the kinds to hide (null first: the others are sized from it)")
    ap.add_argument("--step-after", type=float, metavar="N",
                    help="the damage's step after press number N (default: after the 10th), "
                         "with --at-rules-out sized at that place")
    ap.add_argument("--spiral", action="store_true",
                    help="with --at-plan: plan the design without its presses.csv (the "
                         "presses going round a spiral of positions), as before 2026-11-27")
    args = ap.parse_args()
    if args.at_rules_out is not None and args.at_plan is not None:
        ap.error("give --at-rules-out or --at-plan, not both")
    kinds = tuple(k for k in KINDS if k in args.kinds)
    score = {k: [0, 0, 0] for k in kinds}
    t0 = time.perf_counter()
    for seed in range(args.first_seed, args.first_seed + args.seeds):
        work = Path(tempfile.mkdtemp(prefix="bench_crossings_"))
        try:
            res = one(work, seed, args.fps, args.at_rules_out, args.at_plan, args.spiral, kinds,
                      args.step_after)
        finally:
            shutil.rmtree(work, ignore_errors=True)
        print(f"seed {seed}: " + "; ".join(
            f"{k}: {v or 'nothing'}" + "".join(f" (or {e})" for e in eq)
            + f" (crossings: {c or '-'})" for k, (v, c, eq) in res.items()), flush=True)
        for k, (v, c, eq) in res.items():
            score[k][0] += right(k, v, eq)
            score[k][1] += right(k, c)
            score[k][2] += right(k, v)
    print(f"\n{args.seeds} sessions at {args.fps:g} frames/s ({time.perf_counter() - t0:.0f} s):")
    for k, (v, c, alone) in score.items():
        print(f"  {k:9s}: verdict right in {v} of {args.seeds} (named itself: {alone}); the "
              f"crossings' own finding right in {c}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
