"""Where the default force path's error comes from, press by press: the force model, the
height's pin at the contact's edge, and the optics.

    python benchmarks/bench_forces_decompose.py [--fit FIT.json]

On the shipped gauge-block session (``sample_frames/gelsight_session``), one hold frame per
press (0.25 s into its hold, the misaligned and the pad-edge press left out; its truth from
``truth.json``), the total Fz of ``ForceEstimator(contact='footprint')`` (what
``tactilevision forces`` runs) on four height maps of that press:

- ``true``: the gel's true surface under the indenter (the session's own finite-strain FEM
  profile, :func:`tactilevision.fem.press_profile`, drawn where the press was); against
  the indenter's true force: the force model's own error (linear layer with beta, a
  frictionless face, against a bonded Neo-Hookean punch);
- ``true, pinned``: the true surface's gradients integrated as the default path integrates
  the frame's (zero outside the frame's contact mask,
  :func:`tactilevision.optics.integrate_poisson_masked`): the pin's share;
- ``frame, pinned``: the default path (``DepthReconstructor(boundary='contact')`` on the
  frame through the session's optics); against the F/T log's force (the indenter's and the
  bevel band's, which the frame also shows): what a user gets;
- ``frame, far field``: the frame's height through the whole-image integration levelled on
  the gel beyond the contact: the optics' share without the pin;
- ``true, pinned at the layer's level`` and ``frame, pinned at the layer's level``: the two
  pinned maps raised over the contact region by the level the force model itself puts on
  the region's edge (:func:`layer_level`): the pin's share removed by the model, not by
  the truth.

E, nu and beta from ``--fit`` (default ``out/calibration/fit.json``, the README's first
command), else the truth's E and nu with beta 0.82. Printed per depth: the median ratio of
each to its truth and its range, and the face's depth (the median height over the
indenter's face) over the true depth for the pinned and far-field maps; then how far the
true surface rises beyond the sink-in at each w0 (the thin, nearly incompressible gel).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import cv2
import numpy as np

from tactilevision.fem import ForceEstimator, press_profile
from tactilevision.io import read_session
from tactilevision.optics import (
    DepthReconstructor,
    PhotometricCalibration,
    integrate_poisson_masked,
)

ROOT = Path(__file__).resolve().parents[1]
SESSION = ROOT / "sample_frames" / "gelsight_session"
MAPS = ("true", "true, pinned", "frame, pinned", "frame, far field",
        "true, pinned at the layer's level", "frame, pinned at the layer's level")
#: The ring just outside the contact region on which :func:`layer_level` reads the model's
#: surface: the region dilated by this disc, less the region (3 px wide).
_RING = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (7, 7))


def layer_level(est0: ForceEstimator, z: np.ndarray, region: np.ndarray,
                iters: int = 8) -> float:
    """The level c at the contact region's edge that the linear layer model itself puts
    there, mm: the height map `z` (zero outside `region`, as the contact-pinned
    integration gives it) raised by c over the region, solved for the footprint's traction
    (`est0`: 'footprint', every pixel, no beta), and the model's surface displacement from
    that traction read on the ring just outside the region (median); c is set to it until
    it moves by under 0.01 um (a fixed point: the edge where the model says it lies). A
    pinned height lifts the face by the sink-in the gel still has at the region's edge
    (or lowers it by the rise beyond it): c is the model's estimate of it."""
    op = est0._op
    H, W = z.shape
    Hf, Wf = op.fshape
    ring = cv2.dilate(region.view(np.uint8), _RING).view(bool) & ~region
    c = 0.0
    for _ in range(iters):
        fm = est0((z + c * region).astype(np.float32))
        t = np.zeros((Hf, Wf, 1), np.float32)
        t[:H, :W, 0] = fm.forces_n[..., 2] / op.node_area_mm2
        u = op._apply32(op.C32, t)[:H, :W, 0]
        new = float(np.median(u[ring]))
        done = abs(new - c) < 1e-5
        c = new
        if done:
            break
    return c


def material(fit: Path | None, truth: dict) -> tuple[float, float, float, str]:
    """(E, nu, beta, where they came from)."""
    if fit is not None and fit.is_file():
        d = json.loads(fit.read_text())
        return float(d["E_mpa"]), float(d["nu"]), float(d.get("beta") or 0.0), str(fit)
    return float(truth["E_mpa"]), float(truth["nu"]), 0.82, "the truth (beta 0.82)"


def rows(fit: Path | None) -> tuple[list[dict], str, object]:
    """One dict a press: its w0, depth and the four ratios and three face depths; where E,
    nu and beta came from; the true surface's profile (:class:`~tactilevision.fem.PressProfile`)."""
    s = read_session(SESSION)
    truth = json.loads((SESSION / "truth.json").read_text())
    E, nu, beta, source = material(fit, truth)
    cal = PhotometricCalibration.load(SESSION / "optics.npz")
    mm, h = s.config.mm_per_px, float(truth["thickness_mm"])
    shape = cal.shape
    prof = press_profile(float(truth["radius_mm"]) / h, float(truth["nu"]),
                         w_over_h_max=max(0.22, 1.05 * max(p["depth_mm"] for p in truth["presses"])
                                          / h))
    est = ForceEstimator(shape, mm, thickness_mm=h, E_mpa=E, nu=nu, contact="footprint",
                         beta=beta)
    est0 = ForceEstimator(shape, mm, thickness_mm=h, E_mpa=E, nu=nu, contact="footprint",
                          beta=0.0, binning=1)
    pinned = DepthReconstructor(cal, reference=s.reference, boundary="contact")
    far = DepthReconstructor(cal, reference=s.reference, level="far_field")
    t_frames = s.frame_times_s + float(truth["clock_offset_s"])
    out = []
    for p in truth["presses"]:
        if p["edge"] or p["misaligned"]:
            continue
        frame = s.frame(int(np.argmin(np.abs(t_frames - (p["hold_from_s"] + 0.25)))))
        centre = (p["x_mm"] / mm + (shape[1] - 1) / 2, p["y_mm"] / mm + (shape[0] - 1) / 2)
        true = prof.height_map(shape, mm, h, centre, p["depth_mm"]).astype(np.float64)
        mask = pinned.contact_mask(frame, threshold="frame", fill_holes=True)
        gy, gx = np.gradient(true)
        maps = {"true": true,
                "true, pinned": np.asarray(integrate_poisson_masked(gx, gy, mask), np.float64),
                "frame, pinned": np.asarray(pinned(frame), np.float64),
                "frame, far field": np.asarray(far(frame), np.float64)}
        ring = cv2.dilate(mask.view(np.uint8), _RING).view(bool) & ~mask
        r = {"w0": p["w0_mm"], "depth": p["depth_mm"],
             "ring true": float(np.median(true[ring]))}
        for name in ("true", "frame"):
            c = layer_level(est0, maps[f"{name}, pinned"], mask)
            maps[f"{name}, pinned at the layer's level"] = maps[f"{name}, pinned"] + c * mask
            r[f"level {name}"] = c
        face = true >= 0.999 * p["depth_mm"]            # the indenter's face (float32 map)
        ft = p["force_n"] + p["bevel_force_n"]
        for name, z in maps.items():
            fz = float(est(z).total_n[2])
            r[name] = fz / (p["force_n"] if name.startswith("true") else ft)
            r[f"face {name}"] = float(np.median(z[face])) / p["depth_mm"]
        out.append(r)
    return out, f"E {E:.4g} MPa, nu {nu:.4g}, beta {beta:.3g} from {source}", prof


def by_depth(got: list[dict]) -> list[dict]:
    """Per w0, over the presses of :func:`rows`: ``{"w0", "n", <map>: (median, lo, hi),
    "face <map>": median, "within5": {<map>: presses within 5 %}}`` for the maps of
    :data:`MAPS` (the face depths of all but the first), and the medians of the true
    surface on the region's edge ("ring true") and of the layer's levels there ("level
    true", "level frame"), mm."""
    out = []
    for w0 in sorted({r["w0"] for r in got}):
        sub = [r for r in got if r["w0"] == w0]
        d: dict = {"w0": w0, "n": len(sub)}
        for m in MAPS:
            v = np.array([r[m] for r in sub])
            d[m] = (float(np.median(v)), float(v.min()), float(v.max()))
        for m in MAPS[1:]:
            d[f"face {m}"] = float(np.median([r[f"face {m}"] for r in sub]))
        for k in ("ring true", "level true", "level frame"):
            d[k] = float(np.median([r[k] for r in sub]))
        d["within5"] = {m: int(sum(abs(r[m] - 1) <= 0.05 for r in sub)) for m in MAPS}
        out.append(d)
    return out


def rises(prof, w0s, h: float, far_mm: float = 9.0) -> list[tuple[float, float, float, float]]:
    """How far the true surface rises beyond the sink-in: per w0 (mm), ``(w0, the largest
    rise (um), its distance from the axis (mm), the rise at far_mm (um))``."""
    radii = np.linspace(0.0, far_mm, 361)
    out = []
    for w0 in sorted(set(w0s)):
        d = prof.depth_at(w0 / h, radii / h) * h
        k = int(np.argmin(d))
        out.append((float(w0), float(-1e3 * d[k]), float(radii[k]), float(-1e3 * d[-1])))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fit", type=Path, default=ROOT / "out" / "calibration" / "fit.json")
    args = ap.parse_args()
    got, source, prof = rows(args.fit)
    print(f"{len(got)} presses of {SESSION.name}; {source}")
    print("w0 (mm) | n | " + " | ".join(f"Fz/true, {m}" for m in MAPS)
          + " | face depth / true: true pinned, frame pinned, frame far field")
    for d in by_depth(got):
        cells = [f"{d[m][0]:.3f} [{d[m][1]:.3f}, {d[m][2]:.3f}]" for m in MAPS]
        faces = [f"{d[f'face {m}']:.3f}" for m in MAPS[1:]]
        print(f"{d['w0']:g} | {d['n']} | " + " | ".join(cells) + " | " + ", ".join(faces))
    h = float(json.loads((SESSION / "truth.json").read_text())["thickness_mm"])
    for w0, rise, at, far in rises(prof, [r["w0"] for r in got], h):
        print(f"true surface at w = {w0:g} mm: rises {rise:.0f} um at r = "
              f"{at:.2f} mm from the axis, {far:.0f} um at 9 mm")

if __name__ == "__main__":
    main()
