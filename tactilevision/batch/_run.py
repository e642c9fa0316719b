"""Run a batch on Dask: many inputs, each cut into chunks of frames, on many workers."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import cv2
from tqdm.auto import tqdm

from .._checks import InputError
from ._sources import FrameSource, open_source
from ._store import InputStore, write_json_atomic
from ._tasks import BatchSettings, calibrate_task, process_chunk

__all__ = ["WORKER_ENVIRON", "BatchReport", "InputOutcome", "run_batch"]

#: Dask configuration under which the local cluster's workers are started. Dask sets
#: ``MALLOC_TRIM_THRESHOLD_=65536`` in its workers by default, which turns glibc's
#: dynamic mmap threshold off: every frame-sized temporary (1.2 MB at 640 x 480) is then
#: mapped and unmapped, its pages faulted in anew, and a height map cost 10.9 ms in a
#: worker against 3.3 ms in the parent process on the same frames (the contact mask 6.8
#: against 2.3 ms; 2-core x86_64, 2026-11-26). Workers keep glibc's defaults instead:
#: 3.1 ms and 2.5 ms. A cluster of your own (``--scheduler``) should be started likewise
#: (``distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_: null`` in its Dask
#: configuration).
WORKER_ENVIRON = {"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}

#: Modules whose runtimes keep threads of their own in the process that imported them; a
#: process forked from theirs can deadlock (JAX warns so on every fork).
_THREADED_RUNTIMES = ("jax", "torch", "tensorflow")


def _start_method() -> str:
    """How our local cluster starts its workers: forked on Linux, from a process with one
    Python thread and none of :data:`_THREADED_RUNTIMES` imported; spawned otherwise.

    A forked worker starts with the batch stack already imported; a spawned one imports
    Python, Dask and, on its first task, the stack: about 2 s on the critical path of a
    short batch (``benchmarks/bench_batch_speedup.py``, 1200 frames on 2 workers: 1.22,
    1.27 and 1.39 times one process spawned, 1.44 to 1.71 forked, 2026-11-26). A fork
    from a process whose other threads hold locks can deadlock the child, and OpenCV's
    thread pool does so in any case: :class:`_ForkGuard` shuts that for the instant of
    the fork; for the rest, a busy or threaded parent (a notebook's, one that has run JAX
    or torch) gets spawned workers. Elsewhere (macOS, Windows) fork is unsafe or absent.
    """
    if not sys.platform.startswith("linux"):
        return "spawn"
    if threading.active_count() > 1 or any(m in sys.modules for m in _THREADED_RUNTIMES):
        return "spawn"
    return "fork"


class _ForkGuard:
    """OpenCV's thread pool shut in this process for the instant of a fork while a local
    cluster of ours may fork workers (a nanny restarting one included), restored after.

    A child forked while OpenCV's pthreads pool has threads inherits the pool without
    them, and hangs or crashes at its first ``cv2.setNumThreads`` (a worker segfaulted
    so under pytest, whose process had used the pool; a bare fork hung 3 of 3 times,
    and 0 of 3 with the pool set to one thread first: ``os.fork`` after a
    ``cv2.GaussianBlur``, opencv 5.0.0 built on pthreads). Only forks made while a
    cluster of ours is open are touched (:func:`os.register_at_fork` hooks, registered
    once)."""

    def __init__(self) -> None:
        self.open = 0
        self.saved: int | None = None
        if hasattr(os, "register_at_fork"):
            os.register_at_fork(before=self._before, after_in_parent=self._after)

    def _before(self) -> None:
        if self.open:
            self.saved = cv2.getNumThreads()
            cv2.setNumThreads(1)

    def _after(self) -> None:
        if self.saved is not None:
            cv2.setNumThreads(self.saved)
            self.saved = None


_FORK_GUARD = _ForkGuard()


@dataclass
class InputOutcome:
    """What became of one input of a batch.

    Attributes
    ----------
    input : str
    name : str
        Its outputs' stem in the output folder.
    status : {'done', 'already complete', 'failed'}
    error : str
        Why it failed ('' otherwise).
    n_frames : int
    chunks_run, chunks_skipped : int
        Tasks computed now, and tasks an earlier run had completed.
    """

    input: str
    name: str
    status: str = "pending"
    error: str = ""
    n_frames: int = 0
    chunks_run: int = 0
    chunks_skipped: int = 0


@dataclass
class BatchReport:
    """The outcome of :func:`run_batch` (also written as ``OUT/batch.json``).

    Attributes
    ----------
    kind : str
    out : Path
    inputs : list of InputOutcome
    workers : int
        Worker processes of the cluster.
    seconds : float
    receipts : list of dict
        Every task's receipt (:func:`process_chunk`): start, stop, seconds,
        pid, built.
    """

    kind: str
    out: Path
    inputs: list[InputOutcome]
    workers: int
    seconds: float = 0.0
    receipts: list[dict] = field(default_factory=list)

    @property
    def failed(self) -> list[InputOutcome]:
        return [o for o in self.inputs if o.status == "failed"]

    @property
    def frames_run(self) -> int:
        return sum(r["stop"] - r["start"] for r in self.receipts if "stop" in r)

    def to_json_dict(self) -> dict:
        return {"kind": self.kind, "out": str(self.out), "workers": self.workers,
                "seconds": round(self.seconds, 3), "frames_run": self.frames_run,
                "inputs": [vars(o) for o in self.inputs]}


def _names(paths: Sequence[Path]) -> list[str]:
    """Unique output stems: the file or folder stem, with its parent's name if needed."""
    stems = [p.stem if p.is_file() else p.name for p in paths]
    out = []
    for p, s in zip(paths, stems, strict=True):
        name = s if stems.count(s) == 1 else f"{p.resolve().parent.name}_{s}"
        while name in out:
            name += "_"
        out.append(name)
    return out


def _client(scheduler: str | None, n_workers: int | None):
    """A client of the given scheduler, or of a local cluster of processes (one per core)."""
    try:
        import dask
        from distributed import Client, LocalCluster
        from distributed.deploy.spec import SpecCluster
    except ModuleNotFoundError as exc:  # pragma: no cover - depends on the install
        raise InputError("batch needs Dask: pip install 'tactilevision[dask]'") from exc
    if scheduler:
        try:
            return Client(scheduler, timeout="10s"), None
        except OSError as exc:
            raise InputError(f"no Dask scheduler answers at {scheduler} ({exc})") from None

    n = n_workers or os.cpu_count() or 1
    start = _start_method()
    if start == "fork":
        # the chunks' store, imported once here (the batch imports it before its first
        # task in any case) rather than by every forked worker on its first task; neither
        # starts a thread (pyarrow does: its workers import it themselves)
        import numcodecs.blosc  # noqa: F401
        import zarr  # noqa: F401
    before = set(SpecCluster._instances)
    _FORK_GUARD.open += 1           # until _close, or the failure below
    try:
        method = {"distributed.worker.multiprocessing-method": start}
        with dask.config.set({**WORKER_ENVIRON, **method}):
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                   dashboard_address=":0",   # any free port: never 8787 twice
                                   silence_logs=logging.ERROR)
        return Client(cluster), cluster
    except BaseException as exc:
        _FORK_GUARD.open -= 1
        # Ctrl-C while the workers start comes back as "Nanny failed to start": it is the
        # interrupt, and is raised as one (exit 130, no traceback). The cluster it caught
        # starting is abandoned: its workers stopped, and distributed's exit hook kept from
        # closing it (it asserted on a worker still starting: a traceback after the prompt)
        if _interrupted(exc):
            _quiet_teardown()
            for started in set(SpecCluster._instances) - before:
                _stop_workers(started)
                with contextlib.suppress(Exception):
                    started.shutdown_on_close = False
            raise KeyboardInterrupt from None
        raise


def _interrupted(exc: BaseException) -> bool:
    """Whether an interrupt (KeyboardInterrupt, or the cancellation it caused) lies in the
    chain of causes of `exc`."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        seen.add(id(exc))
        if isinstance(exc, KeyboardInterrupt | asyncio.CancelledError):
            return True
        exc = exc.__cause__ or exc.__context__
    return False


def run_batch(kind: str, inputs: Sequence[str | Path], out: str | Path, *,
              settings: BatchSettings | None = None, scheduler: str | None = None,
              client=None, n_workers: int | None = None, overwrite: bool = False,
              progress: bool = True, on_receipt: Callable[[dict], None] | None = None
              ) -> BatchReport:
    """Process many frame folders, videos or sessions on a Dask cluster.

    Parameters
    ----------
    kind : {'reconstruct', 'forces', 'calibrate'}
        ``reconstruct``: height maps; ``forces``: height and force maps (both:
        inputs are frame folders or videos, cut into chunks of
        ``settings.chunk_frames``); ``calibrate``: each input a session
        folder, calibrated into ``OUT/NAME/`` as ``tactilevision calibrate``.
    inputs : sequence of str or Path
    out : str or Path
        Output folder (created): ``NAME.zarr`` and ``NAME.parquet`` per input
        (``tactilevision.batch._store`` gives the layout), ``batch.json``.
    settings : BatchSettings
        Required for ``reconstruct`` and ``forces``.
    scheduler : str, optional
        Address of a running ``dask.distributed`` scheduler
        (``tcp://host:8786``); default: a local cluster of worker processes.
    client : distributed.Client, optional
        An existing client (the caller keeps it open).
    n_workers : int, optional
        Workers of the local cluster (default: one per core).
    overwrite : bool, default False
        Start inputs again that an earlier run wrote with other settings.
    progress : bool, default True
        A progress bar on standard error (frames, or sessions).
    on_receipt : callable, optional
        Called with each task's receipt as it arrives.

    Returns
    -------
    BatchReport
        A broken input is listed there with its error (status 'failed'); the
        others go on. A rerun skips the inputs and chunks already complete.

    Raises
    ------
    InputError
        For an unknown `kind`, missing settings, an output folder that is a
        file, or a scheduler that does not answer.
    KeyboardInterrupt
        On Ctrl-C: the chunks already written stay, and a rerun resumes.
    """
    if kind not in ("reconstruct", "forces", "calibrate"):
        raise InputError(f"unknown batch kind {kind!r}: reconstruct, forces or calibrate")
    if kind != "calibrate" and (settings is None or settings.kind != kind):
        raise InputError(f"batch {kind} needs BatchSettings(kind={kind!r}, ...)")
    if settings is not None and settings.chunk_frames < 1:
        raise InputError(f"chunk_frames must be >= 1, got {settings.chunk_frames}")
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {out} is a file, not a folder")
    paths = [Path(p) for p in inputs]
    if not paths:
        raise InputError("no inputs given")
    made = _first_missing(out)
    out.mkdir(parents=True, exist_ok=True)
    outcomes = [InputOutcome(str(p), n) for p, n in zip(paths, _names(paths), strict=True)]
    t0 = time.perf_counter()
    own_cluster = None
    try:
        if client is None:
            client, own_cluster = _client(scheduler, n_workers)
        report = BatchReport(kind=kind, out=out, inputs=outcomes,
                             workers=len(client.scheduler_info().get("workers", {})))
    except BaseException:
        # interrupted (or failed) while the cluster started: nothing was written, so the
        # folders this call made go again (an empty output folder is not left behind)
        _remove_empty(out, made)
        raise
    interrupted = False
    try:
        if kind == "calibrate":
            _run_sessions(client, paths, out, outcomes, report, progress, on_receipt)
        else:
            _run_frames(client, paths, out, settings, outcomes, report, overwrite, progress,
                        on_receipt)
    except KeyboardInterrupt:
        interrupted = True
        raise
    finally:
        report.seconds = time.perf_counter() - t0
        write_json_atomic(out / "batch.json", report.to_json_dict())
        if own_cluster is not None:
            _close(client, own_cluster, interrupted=interrupted)
    return report


def _first_missing(path: Path) -> Path | None:
    """The outermost of `path` and its parents that does not exist yet (None if `path`
    does)."""
    first = None
    while not path.exists():
        first, path = path, path.parent
        if path == path.parent:
            break
    return first


def _remove_empty(path: Path, top: Path | None) -> None:
    """Remove `path` and its parents up to `top` (the folders a call made) while empty."""
    if top is None:
        return
    while True:
        try:
            path.rmdir()                 # only an empty folder goes
        except OSError:
            return
        if path == top:
            return
        path = path.parent


def _close(client, cluster, *, interrupted: bool = False) -> None:
    """Close our own client and cluster. An error while closing (distributed asserts on a
    worker still starting when an interrupt closes the cluster) must not replace the
    run's own outcome, its KeyboardInterrupt included: it is logged, not raised. After an
    interrupt the workers are stopped first (:func:`_stop_workers`), and distributed's
    exit hook is kept from closing the cluster a second time (its assertion on a worker
    caught starting was printed as a traceback after the prompt came back)."""
    if interrupted:
        _quiet_teardown()
        _stop_workers(cluster)
    for thing in (client, cluster):
        try:
            thing.close()
        except Exception as exc:        # any failure to close: logged, not raised
            logging.getLogger("tactilevision.batch").debug("closing %s: %r", thing, exc)
    with contextlib.suppress(Exception):
        cluster.shutdown_on_close = False
    _FORK_GUARD.open = max(_FORK_GUARD.open - 1, 0)


def _quiet_teardown() -> None:
    """After an interrupt, the teardown says nothing: the nannies' start-up tasks the
    interrupt cancelled are logged by asyncio as "Task exception was never retrieved",
    and the scheduler's comms to the stopped workers by distributed ("Batched Comm
    Closed"), each with a traceback."""
    for name in ("asyncio", "distributed"):
        logging.getLogger(name).setLevel(logging.CRITICAL)


def _stop_workers(cluster) -> None:
    """Kill the local cluster's worker processes at once, their nannies told not to
    restart them: a worker left running after the command has gone logs its lost
    scheduler with a traceback on the terminal it shares (a chunk it was writing has no
    receipt yet, so a rerun computes it again)."""
    kill = getattr(signal, "SIGKILL", signal.SIGTERM)
    for nanny in list(getattr(cluster, "workers", {}).values()):
        with contextlib.suppress(Exception):
            nanny.auto_restart = False
            pid = nanny.process.process.pid
            if pid:
                os.kill(pid, kill)


def _bar(progress: bool, total: int, unit: str, desc: str):
    if not progress:
        return None

    return tqdm(total=total, unit=unit, desc=desc, file=sys.stderr, mininterval=0.5)


def _run_frames(client, paths, out, settings, outcomes, report, overwrite, progress,
                on_receipt) -> None:
    from distributed import as_completed

    futures = {}
    stores: dict[str, tuple[InputStore, FrameSource]] = {}
    total = 0
    for p, o in zip(paths, outcomes, strict=True):
        try:
            src = open_source(p)
            ref = settings.reference or (str(src.reference_path) if src.reference_path else None)
            store = InputStore(out, o.name)
            shape = _force_shape(settings, src) if settings.kind == "forces" else None
            attrs = {"settings": settings.to_json(), "source": str(p),
                     "reference": ref or "the calibration's", "units": {"height_mm": "mm",
                     "force_n": "N (Fx, Fy, Fz on the gel)", "pressure_kpa": "kPa"}}
            o.n_frames = src.n_frames
            if store.prepare(n_frames=src.n_frames, shape=src.shape,
                             chunk_frames=settings.chunk_frames, force_shape=shape,
                             attrs=attrs, overwrite=overwrite):
                o.status = "already complete"
                continue
        except InputError as exc:
            o.status, o.error = "failed", str(exc)
            continue
        stores[o.name] = (store, src)
        done = store.done_chunks()
        for start in range(0, src.n_frames, settings.chunk_frames):
            if start in done:
                o.chunks_skipped += 1
                continue
            stop = min(start + settings.chunk_frames, src.n_frames)
            fut = client.submit(process_chunk, settings, src, ref, store, start, stop,
                                retries=1, pure=False)
            futures[fut] = o
            total += stop - start
    bar = _bar(progress, total, "frame", f"batch {settings.kind}")
    try:
        for fut in as_completed(list(futures)):
            o = futures.pop(fut)
            if o.status == "failed":
                continue
            try:
                receipt = fut.result()
            except Exception as exc:           # listed with its error; the others go on
                o.status = "failed"
                o.error = str(exc) if isinstance(exc, InputError) else (
                    f"{type(exc).__name__}: {exc}")
                client.cancel([f for f, oo in futures.items() if oo is o])
                continue
            receipt["input"] = o.name
            report.receipts.append(receipt)
            o.chunks_run += 1
            if bar is not None:
                bar.update(receipt["stop"] - receipt["start"])
            if on_receipt is not None:
                on_receipt(receipt)
    except KeyboardInterrupt:
        client.cancel(list(futures))
        raise
    finally:
        if bar is not None:
            bar.close()
    for o in outcomes:
        if o.name in stores and o.status == "pending":
            store, src = stores[o.name]
            try:
                store.finish(src.n_frames)
                o.status = "done"
            except InputError as exc:
                o.status, o.error = "failed", str(exc)


def _force_shape(settings: BatchSettings, src: FrameSource) -> tuple[int, int]:
    """Rows and columns of the force map: the image's, or the FEM grid's (ny, nx)."""
    if settings.method == "spectral":
        return src.shape
    nx, ny = settings.grid
    return (int(ny), int(nx))


def _run_sessions(client, paths, out, outcomes, report, progress, on_receipt) -> None:
    from distributed import as_completed

    futures = {}
    for p, o in zip(paths, outcomes, strict=True):
        dst = out / o.name
        if (dst / "fit.json").is_file():       # calibrate writes its folder whole, or not
            o.status = "already complete"
            continue
        if not (p / "session.toml").is_file():
            o.status, o.error = "failed", f"{p} is not a session folder (no session.toml)"
            continue
        futures[client.submit(calibrate_task, str(p), str(dst), retries=1, pure=False)] = o
    bar = _bar(progress, len(futures), "session", "batch calibrate")
    try:
        for fut in as_completed(list(futures)):
            o = futures.pop(fut)
            try:
                summary = fut.result()
            except Exception as exc:
                o.status, o.error = "failed", str(exc)
            else:
                o.status = "done"
                o.chunks_run = 1
                report.receipts.append({"input": o.name, **summary})
                if on_receipt is not None:
                    on_receipt(summary)
            if bar is not None:
                bar.update(1)
    except KeyboardInterrupt:
        client.cancel(list(futures))
        raise
    finally:
        if bar is not None:
            bar.close()
