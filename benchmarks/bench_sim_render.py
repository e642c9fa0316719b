"""Cost of the simulator's shading (sim.ShadingTable.shading) against the whole-image form.

    python benchmarks/bench_sim_render.py

The shading evaluates Taxim's per-pixel polynomial only where the gel is tilted (slope
bin > 0): a flat pixel's change is exactly zero. The reference operation, timed in the same
run, is the whole-image evaluation the simulator used before (every pixel, the flat bin
subtracted). Prints both times for a 640 x 480 GelSight frame with a 2.4 mm spherical
cap 0.5 mm deep (plus a faint ripple) and for a flat frame, and the largest difference
between the two results (0.0: bit-identical).
"""

from __future__ import annotations

import time

import numpy as np

from tactilevision.sim import taxim_shading


def whole_image(table, height_mm: np.ndarray) -> np.ndarray:
    """The reference: every pixel evaluated, the flat bin of the same direction subtracted."""
    zp = np.asarray(height_mm, np.float64) / table.mm_per_px
    d_row, d_col = np.gradient(zp)
    slope = np.arctan(np.hypot(d_row, d_col))
    direction = np.arctan2(d_row, d_col)
    b = table.num_bins
    i_mag = np.clip(np.floor(slope / (0.5 * np.pi / (b - 1))).astype(np.int64), 0, b - 1)
    i_dir = np.clip(np.floor((direction + np.pi) / (2 * np.pi / (b - 1))).astype(np.int64),
                    0, b - 1)
    f = table._features
    return (np.einsum("hwf,hwfc->hwc", f, table.coeffs[i_mag, i_dir])
            - np.einsum("hwf,hwfc->hwc", f, table.coeffs[np.zeros_like(i_mag), i_dir]))


def _ms(fn, arg, repeats: int = 10) -> float:
    t0 = time.perf_counter()
    for _ in range(repeats):
        fn(arg)
    return 1e3 * (time.perf_counter() - t0) / repeats


def main() -> None:
    table, _ = taxim_shading("gelsight")
    h, w = table.shape
    yy, xx = np.mgrid[:h, :w]
    press = np.clip(1.0 - ((xx - 320) ** 2 + (yy - 240) ** 2) / 80.0**2, 0, None) * 0.5
    press += 0.001 * np.sin(xx / 30.0)
    flat = np.zeros((h, w))
    diff = float(np.abs(table.shading(press) - whole_image(table, press)).max())
    print(f"{w} x {h}, largest difference {diff}")
    for name, z in (("press", press), ("flat", flat)):
        print(f"{name}: shading {_ms(table.shading, z):.1f} ms, whole image "
              f"{_ms(lambda a: whole_image(table, a), z):.1f} ms (same run)")


if __name__ == "__main__":
    main()
