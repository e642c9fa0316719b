"""Batch processing on a real local Dask cluster (worker processes): the results equal
the single-process ones frame for frame, a broken input is listed and the rest goes on,
a killed worker loses and duplicates no frame, and an interrupted batch resumes."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import threading
import types
from pathlib import Path

import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.cli import main

pytest.importorskip("distributed")
pytest.importorskip("zarr")
pytest.importorskip("pyarrow")

import cv2
import pyarrow.parquet as pq
import zarr
from _data import decoded, quarter_gelsight, write_video
from distributed import Client, LocalCluster

from tactilevision.batch import (
    HEIGHT_RESOLUTION_MM,
    BatchSettings,
    open_source,
    quantize_heights,
    run_batch,
)
from tactilevision.batch._run import _start_method
from tactilevision.io import VideoFrames, read_reference
from tactilevision.optics import DepthReconstructor, PhotometricCalibration

#: The stored heights' error bound: half their resolution (and a float32 rounding).
STORED = HEIGHT_RESOLUTION_MM / 2 + 1e-6

BALL = Path(__file__).resolve().parents[1] / "sample_frames" / "gelsight_ball"
N_VIDEO = 24
#: frames a quarter of GelSight's size (160 x 120), so that a test's frames cost little
SIZE = (160, 120)


@pytest.fixture(scope="module")
def small(tmp_path_factory) -> Path:
    """The real GelSight presses at a quarter size: a frame folder (its reference in the
    parent) and a LUT calibration fitted to them (cheap to build in every worker)."""
    root = tmp_path_factory.mktemp("small")
    (root / "frames").mkdir()
    ref, presses, cal = quarter_gelsight(SIZE)
    cv2.imwrite(str(root / "reference.png"), ref)
    for p, img in zip(sorted((BALL / "frames").glob("press_*.png")), presses, strict=True):
        cv2.imwrite(str(root / "frames" / p.name), img)
    cal.save(root / "optics.npz")
    return root


@pytest.fixture(scope="module")
def clip(small) -> Path:
    """A 24-frame MJPG video of the presses, shifted a pixel each frame, with its reference
    beside it (``clip_reference.png``)."""
    ref = cv2.imread(str(small / "reference.png"))
    presses = [cv2.imread(str(p)) for p in sorted((small / "frames").glob("press_*.png"))]
    frames = [ref] + [np.roll(presses[i % 4], i, axis=1) for i in range(1, N_VIDEO)]
    path = small / "clip.avi"
    write_video(path, frames, "MJPG")
    cv2.imwrite(str(small / "clip_reference.png"), ref)
    return path


@pytest.fixture(scope="module")
def client():
    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                           dashboard_address=":0")
    c = Client(cluster)
    yield c
    c.close()
    cluster.close()


def _settings(clip: Path, **kw) -> BatchSettings:
    return BatchSettings(kind=kw.pop("kind", "reconstruct"),
                         calibration=str(clip.parent / "optics.npz"),
                         chunk_frames=kw.pop("chunk_frames", 4), **kw)


def _single_process(clip: Path, frames: np.ndarray, reference: np.ndarray) -> np.ndarray:
    recon = DepthReconstructor(PhotometricCalibration.load(clip.parent / "optics.npz"),
                               reference=reference)
    return np.stack([recon(f) for f in frames]).astype(np.float32)


def _expected(clip: Path) -> np.ndarray:
    return _single_process(clip, decoded(clip),
                           cv2.imread(str(clip.with_name("clip_reference.png"))))


# ---------------------------------------------------------------- video reading


@pytest.mark.parametrize(("suffix", "fourcc"), [(".avi", "MJPG"), (".mp4", "mp4v")])
def test_video_chunks_equal_the_sequential_pass(tmp_path, suffix, fourcc):
    rng = np.random.default_rng(0)
    frames = [rng.integers(0, 255, (48, 64, 3), dtype=np.uint8) for _ in range(40)]
    path = tmp_path / f"v{suffix}"
    write_video(path, frames, fourcc)
    v = VideoFrames(path)
    assert v.n_frames == 40 and v.shape == (48, 64) and v.fps == pytest.approx(90.0)
    seq = decoded(path)
    for start, stop in ((0, 7), (13, 29), (33, 40)):
        np.testing.assert_array_equal(v.read(start, stop), seq[start:stop])
    with pytest.raises(InputError, match="lie outside"):
        v.read(35, 41)


def test_bad_videos_are_named(tmp_path):
    junk = tmp_path / "junk.mp4"
    junk.write_bytes(b"not a video at all")
    with pytest.raises(InputError, match=r"junk\.mp4"):
        VideoFrames(junk)
    with pytest.raises(InputError, match="no such video"):
        VideoFrames(tmp_path / "missing.avi")
    (tmp_path / "notes.txt").write_text("x")
    with pytest.raises(InputError, match="not a video file"):
        open_source(tmp_path / "notes.txt")


# ---------------------------------------------------------------- the cluster


@pytest.mark.slow
def test_batch_equals_the_single_process_run_frame_for_frame(client, clip, tmp_path):
    out = tmp_path / "out"
    broken = tmp_path / "broken.mp4"
    broken.write_bytes(b"\x00" * 100)
    rep = run_batch("reconstruct", [clip.parent / "frames", clip, broken], out,
                    settings=_settings(clip), client=client, progress=False)
    status = {Path(o.input).name: o for o in rep.inputs}
    assert status["broken.mp4"].status == "failed" and "broken.mp4" in status["broken.mp4"].error
    assert status["frames"].status == "done" and status["clip.avi"].status == "done"
    # the video: every frame, against a sequential decode reconstructed in this process
    expected = _expected(clip)
    got = zarr.open_group(str(out / "clip.zarr"), mode="r")["height_mm"][:]
    assert got.shape == (N_VIDEO, SIZE[1], SIZE[0]) and got.dtype == np.float32
    # stored to HEIGHT_RESOLUTION_MM (0.061 um): every height within half of it
    np.testing.assert_allclose(got, expected, atol=STORED)
    table = pq.read_table(out / "clip.parquet").to_pydict()
    assert table["frame"] == list(range(N_VIDEO))
    np.testing.assert_allclose(table["max_depth_mm"], expected.max(axis=(1, 2)), atol=1e-6)
    np.testing.assert_allclose(table["t_s"], np.arange(N_VIDEO) / 90.0)
    # frame 0 is the reference itself (JPEG-compressed in the video): shallower than any press
    assert table["max_depth_mm"][0] < 0.5 * min(table["max_depth_mm"][1:])
    # the contact area and the pixels out of the calibration's range, as reconstruct's
    # heights.csv has them: from the reconstructor's own masks on the sequential decode
    recon = DepthReconstructor(PhotometricCalibration.load(clip.parent / "optics.npz"),
                               reference=cv2.imread(str(clip.with_name("clip_reference.png"))))
    cal = recon.calibration
    want_area = [float(recon.contact_mask(f).sum()) * cal.mm_per_px ** 2 for f in decoded(clip)]
    want_out = [int(recon.out_of_range(f).sum()) for f in decoded(clip)]
    np.testing.assert_allclose(table["contact_area_mm2"], want_area, rtol=1e-12)
    assert table["out_of_range_px"] == want_out and max(want_out) > 0
    # the folder: its reference found in the parent, frame names kept
    ref = read_reference(clip.parent / "reference.png")
    frames = np.stack([cv2.imread(str(p)) for p in
                       sorted((clip.parent / "frames").glob("*.png"))])
    np.testing.assert_allclose(
        zarr.open_group(str(out / "frames.zarr"), mode="r")["height_mm"][:],
        _single_process(clip, frames, ref), atol=STORED)
    assert pq.read_table(out / "frames.parquet").column("source_frame").to_pylist() == [
        "press_01.png", "press_09.png", "press_25.png", "press_41.png"]
    # each worker process built its reconstructor once per input (reference), whatever the
    # number of chunks
    built = [(r["pid"], r["input"]) for r in rep.receipts if r["built"]]
    assert len(built) == len(set(built)) <= 4 and len(rep.receipts) == 1 + N_VIDEO // 4
    saved = json.loads((out / "batch.json").read_text())
    assert [i["status"] for i in saved["inputs"]] == ["done", "done", "failed"]


def test_a_bad_frame_fails_its_input_only_and_is_named(client, clip, tmp_path):
    bad = tmp_path / "bad"
    shutil.copytree(clip.parent / "frames", bad)
    (bad / "press_25.png").write_bytes(b"\x89PNG\r\n\x1a\n truncated")
    rep = run_batch("reconstruct", [bad, clip], tmp_path / "out",
                    settings=_settings(clip, chunk_frames=1), client=client, progress=False)
    st = {Path(o.input).name: o for o in rep.inputs}
    assert st["bad"].status == "failed" and "press_25.png" in st["bad"].error
    assert st["clip.avi"].status == "done"
    assert not (tmp_path / "out" / "bad.parquet").exists()


def test_interrupted_batch_resumes_without_redoing_done_chunks(client, clip, tmp_path):
    out = tmp_path / "out"
    seen = []

    def stop_after_two(receipt):
        seen.append(receipt)
        if len(seen) == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_batch("reconstruct", [clip], out, settings=_settings(clip), client=client,
                  progress=False, on_receipt=stop_after_two)
    assert not (out / "clip.parquet").exists()          # not taken as done
    parts = sorted((out / "clip.parts").glob("part-*.parquet"))
    assert len(parts) >= 2
    (out / "clip.parts" / ".part-00000020.parquet.99.tmp").write_bytes(b"half")  # a torn write
    rep = run_batch("reconstruct", [clip], out, settings=_settings(clip), client=client,
                    progress=False)
    o = rep.inputs[0]
    assert o.status == "done" and o.chunks_skipped >= 2
    assert o.chunks_skipped + o.chunks_run == N_VIDEO // 4
    expected = _expected(clip)
    np.testing.assert_allclose(zarr.open_group(str(out / "clip.zarr"), mode="r")
                               ["height_mm"][:], expected, atol=STORED)
    assert pq.read_table(out / "clip.parquet").column("frame").to_pylist() == list(
        range(N_VIDEO))
    # a third run has nothing left to do; other settings are refused, not mixed in
    again = run_batch("reconstruct", [clip], out, settings=_settings(clip), client=client,
                      progress=False)
    assert again.inputs[0].status == "already complete" and not again.receipts
    other = run_batch("reconstruct", [clip], out, settings=_settings(clip, level="far_field"),
                      client=client, progress=False)
    assert other.inputs[0].status == "failed" and "other settings" in other.inputs[0].error


def test_a_killed_worker_loses_and_duplicates_no_frame(client, clip, tmp_path):
    out = tmp_path / "out"
    pids = client.run(os.getpid)
    victim = {"pid": None}

    def kill_one(receipt):
        if victim["pid"] is None:
            victim["pid"] = next(p for p in pids.values() if p != receipt["pid"])
            os.kill(victim["pid"], signal.SIGKILL)

    rep = run_batch("reconstruct", [clip], out, settings=_settings(clip, chunk_frames=2),
                    client=client, progress=False, on_receipt=kill_one)
    assert victim["pid"] is not None
    assert rep.inputs[0].status == "done", rep.inputs[0].error
    starts = sorted(r["start"] for r in rep.receipts)
    assert starts == list(range(0, N_VIDEO, 2))           # each chunk once
    frames = pq.read_table(out / "clip.parquet").column("frame").to_pylist()
    assert frames == list(range(N_VIDEO))
    expected = _expected(clip)
    np.testing.assert_allclose(zarr.open_group(str(out / "clip.zarr"), mode="r")
                               ["height_mm"][:], expected, atol=STORED)
    client.wait_for_workers(2, timeout=60)                # the nanny restarts it


@pytest.mark.slow
def test_cli_batch_forces_on_a_running_scheduler(client, clip, tmp_path, capsys):
    from tactilevision.fem import ForceEstimator

    out = tmp_path / "forces"
    optics = clip.parent / "optics.npz"
    argv = ["batch", "forces", str(clip), "--out", str(out), "--calibration", str(optics),
            "--E-mpa", "0.2", "--nu", "0.48", "--thickness-mm", "3", "--chunk-frames", "8",
            "--scheduler", client.scheduler.address, "--no-progress",
            "--json", "-"]
    assert main(argv) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["inputs"][0]["status"] == "done" and d["frames_run"] == N_VIDEO
    g = zarr.open_group(str(out / "clip.zarr"), mode="r")
    assert g["force_n"].shape == (N_VIDEO, SIZE[1], SIZE[0], 3)
    # frame 5 against the estimator in this process (forces' defaults: level 'contact',
    # traction on the footprint above 0.02 mm, beta 0)
    cal = PhotometricCalibration.load(optics)
    ref = cv2.imread(str(clip.with_name("clip_reference.png")))
    recon = DepthReconstructor(cal, reference=ref, boundary="contact", level="median")
    est = ForceEstimator(cal.shape, cal.mm_per_px, thickness_mm=3.0, E_mpa=0.2, nu=0.48,
                         contact="footprint", threshold_mm=0.02, beta=0.0)
    # frames 0 to 5 in order, as the batch's first chunk runs them: each solve starts from
    # the frame before it (the height's and the traction's warm starts)
    for frame in decoded(clip)[:6]:
        fm = est(recon(frame))
    table = pq.read_table(out / "clip.parquet").to_pydict()
    assert table["fz_n"][5] == pytest.approx(float(fm.total_n[2]), rel=1e-5)
    np.testing.assert_allclose(g["pressure_kpa"][5], fm.pressure_kpa, rtol=1e-5, atol=1e-6)
    assert table["fz_n"][5] > 0.05 and abs(table["fz_n"][0]) < 0.2 * table["fz_n"][5]


def test_cli_batch_bad_options(tmp_path, capsys, clip):
    assert main(["batch", "forces", str(clip), "--out", str(tmp_path / "o"), "--calibration",
                 str(clip.parent / "optics.npz"), "--E-mpa", "0.2", "--nu", "0.48"]) == 2
    assert "--thickness-mm" in capsys.readouterr().err
    assert main(["batch", "reconstruct", str(clip), "--out", str(tmp_path / "o")]) == 2
    assert "--calibration OPTICS or --sensor" in capsys.readouterr().err
    (tmp_path / "file").write_text("x")
    assert main(["batch", "reconstruct", str(clip), "--out", str(tmp_path / "file"),
                 "--sensor", "gelsight"]) == 2
    assert "not a folder" in capsys.readouterr().err


@pytest.mark.slow
def test_batch_calibrate_lists_a_broken_session_and_calibrates_the_others(client, tmp_path):
    from tactilevision.sim import SessionSpec, make_session, press_profile

    pytest.importorskip("taxim")
    prof = press_profile(2.5 / 3, 0.47, w_over_h_max=0.22, steps=8, cell=0.5,
                         edge_refinements=5)
    good = tmp_path / "day1"
    spec = SessionSpec(E_mpa=0.15, nu=0.47, repeats=2, clock_offset_s=0.05, seed=11,
                       wait_s=(0.5, 0.8))              # short rests: fewer frames
    truth = make_session(good, spec, profile=prof)
    broken = tmp_path / "day2"
    broken.mkdir()
    out = tmp_path / "cal"
    rep = run_batch("calibrate", [good, broken], out, client=client, progress=False)
    st = {Path(o.input).name: o for o in rep.inputs}
    assert st["day2"].status == "failed" and "session.toml" in st["day2"].error
    assert st["day1"].status == "done"
    fit = json.loads((out / "day1" / "fit.json").read_text())
    assert abs(fit["E_mpa"] / truth["E_mpa"] - 1) < 0.15
    again = run_batch("calibrate", [good], out, client=client, progress=False)
    assert again.inputs[0].status == "already complete"


@pytest.mark.slow
def test_cli_batch_starts_its_own_local_cluster(clip, tmp_path, capsys):
    """No --scheduler: a local cluster of worker processes, started and closed by the
    command; the printed summary and batch.json agree."""
    out = tmp_path / "own"
    argv = ["batch", "reconstruct", str(clip), str(clip.parent / "frames"), "--out", str(out),
            "--calibration", str(clip.parent / "optics.npz"), "--workers", "1",
            "--no-progress"]
    assert main(argv) == 0
    printed = capsys.readouterr().out
    assert "2 of 2 input(s) complete" in printed and "on 1 worker(s)" in printed
    saved = json.loads((out / "batch.json").read_text())
    assert saved["workers"] == 1 and saved["frames_run"] == N_VIDEO + 4
    np.testing.assert_allclose(zarr.open_group(str(out / "clip.zarr"), mode="r")
                               ["height_mm"][:], _expected(clip), atol=STORED)


def test_heights_are_rounded_as_numcodecs_quantize_rounds_them():
    """quantize_heights gives numcodecs' Quantize(digits=4) values exactly (float32, NaN
    kept), each within half the stated resolution of its input."""
    from numcodecs import Quantize

    from tactilevision.batch import HEIGHT_DIGITS, HEIGHT_RESOLUTION_MM, quantize_heights

    rng = np.random.default_rng(4)
    h = (rng.normal(0.0, 0.3, (3, 40, 50)) * rng.random((3, 40, 50))).astype(np.float32)
    h[0, 0, :5] = np.nan
    got = quantize_heights(h)
    want = Quantize(digits=HEIGHT_DIGITS, dtype="<f4").encode(h)
    assert got.dtype == np.float32 and got is not h
    np.testing.assert_array_equal(got, want)
    assert np.nanmax(np.abs(got - h)) <= HEIGHT_RESOLUTION_MM / 2
    assert np.all(np.isnan(got[0, 0, :5]))


@pytest.mark.slow
def test_own_cluster_workers_keep_frames_in_the_heap_and_zarr_codecs(clip, tmp_path):
    """run_batch's own cluster starts its workers without Dask's MALLOC_TRIM_THRESHOLD_
    (which made a height map 3 times dearer in a worker: checked in a fresh process, as
    a Nanny leaves the variable in the process that ran it), a worker's tools raise
    glibc's thresholds whatever its cluster, and the heights are stored as plain float32
    under Zarr's own Blosc codec: no numcodecs filter, read without a warning."""
    import subprocess
    import sys
    import warnings

    from tactilevision.batch import keep_frames_in_the_heap

    code = ("import os\n"
            "from tactilevision.batch._run import _client, _close\n"
            "if __name__ == '__main__':\n"
            "    c, cl = _client(None, 1)\n"
            "    print(list(c.run(lambda: os.environ.get('MALLOC_TRIM_THRESHOLD_')).values()))\n"
            "    _close(c, cl)\n")
    env = {k: v for k, v in os.environ.items() if k != "MALLOC_TRIM_THRESHOLD_"}
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=env, timeout=120)
    assert run.returncode == 0, run.stderr[-2000:]
    assert run.stdout.strip().splitlines()[-1] == "[None]"
    if sys.platform == "linux":
        assert keep_frames_in_the_heap()
    out = tmp_path / "codecs"
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                      dashboard_address=":0") as local, Client(local) as c:
        run_batch("reconstruct", [clip], out, settings=_settings(clip), client=c,
                  progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        arr = zarr.open_group(str(out / "clip.zarr"), mode="r")["height_mm"]
        assert arr.metadata.codecs[-1].to_dict()["name"] == "blosc"
        assert len(arr.metadata.codecs) == 2          # bytes, then blosc: no filter
        heights = arr[:]
    np.testing.assert_allclose(heights, _expected(clip), atol=STORED)


@pytest.mark.skipif(sys.platform != "linux", reason="workers are forked on Linux only")
def test_own_cluster_forks_its_workers_safely_from_a_process_that_used_opencv(tmp_path):
    """On Linux run_batch's own cluster forks its workers (they start with the batch stack
    imported: no import on the critical path). A fork from a process whose OpenCV pool
    has threads hung or crashed the child at its first cv2.setNumThreads; the guard shuts
    the pool for the instant of the fork: the worker blurs with one thread and is the
    same process after (not restarted), and this process gets its thread count back."""
    code = ("import os, sys, cv2, numpy as np\n"
            "from tactilevision.batch._run import _client, _close\n"
            "def work():\n"
            "    cv2.setNumThreads(1)\n"
            "    cv2.GaussianBlur(np.ones((600, 600), np.float32), (31, 31), 5)\n"
            "    return os.getpid(), 'tactilevision.batch._tasks' in sys.modules\n"
            "if __name__ == '__main__':\n"
            "    cv2.setNumThreads(2)\n"
            "    for _ in range(3):\n"
            "        cv2.GaussianBlur(np.ones((2000, 2000), np.float32), (31, 31), 5)\n"
            "    c, cl = _client(None, 1)\n"
            "    first = c.submit(work, pure=False).result(timeout=60)\n"
            "    again = c.submit(work, pure=False).result(timeout=60)\n"
            "    print(first[0] == again[0], first[1], cv2.getNumThreads())\n"
            "    _close(c, cl)\n")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120, cwd=tmp_path)
    assert run.returncode == 0, run.stderr[-2000:]
    assert "Fatal Python error" not in run.stderr
    assert run.stdout.strip().splitlines()[-1] == "True True 2"


def test_a_threaded_parent_spawns_its_workers(monkeypatch):
    """Workers are forked only from a process with one Python thread and no runtime that
    keeps threads of its own (JAX warns that a fork from it will likely deadlock): with
    another thread alive, or such a module imported, they are spawned."""
    stop = threading.Event()
    t = threading.Thread(target=stop.wait, daemon=True)
    t.start()
    try:
        assert _start_method() == "spawn"
    finally:
        stop.set()
        t.join()
    monkeypatch.setitem(sys.modules, "jax", types.ModuleType("jax"))
    assert _start_method() == "spawn"


def test_every_chunk_is_written_without_a_scan_for_the_fill_value(tmp_path):
    """A task's chunk is written as it is (zarr's default would first scan it for one all of
    the fill value, and skip it): a chunk of NaN heights lands on disk, and reads back."""
    from tactilevision.batch._store import InputStore

    store = InputStore(tmp_path, "x")
    store.prepare(n_frames=4, shape=(6, 8), chunk_frames=2, force_shape=None,
                  attrs={"settings": {}}, overwrite=False)
    nan = np.full((2, 6, 8), np.nan, np.float32)
    store.write_chunk(2, {"height_mm": nan}, {"frame": [2, 3]})
    chunks = sorted(p.relative_to(store.zarr_path).as_posix()
                    for p in (store.zarr_path / "height_mm").rglob("*") if p.is_file()
                    and p.name != "zarr.json")
    assert chunks == ["height_mm/c/1/0/0"]
    assert np.isnan(zarr.open_group(str(store.zarr_path), mode="r")["height_mm"][2:]).all()


def test_a_worker_thread_reuses_its_chunk_buffer_and_rounds_it_in_place():
    """A task's heights go into its thread's buffer, the same array for the next task of
    that size and another thread's own; rounding in place gives what a new array gets."""
    import threading

    from tactilevision.batch._tasks import _chunk_buffer

    a = _chunk_buffer(4, (6, 8))
    assert _chunk_buffer(4, (6, 8)) is a and a.shape == (4, 6, 8) and a.dtype == np.float32
    other = []
    t = threading.Thread(target=lambda: other.append(_chunk_buffer(4, (6, 8))))
    t.start()
    t.join()
    assert other[0] is not a
    assert _chunk_buffer(3, (6, 8)).shape == (3, 6, 8)          # the short last chunk
    h = np.random.default_rng(0).normal(0, 0.3, (4, 6, 8)).astype(np.float32)
    h[0, 0, 0] = np.nan
    want = quantize_heights(h)
    got = quantize_heights(h, out=h)
    assert got is h
    np.testing.assert_array_equal(got, want)


def test_an_interrupt_while_the_cluster_starts_leaves_no_empty_folder(tmp_path, monkeypatch):
    """Ctrl-C while the local cluster starts (its first 1 to 2 s): the folders the call made
    for --out go again; a folder that was there stays, as do its files."""
    import tactilevision.batch._run as run_mod

    def interrupted(*_a, **_k):
        raise KeyboardInterrupt

    monkeypatch.setattr(run_mod, "_client", interrupted)
    settings = BatchSettings(kind="reconstruct", calibration=str(tmp_path / "none.npz"))
    out = tmp_path / "new" / "out"
    with pytest.raises(KeyboardInterrupt):
        run_batch("reconstruct", [tmp_path], out, settings=settings)
    assert not (tmp_path / "new").exists()
    kept = tmp_path / "kept"
    kept.mkdir()
    with pytest.raises(KeyboardInterrupt):
        run_batch("reconstruct", [tmp_path], kept, settings=settings)
    assert kept.is_dir()
    with pytest.raises(InputError, match="no inputs"):
        run_batch("reconstruct", [], tmp_path / "none", settings=settings)
    assert not (tmp_path / "none").exists()
