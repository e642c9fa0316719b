"""Condensed pad stiffness (inverse-FEM matrix): build, storage, per-frame cost, accuracy.

Prints, for the default pad (grid 40 x 30, 45.2 x 33.8 mm, h = 4 mm, nu = 0.49,
'bbar', 3 layers), on one BLAS thread:

- build time: assembly, factorisation, Schur complement, K_normal, total
  (``pad_surface_stiffness`` with a fresh cache folder);
- memory of K and K_normal, cache file size, load time from the cache;
- per-frame time of ``Fz = K_normal @ uz`` (one frame, and 100 frames as one
  matrix product) and of ``f = K @ u``, as frames per second;
- accuracy against the closed form of a layer on a rigid base under
  uz = cos(k x) (10 mm wavelength, nodes >= 2 h from the edges): the
  amplitude error of Fz / (dx dy) against the hat-weighted exact pressure
  sinc^2(k dx / 2) / S(k) ("hat") and against the point pressure 1 / S(k)
  ("point"), for 'hex1', 'bbar' and 'hex2' (and 'hex2' with its top mid-side
  nodes traction-free instead of tied), at nu = 0.49 and 0.3; the
  convergence of 'bbar' with the grid.

Run: ``python benchmarks/bench_fem_pad.py`` (about 3 minutes on 2 cores, 2
of them 'hex2' on the default grid; ``--quick`` skips that one).
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from tactilevision.fem._pad import _normal_schur, pad_surface_stiffness
from tactilevision.fem._pad_mesh import PadModel, default_layers

GRID, SIZE, H, NU = (40, 30), (45.2, 33.8), 4.0, 0.49
WAVELENGTH = 10.0


def section(title: str) -> None:
    print(f"\n== {title}")


def layer_compliance(k: float, h: float, nu: float) -> float:
    """uz / p for uz = cos(k x) on a layer bonded to a rigid base, E = 1, no shear on top."""
    x = 2.0 * k * h
    sech = 2.0 * np.exp(-x) / (1.0 + np.exp(-2.0 * x))
    a = 3.0 - 4.0 * nu
    return (2.0 * (1.0 - nu**2) / k * (a * np.tanh(x) - x * sech)
            / (a + (x**2 / 2.0 + 5.0 - 12.0 * nu + 8.0 * nu**2) * sech))


def closed_form(k_normal: np.ndarray, x_mm: np.ndarray, y_mm: np.ndarray, h: float,
                nu: float) -> tuple[float, float, float]:
    """(hat error, point error, pointwise spread) of Fz / (dx dy) for uz = cos(k x)."""
    k = 2.0 * np.pi / WAVELENGTH
    x = np.broadcast_to(x_mm[None, :], (len(y_mm), len(x_mm)))
    y = np.broadcast_to(y_mm[:, None], x.shape)
    uz = np.cos(k * x)
    fz = (k_normal @ uz.ravel()).reshape(x.shape)
    dx, dy = x_mm[1] - x_mm[0], y_mm[1] - y_mm[0]
    far = (np.abs(x) <= x_mm[-1] - 2 * h + 1e-9) & (np.abs(y) <= y_mm[-1] - 2 * h + 1e-9)
    p, c = fz[far] / (dx * dy), uz[far]
    amplitude = np.sum(p * c) / np.sum(c * c)
    point = 1.0 / layer_compliance(k, h, nu)
    hat = point * (np.sin(0.5 * k * dx) / (0.5 * k * dx)) ** 2
    return amplitude / hat - 1.0, amplitude / point - 1.0, np.abs(p - hat * c).max() / hat


def build_and_cache() -> None:
    section(f"build, grid {GRID}, {SIZE} mm, h {H} mm, nu {NU}, 'bbar', one BLAS thread")
    layers = default_layers(GRID, SIZE, H)
    t0 = time.perf_counter()
    model = PadModel(GRID, SIZE, H, NU, layers, "bbar")
    k = model.condense()
    t1 = time.perf_counter()
    kn = _normal_schur(k)
    t2 = time.perf_counter()
    s = model.seconds
    print(f"layers {layers}, mesh dofs {model.n_dofs}, condensed {len(model.interior)}, "
          f"top {len(model.top)}")
    print(f"assembly {s['assembly']:.2f} s, factorisation {s['factorisation']:.2f} s, "
          f"Schur (K) {s['schur']:.2f} s, K_normal {t2 - t1:.2f} s, total {t2 - t0:.2f} s")
    print(f"memory: K {k.nbytes / 1e6:.1f} MB, K_normal {kn.nbytes / 1e6:.1f} MB")

    with tempfile.TemporaryDirectory() as folder:
        t0 = time.perf_counter()
        pad = pad_surface_stiffness(GRID, SIZE, H, NU, cache_dir=folder)
        t_first = time.perf_counter() - t0
        files = list(Path(folder).iterdir())
        print(f"pad_surface_stiffness, empty cache: {t_first:.2f} s (build_s "
              f"{pad.build_s:.2f} s, the rest packing and writing); cache file "
              f"{files[0].stat().st_size / 1e6:.1f} MB ({len(files)} file)")
        loads = []
        for _ in range(3):
            t0 = time.perf_counter()
            again = pad_surface_stiffness(GRID, SIZE, H, NU, cache_dir=folder)
            loads.append(time.perf_counter() - t0)
        assert again.cached and np.array_equal(again.K, pad.K)
        print(f"load from the cache: {min(loads):.2f} s (best of 3), cached={again.cached}")
    per_frame(pad.K, pad.K_normal)


def rate(fn, frames: int, repeat: int) -> float:
    best = np.inf
    for _ in range(5):
        t0 = time.perf_counter()
        for _ in range(repeat):
            fn()
        best = min(best, (time.perf_counter() - t0) / repeat)
    return best / frames


def per_frame(k: np.ndarray, kn: np.ndarray) -> None:
    section("per frame, one thread (best of 5)")
    rng = np.random.default_rng(0)
    uz = rng.normal(size=kn.shape[0])
    uz_batch = rng.normal(size=(kn.shape[0], 100))
    u = rng.normal(size=k.shape[0])
    u_batch = rng.normal(size=(k.shape[0], 100))
    for label, fn, frames, repeat in (
            ("Fz = K_normal @ uz, 1 frame", lambda: kn @ uz, 1, 200),
            ("Fz = K_normal @ Uz, 100 frames", lambda: kn @ uz_batch, 100, 5),
            ("f = K @ u, 1 frame", lambda: k @ u, 1, 20),
            ("f = K @ U, 100 frames", lambda: k @ u_batch, 100, 2)):
        t = rate(fn, frames, repeat)
        print(f"{label:32s} {t * 1e3:8.3f} ms/frame  {1.0 / t:10.0f} frames/s")


def accuracy(quick: bool) -> None:
    section(f"closed form, uz = cos(2 pi x / {WAVELENGTH} mm), nodes >= 2 h from the edges; "
            "error of Fz / (dx dy) (hat: vs sinc^2 / S, point: vs 1 / S)")
    cases = [(NU, "hex1", GRID, None, True), (NU, "bbar", GRID, None, True),
             (NU, "hex2", (27, 20), None, True), (NU, "hex2", (27, 20), None, False)]
    if not quick:
        cases.append((NU, "hex2", GRID, None, True))
    cases += [(0.3, "hex1", GRID, None, True), (0.3, "bbar", GRID, None, True),
              (NU, "bbar", GRID, 4, True)]
    print(f"{'nu':>5} {'element':>16} {'grid':>9} {'layers':>6} {'k dx':>5} {'hat':>8} "
          f"{'point':>8} {'spread':>7} {'build s':>8}")
    for nu, element, grid, layers, tied in cases:
        layers = layers or default_layers(grid, SIZE, H)
        t0 = time.perf_counter()
        model = PadModel(grid, SIZE, H, nu, layers, element, tie_surface=tied)
        kn = _normal_schur(model.condense())
        seconds = time.perf_counter() - t0
        hat, point, spread = closed_form(kn, model.x_mm, model.y_mm, H, nu)
        label = element if tied or element != "hex2" else "hex2 free sides"
        kdx = 2 * np.pi / WAVELENGTH * (model.x_mm[1] - model.x_mm[0])
        print(f"{nu:5.2f} {label:>16} {grid[0]:>4}x{grid[1]:<4} {layers:6d} {kdx:5.2f} "
              f"{hat:+8.2%} {point:+8.2%} {spread:7.2%} {seconds:8.1f}")

    section("convergence of 'bbar', nu 0.49 (default layers)")
    for grid in ((20, 15), (27, 20), (40, 30), (53, 40)):
        layers = default_layers(grid, SIZE, H)
        t0 = time.perf_counter()
        model = PadModel(grid, SIZE, H, NU, layers, "bbar")
        kn = _normal_schur(model.condense())
        seconds = time.perf_counter() - t0
        hat, point, _ = closed_form(kn, model.x_mm, model.y_mm, H, NU)
        print(f"grid {grid[0]:>3}x{grid[1]:<3} layers {layers}: hat {hat:+7.2%}, "
              f"point {point:+7.2%}, build {seconds:6.1f} s")


def main() -> None:
    quick = "--quick" in sys.argv[1:]
    build_and_cache()
    accuracy(quick)


if __name__ == "__main__":
    main()
