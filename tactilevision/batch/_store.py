"""Where a batch writes: one Zarr group and one Parquet table per input, resumable.

Layout for an input named ``NAME`` in the output folder ``OUT``::

    OUT/NAME.zarr/            height_mm (N, H, W) float32 [, force_n (N, rows, cols, 3),
                              pressure_kpa (N, rows, cols)], one Zarr chunk per task
    OUT/NAME.parts/part-SSSSSSSS.parquet   a task's rows, written last (the task's receipt)
    OUT/NAME.parquet          every frame's row, assembled when all parts are in

A task writes its Zarr chunk, then its part (to a temporary name, renamed into
place): a part on disk means its frames are complete; a Zarr chunk without its
part is written again on resume. ``NAME.parquet`` and the group's
``complete`` attribute are written last of all.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import numpy as np

from .._checks import InputError

__all__ = ["BLOSC_BLOCK_BYTES", "HEIGHT_DIGITS", "HEIGHT_RESOLUTION_MM", "InputStore",
           "quantize_heights"]

#: Heights are stored to this many decimal digits of a millimetre: rounded to
#: 2^-ceil(log2(10^digits)) mm (:func:`quantize_heights`, the rule of numcodecs'
#: Quantize, done here in float32: the same values, a tenth of its time), NaN kept, then
#: compressed with Blosc's Zstandard (level 1) after a bit shuffle. The array is plain
#: float32 in Zarr's own codecs. On the sample session's height maps (16 frames,
#: 640 x 480) this stores 0.272 MB a frame (0.285 before :data:`BLOSC_BLOCK_BYTES`)
#: against 1.118 MB as plain float32 with Zstandard, every height within 0.031 um of its
#: float32 (issue 54, item 3; benchmarks/bench_height_store.py prints the figures).
#: numcodecs' Quantize as a filter with Zstandard level 5 stored 0.274 MB but its
#: rounding and writing cost 8.87 ms a frame against 2.86 ms for these (32 real
#: 640 x 480 height maps a chunk, one Blosc thread, 2-core x86_64, 2026-11-26, same run).
HEIGHT_DIGITS = 4
#: Blosc's block, bytes: Zstandard then sees 4 MiB at a time (a fraction of a 640 x 480
#: chunk of 32 frames, 39 MB) instead of Blosc's default of tens of kB for level 1. On
#: 320 quantized height maps of ``benchmarks/bench_batch_speedup.py``'s video (one Blosc
#: thread, 2-core x86_64, 2026-11-27, same run): 0.311 MB and 1.24 ms a frame against
#: 0.346 MB and 2.22 ms with the default block; 1 MiB gave 0.329 MB and 1.37 ms, 8 MiB
#: 0.293 and 1.22, 16 MiB 0.283 and 1.66. A reader decompresses whole blocks, so reading
#: one frame costs at most one block more.
BLOSC_BLOCK_BYTES = 2 ** 22
#: The stored heights' resolution, mm (2^-14 mm = 0.061 um: within 0.1 um).
HEIGHT_RESOLUTION_MM = 2.0 ** -int(np.ceil(np.log2(10.0 ** HEIGHT_DIGITS)))


def quantize_heights(heights: np.ndarray, *, out: np.ndarray | None = None) -> np.ndarray:
    """Heights rounded to :data:`HEIGHT_RESOLUTION_MM`, as a batch stores them.

    Parameters
    ----------
    heights : ndarray
        Heights, mm (any shape; NaN kept).
    out : float32 ndarray, optional
        Where to write them (``heights`` itself to round in place); a new array
        by default.

    Returns
    -------
    rounded : float32 ndarray
        ``out``, or a new array: ``rint(heights / res) * res`` for the resolution res, a
        power of two, so every step is exact in float32 and the result equals
        numcodecs' ``Quantize(digits=HEIGHT_DIGITS, dtype='<f4')``; within
        res / 2 of the input.
    """
    q = np.multiply(heights, np.float32(1.0 / HEIGHT_RESOLUTION_MM), out=out,
                    dtype=np.float32)
    np.rint(q, out=q)
    q *= np.float32(HEIGHT_RESOLUTION_MM)
    return q


def _height_codecs() -> dict:
    """The height array's compressor: Zstandard after a bit shuffle (the heights are
    rounded by :func:`quantize_heights` before they are written)."""
    from zarr.codecs import BloscCodec

    return {"compressors": [BloscCodec(cname="zstd", clevel=1, shuffle="bitshuffle",
                                       blocksize=BLOSC_BLOCK_BYTES)]}


def _atomic_write_parquet(table, path: Path) -> None:
    import pyarrow.parquet as pq

    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    pq.write_table(table, tmp)
    os.replace(tmp, path)


class InputStore:
    """The Zarr group and Parquet parts of one batch input.

    Parameters
    ----------
    out : Path
        The batch's output folder.
    name : str
        The input's name (its file or folder stem, made unique).
    """

    def __init__(self, out: str | Path, name: str) -> None:
        self.out = Path(out)
        self.name = name
        self.zarr_path = self.out / f"{name}.zarr"
        self.parts = self.out / f"{name}.parts"
        self.table_path = self.out / f"{name}.parquet"

    # ------------------------------------------------------------------ client side
    def prepare(self, *, n_frames: int, shape: tuple[int, int], chunk_frames: int,
                force_shape: tuple[int, int] | None, attrs: dict, overwrite: bool) -> bool:
        """Create the group, or check one from an earlier run; True when already complete.

        Raises
        ------
        InputError
            If an earlier run wrote this input with other settings or another
            frame count (and `overwrite` is False).
        """
        import zarr

        if self.zarr_path.exists() and not overwrite:
            g = zarr.open_group(str(self.zarr_path), mode="r")
            old = dict(g.attrs)
            if old.get("settings") != attrs["settings"] or old.get("n_frames") != n_frames:
                raise InputError(f"{self.zarr_path} was written by a batch with other settings "
                                 "or frames: give --overwrite, or another --out")
            if old.get("complete") and self.table_path.is_file():
                return True
            self.parts.mkdir(parents=True, exist_ok=True)
            return False
        for p in (self.zarr_path, self.parts):
            if p.exists():
                shutil.rmtree(p)
        self.table_path.unlink(missing_ok=True)
        g = zarr.open_group(str(self.zarr_path), mode="w")
        h, w = shape
        # dimension names: xarray.open_zarr reads the group as a Dataset
        g.create_array("height_mm", shape=(n_frames, h, w), chunks=(chunk_frames, h, w),
                       dtype="float32", fill_value=np.nan, dimension_names=("frame", "y", "x"),
                       **_height_codecs())
        if force_shape is not None:
            r, c = force_shape
            g.create_array("force_n", shape=(n_frames, r, c, 3), chunks=(chunk_frames, r, c, 3),
                           dtype="float32", fill_value=np.nan,
                           dimension_names=("frame", "node_y", "node_x", "component"))
            g.create_array("pressure_kpa", shape=(n_frames, r, c),
                           chunks=(chunk_frames, r, c), dtype="float32", fill_value=np.nan,
                           dimension_names=("frame", "node_y", "node_x"))
        g.attrs.update({**attrs, "n_frames": n_frames, "complete": False,
                        "height_resolution_mm": HEIGHT_RESOLUTION_MM})
        self.parts.mkdir(parents=True, exist_ok=True)
        return False

    def done_chunks(self) -> set[int]:
        """First frames of the tasks whose part is on disk (their frames are complete)."""
        if not self.parts.is_dir():
            return set()
        return {int(p.stem.split("-")[1]) for p in self.parts.glob("part-*.parquet")}

    def finish(self, n_frames: int) -> int:
        """Assemble the parts into ``NAME.parquet`` and mark the group complete.

        Returns
        -------
        n_rows : int

        Raises
        ------
        InputError
            If the parts do not hold every frame exactly once.
        """
        import pyarrow as pa
        import pyarrow.parquet as pq
        import zarr

        parts = sorted(self.parts.glob("part-*.parquet"))
        # a column added since an interrupted run wrote its first parts is null in those
        table = pa.concat_tables([pq.read_table(p) for p in parts],
                                 promote_options="default").sort_by("frame")
        frames = table.column("frame").to_numpy()
        if frames.size != n_frames or not np.array_equal(frames, np.arange(n_frames)):
            raise InputError(f"{self.parts}: the parts hold {frames.size} rows for "
                             f"{n_frames} frames (a frame lost or written twice)")
        _atomic_write_parquet(table, self.table_path)
        g = zarr.open_group(str(self.zarr_path), mode="r+")
        g.attrs["complete"] = True
        shutil.rmtree(self.parts)
        return int(frames.size)

    # ------------------------------------------------------------------ worker side
    def write_chunk(self, start: int, arrays: dict[str, np.ndarray], rows: dict[str, list]
                    ) -> None:
        """Write a task's frames into the group, then its part (the task's receipt). The
        heights (``arrays['height_mm']``, float32) are rounded in place first."""
        import pyarrow as pa
        import zarr

        # every chunk written as it is: zarr's default first scans a chunk for one all of
        # the fill value, 0.15 to 0.25 ms a 640 x 480 frame (the whole write 1.29 to 1.86
        # against 1.50 to 2.11 ms a frame, four alternations, 2-core x86_64, 2026-11-27);
        # an array takes the setting when it is opened (it is not stored with it)
        with zarr.config.set({"array.write_empty_chunks": True}):
            g = zarr.open_group(str(self.zarr_path), mode="r+")
            targets = {key: g[key] for key in arrays}
        for key, value in arrays.items():
            if key == "height_mm":
                value = quantize_heights(value, out=value)
            targets[key][start:start + value.shape[0]] = value
        _atomic_write_parquet(pa.table(rows), self.parts / f"part-{start:08d}.parquet")


def write_json_atomic(path: Path, obj: dict) -> None:
    """Write a JSON file through a temporary name (a reader never sees half of it)."""
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(json.dumps(obj, indent=2, default=str))
    os.replace(tmp, path)
