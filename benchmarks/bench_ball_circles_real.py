"""The contact circles on the real ball presses we have, before and after a change of the
detector: not worse is the target.

    python benchmarks/bench_ball_circles_real.py [--before 8f4cf4a] [--figures DIR]

Sets (``../shared/real``, never copied into the repository; ``taxim``'s data pack):

- ``taxim``: the 48 real GelSight presses of the ``taxim`` package, with hand-annotated
  circles: each detector's contact edge against them (radius ratio median and sd, how many
  within 5 %, the centres' median distance);
- ``gelslim11``, ``gelslim09``: GelSlim 3.0's 75 and 39 presses (the second through a grid
  of markers), no truth;
- ``mini``: the GelSight Mini's 22 presses, about half of them cut by the image's edge, no
  truth.

"Before" is ``tactilevision/optics/_circles.py`` at git revision ``--before`` (default
8f4cf4a, the tree before the dipole-seeded detector), loaded from ``git show``; "after" is
the installed tree: ``detect_contact_circle(edge='contact')`` (the optics calibration's
labels) and :func:`tactilevision.optics.find_contact_circle` (a ball session's circle: the
radial profile's edge, its checks). Printed per set: circles found, the after / before
radius ratio (median; how many differ by more than 5 %), the centres' shift, how many of
the ball session's circles are trusted and why the others are not, the range of their
share of sectors where the change does not fall past the rim, of their rim contrast and of
the image's share beyond 1.6 radii, and the time per frame.
With ``--figures``, the frames where before and after differ by more than 5 % are drawn
(before red, after green, the ball session's circle blue) for a look.
"""

from __future__ import annotations

import argparse
import importlib.util
import subprocess
import tempfile
import time
from collections import Counter
from pathlib import Path

import cv2
import numpy as np

from tactilevision import InputError
from tactilevision.io import read_ball_presses, taxim_datapack
from tactilevision.optics import (
    CIRCLE_ERROR,
    MAX_SECTORS_BEYOND_RIM,
    MIN_RIM_CONTRAST,
    PAD_SHARE,
    detect_contact_circle,
    edge_cut,
    find_contact_circle,
)
from tactilevision.pipeline._ball import CIRCLE_ERROR_RADIUS_PX

ROOT = Path(__file__).resolve().parents[1]
REAL = ROOT.parent / "shared" / "real"


def old_detector(rev: str):
    """The module ``tactilevision/optics/_circles.py`` at git revision `rev`."""
    src = subprocess.run(["git", "show", f"{rev}:tactilevision/optics/_circles.py"],
                         cwd=ROOT, check=True, capture_output=True, text=True).stdout
    src = (src.replace("from .._checks", "from tactilevision._checks")
           .replace("from ._features", "from tactilevision.optics._features")
           .replace("from ._ball_contact", "from tactilevision.optics._ball_contact"))
    path = Path(tempfile.mkdtemp()) / "circles_before.py"
    path.write_text(src)
    spec = importlib.util.spec_from_file_location("circles_before", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def circle(fn, *args, **kwargs) -> tuple[np.ndarray, float]:
    try:
        c, r = fn(*args, **kwargs)
        return np.asarray(c, np.float64), float(r)
    except InputError:
        return np.full(2, np.nan), float("nan")


def set_paths() -> dict[str, Path]:
    """The real sets by name: taxim's GelSight (the ``taxim`` package's data pack) and the
    GelSlim 3.0 and Mini sets of ``../shared/real``."""
    return {"taxim": taxim_datapack(), "gelslim11": REAL / "gelslim3" / "set_2020_11",
            "gelslim09": REAL / "gelslim3" / "set_2020_09", "mini": REAL / "gelsight_mini"}


def session_circle(frame: np.ndarray, reference: np.ndarray) -> dict:
    """A ball session's circle on one frame (:func:`find_contact_circle`): centre, radius,
    its sd, trusted, the problems' heads, the sector share, the rim contrast and the
    image's share beyond 1.6 colour radii (NaN and the error's head where none is found)."""
    try:
        cc = find_contact_circle(frame, reference)
    except InputError as exc:
        return dict(centre=np.full(2, np.nan), radius=float("nan"), sd=float("nan"),
                    trusted=False, problems=[str(exc)[:60]], sectors=float("nan"),
                    contrast=float("nan"), pad=float("nan"))
    yy, xx = np.indices(frame.shape[:2])
    pad = float(np.mean(np.hypot(xx - cc.centre_px[0], yy - cc.centre_px[1])
                        > 1.6 * cc.colour_radius_px))
    return dict(centre=cc.centre_px, radius=cc.radius_px, sd=cc.radius_sd_px,
                trusted=cc.trusted, problems=[p.split(" (")[0].split(":")[0][:60]
                                              for p in cc.problems],
                sectors=cc.sectors_beyond_rim, contrast=cc.rim_contrast, pad=pad)


def within_bound(radius: np.ndarray, sd: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Whether each radius lies within its stated bound of the truth: the shared error
    plus twice the random one, as :func:`tactilevision.pipeline.circle_depths` states
    them (2.5 % of the radius or of 61 px each, the profile's sd added to the random)."""
    scale = np.maximum(radius, CIRCLE_ERROR_RADIUS_PX)
    bound = (CIRCLE_ERROR.radius_bias * scale
             + 2 * np.hypot(CIRCLE_ERROR.radius_sd * scale, sd))
    return np.abs(radius - truth) <= bound


def session_circles(name: str) -> dict:
    """A ball session's circles on one real set: presses, trusted, the refusals' reasons,
    the ranges of the checks' readings and, where the set is annotated, the radius against
    the annotation (median, sd, within 5 %, within the stated bound)."""
    ps = read_ball_presses(set_paths()[name])
    got = [session_circle(f, ps.reference) for f in ps.frames]
    reasons = Counter(p for g in got for p in g["problems"] if not g["trusted"])
    r = np.array([g["radius"] for g in got])
    out = dict(name=name, n=len(got), trusted=sum(g["trusted"] for g in got),
               reasons=dict(reasons),
               sectors=(np.nanmin([g["sectors"] for g in got]),
                        np.nanmax([g["sectors"] for g in got])),
               contrast=(np.nanmin([g["contrast"] for g in got]),
                         np.nanmax([g["contrast"] for g in got])),
               pad=np.nanmin([g["pad"] for g in got]), annotated=None)
    if ps.radii_px is not None:
        ann = np.asarray(ps.radii_px, np.float64)
        q = r / ann
        out["annotated"] = dict(median=float(np.nanmedian(q)), sd=float(np.nanstd(q)),
                                within5=int(np.sum(np.abs(q - 1) < 0.05)),
                                within_bound=int(np.sum(within_bound(
                                    r, np.array([g["sd"] for g in got]), ann))))
    return out


def rays_against_annotation(name: str) -> dict:
    """The optics calibration's contact edge (the rays' detector,
    ``detect_contact_circle(edge='contact')``) against an annotated set's circles:
    radius / annotated, median and sd, and how many within 5 %."""
    ps = read_ball_presses(set_paths()[name])
    if ps.radii_px is None:
        raise InputError(f"set {name!r} has no annotated circles")
    r = np.array([circle(detect_contact_circle, f, ps.reference, edge="contact")[1]
                  for f in ps.frames])
    q = r / np.asarray(ps.radii_px, np.float64)
    return dict(median=float(np.nanmedian(q)), sd=float(np.nanstd(q)),
                within5=int(np.sum(np.abs(q - 1) < 0.05)), n=len(q))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", default="8f4cf4a")
    ap.add_argument("--figures", type=Path, default=None)
    ap.add_argument("--sets", nargs="+", default=["taxim", "gelslim11", "gelslim09", "mini"])
    args = ap.parse_args()
    before = old_detector(args.before)
    paths = set_paths()
    for name in args.sets:
        ps = read_ball_presses(paths[name])
        rows, reasons, tiles, beyond, contrast, pad, sds = [], Counter(), [], [], [], [], []
        t_old = t_new = t_find = 0.0
        for i, f in enumerate(ps.frames):
            t = time.perf_counter()
            c0, r0 = circle(before.detect_contact_circle, f, ps.reference, edge="contact")
            t_old += time.perf_counter() - t
            t = time.perf_counter()
            c1, r1 = circle(detect_contact_circle, f, ps.reference, edge="contact")
            t_new += time.perf_counter() - t
            t = time.perf_counter()
            g = session_circle(f, ps.reference)
            t_find += time.perf_counter() - t
            c2, r2, ok = g["centre"], g["radius"], g["trusted"]
            sds.append(g["sd"])
            beyond.append(g["sectors"])
            contrast.append(g["contrast"])
            pad.append(g["pad"])
            if not ok:
                reasons.update(g["problems"])
            cut = bool(edge_cut(c0[None], [r0], f.shape[:2])[0]) if np.isfinite(r0) else True
            rows.append((r0, r1, r2, np.hypot(*(c1 - c0)), ok, cut))
            if args.figures is not None and not abs(r1 / r0 - 1) <= 0.05:
                g = f.copy()
                for (c, r), col in (((c0, r0), (0, 0, 255)), ((c1, r1), (0, 255, 0)),
                                    ((c2, r2), (255, 0, 0))):
                    if np.isfinite(r):
                        cv2.circle(g, (round(c[0]), round(c[1])), round(r), col, 1)
                cv2.putText(g, str(i), (4, 14), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255,) * 3, 1)
                tiles.append(g)
        r = np.array(rows, np.float64)
        n = len(r)
        rel = r[:, 1] / r[:, 0] - 1
        print(f"== {name}: {n} presses; circles found before {np.isfinite(r[:, 0]).sum()}, "
              f"after {np.isfinite(r[:, 1]).sum()}; time per frame before "
              f"{1e3 * t_old / n:.0f} ms, after {1e3 * t_new / n:.0f} ms (ball session's "
              f"{1e3 * t_find / n:.0f} ms)")
        print(f"   contact edge after / before: median {np.nanmedian(rel):+.4f}, differing by "
              f"more than 5 %: {int(np.sum(~(np.abs(rel) <= 0.05)))}; centre moved median "
              f"{np.nanmedian(r[:, 3]):.2f} px, largest {np.nanmax(r[:, 3]):.1f} px")
        print(f"   ball session's circle (radial profile) / before: median "
              f"{np.nanmedian(r[:, 2] / r[:, 0] - 1):+.4f}; trusted {int(r[:, 4].sum())} of {n} "
              f"(before: {int((r[:, 5] == 0).sum())} inside the image); not trusted: "
              f"{dict(reasons) or 'none'}")
        if beyond:
            print(f"   sectors where the change does not fall past the rim: "
                  f"{np.nanmin(beyond):.2f} to {np.nanmax(beyond):.2f} (refused over "
                  f"{MAX_SECTORS_BEYOND_RIM:g}); rim contrast {np.nanmin(contrast):.1f} to "
                  f"{np.nanmax(contrast):.1f} noise sigmas (refused under {MIN_RIM_CONTRAST:g}); "
                  f"image beyond 1.6 radii {np.nanmin(pad):.2f} or more (the pad's noise read "
                  f"there from {PAD_SHARE:g})")
        if ps.radii_px is not None:
            ann = np.asarray(ps.radii_px, np.float64)
            for label, k in (("before", 0), ("after", 1), ("session", 2)):
                q = r[:, k] / ann
                print(f"   {label:8s} radius / annotated: median {np.nanmedian(q):.3f}, sd "
                      f"{np.nanstd(q):.3f}, within 5 %: {int(np.sum(np.abs(q - 1) < 0.05))} "
                      f"of {n}")
            inb = within_bound(r[:, 2], np.asarray(sds), ann)
            print(f"   session  radius within its stated bound (circle_depths' shared error plus "
                  f"twice its random one): {int(np.sum(inb))} of {n}")
        if tiles and args.figures is not None:
            args.figures.mkdir(parents=True, exist_ok=True)
            while len(tiles) % 4:
                tiles.append(np.zeros_like(tiles[0]))
            grid = np.vstack([np.hstack(tiles[k:k + 4]) for k in range(0, len(tiles), 4)])
            cv2.imwrite(str(args.figures / f"{name}_differing.png"), grid)
            print(f"   drew {args.figures / f'{name}_differing.png'}")


if __name__ == "__main__":
    main()
