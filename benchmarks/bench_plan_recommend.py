"""Time of ``plan --recommend`` and of the search for the cheapest design meeting targets.

On the paper's gauge block (``sample_frames/plan/paper_gauge_block.toml``), times
``recommend`` without targets (the ranked changes) and with E 3 % and nu 0.01 (the
cheapest design meeting both), each beside one ``fit_indentation`` of a 50-press table
timed in the same run, before and after; prints both and their ratio in fits.

Run: ``OMP_NUM_THREADS=1 python benchmarks/bench_plan_recommend.py`` (one core).
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np
from bench_plan import scatter

from tactilevision.mechanics import fem_force, fit_indentation
from tactilevision.planning import read_design, recommend

PAPER = Path(__file__).resolve().parents[1] / "sample_frames" / "plan" / "paper_gauge_block.toml"


def one_fit_s(repeat: int = 20) -> float:
    """Seconds for one fit of a 50-press table (with depth sds, as ``calibrate`` fits)."""
    w = np.repeat(np.linspace(0.12, 0.57, 5), 10)
    P = fem_force(0.2, 0.45, 2.5, 3.0, w)
    t0 = time.perf_counter()
    for _ in range(repeat):
        fit_indentation(w, P * (1 + 1e-3 * np.sin(np.arange(w.size))), thickness_mm=3.0,
                        radius_mm=2.5, depth_std_mm=np.full(w.size, 1e-3))
    return (time.perf_counter() - t0) / repeat


#: The targets :func:`meets` tries on the paper's block: (E %, nu).
TARGETS = ((4.0, 0.01), (3.0, 0.01))


def meets(sessions: int = 300, seed: int = 5, targets=TARGETS) -> list[dict]:
    """For each (E %, nu) target on the paper's block: ``recommend``'s cheapest design, its
    planned totals, and the RMS errors of E (%) and nu over `sessions` sessions drawn of it
    (``bench_plan.scatter``: the FEM's forces, the design's noise, each fitted as
    ``calibrate`` fits)."""
    d = read_design(PAPER)
    out = []
    for e_pct, nu in targets:
        c = recommend(d, target_E_pct=e_pct, target_nu=nu).cheapest
        row = {"target_E_pct": e_pct, "target_nu": nu, "found": c is not None}
        if c is not None:
            est, _ = scatter(c.design, sessions, seed)
            ok = np.isfinite(est).all(axis=1)
            err = np.column_stack([100 * (est[ok, 0] / c.design.E_mpa - 1),
                                   est[ok, 1] - c.design.nu])
            rms = np.sqrt(np.mean(err ** 2, axis=0))
            row.update(presses=c.n_presses, what=c.what, plan_E_pct=c.E_total_pct,
                       plan_nu=c.nu_total, rms_E_pct=float(rms[0]), rms_nu=float(rms[1]),
                       computed=int(ok.sum()), sessions=sessions)
        out.append(row)
    return out


def main() -> int:
    d = read_design(PAPER)
    f0 = one_fit_s()
    t0 = time.perf_counter()
    recommend(d)
    t_rank = time.perf_counter() - t0
    t0 = time.perf_counter()
    r = recommend(d, target_E_pct=3.0, target_nu=0.01)
    t_target = time.perf_counter() - t0
    f1 = one_fit_s()
    fit = 0.5 * (f0 + f1)
    print(f"one fit of a 50-press table: {1e3 * f0:.2f} ms before, {1e3 * f1:.2f} ms after")
    print(f"recommend, ranked changes: {t_rank:.2f} s ({t_rank / fit:.0f} fits)")
    print(f"recommend, cheapest design for E 3 % and nu 0.01: {t_target:.2f} s "
          f"({t_target / fit:.0f} fits); found: "
          f"{'none' if r.cheapest is None else f'{r.cheapest.n_presses} presses'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
