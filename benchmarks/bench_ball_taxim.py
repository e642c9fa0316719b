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

import numpy as np

from tactilevision.pipeline import calibrate_dead_weights

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from _data import flat_gel_taxim, taxim_dead_weights

E = 1.0


def run(seeds: int, repeats: int = 3, *, echo: bool = False) -> list[dict]:
    """Seeds 0 to `seeds` - 1, each a dead-weight folder drawn by Taxim and calibrated: one
    dict a seed (frames read of drawn, the depth errors, mm, and their z against the stated
    total sd, E and its 95 % interval, whether it holds the truth)."""
    out = []
    with flat_gel_taxim() as sim, tempfile.TemporaryDirectory() as tmp:
        for seed in range(seeds):
            folder = Path(tmp) / f"w{seed}"
            w, a = taxim_dead_weights(sim, folder, E_mpa=E, repeats=repeats, seed=seed)
            cal = calibrate_dead_weights(folder, nu=0.5, law="linear")
            d = cal.depths
            err = d.depth_mm - w[cal.used]
            z = err / np.hypot(d.depth_std_mm, d.depth_shared_mm)
            fit = cal.fit
            inside = bool(fit.E_ci95_mpa[0] <= E <= fit.E_ci95_mpa[1])
            out.append(dict(seed=seed, read=len(cal.used), drawn=int(w.size), err_mm=err, z=z,
                            depth_mm=w[cal.used], E_mpa=float(fit.E_mpa),
                            E_ci95_mpa=tuple(float(x) for x in fit.E_ci95_mpa), holds=inside))
            if echo:
                print(f"seed {seed}: {len(cal.used)} of {w.size} frames read")
                for i, k in enumerate(cal.used):
                    print(f"   a {a[k]:.3f} mm ({a[k] / 0.0295:5.1f} px): circle "
                          f"{d.radii_px[i]:5.1f} px "
                          f"({100 * (d.contact_radius_mm[i] / a[k] - 1):+5.1f} %), depth "
                          f"{1e3 * w[k]:6.1f} um, error {1e3 * err[i]:+6.1f} um "
                          f"(stated sd {1e3 * d.depth_std_mm[i]:.1f}, shared "
                          f"{1e3 * d.depth_shared_mm[i]:.1f})")
                print(f"   depth error mean {1e3 * err.mean():+.1f} um; error / stated total "
                      f"sd: mean {z.mean():+.2f}, sd {z.std(ddof=1):.2f}")
                print(f"   E {fit.E_mpa:.4f} MPa, 95 % CI [{fit.E_ci95_mpa[0]:.4f}, "
                      f"{fit.E_ci95_mpa[1]:.4f}] (truth {E:g}: "
                      f"{'inside' if inside else 'OUTSIDE'})")
            shutil.rmtree(folder)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    got = run(args.seeds, args.repeats, echo=True)
    print(f"intervals holding the truth: {sum(g['holds'] for g in got)} of {args.seeds}")


if __name__ == "__main__":
    main()
