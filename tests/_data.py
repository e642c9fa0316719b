"""Test data with known answers: Lambertian ball-press renders and real-frame paths.

Synthetic frames follow a model written out here, independently of the package:
three lights, one per colour channel (B, G, R), at elevation ``LIGHT_ELEVATION_DEG``
and azimuths ``LIGHT_AZIMUTH_DEG``; channel k of a pixel with unit normal n
(pointing out of the gel, ``(-gx, -gy, 1) / norm``) reads

    colour_k = E_k(x, y) * (AMBIENT + n . l_k) / (AMBIENT + sin(elevation))

with ``E_k`` a smooth illumination field (the no-contact reference). The colour
change ``colour / reference - 1`` is therefore an exactly linear function of the
normal, ``(L n - sin(elevation)) / s_flat``, and the in-plane normal an exactly
linear function of the colour change (:func:`nxy_from_change`): the known
answer for lookup tables and networks.

A ball of radius R pressed to contact radius a has the depth (positive into
the gel) ``sqrt(R^2 - r^2) - sqrt(R^2 - a^2)`` inside the contact and 0
outside; its slope stays below ``a / sqrt(R^2 - a^2)`` so with ``a <= 0.6 R``
every light sees every surface element (n . l_k > 0): no shadows.

Real frames: ``GELSLIM`` is the folder of the GelSlim 3.0 release frames
(``set_2020_09``, ``set_2020_11``; CC BY-NC, never committed), given by the
environment variable ``TACTILEVISION_GELSLIM`` (CI sets none and finds them at
its default place beside the repository); tests using it skip when it is absent.
"""

from __future__ import annotations

import contextlib
import importlib.util
import os
import types
from pathlib import Path

import numpy as np

#: Renders shipped with the tests (``tests/data/taxim``): Taxim's frames the default suite
#: reads, keyed by the digest of what drew them (each reader's own key), so that a fresh
#: clone does not spend minutes of Taxim on them; written by running a reader's module
#: with ``TACTILEVISION_SHIP_TAXIM=1``. A changed generator or Taxim gives a new digest,
#: rendered live (and cached) until shipped again.
SHIPPED_TAXIM = Path(__file__).resolve().parent / "data" / "taxim"

ROOT = Path(__file__).resolve().parents[1]
GELSLIM = Path(os.environ.get("TACTILEVISION_GELSLIM",
                              ROOT.parent / "shared" / "real" / "gelslim3"))
GELSLIM_REASON = (f"GelSlim 3.0 frames not found at {GELSLIM} (set TACTILEVISION_GELSLIM to "
                  "their folder)")
GELSIGHT_MINI = Path(os.environ.get("TACTILEVISION_GELSIGHT_MINI",
                                    ROOT.parent / "shared" / "real" / "gelsight_mini"))
GELSIGHT_MINI_REASON = (f"GelSight Mini calibration folder not found at {GELSIGHT_MINI} (set "
                        "TACTILEVISION_GELSIGHT_MINI to it)")
#: GelSight Mini folder's scale (gs_sdk's config calls it ppmm; it is mm per pixel).
GELSIGHT_MINI_MM_PER_PX = 0.0634
#: GelSlim release's ball (7.6 mm diameter). Its calibration script names two
#: scales, 0.10577 mm/px and "0.0806 x 1.5" (the release's README: uncertain).
#: The frames rule out 0.10577: the ball would be 35.9 px in radius, yet the
#: visible contact circles reach 40 to 47 px (set_2020_09) and a contact
#: circle is a section of the ball. 0.0806 mm/px (ball 47.1 px) is the only
#: stated scale consistent with every press; benchmarks/bench_optics_real.py
#: uses the same.
GELSLIM_BALL_RADIUS_MM = 3.8
GELSLIM_MM_PER_PX = 0.0806
#: taxim GelSight data pack (its documented ball and scale).
TAXIM_BALL_RADIUS_MM = 2.0
TAXIM_MM_PER_PX = 0.0295

LIGHT_ELEVATION_DEG = 60.0
LIGHT_AZIMUTH_DEG = (90.0, 210.0, 330.0)
AMBIENT = 0.3


def light_matrix() -> np.ndarray:
    """(3, 3) rows: unit light direction of channel B, G, R."""
    el = np.radians(LIGHT_ELEVATION_DEG)
    az = np.radians(LIGHT_AZIMUTH_DEG)
    return np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az),
                     np.full(3, np.sin(el))], axis=1)


def flat_shading() -> float:
    """Shading of a flat pixel, the same for all three lights."""
    return AMBIENT + float(np.sin(np.radians(LIGHT_ELEVATION_DEG)))


def change_from_normals(n: np.ndarray) -> np.ndarray:
    """Exact colour change ``(L n - sin(el)) / s_flat`` of unit normals (..., 3)."""
    el = np.sin(np.radians(LIGHT_ELEVATION_DEG))
    return (n @ light_matrix().T - el) / flat_shading()


def change_to_nxy_matrix() -> tuple[np.ndarray, np.ndarray]:
    """(A, b) with ``nxy = change @ A.T + b`` exactly (inverse of the light model)."""
    el = np.sin(np.radians(LIGHT_ELEVATION_DEG))
    inv = np.linalg.inv(light_matrix())
    a = flat_shading() * inv[:2]
    b = el * inv[:2].sum(axis=1)
    return a, b


def nxy_from_change(change: np.ndarray) -> np.ndarray:
    """In-plane normal (n_x, n_y) of colour changes (..., 3) under the light model."""
    a, b = change_to_nxy_matrix()
    return change @ a.T + b


def unit_normals(gx: np.ndarray, gy: np.ndarray) -> np.ndarray:
    """``(-gx, -gy, 1) / norm``, written out independently of the package."""
    norm = np.sqrt(1.0 + gx * gx + gy * gy)
    return np.stack([-gx / norm, -gy / norm, 1.0 / norm], axis=-1)


def illumination(shape: tuple[int, int], *, dark_red_right: bool = False) -> np.ndarray:
    """Smooth, uneven illumination E (H, W, 3), counts (the noiseless reference).

    ``dark_red_right``: the red channel is 1 count over the right half, as on
    the GelSlim 3.0 pad where the red LED does not reach a quarter of the gel.
    """
    h, w = shape
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    u, v = x / (w - 1) - 0.5, y / (h - 1) - 0.5
    e = np.stack([150.0 * (1 + 0.25 * u - 0.15 * v),
                  140.0 * (1 - 0.20 * u + 0.20 * v),
                  130.0 * (1 + 0.10 * u + 0.25 * v + 0.3 * u * v)], axis=-1)
    if dark_red_right:
        e[..., 2] = np.where(x > w / 2, 1.0, e[..., 2])
    return e


def ball_depth(shape: tuple[int, int], centre: tuple[float, float], contact_radius: float,
               ball_radius: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Depth (px, positive into the gel) and its exact gradients for a ball press.

    Returns ``depth, gx, gy`` (H, W) float64: ``sqrt(R^2 - r^2) - sqrt(R^2 - a^2)``
    inside the contact disc r < a, 0 (and zero gradient) outside.
    """
    h, w = shape
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    dx, dy = x - centre[0], y - centre[1]
    r2 = dx * dx + dy * dy
    inside = r2 < contact_radius**2
    s = np.sqrt(np.maximum(ball_radius**2 - r2, 1e-9))
    depth = np.where(inside, s - np.sqrt(ball_radius**2 - contact_radius**2), 0.0)
    gx = np.where(inside, -dx / s, 0.0)
    gy = np.where(inside, -dy / s, 0.0)
    return depth, gx, gy


def _to_uint8(img: np.ndarray, noise: float, rng: np.random.Generator) -> np.ndarray:
    if noise > 0:
        img = img + rng.normal(0.0, noise, img.shape)
    return np.clip(np.rint(img), 0, 255).astype(np.uint8)


def render_reference(shape: tuple[int, int], *, noise: float = 1.0, seed: int = 0,
                     dark_red_right: bool = False) -> np.ndarray:
    """No-contact frame (H, W, 3) uint8 BGR: the illumination plus camera noise."""
    rng = np.random.default_rng(seed)
    return _to_uint8(illumination(shape, dark_red_right=dark_red_right), noise, rng)


def render_press(shape: tuple[int, int], centre: tuple[float, float], contact_radius: float,
                 ball_radius: float, *, noise: float = 1.0, gain: float = 1.0, seed: int = 1,
                 dark_red_right: bool = False) -> np.ndarray:
    """Ball-press frame (H, W, 3) uint8 BGR under the Lambertian light model."""
    _, gx, gy = ball_depth(shape, centre, contact_radius, ball_radius)
    rho = 1.0 + change_from_normals(unit_normals(gx, gy))
    rng = np.random.default_rng(seed)
    img = gain * illumination(shape, dark_red_right=dark_red_right) * rho
    return _to_uint8(img, noise, rng)


def synthetic_presses(n: int = 6, *, shape: tuple[int, int] = (120, 160),
                      ball_radius: float = 40.0, seed: int = 0
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``reference, frames (n, H, W, 3), centres (n, 2), radii (n,)`` of ball presses.

    Centres spread over the pad, contact radii between 0.45 R and 0.6 R.
    """
    rng = np.random.default_rng(seed)
    h, w = shape
    ref = render_reference(shape, seed=seed)
    centres = np.column_stack([rng.uniform(0.35 * w, 0.65 * w, n),
                               rng.uniform(0.35 * h, 0.65 * h, n)])
    radii = rng.uniform(0.45, 0.6, n) * ball_radius
    frames = np.stack([render_press(shape, tuple(c), r, ball_radius, seed=seed + 1 + i)
                       for i, (c, r) in enumerate(zip(centres, radii, strict=True))])
    return ref, frames, centres, radii


def quarter_gelsight(size: tuple[int, int] = (160, 120)):
    """The real GelSight ball presses of ``sample_frames/gelsight_ball`` resized to `size`
    (W, H; a quarter of the sensor's by default, cheap to process), their reference, and a
    LUT calibration fitted to them: ``(reference, presses, calibration)``, BGR uint8."""
    import cv2
    import numpy as np

    from tactilevision.optics import PhotometricCalibration

    ball = ROOT / "sample_frames" / "gelsight_ball"

    def small(img):
        return cv2.resize(img, size, interpolation=cv2.INTER_AREA)

    ref = small(cv2.imread(str(ball / "reference.png")))
    presses = [small(cv2.imread(str(p))) for p in sorted((ball / "frames").glob("press_*.png"))]
    cal = PhotometricCalibration.from_ball_presses(
        ref, np.stack(presses), ball_radius_mm=2.0, mm_per_px=0.0295 * 640 / size[0],
        model="lut")
    return ref, presses, cal


def write_video(path, frames, fourcc: str = "MJPG", fps: float = 90.0) -> None:
    """Write BGR frames to a video with OpenCV (MJPG .avi by default)."""
    import cv2

    h, w = frames[0].shape[:2]
    vw = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*fourcc), fps, (w, h))
    for f in frames:
        vw.write(f)
    vw.release()


def decoded(path):
    """Every frame of a video, read sequentially (no seeking): (N, H, W, 3) uint8."""
    import cv2
    import numpy as np

    cap = cv2.VideoCapture(str(path))
    out = []
    while True:
        ok, f = cap.read()
        if not ok:
            break
        out.append(f)
    cap.release()
    return np.stack(out)


@contextlib.contextmanager
def flat_gel_taxim():
    """Taxim's own renderer (jax backend) on its GelSight calibration with the gel made
    flat (its ``gelmap.npy`` at its maximum everywhere) and ``contact_scale = 0``, the
    conventions of ``benchmarks/taxim_gauge_session.py``; the caller has skipped when
    ``taxim`` or ``jax`` is missing. Yields the ``taxim.Taxim`` instance."""
    import shutil
    import tempfile

    import taxim

    src = Path(taxim.__file__).parent / "calib" / "gelsight"
    with tempfile.TemporaryDirectory(prefix="taxim_flat_") as tmp:
        flat = Path(tmp) / "gelsight"
        shutil.copytree(src, flat)
        gel = np.load(flat / "gelmap.npy")
        np.save(flat / "gelmap.npy", np.full_like(gel, gel.max()))
        yield taxim.Taxim(calib_folder=flat, backend="jax",
                          params={"simulator": {"contact_scale": 0.0}})


def plan_sessions(d, n: int, seed: int) -> np.ndarray:
    """(E, nu) rows of `n` sessions of a ``tactilevision.planning.Design``: the
    generator's finite-strain FEM forces at the planned depths, the design's random
    noise (F/T over the window; each certified depth off by the design's depth sd), each
    fitted as ``calibrate`` fits (the depth sds given). The truth is the design's E, nu."""
    import warnings

    from tactilevision.mechanics import fit_indentation
    from tactilevision.planning import depth_uncertainty
    from tactilevision.sim._tables import _fem_force

    rng = np.random.default_rng(seed)
    w = np.repeat(np.asarray(d.depths_mm), d.repeats)
    P = _fem_force(d.E_mpa, d.nu, d.radius_mm, d.thickness_mm, w)
    sd = depth_uncertainty(d)[0] * 1e-3
    s_P = d.force_noise_n / np.sqrt(d.window_samples)
    out = np.full((n, 2), np.nan)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for i in range(n):
            f = fit_indentation(w + rng.normal(0, sd, w.size), P + rng.normal(0, s_P, w.size),
                                thickness_mm=d.thickness_mm, radius_mm=d.radius_mm,
                                depth_std_mm=np.full(w.size, sd))
            out[i] = f.E_mpa, f.nu
    return out


def taxim_dead_weights(sim, folder: Path, *, E_mpa: float = 1.0,
                       masses_kg: tuple[float, ...] = (0.02, 0.05, 0.1, 0.15, 0.2),
                       repeats: int = 3, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A dead-weight folder (``tactilevision.io.read_dead_weights``) drawn by Taxim's own
    renderer `sim` (:func:`flat_gel_taxim`): a 2 mm ball on a 100 mm gel, for each mass
    Sneddon's contact radius a where the force is m g, its depth w and the gel's surface u
    (``tactilevision.sim.sphere_press_surface``); Taxim renders an indenter whose lower
    face is that surface pressed to w, so its gel takes u (none of our shading), plus 1.5
    grey levels of noise. Returns the true depths and contact radii, mm."""
    import cv2
    from scipy.optimize import brentq

    from tactilevision.io import STANDARD_GRAVITY
    from tactilevision.sim import sneddon_sphere, sphere_press_surface

    R, H, s, shape = 2.0, 100.0, 0.0295, (480, 640)

    def to8(rgb):
        return cv2.cvtColor((np.clip(rgb, 0, 1) * 255).round().astype(np.uint8),
                            cv2.COLOR_RGB2BGR)

    rng = np.random.default_rng(seed)
    (folder / "frames").mkdir(parents=True)
    cv2.imwrite(str(folder / "reference.png"),
                to8(sim.render(np.full(shape, 5.0), press_depth=None)))
    masses = np.repeat(np.asarray(masses_kg, np.float64), repeats)
    w_true, a_true, rows = [], [], ["frame,mass_kg,mass_std_kg"]
    for i, m in enumerate(masses):
        a = brentq(lambda x, m=m: float(sneddon_sphere(x, radius_mm=R, E_mpa=E_mpa,
                                                       thickness_mm=H)[1])
                   - m * STANDARD_GRAVITY, 1e-6, 0.95 * R, xtol=1e-13)
        w = float(sneddon_sphere(a, radius_mm=R, E_mpa=E_mpa)[0])
        centre = (shape[1] / 2 + rng.uniform(-80, 80), shape[0] / 2 + rng.uniform(-60, 60))
        u = sphere_press_surface(shape, centre, a, radius_mm=R, mm_per_px=s)
        frame = to8(sim.render(w - u, press_depth=w)) + rng.normal(0.0, 1.5, (*shape, 3))
        cv2.imwrite(str(folder / "frames" / f"{i:03d}.png"),
                    np.clip(frame, 0, 255).round().astype(np.uint8))
        rows.append(f"{i:03d}.png,{m:.6g},0.0001")
        w_true.append(w)
        a_true.append(a)
    (folder / "weights.csv").write_text("\n".join(rows) + "\n")
    (folder / "session.toml").write_text(
        f"[sensor]\nmm_per_px = {s}\ngel_thickness_mm = {H}\ngel_radius_mm = 1000.0\n\n"
        f'[indenter]\nradius_mm = {R}\nshape = "sphere"\ncontact = "frictionless"\n')
    return np.array(w_true), np.array(a_true)


def taxim_mixed_presses(sim, folder: Path, *, balls: int = 10, seed: int = 0) -> list[str]:
    """A ball-press folder drawn by Taxim's own renderer `sim` (:func:`flat_gel_taxim`) with
    three frames of other objects among the ball presses: `balls` presses of a 2 mm ball
    (each press's contact radius 0.6 to 1.3 mm, the gel taking the ball's cap and Hertz's
    sink-in: ``tactilevision.sim.sphere_press_surface``) and, pressed 0.25 mm, a ring
    (0.9 to 1.4 mm), a flat punch (1.2 mm) and a slotted screw head (1.4 mm, a 0.4 mm
    slot), each with a circle in ``circles.csv`` as a hand would draw one (1.3 mm about
    the object's centre). 1.5 grey levels of noise. Returns the other objects' file names.
    """
    import cv2

    from tactilevision.sim import sphere_press_surface

    shape, s, R = (480, 640), 0.0295, 2.0

    def to8(rgb):
        return cv2.cvtColor((np.clip(rgb, 0, 1) * 255).round().astype(np.uint8),
                            cv2.COLOR_RGB2BGR)

    rng = np.random.default_rng(seed)

    def save(name, rgb):
        img = to8(rgb) + rng.normal(0.0, 1.5, (*shape, 3))
        cv2.imwrite(str(folder / name), np.clip(img, 0, 255).round().astype(np.uint8))

    folder.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(folder / "reference.png"),
                to8(sim.render(np.full(shape, 5.0), press_depth=None)))
    rows = ["frame,x_px,y_px,radius_px"]
    for i in range(balls):
        a = rng.uniform(0.6, 1.3)
        w = R - np.sqrt(R * R - a * a)
        c = (shape[1] / 2 + rng.uniform(-200, 200), shape[0] / 2 + rng.uniform(-130, 130))
        u = sphere_press_surface(shape, c, a, radius_mm=R, mm_per_px=s)
        save(f"ball_{i:02d}.png", sim.render(w - u, press_depth=w))
        rows.append(f"ball_{i:02d}.png,{c[0]:.2f},{c[1]:.2f},{a / s:.2f}")
    yy, xx = np.mgrid[0:shape[0], 0:shape[1]].astype(np.float64)
    rho = np.hypot(xx - 320, yy - 240) * s
    others = {"ring.png": (rho > 0.9) & (rho < 1.4), "punch.png": rho < 1.2,
              "screw.png": (rho < 1.4) & (np.abs(xx - 320) * s > 0.2)}
    for name, face in others.items():
        save(name, sim.render(np.where(face, 0.0, 5.0), press_depth=0.25))
        rows.append(f"{name},320,240,{1.3 / s:.2f}")
    (folder / "circles.csv").write_text("\n".join(rows) + "\n")
    return list(others)


def load_benchmark(name: str) -> types.ModuleType:
    """The module ``benchmarks/<name>.py`` (benchmarks are scripts, not a package)."""
    spec = importlib.util.spec_from_file_location(name, ROOT / "benchmarks" / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@contextlib.contextmanager
def hertz_pad_sweeps(monkeypatch, w_over_h_max: float):
    """Stand in Hertz's ball (a^2 = R w, force ratio 1) for every finite pad's FEM sweep
    (:func:`tactilevision.mechanics._indenter.pad_sweep_result`), from each sweep's first
    depth to `w_over_h_max`: yields the list of sweep keys asked for, the sweeps'
    in-memory cache cleared before and after."""
    import tactilevision.mechanics._indenter as ind

    keys: list[tuple] = []

    def hertz_sweep(radius_over_h, *rest):
        keys.append((radius_over_h, *rest))
        w = np.geomspace(rest[4], w_over_h_max, 40)
        return types.SimpleNamespace(w_over_h=w, hertz_ratio=np.ones_like(w),
                                     contact_radius=np.sqrt(radius_over_h * w))

    monkeypatch.setattr(ind, "pad_sweep_result", hertz_sweep)
    ind._pad_sweep.cache_clear()
    try:
        yield keys
    finally:
        ind._pad_sweep.cache_clear()

