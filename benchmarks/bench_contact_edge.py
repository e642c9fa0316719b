"""The contact edge of ball presses, and what labelling to it does to a calibration.

    python benchmarks/bench_contact_edge.py [--skip-mlp] [--presses 40 20] [--json PATH]

Part 1, where the circles lie (``detect_contact_circles(edge='colour' | 'contact')``)
against truths none of this project's code drew:

- the 48 real GelSight presses of ``taxim`` against their hand-annotated circles;
- presses rendered by Taxim's own renderer (``taxim.Taxim(backend="jax")``, flat gel,
  ``contact_scale = 0``, 1.5 grey levels of camera noise; balls of 2 and 3 mm at random
  places, 0.15 to 1.2 mm deep; shadows off and on) against Taxim's own deformed gel:
  the radius where its tilt is largest, where the gel leaves the ball (a circle fitted
  over 120 rays; Taxim smooths its gel, so this lies at 0.86 to 0.93 of the geometric
  sqrt(2 R d - d^2));
- the GelSlim 3.0 presses (no truth): the shoulder's ratio to the colour edge, and how
  many presses the 0.85 floor holds.

Part 2, calibrations from detected circles, labelled to the contact edge (the default,
``detect_edge='contact'``) or to 0.85 of the colour edge (``detect_edge='colour'``, the
earlier default), trained on the even presses of the first ball and scored on the
held-out presses (the odd ones, and every press of the second ball, a size not trained
on): the median over presses of the mean normal-angle error and of the deepest point's
relative error (the height at the deepest point above the median height on a ring at the
contact radius, against the same of the truth). Truth: the annotated circles and the
ball for the real presses (angle inside 0.9 of the annotated radius; the cap
R - sqrt(R^2 - a^2)); Taxim's own gel for the renders (angle inside 0.85 of the
geometric radius, the ring at the geometric radius for both).

Taxim's gel comes from a private method of its jax backend
(``_TaximJax__compute_gel_pad_deformation``); without it the Taxim parts are skipped.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import time
from pathlib import Path

_DETERMINISTIC_XLA = "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"
if "jax" not in sys.modules:
    os.environ["XLA_FLAGS"] = (os.environ.get("XLA_FLAGS", "") + " " + _DETERMINISTIC_XLA).strip()

import numpy as np  # noqa: E402
from scipy.ndimage import map_coordinates  # noqa: E402

from tactilevision.io import read_ball_presses, taxim_datapack  # noqa: E402
from tactilevision.optics import (  # noqa: E402
    DepthReconstructor,
    PhotometricCalibration,
    ball_press_metrics,
    detect_contact_circles,
    fit_circle,
    normals_from_gradients,
)

ROOT = Path(__file__).resolve().parents[1]
GELSLIM = Path(os.environ.get("TACTILEVISION_GELSLIM",
                              ROOT.parent / "shared" / "real" / "gelslim3"))
MM = 0.0295                       # taxim's GelSight pad, real and rendered
SHAPE = (480, 640)
NOISE = 1.5


def render_taxim(n_first: int, n_second: int, *, shadow: bool, balls=(2.0, 3.0),
                 seed: int = 7) -> dict:
    """Ball presses drawn by Taxim with its own gel: frames, reference, centres, geometric
    radii, ball radius (mm) per press, and the gel edge radius (px) per press."""
    import jax
    from bench_absolute_depth import flat_gel_taxim

    rng = np.random.default_rng(seed)
    h, w = SHAPE
    xx, yy = np.meshgrid(np.arange(w, dtype=float), np.arange(h, dtype=float))
    with flat_gel_taxim() as sim:
        deform = getattr(sim, "_TaximJax__compute_gel_pad_deformation", None)
        shift = getattr(sim, "_TaximJax__get_shifted_height_map", None)
        if deform is None or shift is None:
            raise RuntimeError("this taxim hides its gel deformation")
        gel_fn = jax.jit(lambda hm, d: -deform(shift(d, hm))[0])

        def bgr(img, noise):
            img = np.asarray(img, np.float64) * 255.0
            if noise:
                img = img + rng.normal(0, noise, img.shape)
            return np.clip(np.rint(img), 0, 255).astype(np.uint8)[..., ::-1]

        ref = bgr(sim.render(np.full(SHAPE, 1.0, np.float32), with_shadow=shadow), 0)
        out = {k: [] for k in ("frames", "centres", "radii", "ball_mm", "gel_edge", "gel")}
        theta = np.linspace(0, 2 * np.pi, 120, endpoint=False)
        for k in range(n_first + n_second):
            big = balls[0] if k < n_first else balls[1]
            c = (rng.uniform(0.1 * w, 0.9 * w), rng.uniform(0.1 * h, 0.9 * h))
            d = float(rng.uniform(0.15, min(1.2, 0.6 * big)))
            rr = np.hypot(xx - c[0], yy - c[1]) * MM
            obj = np.where(rr < big, big - np.sqrt(np.maximum(big * big - rr * rr, 0)),
                           big + 1.0).astype(np.float32)
            out["frames"].append(bgr(sim.render(obj, with_shadow=shadow, press_depth=d), NOISE))
            tgel = np.asarray(gel_fn(obj, d), np.float64)
            a = math.sqrt(2 * big * d - d * d) / MM
            gy, gx = np.gradient(tgel)
            rs = np.arange(0.6, 1.2, 0.002) * a
            xs = c[0] + np.cos(theta)[:, None] * rs
            ys = c[1] + np.sin(theta)[:, None] * rs
            ok = (xs.min(1) >= 0) & (xs.max(1) <= w - 1) & (ys.min(1) >= 0) & (ys.max(1) <= h - 1)
            tilt = map_coordinates(np.hypot(gx, gy), [ys.ravel(), xs.ravel()],
                                   order=1).reshape(xs.shape)
            j = tilt.argmax(axis=1)
            edge = (fit_circle(xs[ok][np.arange(ok.sum()), j[ok]],
                               ys[ok][np.arange(ok.sum()), j[ok]])[2]
                    if ok.sum() >= 30 else math.nan)
            out["centres"].append(c)
            out["radii"].append(a)
            out["ball_mm"].append(big)
            out["gel_edge"].append(edge)
            out["gel"].append(tgel.astype(np.float32))
    return {"reference": ref, **{k: np.asarray(v) for k, v in out.items()}}


# ------------------------------------------------------------------ part 1


def edge_stats(located: np.ndarray, colour: np.ndarray, truth: np.ndarray,
               c_located: np.ndarray, c_truth: np.ndarray | None) -> dict:
    ok = np.isfinite(truth)
    q, q0 = located[ok] / truth[ok], colour[ok] / truth[ok]
    row = {"n": int(ok.sum()), "contact_median": float(np.median(q)), "contact_sd": float(q.std()),
           "contact_within_5pc": float(np.mean(np.abs(q - 1) < 0.05)),
           "colour_median": float(np.median(q0)), "colour_sd": float(q0.std())}
    if c_truth is not None:
        row["centre_px"] = float(np.median(np.hypot(*(c_located[ok] - c_truth[ok]).T)))
    return row


# ------------------------------------------------------------------ part 2


def _deepest(height: np.ndarray, centre, radius: float) -> float:
    hh, ww = height.shape
    yy, xx = np.mgrid[0:hh, 0:ww]
    d = np.hypot(xx - centre[0], yy - centre[1])
    return float(height[d <= radius].max() - np.median(height[np.abs(d - radius) <= 1.0]))


def _cut(c, r, shape) -> bool:
    h, w = shape
    return c[0] - r < 0 or c[0] + r > w - 1 or c[1] - r < 0 or c[1] + r > h - 1


def score(recon: DepthReconstructor, frames, idx, centres, radii, ball_px, *,
          gel=None) -> dict:
    """Median normal angle and deepest-point error over presses idx (not cut by the
    image edge): against the ball (gel None) or against Taxim's gel."""
    angles, deep = [], []
    for i in idx:
        if _cut(centres[i], radii[i], frames.shape[1:3]):
            continue
        gx, gy = recon.gradients(frames[i])
        height_px = recon(frames[i]) / MM
        if gel is None:
            m = ball_press_metrics(gx, gy, height_px, centres[i], 0.9 * radii[i], ball_px[i])
            angles.append(m.normal_angle_deg)
            cap = ball_px[i] - math.sqrt(ball_px[i] ** 2 - radii[i] ** 2)
        else:
            hh, ww = gx.shape
            yy, xx = np.mgrid[0:hh, 0:ww]
            disc = np.hypot(xx - centres[i][0], yy - centres[i][1]) < 0.85 * radii[i]
            tgy, tgx = np.gradient(gel[i].astype(np.float64) / MM)
            n1 = normals_from_gradients(gx[disc], gy[disc])
            n2 = normals_from_gradients(tgx[disc], tgy[disc])
            angles.append(float(np.degrees(np.arccos(np.clip((n1 * n2).sum(-1), -1, 1))).mean()))
            cap = _deepest(gel[i].astype(np.float64) / MM, centres[i], radii[i])
        deep.append(_deepest(height_px, centres[i], radii[i]) / cap - 1)
    return {"n": len(angles), "angle_deg": float(np.median(angles)),
            "deepest": float(np.median(deep))}


def calibrations(ref, frames, ball_mm, train, models, *, log) -> dict:
    """{(model, edge): calibration} from detected circles on the presses `train`."""
    out = {}
    for model in models:
        for edge in ("contact", "colour"):
            t0 = time.perf_counter()
            out[model, edge] = PhotometricCalibration.from_ball_presses(
                ref, frames[train], ball_radius_mm=ball_mm[train], mm_per_px=MM, model=model,
                detect_edge=edge)
            log(f"  {model}, {edge} edge: calibrated in {time.perf_counter() - t0:.0f} s")
    return out


def part2(ref, frames, centres, radii, ball_mm, models, *, log, gel=None) -> list[dict]:
    n = len(frames)
    first = ball_mm == ball_mm[0]
    train = first & (np.arange(n) % 2 == 0)
    cals = calibrations(ref, frames, ball_mm, train, models, log=log)
    rows = []
    for (model, edge), cal in cals.items():
        recon = DepthReconstructor(cal, reference=ref)
        for b in np.unique(ball_mm):
            idx = np.flatnonzero((ball_mm == b) & ~train)
            s = score(recon, frames, idx, centres, radii, ball_mm / MM, gel=gel)
            rows.append({"model": model, "edge": edge, "ball_mm": float(b),
                         "held_out": "odd presses" if b == ball_mm[0] else "unseen ball", **s})
    return rows


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--skip-mlp", action="store_true", help="LUT calibrations only")
    p.add_argument("--presses", nargs=2, type=int, default=(40, 20), metavar=("FIRST", "SECOND"),
                   help="Taxim presses of the 2 mm and of the 3 mm ball (default 40 20)")
    p.add_argument("--json", type=Path, default=None)
    args = p.parse_args(argv)
    models = ("lut",) if args.skip_mlp else ("lut", "mlp")
    t_start = time.perf_counter()

    def log(msg: str) -> None:
        print(f"[{time.perf_counter() - t_start:6.0f} s] {msg}", file=sys.stderr, flush=True)

    result: dict = {"machine": f"{platform.processor() or platform.machine()}, "
                               f"{os.cpu_count()} cores, Python {platform.python_version()}",
                    "command": "python benchmarks/bench_contact_edge.py " + " ".join(sys.argv[1:])}
    # real GelSight
    ps = read_ball_presses(taxim_datapack("gelsight"))
    _, r0 = detect_contact_circles(ps.frames, ps.reference)
    c1, r1 = detect_contact_circles(ps.frames, ps.reference, edge="contact")
    result["edge"] = {"real GelSight (annotated)": edge_stats(r1, r0, ps.radii_px, c1,
                                                              ps.centers_px)}
    log("real GelSight circles located")
    ball = np.full(len(ps.frames), 2.0)
    result["calibration"] = {"real GelSight": part2(ps.reference, ps.frames, ps.centers_px,
                                                    ps.radii_px, ball, models, log=log)}
    # Taxim renders
    for shadow in (False, True):
        name = f"Taxim, shadows {'on' if shadow else 'off'}"
        try:
            t0 = time.perf_counter()
            tx = render_taxim(*args.presses, shadow=shadow)
            log(f"{name}: {sum(args.presses)} renders in {time.perf_counter() - t0:.0f} s")
        except (ImportError, RuntimeError) as exc:
            result["edge"][name] = {"skipped": str(exc)}
            continue
        _, tr0 = detect_contact_circles(tx["frames"], tx["reference"])
        tc1, tr1 = detect_contact_circles(tx["frames"], tx["reference"], edge="contact")
        result["edge"][name + " (Taxim's gel edge)"] = edge_stats(
            tr1, tr0, tx["gel_edge"], tc1, tx["centres"])
        result["calibration"][name] = part2(tx["reference"], tx["frames"], tx["centres"],
                                            tx["radii"], tx["ball_mm"], models, log=log,
                                            gel=tx["gel"])
    # GelSlim 3.0: no truth, the ratio and the floor
    for sub in ("set_2020_11", "set_2020_09"):
        if not (GELSLIM / sub).is_dir():
            continue
        gs = read_ball_presses(GELSLIM / sub)
        _, g0 = detect_contact_circles(gs.frames, gs.reference)
        _, g1 = detect_contact_circles(gs.frames, gs.reference, edge="contact")
        q = g1 / g0
        result["edge"][f"GelSlim 3.0 {sub} (no truth)"] = {
            "n": len(q), "contact_over_colour_median": float(np.median(q)),
            "held_by_floor": int(np.count_nonzero(np.isclose(q, 0.85)))}
    result["seconds"] = time.perf_counter() - t_start
    print(format_report(result))
    if args.json:
        args.json.write_text(json.dumps(result, indent=2) + "\n")
    return 0


def format_report(res: dict) -> str:
    lines = [f"Machine: {res['machine']}. Command: {res['command']}. Total "
             f"{res['seconds']:.0f} s.", "", "Where the circles lie (radius over the truth's):",
             "", "| data | presses | contact edge: median, sd | within 5 % | colour edge: "
             "median | centre off (px, median) |", "|---|---|---|---|---|---|"]
    for name, row in res["edge"].items():
        if "skipped" in row:
            lines.append(f"| {name} | skipped: {row['skipped']} | | | | |")
        elif "contact_over_colour_median" in row:
            lines.append(f"| {name} | {row['n']} | contact / colour edge "
                         f"{row['contact_over_colour_median']:.3f}; {row['held_by_floor']} "
                         "held at the 0.85 floor | | | |")
        else:
            lines.append(f"| {name} | {row['n']} | {row['contact_median']:.3f}, "
                         f"{row['contact_sd']:.3f} | {100 * row['contact_within_5pc']:.0f} % | "
                         f"{row['colour_median']:.3f} | {row.get('centre_px', math.nan):.2f} |")
    lines += ["", "Calibrations from detected circles, held-out presses:", "",
              "| data | model | labelled to | scored | presses | normal angle (deg) | "
              "deepest point |", "|---|---|---|---|---|---|---|"]
    for name, rows in res["calibration"].items():
        for r in rows:
            label = "the contact edge" if r["edge"] == "contact" else "0.85 x the colour edge"
            lines.append(f"| {name} | {r['model']} | {label} | {r['held_out']} "
                         f"({r['ball_mm']:g} mm) | {r['n']} | {r['angle_deg']:.2f} | "
                         f"{100 * r['deepest']:+.1f} % |")
    return "\n".join(lines)


if __name__ == "__main__":
    raise SystemExit(main())
