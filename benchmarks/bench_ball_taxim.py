"""A ball's depths from frames drawn by Taxim's own renderer: the contact circles against
the truth, and the E they give.

Dead weights on a thick gel (no F/T: the force is m g, so the frames alone decide the
depths): for each mass, Sneddon's closed form gives the contact radius a where the
force is m g, the depth w and the gel's surface u (the ball's cap inside a, Hertz's
sink-in outside; :func:`tactilevision.sim.sphere_press_surface`). Taxim's renderer
(``taxim.Taxim(backend="jax").render``, its GelSight calibration with the gel made flat,
``contact_scale = 0``) draws the frame of an indenter whose lower face is that surface,
pressed to w: the gel takes u everywhere (none of our shading). Then
:func:`tactilevision.pipeline.calibrate_dead_weights` reads each circle, inverts a(w) and
fits E; this prints each press's circle against the true a, its depth error in units of
its stated sd, and E with its interval against the truth.

Needs ``taxim`` and ``jax`` (the test extra). Usage:
python benchmarks/bench_ball_taxim.py [--seeds 1] [--repeats 3]
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np
from scipy.optimize import brentq

from tactilevision.io import STANDARD_GRAVITY
from tactilevision.pipeline import calibrate_dead_weights
from tactilevision.sim import sneddon_sphere, sphere_press_surface

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from _data import flat_gel_taxim

R, H, PAD, E = 2.0, 100.0, 1000.0, 1.0
MASSES = (0.02, 0.05, 0.1, 0.15, 0.2)
S, SHAPE = 0.0295, (480, 640)


def to8(rgb: np.ndarray) -> np.ndarray:
    return cv2.cvtColor((np.clip(rgb, 0, 1) * 255).round().astype(np.uint8),
                        cv2.COLOR_RGB2BGR)


def write_folder(sim, folder: Path, repeats: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A dead-weight folder rendered by Taxim; the true depths and contact radii."""
    rng = np.random.default_rng(seed)
    (folder / "frames").mkdir(parents=True)
    ref = to8(sim.render(np.full(SHAPE, 5.0), press_depth=None))
    cv2.imwrite(str(folder / "reference.png"), ref)
    masses = np.repeat(MASSES, repeats)
    w_true, a_true, rows = [], [], ["frame,mass_kg,mass_std_kg"]
    for i, m in enumerate(masses):
        a = brentq(lambda x, m=m: float(sneddon_sphere(x, radius_mm=R, E_mpa=E,
                                                       thickness_mm=H)[1])
                   - m * STANDARD_GRAVITY, 1e-6, 0.95 * R, xtol=1e-13)
        w = float(sneddon_sphere(a, radius_mm=R, E_mpa=E)[0])
        centre = (SHAPE[1] / 2 + rng.uniform(-80, 80), SHAPE[0] / 2 + rng.uniform(-60, 60))
        u = sphere_press_surface(SHAPE, centre, a, radius_mm=R, mm_per_px=S)
        frame = to8(sim.render(w - u, press_depth=w))
        noise = rng.normal(0.0, 1.5, frame.shape)
        frame = np.clip(frame + noise, 0, 255).round().astype(np.uint8)
        cv2.imwrite(str(folder / "frames" / f"{i:03d}.png"), frame)
        rows.append(f"{i:03d}.png,{m:.6g},0.0001")
        w_true.append(w)
        a_true.append(a)
    (folder / "weights.csv").write_text("\n".join(rows) + "\n")
    (folder / "session.toml").write_text(
        f"[sensor]\nmm_per_px = {S}\ngel_thickness_mm = {H}\ngel_radius_mm = {PAD}\n\n"
        f'[indenter]\nradius_mm = {R}\nshape = "sphere"\ncontact = "frictionless"\n')
    return np.array(w_true), np.array(a_true)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    covered = 0
    with flat_gel_taxim() as sim, tempfile.TemporaryDirectory() as tmp:
        for seed in range(args.seeds):
            folder = Path(tmp) / f"w{seed}"
            w, a = write_folder(sim, folder, args.repeats, seed)
            cal = calibrate_dead_weights(folder, nu=0.5, law="linear")
            d = cal.depths
            err = d.depth_mm - w[cal.used]
            z = err / np.hypot(d.depth_std_mm, d.depth_shared_mm)
            fit = cal.fit
            inside = fit.E_ci95_mpa[0] <= E <= fit.E_ci95_mpa[1]
            covered += inside
            print(f"seed {seed}: {len(cal.used)} of {w.size} frames read")
            for i, k in enumerate(cal.used):
                print(f"   a {a[k]:.3f} mm ({a[k] / S:5.1f} px): circle {d.radii_px[i]:5.1f} px "
                      f"({100 * (d.contact_radius_mm[i] / a[k] - 1):+5.1f} %), depth "
                      f"{1e3 * w[k]:6.1f} um, error {1e3 * err[i]:+6.1f} um "
                      f"(stated sd {1e3 * d.depth_std_mm[i]:.1f}, shared "
                      f"{1e3 * d.depth_shared_mm[i]:.1f})")
            print(f"   depth error mean {1e3 * err.mean():+.1f} um; error / stated total sd: "
                  f"mean {z.mean():+.2f}, sd {z.std(ddof=1):.2f}")
            print(f"   E {fit.E_mpa:.4f} MPa, 95 % CI [{fit.E_ci95_mpa[0]:.4f}, "
                  f"{fit.E_ci95_mpa[1]:.4f}] (truth {E:g}: {'inside' if inside else 'OUTSIDE'})")
            shutil.rmtree(folder)
    print(f"intervals holding the truth: {covered} of {args.seeds}")


if __name__ == "__main__":
    main()
