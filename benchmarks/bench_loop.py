"""The whole loop on frames no project code drew: session -> calibrate -> diagnose -> fit.

    python benchmarks/bench_loop.py SESSION_DIR [--out DIR] [--kinds K1 K2 ...] [--seed S]
        [--noise-per-log]
        [--json FILE] [--from-json FILE] [--reuse] [--at-rules-out K]
        [--at-plan K [--bracket-periods P] [--unseen-share Q]]

Issue 23's loop. SESSION_DIR is a gauge-block session rendered by Taxim's own
renderer (``benchmarks/taxim_gauge_session.py``; its holds long enough for the
relaxation, e.g. ``HOLD_S = 1.5``). Its frames are kept; its F/T log is written
anew for each kind below by the project's generator (1 kHz, the session's clock
offset 0.137 s, noise sd 1/40, 1/40, 1/80 N, tangential forces 1 % of fz), from
eq. (5) with the paper's beta relation (7) and Hayes' kappa at the exact a/h
(E = 0.20 MPa, nu = 0.48), each hiding one effect or none:

=================  ===========================================================
``null``           nothing
``spatial``        E 10 % higher per 10 mm across the pad in x (P (1 + 0.01 x))
``offset``         the F/T zeroed before a 0.3 N fixture was mounted (+0.3 N)
``softening``      E falls 10 % over the session, linearly in time
``damage``         E drops 10 % after the 10th press (a damaged gel)
``relaxation``     a viscoelastic gel, g 0.25, tau 0.7 s (Boltzmann superposition)
=================  ===========================================================

Then, for each: ``tactilevision calibrate --beta-table paper`` (its relaxation
fit on), ``tactilevision diagnose --beta-table paper`` on its measurements.csv,
and ``tactilevision fit --effects <the named effect> --beta-table paper`` on what
``diagnose`` says to fit it to (its verdict's ``fit_data``: ``--holds`` for a relaxation
named from calibrate's holds.csv, ``--crossings`` for an effect the crossing forces found
under the mark rule).
Printed per kind: the certified depths against truth.json, the verdict, whether it is
right (:func:`score`: ``yes``, ``shape`` where a change of stiffness was named in the other
shape, ``no``), E from
calibrate, E after the named effect (or after the trend offered for an unexplained
covariate), and the truth that effect's E stands for (the catalogue's parametrisation: at x =
0 for spatial_nonuniformity, before the step for stiffness_step, at the
table's mean of the column for stiffness_trend, at time 0 for force_drift's
counterpart; E_0 for the relaxation).

The noise of every log is drawn from seed S (default 1000): one draw shared by the six
logs of a design, so that the null and the offset (which the F/T's zero takes off) read
nearly the same data and one chance event costs both verdicts. ``--noise-per-log`` draws
each log's own (seed S + the kind's place in :data:`KINDS`: :func:`noise_seed`), six
independent trials.

``--at-rules-out K`` hides the gradient, the softening and the step at K times what the
null session's own crossing forces rule out; ``--at-plan K`` at K times what ``plan`` says
the session's design can see (its null calibration's design, with ``--bracket-periods P``
and ``--unseen-share Q`` the brackets' mean frame periods and the share of presses whose
mark is not seen, measured on other sessions of the sensor).
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from tactilevision.cli import main as cli
from tactilevision.diagnosis import CROSSING_UNITS, crossing_sizes, crossing_step_places
from tactilevision.io import read_measurements
from tactilevision.mechanics import EFFECT_SIZE_PARAMS, beta_relation, fit_relaxation, kappa
from tactilevision.planning import crossing_effect_sizes, design_from_calibration
from tactilevision.sim._schedule import PressSchedule, ft_log

E_TRUE, NU_TRUE = 0.20, 0.48
KINDS = ("null", "spatial", "offset", "softening", "damage", "relaxation")


def _schedule(truth: dict) -> PressSchedule:
    ps = truth["presses"]
    col = {k: np.array([p[k] for p in ps], np.float64) for k in
           ("depth_mm", "x_mm", "y_mm", "t_start_s", "hold_from_s", "hold_to_s",
            "release_end_s", "wait_s")}
    return PressSchedule(indenter=np.array([p["indenter"] for p in ps], np.int64),
                         depth_mm=col["depth_mm"], x_mm=col["x_mm"], y_mm=col["y_mm"],
                         t_start_s=col["t_start_s"],
                         approach_s=col["hold_from_s"] - col["t_start_s"],
                         hold_s=col["hold_to_s"] - col["hold_from_s"],
                         release_s=col["release_end_s"] - col["hold_to_s"], wait_s=col["wait_s"])


#: Each kind's size by default: gx (1/mm), the fall over the session, the step after the
#: 10th press (``--at-rules-out`` replaces them).
DEFAULT_SIZE = {"spatial": 0.01, "softening": 0.1, "damage": 0.1}


def noise_seed(seed: int, kind: str, per_log: bool = False) -> int:
    """The F/T noise's seed of the log hiding `kind`: `seed` for every log, or with
    `per_log` its own, ``seed + KINDS.index(kind)``."""
    return seed + KINDS.index(kind) if per_log else seed


def write_forces(session: Path, dest: Path, kind: str, seed: int,
                 size: float | None = None, step_after: float = 9.5) -> dict:
    """Copy the session (frames linked) with a new forces.csv hiding `kind` (of `size`, the
    kind's parameter of :data:`DEFAULT_SIZE`, where given; the damage's step falls after
    press number `step_after`: after the 10th by default); its truth."""
    size = DEFAULT_SIZE.get(kind) if size is None else size
    truth = json.loads((session / "truth.json").read_text())
    h, a = truth["thickness_mm"], truth["radius_mm"]
    beta = float(beta_relation("paper").beta(NU_TRUE))
    c = 2 * a * E_TRUE * float(kappa(NU_TRUE, a / h, source="hayes")) / (1 - NU_TRUE ** 2)
    sched = _schedule(truth)
    n = sched.n_presses
    t_end = float(sched.t_end_s[-1]) + 0.5
    scale = np.ones(n)
    bias = 0.0
    relax = (0.0, 1.0)
    e_named = E_TRUE
    if kind == "spatial":
        scale = 1 + size * sched.x_mm                  # 10 % per 10 mm along x by default
    elif kind == "offset":
        bias = 0.3
    elif kind == "softening":
        scale = 1 - size * sched.t_start_s / float(sched.t_start_s[-1])
        e_named = E_TRUE * float(np.mean(scale))     # stiffness_trend: at the mean time
    elif kind == "damage":
        scale = np.where(np.arange(n) > step_after, 1.0 - size, 1.0)
    elif kind == "relaxation":
        relax = (0.25, 0.7)
    elif kind != "null":
        raise ValueError(f"unknown kind {kind!r}")

    def law(i: int, d: np.ndarray) -> np.ndarray:
        return scale[i] * c * d * (1 + beta * d / h)

    t, f = ft_log(sched, law, duration_s=t_end, rate_hz=1000.0,
                  clock_offset_s=truth["clock_offset_s"], tangential_fraction=0.01,
                  bias_n=(0.0, 0.0, bias), relaxation=relax, seed=seed)
    if dest.exists():
        shutil.rmtree(dest)
    dest.mkdir(parents=True)
    for item in session.iterdir():
        if item.name == "forces.csv":
            continue
        (dest / item.name).symlink_to(item.resolve())
    np.savetxt(dest / "forces.csv", np.column_stack([t, f]), fmt="%.4f", delimiter=",",
               header="t_s,fx_n,fy_n,fz_n", comments="")
    return {"E_named": e_named, "c": c, "beta": beta, "relaxation": relax, "size": size}


def null_holds_p(session: Path, seeds: list[int]) -> list[tuple[float, str]]:
    """The holds' F test on the null F/T log of `session` drawn with each of `seeds` (the
    loop draws one noise for all six logs of a design: seed 1000), over the truth's own
    hold spans: its p-value and verdict (:func:`~tactilevision.mechanics.fit_relaxation`;
    ``diagnose`` names a relaxation where the decay's p is under ``RELAX_ALPHA``)."""
    truth = json.loads((session / "truth.json").read_text())
    off = truth["clock_offset_s"]
    out = []
    for seed in seeds:
        with tempfile.TemporaryDirectory() as tmp:
            write_forces(session, Path(tmp) / "s", "null", seed)
            log = np.genfromtxt(Path(tmp) / "s" / "forces.csv", delimiter=",", names=True)
        t, fz = log["t_s"], log["fz_n"]
        press, ts, fs = [], [], []
        for i, p in enumerate(truth["presses"]):
            t0, t1 = p["hold_from_s"] + off, p["hold_to_s"] + off
            sel = (t >= t0) & (t <= t1)
            press.append(np.full(int(sel.sum()), i))
            ts.append(t[sel] - t0)
            fs.append(fz[sel])
        r = fit_relaxation(np.concatenate(press), np.concatenate(ts), np.concatenate(fs),
                           n_boot=20)
        out.append((float(r.p_value), r.verdict))
    return out


def one(session: Path, out: Path, kind: str, seed: int, reuse: bool = False,
        size: float | None = None, step_after: float = 9.5) -> dict:
    folder = out / kind
    done = reuse and all((folder / f).is_file() for f in ("calibrate.json", "diagnose.json"))
    tr = (json.loads((folder / "truth.json").read_text()) if done and (
        folder / "truth.json").is_file() else write_forces(session, folder / "session", kind, seed,
                                                            size, step_after))
    (folder / "truth.json").write_text(json.dumps(tr) + "\n")
    cal = folder / "calibration"
    meas = cal / "measurements.csv"
    t_cal = float("nan")
    if not done:
        if cal.exists():
            shutil.rmtree(cal)
        t0 = time.perf_counter()
        cli(["calibrate", str(folder / "session"), "--out", str(cal), "--no-report",
             "--no-progress", "--beta-table", "paper", "--json", str(folder / "calibrate.json")])
        t_cal = time.perf_counter() - t0
        cli(["diagnose", str(meas), "--beta-table", "paper", "--no-progress",
             "--json", str(folder / "diagnose.json")])
    c = json.loads((folder / "calibrate.json").read_text())
    d = json.loads((folder / "diagnose.json").read_text())
    v = d["verdict"]
    named = v["missing_effect"]
    e_after, e_ci = None, None
    fitted = named or v["offered_effect"]      # an unexplained covariate: the trend offered
    if fitted:
        if not (done and (folder / "fit.json").is_file()):
            # what diagnose says to fit it to: a relaxation the holds named from them (a
            # table read at one time of every hold cannot carry it as a column effect), an
            # effect the crossing forces found under the mark rule on them
            data = v.get("fit_data", "table")
            how = (["--holds", str(cal / "holds.csv")] if data == "holds" else
                   ["--crossings", "--effects", fitted] if data == "crossings" else
                   ["--effects", fitted])
            cli(["fit", str(meas), *how, "--beta-table", "paper",
                 "--json", str(folder / "fit.json")])
        got = json.loads((folder / "fit.json").read_text())
        e_after, e_ci = got.get("E_mpa"), got.get("E_ci95_mpa")
    relax = c.get("relaxation") or {}
    budget = d.get("noise_budget") or {}
    # the certified depths against the renderer's truth (um)
    true_depth = {p["press"]: p["depth_mm"]
                  for p in json.loads((session / "truth.json").read_text())["presses"]}
    rows = np.genfromtxt(meas, delimiter=",", names=True)
    err_um = 1e3 * (rows["depth_mm"] - [true_depth[int(k)] for k in rows["press"]])
    return {"kind": kind, "n_rejected": c["n_rejected"], "clock_s": c["clock_offset_s"],
            "E_calibrate": c["E_mpa"], "nu_calibrate": c["nu"],
            "relaxation_resolved": relax.get("resolved"), "g": relax.get("g"),
            "E_inf": relax.get("E_inf_mpa"), "verdict": named, "fitted": fitted,
            "equivalent": v["equivalent_effects"], "unexplained": v["unexplained_covariate"],
            "E_after": e_after, "E_after_ci": e_ci, "E_named_truth": tr["E_named"],
            "budget_ratio": budget.get("ratio"), "budget_exceeds": budget.get("exceeds"),
            "depth_error_um": [float(err_um.mean()), float(err_um.std()),
                               float(np.abs(err_um).max())],
            "calibrate_s": t_cal, "message": d["message"],
            "fit_data": v.get("fit_data", "table") if fitted else None,
            "holds": {k: (d.get("holds") or {}).get(k) for k in
                      ("verdict", "named", "decay_rate_per_s", "smallest_rate_per_s")}}


def rules_out_sizes(session: Path, table: Path, k: float, step_after: float | None = None
                    ) -> dict[str, float]:
    """`k` times the sizes the null table's crossing forces rule out, in the kinds'
    parameters (:data:`DEFAULT_SIZE`): gx, the fall over the session (the trend per second
    times the last press's start), the step half-way (with `step_after`, the step at that
    place: :func:`crossing_step_places`). A table without crossing forces (a vernier's):
    the sizes its null diagnosis states it rules out (``rules_out``, beside the table's
    calibration folder)."""
    cols = read_measurements(table).columns
    got = crossing_sizes(cols)
    if got and step_after is not None:
        places = [(a, s) for a, s in crossing_step_places(cols) if a <= step_after]
        if not places:
            raise ValueError(f"no step place at or before press {step_after:g} in {table}")
        got["stiffness_step:press"] = places[-1][1]
    if not got:
        ruled = json.loads((table.parents[1] / "diagnose.json").read_text())["rules_out"]
        scale = {"spatial_nonuniformity": EFFECT_SIZE_PARAMS["spatial_nonuniformity"][2],
                 **{k: v[2] for k, v in CROSSING_UNITS.items() if k.startswith("stiffness")}}
        got = {k: ruled[k]["size"] / f for k, f in scale.items()}
    last = max(p["t_start_s"] for p in json.loads((session / "truth.json").read_text())[
        "presses"])
    return {"spatial": k * got["spatial_nonuniformity"],
            "softening": k * got["stiffness_trend:time_s"] * last,
            "damage": k * got["stiffness_step:press"]}


def plan_sizes(session: Path, calibration: Path, k: float, after: float,
               periods: float | None = None, unseen: float | None = None
               ) -> tuple[dict[str, float], float, float]:
    """`k` times the sizes ``plan`` says the session's design lets the crossing forces
    name (:func:`~tactilevision.planning.crossing_effect_sizes` of
    :func:`~tactilevision.planning.design_from_calibration` on the null calibration: its
    presses.csv as the schedule, its stage's motion, frame rate and F/T noise), in the
    kinds' parameters as :func:`rules_out_sizes`, the step at its place (after press
    number `after`). `periods`, `unseen`: the brackets' mean frame periods and the share
    of presses unseen to plan with (figures measured on other sessions) instead of this
    session's own; returns the sizes and the periods and share planned with."""
    design = design_from_calibration(calibration, session)
    if periods is not None:
        design = replace(design, bracket_periods=periods)
    if unseen is not None:
        design = replace(design, unseen_share=unseen)
    got = crossing_effect_sizes(design)
    places = [(a, s) for a, s in got["stiffness_step:press"].at_places or () if a <= after]
    step = (places[-1][1] / 100.0 if places else got["stiffness_step:press"].size_param)
    last = max(p["t_start_s"] for p in json.loads((session / "truth.json").read_text())[
        "presses"])
    return ({"spatial": k * got["spatial_nonuniformity"].size_param,
             "softening": k * got["stiffness_trend:time_s"].size_param * last,
             "damage": k * step}, design.bracket_periods, design.unseen_share)


def _pct(x, truth) -> str:
    return "-" if x is None or not math.isfinite(x) else f"{100 * (x / truth - 1):+.1f} %"


def _fmt(x, spec: str = ".4f") -> str:
    return "-" if x is None or not math.isfinite(x) else format(x, spec)


#: What each kind is right to name (named, offered for an unexplained covariate, or listed
#: as equivalent); a change of stiffness in the other shape (a step for a steady softening,
#: a trend for a step) scores ``shape``. The offset is taken off by calibrate's F/T zero, so
#: nothing named is right there, as is the offset itself.
RIGHT = {"null": (), "offset": ("force_offset",), "spatial": ("spatial_nonuniformity",),
         "softening": ("stiffness_trend:time_s", "stiffness_trend:press"),
         "damage": ("stiffness_step:time_s", "stiffness_step:press"),
         "relaxation": ("viscoelastic_relaxation",)}
_OTHER_SHAPE = {"softening": ("stiffness_step:time_s", "stiffness_step:press"),
                "damage": ("stiffness_trend:time_s", "stiffness_trend:press")}


def score(row: dict) -> str:
    """'yes', 'shape' or 'no' for one row of :func:`one` by :data:`RIGHT`: null and offset
    right where nothing is named (no effect, no unexplained covariate); the others where
    their effect is named, offered or equivalent."""
    kind = row["kind"]
    said = {e for e in (row["verdict"], row["fitted"], *(row["equivalent"] or ())) if e}
    if not said and not row["unexplained"]:
        return "yes" if kind in ("null", "offset") else "no"
    if said & set(RIGHT[kind]):
        return "yes"
    return "shape" if said & set(_OTHER_SHAPE.get(kind, ())) else "no"


def print_rows(rows: list[dict], session: Path | str) -> None:
    """The markdown table of docs/loop.md."""
    print(f"session {session} (Taxim's renderer), E = {E_TRUE} MPa, nu = {NU_TRUE}; "
          "forces: eq. (5), the paper's beta, Hayes' kappa")
    print("| hidden | rejected | clock (s) | depth error (um): mean, sd, max | calibrate: E "
          "(error) | verdict (equivalent) | scatter / noise budget | E after it (error against "
          "the effect's E) [95 % CI, covers] | relaxation | right |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        verdict = (r["verdict"] or (f"unexplained {r['unexplained']} (offered "
                                    f"{r['fitted']})" if r["unexplained"]
                                    else "nothing missing"))
        if r["equivalent"]:
            verdict += f" ({', '.join(r['equivalent'])})"
        ratio = r.get("budget_ratio")
        budget = ("-" if ratio is None else
                  f"{ratio:.1f}{' (measurement chain flagged)' if r.get('budget_exceeds') else ''}")
        e_cal = r["E_calibrate"]
        relax = ("-" if not r["relaxation_resolved"] else
                 f"g {_fmt(r['g'], '.3f')}, E_0 {_fmt(e_cal)} ({_pct(e_cal, E_TRUE)}), E_inf "
                 f"{_fmt(r['E_inf'])} ({_pct(r['E_inf'], 0.75 * E_TRUE)})")
        e_after, ci = r["E_after"], r.get("E_after_ci")
        truth = r["E_named_truth"]
        cover = ("" if not ci or None in ci else
                 f" [{ci[0]:.4f}, {ci[1]:.4f}, {'yes' if ci[0] <= truth <= ci[1] else 'no'}]")
        de = r.get("depth_error_um")
        depth = "-" if not de else f"{de[0]:+.1f}, {de[1]:.1f}, {de[2]:.1f}"
        print(f"| {r['kind']} | {r['n_rejected']} | {r['clock_s']:.4f} | {depth} | "
              f"{_fmt(e_cal)} ({_pct(e_cal, E_TRUE)}) | {verdict} | {budget} | "
              f"{_fmt(e_after)} ({_pct(e_after, truth)}){cover} | {relax} | {score(r)} |",
              flush=True)
    marks = [score(r) for r in rows]
    print(f"right: {marks.count('yes')} of {len(rows)}"
          + (f" ({marks.count('shape')} more as a change of stiffness in the other shape)"
             if "shape" in marks else ""))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("session", type=Path)
    ap.add_argument("--out", type=Path, default=Path("out/loop"))
    ap.add_argument("--kinds", nargs="+", default=list(KINDS), choices=KINDS)
    ap.add_argument("--seed", type=int, default=1000)
    ap.add_argument("--noise-per-log", action="store_true",
                    help="each log its own noise (seed + the kind's place), not one shared")
    ap.add_argument("--json", type=Path)
    ap.add_argument("--from-json", type=Path, help="print the table of an earlier --json")
    ap.add_argument("--at-rules-out", type=float, metavar="K",
                    help="hide the spatial gradient, the softening and the step at K times the "
                         "smallest the null session's crossing forces rule out "
                         "(tactilevision.diagnosis.crossing_sizes; without crossing forces, "
                         "its null diagnosis's rules_out); null is run first")
    ap.add_argument("--step-after", type=float, metavar="N",
                    help="the damage's step falls after press number N (default: after the "
                         "10th press, sized half-way); with --at-rules-out, sized at that place "
                         "(tactilevision.diagnosis.crossing_step_places)")
    ap.add_argument("--at-plan", type=float, metavar="K",
                    help="hide the spatial gradient, the softening and the step at K times the "
                         "smallest plan says the session's design lets its crossing forces "
                         "name (planning.crossing_effect_sizes of design_from_calibration on "
                         "the null calibration; the step at its place); null is run first")
    ap.add_argument("--bracket-periods", type=float, metavar="P",
                    help="with --at-plan: plan with crossing brackets of P frame periods on "
                         "average (measured on other sessions) instead of the null "
                         "calibration's own")
    ap.add_argument("--unseen-share", type=float, metavar="Q",
                    help="with --at-plan: plan with this share of presses whose mark is not "
                         "seen (measured on other sessions) instead of the null "
                         "calibration's own")
    ap.add_argument("--reuse", action="store_true",
                    help="keep the calibrate, diagnose and fit outputs already in --out")
    a = ap.parse_args(argv)
    if a.from_json:
        print_rows(json.loads(a.from_json.read_text()), a.session)
        return 0
    sizes: dict[str, float] = {}
    after = 9.5 if a.step_after is None else a.step_after
    if a.at_rules_out is not None and a.at_plan is not None:
        ap.error("--at-rules-out and --at-plan: one of them")
    if a.at_rules_out is not None or a.at_plan is not None:
        rows = [one(a.session, a.out, "null", noise_seed(a.seed, "null", a.noise_per_log),
                    a.reuse)]
        if a.at_plan is not None:
            sizes, periods, unseen = plan_sizes(a.session, a.out / "null" / "calibration",
                                                a.at_plan, after, a.bracket_periods,
                                                a.unseen_share)
            print(f"sizes: {a.at_plan:g} times what plan says the design can see (brackets "
                  f"of {periods:.3g} frame periods, {unseen:.3g} of presses unseen): ",
                  end="")
        else:
            sizes = rules_out_sizes(a.session,
                                    a.out / "null" / "calibration" / "measurements.csv",
                                    a.at_rules_out, a.step_after)
            print(f"sizes: {a.at_rules_out:g} times what the null session rules out (its "
                  f"crossing forces, or its diagnosis's rules_out): ", end="")
        print(", ".join(f"{k} {v:.4g}" for k, v in sizes.items()), flush=True)
        rows += [one(a.session, a.out, k, noise_seed(a.seed, k, a.noise_per_log), a.reuse,
                     sizes.get(k), after)
                 for k in a.kinds if k != "null"]
    else:
        rows = [one(a.session, a.out, k, noise_seed(a.seed, k, a.noise_per_log), a.reuse,
                    step_after=after)
                for k in a.kinds]
    if a.json:
        a.json.write_text(json.dumps(rows, indent=1) + "\n")
    print_rows(rows, a.session)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
