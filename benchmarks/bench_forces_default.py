"""`tactilevision forces` with its default options against the sample session's F/T log.

    python benchmarks/bench_forces_default.py [--fit FIT.json] [--every N]
        [--variants default,shipped,field,before]
    python benchmarks/bench_forces_default.py --rate [--frames N] [--start I]
    python benchmarks/bench_forces_default.py --sweeps [--frames N] [--start I]
    python benchmarks/bench_forces_default.py --cli

Runs the command on every N-th frame of ``sample_frames/gelsight_session``
(default 3) once per variant and compares each frame's total Fz with the F/T
log's at the frame's time (the fit's clock offset):

- **hold frames** of presses at least 0.3 mm deep (issue 16's target: within
  5 %), and of the 0.15 mm presses; hold times from ``truth.json``, used only
  to group frames; the misaligned and the pad-edge press are left out;
- **no-contact frames** (outside every hold, |F/T| under 50 mN; target under
  20 mN).

Variants: ``default`` (no options but ``--fit``); ``shipped`` (``--sensor
gelsight``: the shipped calibration, fitted on real GelSight frames, instead
of the session's own optics); ``field`` (``--contact field --level
far_field``: the height field trusted everywhere); ``before`` (the defaults
before issue 16: ``--sensor gelsight --contact field --level far_field
--beta 0``); the faster choices ``fem`` (``--method fem``), ``far_field`` (``--level
far_field``) and ``far_field_fem`` (both); ``every_pixel`` (``--binning 1``: the
footprint solved on every pixel instead of blocks). ``--fit`` defaults to
``out/calibration/fit.json`` (the README's first command), else the truth (E, nu, clock
offset; beta 0.82).

``--rate``: the cost of a force frame on the default path in bare height maps,
in one process and one run: N consecutive frames of the session from frame I
(default 60 from 30: presses being made, held and released) through a bare
``DepthReconstructor`` on the session's optics (the reference), through the
default path (``boundary='contact'`` heights, 'footprint' forces with beta: what
the command does per frame), through the pieces of that path alone, and through
the solvers it had before (the sparse direct masked solve and the padded
whole-image footprint solve) and the default path on a spread of those frames
(no warm start between them), and through the faster choices; the ratios of
their per-frame times to the bare height map's.

``--cli``: the command's own marginal cost of a force frame (``--every 100`` against
``--every 10``, the difference cancelling the set-up, as issue 85 measured it) against a bare
``DepthReconstructor`` reading the same frames from the session, in the same run.

``--blocks``: the contact-pinned heights' block rule (blocks at most the contact region's
width over 20, 30 or 40): the default path's total over every pixel's on the presses' hold
frames.

``--sweeps``: where the default force solve's work goes on those frames (its sweeps, the
pixels each drops or takes back, the iterations), and its answer against the same
problem solved with every sweep to 1e-5, against the rule before (pulling pixels dropped
and never taken back) and that rule along a looser path.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from tactilevision.cli import main as cli
from tactilevision.fem import ForceEstimator
from tactilevision.io import read_session
from tactilevision.optics import (
    DepthReconstructor,
    PhotometricCalibration,
    integrate_poisson_masked,
)

ROOT = Path(__file__).resolve().parents[1]
SESSION = ROOT / "sample_frames" / "gelsight_session"
VARIANTS = {
    "default": [],
    "shipped": ["--sensor", "gelsight"],
    "field": ["--contact", "field", "--level", "far_field"],
    "before": ["--sensor", "gelsight", "--contact", "field", "--level", "far_field",
               "--beta", "0"],
    # the faster choices: the FEM's force map on its node grid, the whole-image height
    # levelled at the far field (no contact-pinned solve), and both
    "fem": ["--method", "fem"],
    "far_field": ["--level", "far_field"],
    "far_field_fem": ["--level", "far_field", "--method", "fem"],
    # the footprint solved on every pixel instead of blocks (the default before --binning)
    "every_pixel": ["--binning", "1"],
}


def evaluate(rows: list[dict], truth: dict) -> dict:
    """Fz / F_T on hold frames by indenter depth, |Fz| on no-contact frames."""
    hold, free = [], []
    for r in rows:
        t, fz, ft = float(r["t_s"]), float(r["fz_n"]), float(r["ft_fz_n"])
        press = next((p for p in truth["presses"]
                      if p["hold_from_s"] + 0.05 <= t <= p["hold_from_s"] + 0.45), None)
        if press is None:
            if abs(ft) < 0.05:
                free.append(abs(fz))
        elif not (press["edge"] or press["misaligned"]):
            hold.append((press["w0_mm"], fz / ft))
    h = np.array(hold)
    out = {}
    for name, sel in (("deep", h[:, 0] >= 0.3), ("shallow", h[:, 0] < 0.3)):
        r = h[sel, 1]
        out[name] = dict(n=int(r.size), median=float(np.median(r)), lo=float(r.min()),
                         hi=float(r.max()), within5=float(np.mean(np.abs(r - 1) <= 0.05)))
    out["free"] = dict(n=len(free), median_mn=1e3 * float(np.median(free)),
                       max_mn=1e3 * float(np.max(free)))
    return out


def rate_rows(frames: int, start: int, before: int) -> dict:
    """Per-frame times of the default path and its pieces against bare height maps:
    ``{"rows": [(path, ms, bare height maps)], "n", "n_spread", "every", "bare_ms"}``."""
    s = read_session(SESSION)
    cal = PhotometricCalibration.load(SESSION / "optics.npz")
    mm = s.config.mm_per_px
    kw = dict(thickness_mm=s.config.gel_thickness_mm, E_mpa=0.2, nu=0.48,
              contact="footprint", threshold_mm=0.02, beta=0.82)
    frames_ = [s.frame(i) for i in range(start, min(start + frames, s.n_frames))]
    bare = DepthReconstructor(cal, reference=s.reference)
    # the command's default: heights and footprint on blocks ('auto'); every pixel beside it
    recon = DepthReconstructor(cal, reference=s.reference, boundary="contact",
                               binning="auto")
    recon1 = DepthReconstructor(cal, reference=s.reference, boundary="contact")
    far = DepthReconstructor(cal, reference=s.reference, level="far_field")
    est = ForceEstimator(cal.shape, mm, **kw)
    every_px = ForceEstimator(cal.shape, mm, binning=1, **kw)
    fem = ForceEstimator(cal.shape, mm, method="fem", **kw)
    old = ForceEstimator(cal.shape, mm, binning=1, **kw)
    old._op.box = False                     # the padded whole-image footprint solve

    def per_frame(fn, fs) -> float:
        fn(fs[0])                           # warm: tables, FFT plans
        t0 = time.perf_counter()
        for f in fs:
            fn(f)
        return (time.perf_counter() - t0) / len(fs)

    def old_path(f):
        gx, gy = recon1.gradients(f)
        mask = recon1.contact_mask(f, threshold="frame", fill_holes=True)
        h = integrate_poisson_masked(gx, gy, mask, method="direct") * np.float32(mm)
        return old(h)

    heights = [recon(f) for f in frames_]
    heights1 = [recon1(f) for f in frames_]
    t_bare = per_frame(bare, frames_)
    t_default = per_frame(lambda f: est(recon(f)), frames_)
    t_heights = per_frame(recon, frames_)
    t_mask = per_frame(lambda f: recon.contact_mask(f, threshold="frame", fill_holes=True),
                       frames_)
    it = iter(heights * 2)
    t_forces = per_frame(lambda _f: est(next(it)), frames_)
    it = iter(heights1 * 2)
    t_forces1 = per_frame(lambda _f: every_px(next(it)), frames_)
    t_default1 = per_frame(lambda f: every_px(recon1(f)), frames_)
    t_heights1 = per_frame(recon1, frames_)
    every = max(1, len(frames_) // before)
    sub = frames_[::every]
    t_before = per_frame(old_path, sub)
    t_after = per_frame(lambda f: est(recon(f)), sub)
    t_fem = per_frame(lambda f: fem(recon1(f)), frames_)
    t_far = per_frame(lambda f: est(far(f)), frames_)
    t_far_fem = per_frame(lambda f: fem(far(f)), frames_)
    t_bare2 = per_frame(bare, frames_)
    ref = 0.5 * (t_bare + t_bare2)
    rows = [(f"bare DepthReconstructor (the reference; mean of a run before and after: "
             f"{t_bare * 1e3:.1f}, {t_bare2 * 1e3:.1f} ms)", ref),
            ("default path: contact-pinned height + footprint force", t_default),
            ("  its contact-pinned height map alone (blocks)", t_heights),
            ("    of which the frame's contact mask (every pixel)", t_mask),
            ("  its footprint force map alone (blocks: --binning auto)", t_forces),
            ("the default path on every pixel (--binning 1)", t_default1),
            ("  its contact-pinned height map alone on every pixel", t_heights1),
            ("  its footprint force map alone on every pixel", t_forces1),
            ("the solvers before (direct masked solve, padded footprint solve on every "
             "pixel), on the spread frames", t_before),
            ("the default path on the same spread frames", t_after),
            ("choice `--method fem`: contact-pinned height + the FEM's force map",
             t_fem),
            ("choice `--level far_field`: whole-image height + footprint force",
             t_far),
            ("choice `--level far_field --method fem`", t_far_fem)]
    return {"rows": [(name, t * 1e3, t / ref) for name, t in rows], "n": len(frames_),
            "n_spread": len(sub), "every": every, "bare_ms": ref * 1e3}


def _mixed_solve_greedy(loose: float | None, counts: list):
    """The footprint solve's rule before the Signorini one (a probe for :func:`sweeps_rows`):
    sweeps that drop pulling pixels and never take one back, each a preconditioned
    conjugate-gradient solve; every sweep but the last to the residual `loose` (None: every
    sweep to the solve's tol, as that rule ran). Appends (sweeps, iterations) to
    `counts`."""
    from tactilevision.fem import _forces as F

    def solve(compliance, stiffness, u, mask, *, tol=1e-5, max_iter=500, max_sweeps=8,
              t0=None, log=None, sweep_tol=None):
        mask = mask.copy()
        t = np.zeros_like(u) if t0 is None else t0
        final, sweeps, iterations = loose is None, 0, 0
        for _ in range(3 * max_sweeps):
            if not mask.any():
                break
            sweeps += 1
            m = mask[..., None]
            b = np.where(m, u, 0.0)
            t = np.where(m, t, 0.0)
            r = b - np.where(m, compliance(t), 0.0)
            if t0 is not None and F._norm(r) > F._norm(b):
                t, r = np.zeros_like(u), b
            t0 = None
            z = np.where(m, stiffness(r), 0.0)
            p, rz, bn = z.copy(), F._dot(r, z), F._norm(b) or 1.0
            stop = (tol if final else loose) * bn
            while F._norm(r) >= stop and iterations < 10 * max_iter:
                iterations += 1
                Ap = np.where(m, compliance(p), 0.0)
                alpha = rz / F._dot(p, Ap)
                t, r = t + alpha * p, r - alpha * Ap
                if F._norm(r) < stop:
                    break
                z = np.where(m, stiffness(r), 0.0)
                rz_new = F._dot(r, z)
                p, rz = z + (rz_new / rz) * p, rz_new
            tensile = mask & (t[..., -1] < 0)
            if not tensile.any():
                if final:
                    break
                final = True
                continue
            mask &= ~tensile
        counts.append((sweeps, iterations))
        return np.where(mask[..., None], t, 0.0)
    return solve


def sweeps_rows(frames: int, start: int) -> dict:
    """Where the default path's force solve spends its work, and its answer against other
    solves of the same footprint problem, on the same heights: per frame with contact,
    the default's sweeps (pixels dropped, taken back) and conjugate-gradient iterations;
    then the maps and totals of (1) every sweep to the solve's own 1e-5, (2) the rule
    before (pulling pixels dropped, never taken back, every sweep to 1e-5) and (3) that
    rule along another path (sweeps before the last to 1e-3 or 1e-2), each against the
    default's or the line it departs from."""
    from functools import partial

    from tactilevision.fem import _forces as F

    s = read_session(SESSION)
    cal = PhotometricCalibration.load(SESSION / "optics.npz")
    kw = dict(thickness_mm=s.config.gel_thickness_mm, E_mpa=0.2, nu=0.48,
              contact="footprint", threshold_mm=0.02, beta=0.82)
    recon = DepthReconstructor(cal, reference=s.reference, boundary="contact")
    heights = [recon(s.frame(i)) for i in range(start, min(start + frames, s.n_frames))]
    # the solver on every pixel (with blocks each block size has its own operator)
    est = ForceEstimator(cal.shape, s.config.mm_per_px, binning=1, **kw)
    est._op.solve_log = log = []
    default = [est(h) for h in heights]
    solve = F._mixed_solve

    def apart(out, against) -> tuple[float, float, float, int, int]:
        maps, totals = [], []
        for fm, r in zip(out, against, strict=True):
            if float(r.total_n[2]) > 1e-3:
                peak = float(np.abs(r.pressure_kpa).max())
                maps.append(float(np.abs(fm.pressure_kpa - r.pressure_kpa).max()) / peak)
                totals.append(abs(float(fm.total_n[2]) / float(r.total_n[2]) - 1))
        return (max(maps), float(np.median(maps)), max(totals),
                int(np.sum(np.array(maps) > 0.01)), len(maps))

    def run(solver, solve_log: list | None = None) -> list:
        F._mixed_solve = solver
        try:
            # on every pixel, as the default above (blocks would spread each map)
            other = ForceEstimator(cal.shape, s.config.mm_per_px, binning=1, **kw)
            other._op.solve_log = solve_log
            return [other(h) for h in heights]
        finally:
            F._mixed_solve = solve

    rows = []
    tight_log: list = []
    tight = run(partial(solve, sweep_tol=1e-5), tight_log)
    rows.append(("every sweep to 1e-5", "the default", *apart(tight, default),
                 float(np.median([sum(x[0] for x in sw) for sw in tight_log]))))
    mid_log: list = []
    mid = run(partial(solve, sweep_tol=1e-4), mid_log)
    rows.append(("sweeps before the last to 1e-4 (the default's 1e-3 before)", "the default",
                 *apart(mid, default),
                 float(np.median([sum(x[0] for x in sw) for sw in mid_log]))))
    counts: list = []
    before = run(_mixed_solve_greedy(None, counts))
    rows.append(("the rule before: pulling pixels dropped, never taken back, every sweep "
                 "to 1e-5", "the default", *apart(before, default),
                 float(np.median([n for _, n in counts]))))
    for lo in (1e-3, 1e-2):
        counts = []
        out = run(_mixed_solve_greedy(lo, counts))
        rows.append((f"the rule before, sweeps before the last to {lo:g}", "the rule before",
                     *apart(out, before), float(np.median([n for _, n in counts]))))
    return {"n": len(heights), "solves": len(log),
            "sweeps": [len(x) for x in log], "iters": [x[0] for sw in log for x in sw],
            "per_solve": [sum(x[0] for x in sw) for sw in log],
            "first": [sw[0][1] for sw in log], "taken": [sum(x[2] for x in sw) for sw in log],
            "rows": rows}


def sweeps(frames: int, start: int) -> None:
    """Print :func:`sweeps_rows`."""
    r = sweeps_rows(frames, start)
    print(f"Command: python benchmarks/bench_forces_default.py --sweeps --frames {frames} "
          f"--start {start}\n{r['n']} consecutive frames, {r['solves']} with a footprint\n")
    print(f"the default solve: sweeps per frame median {np.median(r['sweeps']):.0f} "
          f"({min(r['sweeps'])} to {max(r['sweeps'])}); conjugate-gradient iterations per "
          f"sweep median {np.median(r['iters']):.0f} ({min(r['iters'])} to "
          f"{max(r['iters'])}), per frame median {np.median(r['per_solve']):.0f} "
          f"({min(r['per_solve'])} to {max(r['per_solve'])}); pixels dropped by the first "
          f"sweep {min(r['first'])} to {max(r['first'])}; taken back per frame "
          f"{min(r['taken'])} to {max(r['taken'])}\n")
    print("| solve | against | map apart: largest, median (of its peak) | frames apart by "
          "over 1 % of the peak | total apart: largest | iterations a frame, median |")
    print("|---|---|---|---|---|---|")
    for label, against, mx, med, tot, over, n, it in r["rows"]:
        print(f"| {label} | {against} | {mx:.2%}, {med:.2%} | {over} of {n} | {tot:.1e} | "
              f"{it:.0f} |")


def rate(frames: int, start: int, before: int) -> None:
    """Print :func:`rate_rows` as a Markdown table."""
    r = rate_rows(frames, start, before)
    print(f"Command: python benchmarks/bench_forces_default.py --rate --frames {frames} "
          f"--start {start} --before {before}\n{r['n']} consecutive frames from "
          f"{start} (every {r['every']}th, {r['n_spread']} frames, for the "
          "solvers before), 640 x 480, one process\n")
    print("| path | ms per frame | bare height maps per frame |")
    print("|---|---|---|")
    for name, ms, ratio in r["rows"]:
        print(f"| {name} | {ms:.1f} | {ratio:.1f} |", flush=True)


def cli_rows(every: tuple[int, int] = (100, 10), repeats: int = 2) -> dict:
    """The command's own marginal cost of a force frame, measured as issue 85 did: ``tactilevision
    forces SESSION --E-mpa 0.2 --nu 0.48 --every N`` (its defaults otherwise) for the two N
    of `every`, the difference of their wall times over the difference of their frame
    counts cancelling the set-up (imports, the session's reading, the first frame's tables);
    beside them, in the same run (before and after, their mean), a bare
    ``DepthReconstructor`` on the session's own optics over the same frames as a user's loop
    reads them (``session.frame(i)`` then the height map). Each command's wall time is the
    least of `repeats` runs. ``{"every": (n_a, n_b), "frames": (f_a, f_b), "wall_s": (t_a,
    t_b), "marginal_ms", "bare_ms", "ratio"}``."""
    s = read_session(SESSION)
    cal = PhotometricCalibration.load(SESSION / "optics.npz")
    bare = DepthReconstructor(cal, reference=s.reference)
    picks = range(0, s.n_frames, min(every))

    def bare_ms() -> float:
        bare(s.frame(0))
        t0 = time.perf_counter()
        for i in picks:
            bare(s.frame(i))
        return (time.perf_counter() - t0) / len(picks) * 1e3

    before = bare_ms()
    walls, counts = [], []
    for n in every:
        best = math.inf
        for _ in range(repeats):
            with tempfile.TemporaryDirectory() as tmp:
                t0 = time.perf_counter()
                done = subprocess.run(
                    [sys.executable, "-m", "tactilevision", "forces", str(SESSION), "--E-mpa",
                     "0.2", "--nu", "0.48", "--every", str(n), "--out", tmp,
                     "--no-progress"], capture_output=True, text=True)
                wall = time.perf_counter() - t0
                if done.returncode != 0:
                    raise RuntimeError(f"forces --every {n} failed: {done.stderr[-500:]}")
                rows = len((Path(tmp) / "forces.csv").read_text().splitlines()) - 1
            best = min(best, wall)
        walls.append(best)
        counts.append(rows)
    after = bare_ms()
    marginal = (walls[1] - walls[0]) / (counts[1] - counts[0]) * 1e3
    ref = 0.5 * (before + after)
    return {"every": tuple(every), "frames": tuple(counts), "wall_s": tuple(walls),
            "marginal_ms": marginal, "bare_ms": ref, "bare_runs_ms": (before, after),
            "ratio": marginal / ref}


def blocks_rows(per_widths=(20.0, 30.0, 40.0), session: Path = SESSION,
                sensor: str | None = None) -> list[tuple[float, int, float, float, float]]:
    """The heights' block rule: for each width-over ratio of the contact region
    (``auto_binning(mask, per_width)``; 40 is ``DepthReconstructor(binning='auto')``'s), the
    default path's total (heights and footprint on blocks) over every pixel's on one hold
    frame of each press of `session` (0.25 s into its hold, or its middle if shorter;
    truth.json's E and nu, else 0.2 MPa and 0.48; beta 0.82; presses reading over 0.3 N),
    through the session's own optics (``optics.npz``) or the shipped `sensor`'s:
    ``[(per_width, n, smallest, median, largest)]``."""
    from tactilevision import default_calibration_path
    from tactilevision.fem import auto_binning

    s = read_session(session)
    truth = json.loads((session / "truth.json").read_text())
    cal = PhotometricCalibration.load(session / "optics.npz" if sensor is None
                                      else default_calibration_path(sensor))
    mm = s.config.mm_per_px
    kw = dict(thickness_mm=s.config.gel_thickness_mm, E_mpa=truth.get("E_mpa", 0.2),
              nu=truth.get("nu", 0.48), beta=0.82)
    every = (DepthReconstructor(cal, reference=s.reference, boundary="contact"),
             ForceEstimator(cal.shape, mm, binning=1, **kw))
    est = ForceEstimator(cal.shape, mm, **kw)
    recons = {k: DepthReconstructor(cal, reference=s.reference, boundary="contact", binning=k)
              for k in range(1, 9)}
    t = s.frame_times_s + float(truth["clock_offset_s"])
    at = [min(p["hold_from_s"] + 0.25, 0.5 * (p["hold_from_s"] + p.get("hold_to_s", 1e9)))
          for p in truth["presses"]]
    frames = [s.frame(int(np.argmin(np.abs(t - a)))) for a in at]
    ref = [float(every[1](every[0](f)).total_n[2]) for f in frames]
    masks = [every[0].contact_mask(f, threshold="frame", fill_holes=True) for f in frames]
    out = []
    for per in per_widths:
        ratios = [float(est(recons[auto_binning(m, per)](f)).total_n[2]) / a
                  for f, m, a in zip(frames, masks, ref, strict=True) if a > 0.3]
        out.append((per, len(ratios), min(ratios), float(np.median(ratios)), max(ratios)))
    return out


def variant_rows(fit: Path | None, every: int, variants: list[str]) -> list[dict]:
    """Each variant's ``tactilevision forces`` run on every `every`-th frame of the sample
    session, evaluated (:func:`evaluate`): ``[{"name", "options", "frames", "s_per_frame",
    "status", **evaluate}]``. `fit` None or missing: the truth's E, nu and clock offset,
    beta 0.82."""
    truth = json.loads((SESSION / "truth.json").read_text())
    out_rows = []
    with tempfile.TemporaryDirectory() as tmp:
        if fit is None or not fit.is_file():
            fit = Path(tmp) / "fit.json"
            fit.write_text(json.dumps({"E_mpa": truth["E_mpa"], "nu": truth["nu"],
                                       "beta": 0.82,
                                       "clock_offset_s": truth["clock_offset_s"]}))
        for name in variants:
            out = Path(tmp) / name
            t0 = time.perf_counter()
            rc = cli(["forces", str(SESSION), "--fit", str(fit), "--every", str(every),
                      "--out", str(out), "--no-images", "--no-progress", *VARIANTS[name]])
            dt = time.perf_counter() - t0
            row = {"name": name, "options": " ".join(VARIANTS[name]) or "(none)",
                   "status": rc}
            if rc == 0:
                rows = list(csv.DictReader((out / "forces.csv").open()))
                row.update(frames=len(rows), s_per_frame=dt / len(rows), **evaluate(rows, truth))
            out_rows.append(row)
    return out_rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fit", type=Path, default=ROOT / "out" / "calibration" / "fit.json")
    ap.add_argument("--every", type=int, default=3)
    ap.add_argument("--variants", default="default,shipped,field,before")
    ap.add_argument("--rate", action="store_true",
                    help="the default path's cost per frame in bare height maps (in-process)")
    ap.add_argument("--frames", type=int, default=60)
    ap.add_argument("--start", type=int, default=30)
    ap.add_argument("--before", type=int, default=10,
                    help="--rate: frames (spread over the N) through the solvers before "
                    "(about 1.5 s each)")
    ap.add_argument("--cli", action="store_true",
                    help="the command's own marginal cost of a force frame (--every 100 "
                    "against --every 10) in bare height maps of the same run")
    ap.add_argument("--sweeps", action="store_true",
                    help="where the default force solve's work goes: its sweeps and "
                    "iterations, and how far another path of its tensile rule moves the maps")
    ap.add_argument("--blocks", action="store_true",
                    help="the heights' block rule: the default path's totals over every "
                    "pixel's on the presses' hold frames, for three rules")
    ap.add_argument("--session", type=Path, default=SESSION,
                    help="--blocks: another session with a truth.json (e.g. one of "
                    "benchmarks/taxim_gauge_session.py's)")
    ap.add_argument("--sensor", default=None,
                    help="--blocks: the shipped optics of this sensor instead of the "
                    "session's optics.npz")
    args = ap.parse_args()
    if args.blocks:
        print(f"Command: python benchmarks/bench_forces_default.py --blocks --session "
              f"{args.session}" + (f" --sensor {args.sensor}" if args.sensor else "") + "\n")
        print("| heights' blocks at most the region's width over | hold frames | "
              "total / every pixel's: smallest, median, largest |")
        print("|---|---|---|")
        for per, n, lo, med, hi in blocks_rows(session=args.session, sensor=args.sensor):
            print(f"| {per:g} | {n} | {lo:.4f}, {med:.4f}, {hi:.4f} |", flush=True)
        return
    if args.cli:
        r = cli_rows()
        print(f"tactilevision forces --every {r['every'][0]} and --every {r['every'][1]}: "
              f"{r['frames'][0]} and {r['frames'][1]} frames in {r['wall_s'][0]:.2f} and "
              f"{r['wall_s'][1]:.2f} s (least of 2): {r['marginal_ms']:.1f} ms a frame; a bare "
              f"height map with its frame's decoding {r['bare_ms']:.1f} ms (runs before and "
              f"after: {r['bare_runs_ms'][0]:.1f}, {r['bare_runs_ms'][1]:.1f}): "
              f"{r['ratio']:.2f} bare height maps a force frame")
        return
    if args.sweeps:
        sweeps(args.frames, args.start)
        return
    if args.rate:
        rate(args.frames, args.start, args.before)
        return
    print(f"Command: python benchmarks/bench_forces_default.py --fit {args.fit} "
          f"--every {args.every}\nfit: {args.fit if args.fit.is_file() else 'the truth'}\n")
    print("| variant | options | frames | s per frame | presses >= 0.3 mm: hold frames, "
          "median Fz/F_T (range), within 5 % | 0.15 mm: median (range) | "
          "no-contact frames: median, max |Fz| |")
    print("|---|---|---|---|---|---|---|")
    for r in variant_rows(args.fit, args.every, args.variants.split(",")):
        if r["status"] != 0:
            print(f"| {r['name']} | failed with status {r['status']} |")
            continue
        d, s, f = r["deep"], r["shallow"], r["free"]
        print(f"| {r['name']} | `{r['options']}` | {r['frames']} | {r['s_per_frame']:.2f} | "
              f"{d['n']}, {d['median']:.3f} ({d['lo']:.3f} to {d['hi']:.3f}), "
              f"{d['within5']:.0%} | {s['median']:.3f} ({s['lo']:.3f} to {s['hi']:.3f}) | "
              f"{f['median_mn']:.1f}, {f['max_mn']:.1f} mN |", flush=True)


if __name__ == "__main__":
    main()
