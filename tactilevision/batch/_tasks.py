"""The work of one batch task, run in a Dask worker: a chunk of frames, or a session.

A worker process builds its reconstructor and force estimator once
(:func:`worker_tools`, cached per process) and keeps them for every chunk it
is given; each chunk's results go straight to disk (:class:`InputStore`), so
only a few numbers travel back to the client.
"""

from __future__ import annotations

import ctypes
import json
import os
import threading
import time
from dataclasses import asdict, dataclass
from functools import lru_cache
from pathlib import Path

import cv2
import numpy as np

from .._checks import InputError
from ..fem import ForceEstimator
from ..io import check_output_folder, check_overwrite, read_reference
from ..optics import DepthReconstructor, PhotometricCalibration
from ..pipeline import CALIBRATION_FILES, calibrate_session, write_calibration
from ._sources import FrameSource
from ._store import InputStore

__all__ = ["BatchSettings", "calibrate_task", "keep_frames_in_the_heap", "process_chunk",
           "worker_tools"]


@dataclass(frozen=True)
class BatchSettings:
    """What every chunk of a ``reconstruct`` or ``forces`` batch is processed with.

    Attributes
    ----------
    kind : {'reconstruct', 'forces'}
    calibration : str
        Photometric calibration file (.npz).
    reference : str or None
        One no-contact frame for every input; None: each input's own
        (:attr:`FrameSource.reference_path`), else the calibration's.
    level : {'median', 'far_field', 'contact'}
        The height's zero, as ``tactilevision reconstruct --level``.
    flat_reference : bool
    engine : {'table', 'onnx'}
        The reconstructor's engine (:class:`~tactilevision.optics.DepthReconstructor`):
        'table' tabulates an MLP calibration once per worker (seconds to tens of
        seconds), then runs fastest; 'onnx' starts at once.
    chunk_frames : int
        Frames per task and per Zarr chunk.
    E_mpa, nu, thickness_mm : float or None
        Forces: the gel (MPa, -, mm); None for ``reconstruct``.
    beta : float
        Forces: eq. (5)'s stiffening.
    method : {'spectral', 'fem'}
    grid : (int, int)
    contact : {'footprint', 'field'}
    threshold_mm : float
    binning : int or 'auto'
        Forces: the footprint's solve and the contact-pinned heights on blocks of pixels
        (:class:`~tactilevision.fem.ForceEstimator`'s `binning`).
    """

    kind: str
    calibration: str
    reference: str | None = None
    level: str = "median"
    flat_reference: bool = False
    engine: str = "table"
    chunk_frames: int = 32
    # None, not NaN, when unused: the settings key each worker's cache (NaN != NaN)
    E_mpa: float | None = None
    nu: float | None = None
    thickness_mm: float | None = None
    beta: float = 0.0
    method: str = "spectral"
    grid: tuple[int, int] = (40, 30)
    contact: str = "footprint"
    threshold_mm: float = 0.02
    binning: int | str = "auto"

    def to_json(self) -> str:
        """The settings as canonical JSON (stored with the outputs, compared on resume)."""
        return json.dumps(asdict(self), sort_keys=True)


#: glibc's mallopt parameters (malloc.h): M_TRIM_THRESHOLD, M_MMAP_THRESHOLD.
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3


def keep_frames_in_the_heap() -> bool:
    """Let this process keep frame-sized arrays in its heap (glibc only).

    Dask starts its workers with ``MALLOC_TRIM_THRESHOLD_=65536``, which turns
    glibc's dynamic mmap threshold off: every array above 128 kB (a 640 x 480
    float32 map is 1.2 MB) is then mapped and unmapped and its pages faulted
    in anew, and a height map cost 10.9 ms in a worker against 3.3 ms in the
    parent on the same frames (2-core x86_64, 2026-11-26). Raising the mmap
    threshold to glibc's largest (32 MiB) and the trim threshold to 128 MiB
    brings it back (3.6 to 3.8 ms), on any cluster, a user's own included.

    Returns
    -------
    done : bool
        False where there is no glibc (macOS, Windows, musl): nothing changed.
    """
    try:
        libc = ctypes.CDLL("libc.so.6")
        return bool(libc.mallopt(_M_MMAP_THRESHOLD, 32 * 2**20)
                    and libc.mallopt(_M_TRIM_THRESHOLD, 128 * 2**20))
    except (OSError, AttributeError):
        return False


@lru_cache(maxsize=4)
def worker_tools(settings: BatchSettings, reference: str | None):
    """The reconstructor and force estimator of a worker process, built on first use.

    Returns
    -------
    calibration : PhotometricCalibration
    reconstructor : DepthReconstructor
    estimator : ForceEstimator or None
        None for ``kind='reconstruct'``.
    """
    import numcodecs.blosc  # the dask extra's (through zarr)

    keep_frames_in_the_heap()
    cv2.setNumThreads(1)                # one task per core: the cores are the workers'
    numcodecs.blosc.set_nthreads(1)     # the Zarr writes' compression likewise
    cal = PhotometricCalibration.load(settings.calibration)
    ref = read_reference(reference, cal.shape) if reference else "calibration"
    est = None
    blocks = 1
    if settings.kind == "forces":
        est = ForceEstimator(cal.shape, cal.mm_per_px, thickness_mm=settings.thickness_mm,
                             E_mpa=settings.E_mpa, nu=settings.nu, grid=tuple(settings.grid),
                             method=settings.method, contact=settings.contact,
                             threshold_mm=settings.threshold_mm, beta=settings.beta,
                             binning=settings.binning)
        blocks = est.blocks if settings.level == "contact" else 1
    recon = DepthReconstructor(
        cal, reference=ref, boundary="contact" if settings.level == "contact" else "neumann",
        level="median" if settings.level == "contact" else settings.level,
        flat_reference=settings.flat_reference, engine=settings.engine, binning=blocks)
    return cal, recon, est


#: Each worker thread's chunk of heights, kept from one task to the next: a chunk of 32
#: frames of 640 x 480 (39 MB) is above glibc's largest mmap threshold (32 MiB), so a new
#: one is mapped, its pages faulted in and unmapped again every task (about 850 page
#: faults a task fewer, 2026-11-27). Per thread: a worker of several threads runs tasks
#: side by side.
_BUFFERS = threading.local()


def _chunk_buffer(n: int, shape: tuple[int, int]) -> np.ndarray:
    """A float32 (n, H, W) array of this thread's, reused by its next task of that size."""
    key = (n, *shape)
    if getattr(_BUFFERS, "key", None) != key:
        _BUFFERS.key, _BUFFERS.array = key, np.empty(key, np.float32)
    return _BUFFERS.array


def process_chunk(settings: BatchSettings, source: FrameSource, reference: str | None,
                  store: InputStore, start: int, stop: int) -> dict:
    """Height maps (and force maps) of frames ``start`` to ``stop - 1``, written to disk.

    Parameters
    ----------
    settings : BatchSettings
    source : FrameSource
    reference : str or None
        The no-contact frame for this input.
    store : InputStore
    start, stop : int

    Returns
    -------
    receipt : dict
        ``start``, ``stop``, ``seconds``, ``pid`` (the worker process) and
        ``built`` (whether this task built the worker's tools).

    Raises
    ------
    InputError
        For a frame that cannot be read (named).
    """
    t0 = time.perf_counter()
    misses = worker_tools.cache_info().misses
    cal, recon, est = worker_tools(settings, reference)
    built = worker_tools.cache_info().misses > misses
    n = stop - start
    px_mm2 = cal.mm_per_px ** 2
    heights = _chunk_buffer(n, source.shape)
    rows: dict[str, list] = {"frame": [], "source_frame": [], "t_s": [], "max_depth_mm": [],
                             "contact_area_mm2": []}
    forces = pressure = None
    if est is None:
        rows["out_of_range_px"] = []      # as reconstruct's heights.csv
    else:
        rows.update({"fx_n": [], "fy_n": [], "fz_n": [], "max_pressure_kpa": []})
    for k, frame in enumerate(source.iter(start, stop)):
        i = start + k
        h = recon(frame)
        heights[k] = h
        rows["frame"].append(i)
        rows["source_frame"].append(source.frame_name(i))
        rows["t_s"].append(float(source.times_s[i]))
        rows["max_depth_mm"].append(float(h.max()))
        if est is None:
            contact, outside = recon.contact_and_out_of_range(frame)
            rows["contact_area_mm2"].append(float(contact.sum()) * px_mm2)
            rows["out_of_range_px"].append(int(outside.sum()))
            continue
        fm = est(h)
        if forces is None:
            forces = np.empty((n, *fm.forces_n.shape), np.float32)
            pressure = np.empty((n, *fm.pressure_kpa.shape), np.float32)
        forces[k] = fm.forces_n
        pressure[k] = fm.pressure_kpa
        if fm.contact is None:       # 'field': the colour change above the noise level
            area = float(recon.contact_mask(frame).sum()) * px_mm2
        else:                        # the footprint the traction acts on (as `forces`)
            c = fm.contact
            area = float(np.sum(fm.forces_n[..., 2][c] / fm.pressure_kpa[c])) * 1e3
        rows["contact_area_mm2"].append(area)
        for j, key in enumerate(("fx_n", "fy_n", "fz_n")):
            rows[key].append(float(fm.total_n[j]))
        rows["max_pressure_kpa"].append(float(fm.pressure_kpa.max()))
    arrays = {"height_mm": heights}
    if forces is not None:
        arrays.update({"force_n": forces, "pressure_kpa": pressure})
    store.write_chunk(start, arrays, rows)
    return {"start": start, "stop": stop, "seconds": time.perf_counter() - t0,
            "pid": os.getpid(), "built": built}


def calibrate_task(session: str, out: str) -> dict:
    """The main job on one session in a worker: what ``tactilevision calibrate SESSION
    --out OUT`` writes, through the library (:func:`~tactilevision.pipeline.calibrate_session`,
    :func:`~tactilevision.pipeline.write_calibration`).

    Returns
    -------
    summary : dict
        ``E_mpa``, ``nu`` and ``n_presses`` of the written ``fit.json``.

    Raises
    ------
    InputError
        When the session is refused, or too few presses are certified (then
        rejected.csv and report.html in `out` say why, as calibrate's).
    """
    check_output_folder(Path(out))
    check_overwrite(Path(out), CALIBRATION_FILES)
    cal = calibrate_session(session, allow_failure=True)
    result = write_calibration(cal, out)
    if cal.fit is None:
        raise InputError(f"{cal.failure}; rejected.csv, the bevel panels and report.html in "
                         f"{out} say why")
    return {"E_mpa": result.fit.get("E_mpa"), "nu": result.fit.get("nu"),
            "n_presses": result.n_presses}
