"""A ball's contact on frames that are not clean, drawn by Taxim at random seeds: how many get
their right answer.

    python benchmarks/bench_ball_texture.py [--seeds 20] [--first 0]

Each seed draws one press (``tests/test_ball_texture.py`` renders it with Taxim's own
renderer; 240 x 320 px at 0.0295 mm/px; none of our shading):

- the ball: smooth, dimpled, knurled or printed (probabilities 0.2, 0.4, 0.25, 0.15), of
  radius R = a / U(0.3, 0.65) (a rim tilt of 17 to 40 degrees);
- the contact radius a: 22 px to 45 % of the image's height, or (three presses in ten) 45
  to 60 % of it, a contact that covers much of the pad;
- its place: inside the image (seven in ten), else its centre 0.9 a inside to 0.2 a
  outside one edge, so that the image cuts its rim;
- a drift between the reference and the frame (one in two): a gain U(0.8, 1.2) times
  U(0.95, 1.05) per channel and an offset U(-12, 12) grey levels per channel;
- the gel's E, log-uniform on 0.05 to 2 MPa, and the press's force Sneddon's at a on a
  half-space; one press in five has a force that is not its own, 40 to 400 MPa or 0.001 to
  0.0025 MPa worth at its true depth (a load in the wrong unit, another press's force).

Each press is read as a ball session reads it: :func:`tactilevision.optics.find_contact_circle`,
the depth through the ball's a(w) on a gel 2 R thick (R/h = 0.5, the sphere table's thickest;
:func:`tactilevision.pipeline.circle_depths`), and its force against
:data:`tactilevision.pipeline.E_PLAUSIBLE_MPA` at that depth (the law's force at E = 1). The
right answer, stated from the truth before the press is read:

- a force that is not its own: refused for its force (or by its circle, where less than
  70 % of the true rim is in the image);
- at least 75 % of the true rim in the image: the radius within its stated bound (the
  shared error plus twice the random one);
- less than 65 %: refused by its circle;
- between: either.

Printed: each press and its outcome, the count of right answers, the confident wrong ones
(a radius accepted outside its bound, a wrong force accepted: the target is none) and the
refusals by reason. Needs ``taxim`` and ``jax`` (the test extra).
"""

from __future__ import annotations

import argparse
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np

from tactilevision import InputError
from tactilevision.mechanics import Sphere
from tactilevision.optics import find_contact_circle
from tactilevision.pipeline import E_PLAUSIBLE_MPA, circle_depths

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from _data import flat_gel_taxim
from test_ball_texture import (
    KINDS,
    SHAPE,
    S,
    render_press,
    render_reference,
    sneddon_depth,
    sneddon_force,
    true_rim_in_frame,
)


def draw(seed: int) -> dict:
    """One press's design, from its seed."""
    rng = np.random.default_rng(seed)
    h, w = SHAPE
    kind = str(rng.choice(KINDS, p=[0.2, 0.4, 0.25, 0.15]))
    big = rng.uniform() < 0.3
    a_px = rng.uniform(0.45, 0.6) * h if big else rng.uniform(22.0, 0.45 * h)
    a = a_px * S
    R = a / rng.uniform(0.3, 0.65)
    if rng.uniform() < 0.3:                                   # the image cuts its rim
        d = rng.uniform(-0.2, 0.9) * a_px
        side = int(rng.integers(4))
        cx, cy = rng.uniform(0, w - 1), rng.uniform(0, h - 1)
        cx, cy = [(d, cy), (w - 1 - d, cy), (cx, d), (cx, h - 1 - d)][side]
    else:
        cx = rng.uniform(min(1.05 * a_px, w / 2), max(w - 1 - 1.05 * a_px, w / 2))
        cy = rng.uniform(min(1.05 * a_px, h / 2), max(h - 1 - 1.05 * a_px, h / 2))
    drift = rng.uniform() < 0.5
    gain = tuple(rng.uniform(0.8, 1.2) * rng.uniform(0.95, 1.05, 3)) if drift else (1.0,) * 3
    offset = tuple(rng.uniform(-12, 12, 3)) if drift else (0.0,) * 3
    E = float(np.exp(rng.uniform(np.log(0.05), np.log(2.0))))
    force = sneddon_force(a, R, E)
    fault = rng.uniform() < 0.2
    if fault:
        wrong = (np.exp(rng.uniform(np.log(40), np.log(400))) if rng.uniform() < 0.5
                 else np.exp(rng.uniform(np.log(0.001), np.log(0.0025))))
        force *= wrong / E
    return dict(seed=seed, kind=kind, a=a, R=R, centre=(float(cx), float(cy)), gain=gain,
                offset=offset, E=E, force=force, fault=fault, drift=drift,
                rim=true_rim_in_frame((cx, cy), a))


def read(frame: np.ndarray, reference: np.ndarray, R: float, force: float
         ) -> tuple[str, str, float, float]:
    """As a ball session reads one press: (outcome, detail, radius px, its stated bound px);
    outcome 'accepted', 'circle' (refused by its circle) or 'force' (refused for its
    force)."""
    try:
        c = find_contact_circle(frame, reference)
    except InputError as exc:
        return "circle", str(exc), float("nan"), float("nan")
    if c.problems:
        return "circle", "; ".join(c.problems), c.radius_px, float("nan")
    ball = Sphere(R)
    kw = dict(thickness_mm=2 * R, nu=0.5, law="linear")
    try:
        d = circle_depths(c, ball, mm_per_px=S, **kw)
    except InputError as exc:
        return "circle", str(exc), c.radius_px, float("nan")
    bound = d.radius_bias_px + 2 * d.radius_sd_px
    e_app = force / float(ball.force(d.depth_mm, E_mpa=1.0, contact="frictionless", **kw)[0])
    if not E_PLAUSIBLE_MPA[0] <= e_app <= E_PLAUSIBLE_MPA[1]:
        return "force", f"E = {e_app:.3g} MPa", c.radius_px, bound
    return "accepted", f"E = {e_app:.3g} MPa", c.radius_px, bound


def judge(case: dict, outcome: str, radius: float, bound: float) -> tuple[bool, bool]:
    """(right, confidently wrong) for the case's stated right answer."""
    err = abs(radius - case["a"] / S)
    within = outcome == "accepted" and err <= bound
    if case["fault"]:
        return outcome == "force" or (outcome == "circle" and case["rim"] < 0.7), \
            outcome == "accepted"
    if case["rim"] >= 0.75:
        return within, outcome == "accepted" and not within
    if case["rim"] < 0.65:
        return outcome == "circle", outcome == "accepted" and not within
    return within or outcome == "circle", outcome == "accepted" and not within


def run(first: int, n: int, *, echo: bool = False) -> list[dict]:
    """Draw, render and read seeds `first` to `first + n - 1`: one dict a press (its case,
    outcome, detail, radius and bound px, right, confidently wrong)."""
    out = []
    with flat_gel_taxim() as sim:
        reference = render_reference(sim)
        for seed in range(first, first + n):
            case = draw(seed)
            frame = render_press(sim, reference, kind=case["kind"], a=case["a"], R=case["R"],
                                 centre=case["centre"], gain=case["gain"],
                                 offset=case["offset"], seed=seed)
            outcome, detail, radius, bound = read(frame, reference, case["R"], case["force"])
            ok, bad = judge(case, outcome, radius, bound)
            out.append(dict(case=case, outcome=outcome, detail=detail, radius=radius,
                            bound=bound, right=ok, wrong=bad))
            if echo:
                a_px = case["a"] / S
                print(f"seed {seed:3d} {case['kind']:8s} a {a_px:5.1f} px (R {case['R']:.2f} mm, "
                      f"w {1e3 * sneddon_depth(case['a'], case['R']):4.0f} um) rim in image "
                      f"{100 * case['rim']:3.0f} %{' drift' if case['drift'] else '':6s}"
                      f"{' FORCE FAULT' if case['fault'] else '':12s}: {outcome:8s} "
                      f"r {radius:6.1f} px ({radius - a_px:+6.1f}, bound {bound:5.1f}) "
                      f"{'right' if ok else 'WRONG' if bad else 'not right'}; {detail[:90]}",
                      flush=True)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--first", type=int, default=0)
    args = ap.parse_args()
    t0 = time.perf_counter()
    got = run(args.first, args.seeds, echo=True)
    refusals = Counter(g["outcome"] for g in got if g["outcome"] != "accepted")
    print(f"right answers: {sum(g['right'] for g in got)} of {args.seeds} (seeds {args.first} "
          f"to {args.first + args.seeds - 1}); confidently wrong: "
          f"{sum(g['wrong'] for g in got)}; refusals: {dict(refusals)}; "
          f"{time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
