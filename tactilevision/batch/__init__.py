"""Batch processing on Dask: hours of frames, many sensors, one command.

``run_batch('reconstruct' | 'forces', inputs, out, settings=BatchSettings(...))``
cuts every input (a frame folder or a video file) into chunks of frames and
runs them on a Dask cluster: a local one of worker processes by default, or a
running ``dask.distributed`` scheduler. Each worker builds its reconstructor
and force estimator once. Height and force maps go to Zarr (chunked,
compressed, readable while the batch runs), per-frame tables to Parquet; a
rerun skips what is complete. ``run_batch('calibrate', sessions, out)``
calibrates many sessions side by side.

Needs the ``dask`` extra: ``pip install 'tactilevision[dask]'``.
"""

from ._run import WORKER_ENVIRON, BatchReport, InputOutcome, run_batch
from ._sources import FrameSource, open_source
from ._store import HEIGHT_DIGITS, HEIGHT_RESOLUTION_MM, InputStore, quantize_heights
from ._tasks import (
    BatchSettings,
    calibrate_task,
    keep_frames_in_the_heap,
    process_chunk,
    worker_tools,
)

__all__ = ["HEIGHT_DIGITS", "HEIGHT_RESOLUTION_MM", "WORKER_ENVIRON", "BatchReport",
           "BatchSettings", "FrameSource", "InputOutcome", "InputStore", "calibrate_task",
           "keep_frames_in_the_heap", "open_source", "process_chunk", "quantize_heights",
           "run_batch", "worker_tools"]
