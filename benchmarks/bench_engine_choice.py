"""Does ``optics calibrate --model auto`` keep the engine that reads best where it did not
look?

Issue 55's target: on each shared sensor, trained on 7 presses only, the engine chosen is
within 0.3 deg (normal angle inside 0.8 of the contact radius) and 3 % (inner cap) of the
best candidate scored on all the other presses. For each sensor and several selections of
7 presses spread over the folder (every ``n // 7``-th press from an offset), this runs
``optics calibrate --presses SEL`` with ``--model auto`` (which engine it keeps) and with
each candidate forced (``--model lut``, ``--model lut --lut-cells NX,NY``, and with 8 or
more presses ``--model mlp``), each scored by its report on the presses it was not given,
and prints each candidate's score there and the kept engine's gap to the best.

    python benchmarks/bench_engine_choice.py [--sensors taxim mini gelslim] [--presses 7]
        [--selections 4] [--random K --seed S] [--dump FILE]

``--random K`` draws K selections of ``--presses`` presses at random (seed ``--seed``)
per sensor instead of the spread ones: fresh selections no rule was chosen on. Each row
also says which candidate the cross-validation's mean over the presses (the rule until
2026-11-27) would have kept, from the same folds' per-press scores the report saves,
and which candidate is the best on the others by the choice's own cost (angle +
``CAP_DEG`` x |inner cap|): where the candidates trade angle against cap, none may lie
within both bounds of the best of each. Last, whether the choice's margin said the
training presses told the kept engine from the runner-up (its 95 % interval excluding 0),
and how often the kept engine was right where it said so; and the kept engine's cost on
the others less the best candidate's (0 where it is the best by the cost), with the
selections where the best by the cost misses one of the two bounds (there the candidates
trade angle against cap, and no choice by the cost meets both).
``--dump FILE`` appends each selection's choice record (candidates, per-press scores of
the folds, margin) and every candidate's score on the others as JSON lines, to try a
rule on recorded selections before drawing fresh ones.

Needs ``taxim`` (its GelSight presses, circles annotated by hand) and ``../shared/real``
(the GelSight Mini and GelSlim 3.0 presses, circles detected).
"""

from __future__ import annotations

import argparse
import json
import tempfile
from contextlib import redirect_stdout
from io import StringIO
from pathlib import Path

import numpy as np

from tactilevision.cli import main as cli
from tactilevision.io import read_ball_presses, taxim_datapack
from tactilevision.optics import CAP_DEG

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "real"
SENSORS = {
    "taxim": ("taxim:gelsight", ["--ball-radius-mm", "2.0", "--mm-per-px", "0.0295"]),
    "mini": (str(SHARED / "gelsight_mini"), ["--mm-per-px", "0.0634"]),
    "gelslim": (str(SHARED / "gelslim3" / "set_2020_11"),
                ["--ball-radius-mm", "3.8", "--mm-per-px", "0.0806"]),
}


def _run(src: str, opts: list[str], sel: str, extra: list[str], out: Path) -> dict:
    """One ``optics calibrate`` run; its accuracy report."""
    with redirect_stdout(StringIO()):
        rc = cli(["optics", "calibrate", src, *opts, "--presses", sel, "--out", str(out),
                  "--no-progress", "--overwrite", *extra])
    if rc != 0:
        raise SystemExit(f"optics calibrate {src} --presses {sel} {extra} exited {rc}")
    return json.loads(out.with_name(out.stem + "_accuracy.json").read_text())


def _score(report: dict) -> tuple[float, float]:
    """Angle inside 0.8 and inner cap over the scored presses (balls weighed by presses)."""
    b = [x for x in report["balls"] if x["n_scored"]]
    n = np.array([x["n_scored"] for x in b], float)
    return (float(np.sum(n * [x["normal_angle_08_deg"] for x in b]) / n.sum()),
            float(np.sum(n * [x["inner_cap"] for x in b]) / n.sum()))


def _cost(score: tuple[float, float]) -> float:
    """The choice's own cost of a score on the others: angle + ``CAP_DEG`` x |inner cap|."""
    return score[0] + CAP_DEG * abs(score[1])


def _mean_choice(choice: dict) -> str:
    """The table the rule before 2026-11-27 kept: the folds' mean angle + CAP_DEG x the
    mean |cap| over the presses they scored (each fold's medians averaged, one press a
    fold here), from the per-press scores the report saves."""
    def cost(r: dict) -> float:
        pp = r["per_press"]
        return (float(np.mean(pp["angle_08_deg"]))
                + CAP_DEG * float(np.mean(np.abs(pp["inner_cap"]))))
    tables = [r for r in choice["candidates"] if r["model"] == "lut" and r["per_press"]
              ["angle_08_deg"]]
    return min(tables, key=cost)["engine"] if tables else choice["chosen"]


def _cv_choice(choice: dict) -> str:
    """The table of the lowest cost over the presses the folds scored: the choice before
    a table the presses cannot tell from its position cells gave way to the cells
    (2026-11-27)."""
    tables = [r for r in choice["candidates"] if r["model"] == "lut" and np.isfinite(r["cost"])]
    return min(tables, key=lambda r: r["cost"])["engine"] if tables else choice["chosen"]


def draws(sensors: list[str], presses: int, random: int, selections: int, seed: int
          ) -> list[tuple[str, str]]:
    """The selections judged, ``(sensor, presses)`` in order: `random` drawn at random a
    sensor (one generator seeded `seed`, drawn through the sensors in turn), else
    `selections` spread ones (every ``n // presses``-th press from an offset)."""
    rng = np.random.default_rng(seed)
    out = []
    for name in sensors:
        src, _ = SENSORS[name]
        n = len(read_ball_presses(taxim_datapack(src.split(":")[1])
                                  if src.startswith("taxim:") else src).frames)
        stride = n // presses
        sels = ([",".join(map(str, sorted(rng.choice(n, presses, replace=False))))
                 for _ in range(random)] if random else
                [f"{off}:{off + stride * presses}:{stride}"
                 for off in range(min(selections, stride))])
        out += [(name, sel) for sel in sels]
    return out


def judge(name: str, sel: str, out: Path) -> dict:
    """One selection: ``optics calibrate --model auto`` and each candidate forced, each
    scored on the presses it was not given. Returns the choice record (``choice``), each
    candidate's ``(angle, cap)`` on the others (``scores``), whether each lies within 0.3
    deg and 3 % of the best there (``ok``), the best by the choice's cost (``by_cost``),
    the kept engine's cost less its (``excess``), the mean's and the folds' lowest cost's
    choices (``mean``, ``cv``) and whether the margin told the candidates apart
    (``told``)."""
    src, opts = SENSORS[name]
    choice = _run(src, opts, sel, [], out)["engine"]
    scores = {}
    for r in choice["candidates"]:
        extra = ["--model", r["model"]]
        if r["engine"] == "table_cells":
            extra += ["--lut-cells", ",".join(map(str, r["lut_cells"]))]
        scores[r["engine"]] = _score(_run(src, opts, sel, extra, out))
    best_a = min(s[0] for s in scores.values())
    best_c = min(abs(s[1]) for s in scores.values())
    ok = {e: sc[0] - best_a <= 0.3 and abs(sc[1]) - best_c <= 0.03 for e, sc in scores.items()}
    by_cost = min(scores, key=lambda e: _cost(scores[e]))
    kept = scores[choice["chosen"]]
    return {"sensor": name, "presses": sel, "choice": choice, "scores": scores, "ok": ok,
            "by_cost": by_cost, "excess": _cost(kept) - _cost(scores[by_cost]),
            "d_angle": kept[0] - best_a, "d_cap": abs(kept[1]) - best_c,
            "mean": _mean_choice(choice), "cv": _cv_choice(choice),
            "told": bool(choice.get("margin") and choice["margin"]["told_apart"])}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sensors", nargs="+", default=list(SENSORS), choices=list(SENSORS))
    ap.add_argument("--presses", type=int, default=7)
    ap.add_argument("--selections", type=int, default=4)
    ap.add_argument("--random", type=int, default=0,
                    help="K random selections a sensor instead of the spread ones")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--dump", type=Path, default=None,
                    help="append every selection's choice record and its candidates' "
                         "scores on the other presses here (JSON lines)")
    a = ap.parse_args()
    if a.dump and not a.dump.parent.is_dir():
        ap.error(f"--dump {a.dump}: no folder {a.dump.parent}")
    print("| sensor | presses | kept | candidates on the others: angle inside 0.8 (deg), "
          "inner cap | kept - best: angle, |cap| | within 0.3 deg and 3 % | the mean's "
          "choice, within | best by the cost on the others | told apart |")
    print("|---|---|---|---|---|---|---|---|---|")
    hits = {"median": 0, "mean": 0, "any": 0, "n": 0, "cost": 0, "cv": 0}
    excess: list[float] = []          # the kept engine's cost on the others less the best's
    best_out = 0                      # the best by the cost outside the bounds
    sure = {"n": 0, "within": 0, "cost": 0}
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "o.npz"
        for name, sel in draws(a.sensors, a.presses, a.random, a.selections, a.seed):
            j = judge(name, sel, out)
            choice, scores, ok, by_cost = j["choice"], j["scores"], j["ok"], j["by_cost"]
            hits["cost"] += by_cost == choice["chosen"]
            excess.append(j["excess"])
            best_out += not ok[by_cost]
            if j["told"]:
                sure["n"] += 1
                sure["within"] += ok[choice["chosen"]]
                sure["cost"] += by_cost == choice["chosen"]
            mean = j["mean"]
            hits["cv"] += ok[j["cv"]]
            hits["n"] += 1
            hits["median"] += ok[choice["chosen"]]
            hits["mean"] += ok[mean]
            hits["any"] += any(ok.values())
            if a.dump:
                with a.dump.open("a") as fh:
                    fh.write(json.dumps({"sensor": name, "presses": sel, "choice": choice,
                                         "others": scores}) + "\n")
            text = ", ".join(f"{k} {s[0]:.2f}, {100 * s[1]:+.1f} %" for k, s in scores.items())
            print(f"| {name} | {sel} | {choice['chosen']} | {text} | {j['d_angle']:+.2f}, "
                  f"{100 * j['d_cap']:+.1f} % | {'yes' if ok[choice['chosen']] else 'no'} | "
                  f"{mean}, {'yes' if ok[mean] else 'no'} | {by_cost} | "
                  f"{'yes' if j['told'] else 'no'} |", flush=True)
    print(f"(the choice's cost: angle + {CAP_DEG:g} deg x |inner cap|, medians over the "
          "presses the folds scored)")
    print(f"within 0.3 deg and 3 %: kept (medians) {hits['median']} of {hits['n']}; the mean's "
          f"choice {hits['mean']}; the folds' lowest cost (no undecided rule) {hits['cv']}; "
          f"some candidate {hits['any']}; the kept engine the best by "
          f"the cost on the others {hits['cost']} of {hits['n']}")
    ex = np.asarray(excess)
    print(f"the kept engine's cost on the others less the best's (deg): 0 in "
          f"{np.count_nonzero(ex == 0)} of {ex.size}, mean {ex.mean():.2f}, over 0.3 in "
          f"{np.count_nonzero(ex > 0.3)}, largest {ex.max():.2f}; the best by the cost "
          f"outside the two bounds in {best_out} (no choice by the cost meets them there)")
    print(f"told apart (the margin's 95 % interval excludes 0) on {sure['n']} of {hits['n']}: "
          f"there within 0.3 deg and 3 % {sure['within']}, the best by the cost "
          f"{sure['cost']}")


if __name__ == "__main__":
    main()
