"""A frame pipeline for a robot's perception loop: camera or file in, one result per frame out.

Capture runs on its own thread and hands frames to the processing loop under a
stated policy:

- ``'latest'`` (live use): a one-frame mailbox. When processing is slower than
  the camera, the newest frame replaces the waiting one and the stale one is
  dropped (counted in :attr:`LiveResult.dropped`): the result is always about
  the present, never a growing backlog.
- ``'every'`` (offline use): a bounded queue; capture waits for processing, so
  every frame is processed, in order.

Each result carries its capture time and its latency, capture to result.
"""

from __future__ import annotations

import collections
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._blas import openblas_thread_controls
from .._blocks import check_binning
from .._checks import InputError, check_positive
from ..fem import ForceEstimator
from ..io import open_source
from ..optics import (
    DepthReconstructor,
    PhotometricCalibration,
    lateral_displacement,
    marker_centres,
    track_markers,
)

__all__ = ["LiveResult", "Pipeline", "auto_reference", "open_frames", "stream"]


@dataclass(frozen=True)
class LiveResult:
    """One processed frame.

    Attributes
    ----------
    index : int
        The frame's position in the source (0 for the first captured).
    t_capture_s : float
        When the frame was captured, ``time.perf_counter()`` seconds.
    latency_s : float
        Capture to result, s: on a camera what the latency means; on a file or folder
        (read ahead of the processing) it holds the time the frame waited in line.
    frame : (H, W, 3) uint8 ndarray
        The tactile frame, BGR.
    height_mm : (H, W) float32 ndarray
        Height map, mm, positive into the gel.
    contact : (H, W) bool ndarray
        Contact mask (colour change above the calibration's noise level).
    forces : ForceMap or None
        The force map, when the pipeline has E and nu.
    total_force_n : (3,) float64 ndarray or None
        (Fx, Fy, Fz) summed over the pad, N.
    dropped : int
        Frames the ``'latest'`` policy dropped since the previous result.
    markers : MarkerFlow or None
        For a marker gel: the reference's markers tracked into the frame
        (:func:`~tactilevision.optics.track_markers`).
    lateral_mm : (H, W, 2) float32 ndarray or None
        For a marker gel: the lateral displacement field of the gel surface,
        (ux, uy) mm (:func:`~tactilevision.optics.lateral_displacement`, thin-plate
        spline through the valid tracks); None with fewer than 3 valid tracks.
    process_s : float
        The processing alone, from taking the frame to the result, s (no waiting in
        line): the figure to compare with the frame period.
    live : bool
        True for a camera (the latency is capture to result), False for a file,
        folder or iterable (read ahead: the latency includes the queue).
    """

    index: int
    t_capture_s: float
    latency_s: float
    frame: np.ndarray
    height_mm: np.ndarray
    contact: np.ndarray
    forces: object | None
    total_force_n: np.ndarray | None
    dropped: int
    markers: object | None = None
    lateral_mm: np.ndarray | None = None
    process_s: float = float("nan")
    live: bool = True


def open_frames(source) -> tuple[Iterator[np.ndarray], bool]:
    """Frames of a camera index, a video file, a frame folder, or an iterable of frames.

    Parameters
    ----------
    source : int, str, Path or iterable of (H, W, 3) uint8 ndarray
        An int is a camera (``cv2.VideoCapture(index)``); a path to a file is
        a video, to a folder its frames in name order, to a session folder its
        frames (:func:`~tactilevision.io.open_source`).

    Returns
    -------
    frames : iterator of (H, W, 3) uint8 ndarray
        BGR.
    live : bool
        True for a camera (the default policy is then ``'latest'``).

    Raises
    ------
    InputError
        A camera that does not open, a missing path, a file that is not a
        video, a folder without frames.
    """
    if isinstance(source, int | np.integer | str | Path) and not isinstance(source, bool):
        src = open_source(source)
        return src.iter(), src.kind == "camera"
    if isinstance(source, np.ndarray) and source.ndim == 3:
        raise InputError("a single frame is not a stream: pass a list of frames")
    return iter(source), False


def auto_reference(frames: np.ndarray, *, k: float = 3.0) -> tuple[np.ndarray, np.ndarray]:
    """A no-contact reference from the first frames of a stream.

    The median of the frames, then again over only the frames whose mean
    absolute colour difference from that median is within `k` times the
    median of those differences (a press among them is left out).

    Parameters
    ----------
    frames : (N, H, W, 3) uint8 ndarray
    k : float, default 3.0

    Returns
    -------
    reference : (H, W, 3) uint8 ndarray
    used : (N,) bool ndarray
        The frames it was taken from.

    Raises
    ------
    InputError
        For fewer than one frame.
    """
    f = np.asarray(frames)
    if f.ndim != 4 or f.shape[0] < 1:
        raise InputError("auto_reference needs at least one (H, W, 3) frame")
    med = np.median(f, axis=0)
    diff = np.abs(f.astype(np.float32) - med).mean(axis=(1, 2, 3))
    used = diff <= k * max(float(np.median(diff)), 0.25)
    ref = np.median(f[used], axis=0)
    return np.clip(np.rint(ref), 0, 255).astype(np.uint8), used


class _Mailbox:
    """Frames from the capture thread to the processing loop, under the policy."""

    def __init__(self, policy: str, depth: int = 64) -> None:
        self.latest = policy == "latest"
        self.items: collections.deque = collections.deque(maxlen=1 if self.latest else None)
        self.depth = depth
        self.cond = threading.Condition()
        self.done = False
        self.dropped = 0
        self.error: BaseException | None = None

    def put(self, item, stop: threading.Event) -> None:
        with self.cond:
            if self.latest:
                if self.items:
                    self.dropped += 1
                self.items.append(item)          # maxlen 1: the stale frame goes
            else:
                while len(self.items) >= self.depth and not stop.is_set():
                    self.cond.wait(0.05)
                self.items.append(item)
            self.cond.notify_all()

    def get(self):
        """The next item and the frames dropped before it; None at the end of the source."""
        with self.cond:
            while not self.items and not self.done:
                self.cond.wait(0.05)
            if self.error is not None:
                raise self.error
            if not self.items:
                return None
            item = self.items.popleft()
            dropped, self.dropped = self.dropped, 0
            self.cond.notify_all()
            return item, dropped

    def finish(self, error: BaseException | None = None) -> None:
        with self.cond:
            self.done = True
            self.error = error
            self.cond.notify_all()


class _OneBlasThread:
    """BLAS on one thread around one frame's work, the previous counts restored after.

    A frame's dense products (the inverse FEM's 1200-node operator, the least-squares
    levelling) are small: with OpenBLAS's threads they cost 5 to 10 times more as soon as
    another process competes for a core (the inverse FEM's 'field' call: 8.0 against
    1.1 ms a 427 x 320 frame on this 2-core machine under load, run once each way,
    2026-11-23), and the capture thread is such a competitor. The loaded OpenBLAS
    libraries' own setters, found once (a few microseconds a frame); nothing on other
    BLAS builds.
    """

    def __init__(self) -> None:
        self.controls = openblas_thread_controls()
        self.saved: list = []

    def __enter__(self) -> None:
        self.saved = [(setter, int(getter())) for setter, getter in self.controls]
        for setter, _ in self.saved:
            setter(1)

    def __exit__(self, *exc) -> None:
        for setter, count in self.saved:
            setter(count)


class Pipeline:
    """Tactile frames to height maps, contact masks and force maps, one frame at a time.

    Parameters
    ----------
    calibration : PhotometricCalibration or str or Path
        The sensor's photometric calibration (or its .npz file).
    reference : (H, W, 3) uint8 ndarray, 'auto' or 'calibration', default 'auto'
        The no-contact frame: given, taken from the first `n_reference` frames
        of the stream (:func:`auto_reference`; those frames are then
        processed too), or the calibration's own.
    n_reference : int, default 10
    E_mpa, nu, thickness_mm : float, optional
        The gel; with all three, every result has a force map
        (:class:`~tactilevision.fem.ForceEstimator`).
    method : {'spectral', 'fem'}, default 'spectral'
        The force estimator's method: the infinite layer's Green's function
        on every pixel, or the inverse FEM of the finite pad on its 40 x 30
        node grid (forces per node; a fraction of the spectral method's cost
        a frame, ``benchmarks/bench_live.py``; the pad's stiffness is built
        once per sensor size and cached on disk).
    beta : float, default 0.0
        Eq. (5)'s large-deformation stiffening for the forces.
    contact : {'footprint', 'field'}, default 'footprint'
    threshold_mm : float, default 0.02
        The forces' traction region, :class:`~tactilevision.fem.ForceEstimator`'s
        defaults and ``tactilevision forces``': only the pixels higher than
        `threshold_mm`, or the whole height map. The footprint's solve is slow on
        median-levelled heights, whose background is not zero (432 ms a 427 x 320
        frame against 15 ms with 'field', ``benchmarks/bench_live.py``): it goes with
        ``level='contact'``, the default with forces; 'field' with
        ``level='median'`` or ``'far_field'`` is the camera-rate choice.
    binning : int or 'auto', default 'auto'
        The footprint's solve and, with ``level='contact'``, the heights on
        blocks of pixels (:class:`~tactilevision.fem.ForceEstimator`'s
        `binning`, ``tactilevision forces --binning``); 1: every pixel.
    engine : {'table', 'onnx'}, default 'table'
        The reconstructor's engine.
    markers : bool, optional
        Track the gel's markers and give each result the lateral displacement
        field. Default: the calibration's ``markers`` (a marker gel).
    level : {'contact', 'median', 'far_field'}, optional
        The height's zero, as ``tactilevision forces --level``. Default
        'contact' with forces (zero outside the contact, heights integrated
        over it: the accurate footprint, at several times the cost a frame,
        ``benchmarks/bench_live.py``), 'median' without.

    Raises
    ------
    InputError
        For only some of E_mpa, nu and thickness_mm, a bad reference, an unknown
        method, level or contact, a threshold_mm that is not positive, or a bad
        binning.

    Examples
    --------
    >>> pipe = Pipeline("calibration/gelsight.npz", E_mpa=0.2, nu=0.48,
    ...                 thickness_mm=3.0)                        # doctest: +SKIP
    >>> for r in pipe.stream(0):  # camera 0  # doctest: +SKIP
    ...     print(r.index, r.total_force_n[2], r.latency_s)
    """

    def __init__(self, calibration, *, reference="auto", n_reference: int = 10,
                 E_mpa: float | None = None, nu: float | None = None,
                 thickness_mm: float | None = None, beta: float = 0.0,
                 engine: str = "table", level: str | None = None,
                 contact: str = "footprint", threshold_mm: float = 0.02,
                 method: str = "spectral", markers: bool | None = None,
                 binning: int | str = "auto") -> None:
        self.calibration = (calibration if isinstance(calibration, PhotometricCalibration)
                            else PhotometricCalibration.load(calibration))
        given = [v is not None for v in (E_mpa, nu, thickness_mm)]
        if any(given) and not all(given):
            raise InputError("forces need all of E_mpa, nu and thickness_mm")
        self.material = (E_mpa, nu, thickness_mm, beta) if all(given) else None
        if contact not in ("footprint", "field"):
            raise InputError(f"contact must be 'footprint' or 'field', got {contact!r}")
        self.contact = contact
        self.threshold_mm = check_positive(threshold_mm, "threshold_mm")
        if method not in ("spectral", "fem"):
            raise InputError(f"method must be 'spectral' or 'fem', got {method!r}")
        self.method = method
        self.binning = check_binning(binning)
        self.markers = bool(self.calibration.markers if markers is None else markers)
        self._marker_ref: np.ndarray | None = None
        self._marker_pos: np.ndarray | None = None
        if isinstance(reference, str) and reference not in ("auto", "calibration"):
            raise InputError(f"reference must be a frame, 'auto' or 'calibration', got "
                             f"{reference!r}")
        if n_reference < 1:
            raise InputError(f"n_reference must be >= 1, got {n_reference}")
        self.n_reference = int(n_reference)
        self.engine = engine
        self.level = level or ("contact" if self.material is not None else "median")
        if self.level not in ("contact", "median", "far_field"):
            raise InputError(f"level must be 'contact', 'median' or 'far_field', got {level!r}")
        self.reference = reference
        self._recon = None
        self._est = None
        self._blas = _OneBlasThread()
        if not (isinstance(reference, str) and reference == "auto"):
            self._build(reference)

    def _build(self, reference) -> None:
        cal = self.calibration
        forces = self.material is not None
        blocks = 1
        if forces:
            E, nu, h, beta = self.material
            self._est = ForceEstimator(cal.shape, cal.mm_per_px, thickness_mm=h, E_mpa=E,
                                       nu=nu, beta=beta, contact=self.contact,
                                       threshold_mm=self.threshold_mm, method=self.method,
                                       binning=self.binning)
            blocks = self._est.blocks if self.level == "contact" else 1
        self._recon = DepthReconstructor(
            cal, reference=reference, engine=self.engine,
            boundary="contact" if self.level == "contact" else "neumann",
            level="median" if self.level == "contact" else self.level, binning=blocks)
        if self.markers:
            ref = cal.reference if isinstance(reference, str) else np.asarray(reference)
            pos = marker_centres(ref)
            if len(pos) < 3:
                raise InputError(f"markers: the reference shows {len(pos)} marker(s); the "
                                 "lateral field needs 3 or more (markers=False for a gel "
                                 "without them)")
            self._marker_ref, self._marker_pos = ref, pos
        self.reference = reference

    def lateral(self, frame: np.ndarray):
        """The markers tracked into `frame` and the lateral field (or None), for a
        marker gel; (None, None) otherwise."""
        if self._marker_ref is None:
            return None, None
        flow = track_markers(self._marker_ref, frame, positions_px=self._marker_pos)
        if int(np.count_nonzero(flow.valid)) < 3:
            return flow, None
        return flow, lateral_displacement(flow, self.calibration.shape,
                                          self.calibration.mm_per_px)

    def process(self, frame: np.ndarray):
        """Height map, contact mask and force map (or None) of one frame.

        Raises
        ------
        InputError
            Before a reference is set (``reference='auto'`` outside :meth:`stream`).
        """
        if self._recon is None:
            raise InputError("no reference yet: give one, or run stream() to take it "
                             "from the first frames")
        with self._blas:
            h = self._recon(frame)
            contact = self._recon.contact_mask(frame)
            fm = self._est(h) if self._est is not None else None
        return h, contact, fm

    def stream(self, source, *, policy: str | None = None, max_frames: int | None = None
               ) -> Iterator[LiveResult]:
        """Process a source frame by frame (module docstring: capture thread, policies).

        Parameters
        ----------
        source : int, str, Path or iterable of frames
            :func:`open_frames`.
        policy : {'latest', 'every'}, optional
            Default: 'latest' for a camera, 'every' for files, folders and
            iterables.
        max_frames : int, optional
            Stop after this many results.

        Yields
        ------
        LiveResult

        Notes
        -----
        Closing the generator (``break``, Ctrl-C in the loop, garbage
        collection) stops the capture thread and releases the camera or file.
        """
        frames, live = open_frames(source)
        policy = policy or ("latest" if live else "every")
        if policy not in ("latest", "every"):
            raise InputError(f"policy must be 'latest' or 'every', got {policy!r}")
        box = _Mailbox(policy)
        stop = threading.Event()

        def capture() -> None:
            try:
                for i, frame in enumerate(frames):
                    if stop.is_set():
                        break
                    box.put((i, time.perf_counter(), frame), stop)
            except BaseException as exc:       # handed to the loop, raised there
                box.finish(exc)
                return
            box.finish()

        thread = threading.Thread(target=capture, name="tactilevision-capture", daemon=True)
        thread.start()
        n_out = 0
        try:
            pending: list = []
            if self._recon is None:              # 'auto': the first frames make the reference
                while len(pending) < self.n_reference:
                    got = box.get()
                    if got is None:
                        break
                    pending.append(got[0])
                if not pending:
                    raise InputError("the source gave no frame to take a reference from")
                ref, _ = auto_reference(np.stack([p[2] for p in pending]))
                self._build(ref)
            queue_ = collections.deque(pending)
            while max_frames is None or n_out < max_frames:
                if queue_:
                    (i, t_cap, frame), dropped = queue_.popleft(), 0
                else:
                    got = box.get()
                    if got is None:
                        break
                    (i, t_cap, frame), dropped = got
                t_take = time.perf_counter()
                h, contact, fm = self.process(frame)
                flow, lateral = self.lateral(frame)
                total = None if fm is None else np.asarray(fm.total_n, np.float64)
                t_done = time.perf_counter()
                yield LiveResult(index=i, t_capture_s=t_cap,
                                 latency_s=t_done - t_cap, frame=frame,
                                 height_mm=h, contact=contact, forces=fm, total_force_n=total,
                                 dropped=dropped, markers=flow, lateral_mm=lateral,
                                 process_s=t_done - t_take, live=live)
                n_out += 1
        finally:
            stop.set()
            thread.join(timeout=2.0)


def stream(source, calibration, *, policy: str | None = None, max_frames: int | None = None,
           **kwargs) -> Iterator[LiveResult]:
    """``Pipeline(calibration, **kwargs).stream(source, policy=, max_frames=)``.

    Parameters
    ----------
    source : int, str, Path or iterable of frames
    calibration : PhotometricCalibration or str or Path
    policy : {'latest', 'every'}, optional
    max_frames : int, optional
    **kwargs
        :class:`Pipeline`'s (reference, n_reference, E_mpa, nu, thickness_mm,
        beta, engine, level, contact, threshold_mm, method, markers, binning).

    Yields
    ------
    LiveResult
    """
    yield from Pipeline(calibration, **kwargs).stream(source, policy=policy,
                                                      max_frames=max_frames)
