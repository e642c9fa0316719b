"""Identification and false-alarm rates of ``diagnose`` over generated tables.

    python benchmarks/bench_diagnose.py [TABLES_PER_KIND] [JOBS] [KIND,KIND,...|all] [NULLS]

For each hidden effect of :data:`tactilevision.sim.HIDDEN_EFFECTS` and for
null tables, TABLES_PER_KIND (default 30) tables with seeds 1000, 1001, ...
(the tests use seeds below 1000) are generated and diagnosed; prints per
kind: identified (the hidden effect is the verdict or among its equivalent
effects; the generator's ``crosstalk`` is the catalogue's ``force_crosstalk``;
for the out-of-catalogue ``temperature``, the unexplained covariate is
the hidden one), false alarms (a verdict on a null table), the CV RMSE of
the last rung against the noise floor, E within 5 % (with the hidden effect
itself when the verdict names an equivalent partner), E inside its 95 %
interval, E within 5 % among the tables whose interval is itself within
+-5 % (the data resolve E to 5 %), and time per table. KIND,KIND,... runs those
kinds only (``null`` for the null tables; ``all``, every kind); NULLS null tables in
place of TABLES_PER_KIND.
"""

from __future__ import annotations

import sys
import time
import warnings
from multiprocessing import Pool

import numpy as np

from tactilevision.diagnosis import diagnose
from tactilevision.mechanics import IndentationModel, fit_model
from tactilevision.sim import HIDDEN_EFFECTS, make_measurement_table

OUT_OF_CATALOGUE = ("temperature",)
#: hidden names of the generator whose catalogue effect has another name
CATALOGUE_NAME = {"crosstalk": "force_crosstalk"}


def one(job: tuple[str | None, int]) -> dict:
    hidden, seed = job
    warnings.simplefilter("ignore")
    t = make_measurement_table(hidden, seed)
    t0 = time.perf_counter()
    d = diagnose(t.columns, thickness_mm=t.thickness_mm, radius_mm=t.radius_mm,
                 base=t.truth["base"])
    dt = time.perf_counter() - t0
    named = (d.missing_effect, *d.equivalent_effects)
    # the generator's stiffness step is after one press: any stiffness_step:<column>
    match = next((n for n in named if n == CATALOGUE_NAME.get(hidden, hidden) or (
        hidden == "stiffness_step" and n and n.startswith("stiffness_step:"))), None)
    if hidden is None:
        ok = d.missing_effect is None and d.unexplained_covariate is None
    elif hidden in OUT_OF_CATALOGUE:
        ok = d.unexplained_covariate == t.truth["covariate"]
    else:
        ok = match is not None
    last = d.ladder[-1]
    base = t.truth["base"]
    # E as diagnose reads it: the law's curvature is a nuisance of the comparison, not of E
    effects = [n for n in last.model[1:] if not (base == "paper" and n == "large_deformation")
               and n != "law_curvature"]
    if ok and match is not None and match != d.missing_effect:   # the partner was picked
        effects = [match if n == d.missing_effect else n for n in effects]
    fit, _ = fit_model(t.columns, IndentationModel(base, tuple(effects)),
                       thickness_mm=t.thickness_mm, radius_mm=t.radius_mm)
    E0 = t.truth["E_mpa"]
    lo, hi = fit.E_ci95_mpa
    return {"hidden": hidden, "ok": ok, "alarm": d.missing_effect is not None
            or d.unexplained_covariate is not None,
            "cv_ratio": last.cv_rmse_n / d.noise_floor_n, "E_err": fit.E_mpa / E0 - 1,
            "covered": bool(lo <= E0 <= hi), "resolved": bool(lo >= 0.95 * fit.E_mpa
                                                              and hi <= 1.05 * fit.E_mpa),
            "s": dt}


#: The summary's columns (:func:`rows`).
COLUMNS = ["hidden effect", "tables", "identified", "false alarms", "CV RMSE <= 1.3 x floor",
           "E within 5 %", "median abs E error", "E in its 95 % interval", "s per table"]


def run(n: int, jobs: int = 2, kinds: list[str | None] | None = None,
        n_null: int | None = None) -> list[dict]:
    """Diagnose `n` generated tables per kind (seeds 1000, 1001, ...; `n_null` null tables,
    default `n`) on `jobs` processes: one dict a table (:func:`one`)."""
    kinds = [None, *HIDDEN_EFFECTS] if kinds is None else kinds
    work = [(k, 1000 + s) for k in kinds
            for s in range(n if k is not None or n_null is None else n_null)]
    with Pool(jobs) as pool:
        return pool.map(one, work, chunksize=4)


def rows(res: list[dict]) -> list[list[object]]:
    """Per kind, in the order met: the kind ("none (null tables)" for the nulls), tables,
    identified (for nulls: a null verdict), false alarms (nulls only: a verdict that
    names something), the CV RMSE within 1.3 noise
    floors, E within 5 %, the median |E error|, E inside its 95 % interval (these three
    over the tables identified; the median over all), seconds per table."""
    out = []
    for k in dict.fromkeys(x["hidden"] for x in res):
        r = [x for x in res if x["hidden"] == k]
        ok = np.array([x["ok"] for x in r])
        e = np.abs([x["E_err"] for x in r])
        cv = np.array([x["cv_ratio"] for x in r])
        cov = np.array([x["covered"] for x in r])

        def pct(v: np.ndarray) -> str:
            return f"{100 * np.mean(v):.0f} %" if v.size else "-"
        out.append([("none (null tables)" if k is None else CATALOGUE_NAME.get(k, k)), len(r),
                    pct(ok), pct(np.array([x["alarm"] for x in r])) if k is None else "-",
                    pct(cv[ok] <= 1.3),
                    pct(e[ok] <= 0.05), f"{100 * np.nanmedian(e):.1f} %", pct(cov[ok]),
                    round(float(np.mean([x["s"] for x in r])), 2)])
    return out


def main() -> None:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 30
    jobs = int(sys.argv[2]) if len(sys.argv) > 2 else 2
    kinds: list[str | None] = [None, *HIDDEN_EFFECTS]
    if len(sys.argv) > 3 and sys.argv[3] != "all":
        kinds = [None if k == "null" else k for k in sys.argv[3].split(",")]
    n_null = int(sys.argv[4]) if len(sys.argv) > 4 else None
    t0 = time.perf_counter()
    res = run(n, jobs, kinds, n_null)
    print(f"{len(res)} tables, {n} per kind, {time.perf_counter() - t0:.0f} s on {jobs} "
          "processes")
    print(f"{'hidden':26s} {'identified':>10s} {'alarms':>7s} {'cv<=1.3 fl':>10s} "
          f"{'|dE|<=5%':>9s} {'median|dE|':>10s} {'in CI':>6s} {'res.':>5s} {'|dE|<=5% res.':>13s} "
          f"{'s/table':>8s}")
    for k in kinds:
        r = [x for x in res if x["hidden"] == k]
        ok = np.array([x["ok"] for x in r])
        e = np.abs([x["E_err"] for x in r])
        cv = np.array([x["cv_ratio"] for x in r])
        cov = np.array([x["covered"] for x in r])
        res_ = np.array([x["resolved"] for x in r]) & ok
        print(f"{k!s:26s} {ok.mean():10.0%} {np.mean([x['alarm'] for x in r]):7.0%} "
              f"{np.mean(cv[ok] <= 1.3) if ok.any() else float('nan'):10.0%} "
              f"{np.mean(e[ok] <= 0.05) if ok.any() else float('nan'):9.0%} "
              f"{np.nanmedian(e):10.3f} {np.mean(cov[ok]) if ok.any() else float('nan'):6.0%} "
              f"{np.mean(res_):5.0%} "
              f"{np.mean(e[res_] <= 0.05) if res_.any() else float('nan'):13.0%} "
              f"{np.mean([x['s'] for x in r]):8.2f}")
    cat = [x for x in res if x["hidden"] not in (None, *OUT_OF_CATALOGUE)] or [{"ok": np.nan}]
    print(f"catalogue effects identified: {np.mean([x['ok'] for x in cat]):.1%}; "
          f"false alarms on null tables: "
          f"{np.mean([x['alarm'] for x in res if x['hidden'] is None]):.1%}; "
          f"E not derived (NaN): {np.mean([not np.isfinite(x['E_err']) for x in res]):.1%}")


if __name__ == "__main__":
    main()
