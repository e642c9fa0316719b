"""The first-order table lookup compiled by numba (``first_order_kernel``, the ``fast``
extra) against the OpenCV and numpy path and against the plane's definition."""

from __future__ import annotations

import sys

import cv2
import numpy as np
import pytest
from _data import GELSIGHT_MINI, GELSIGHT_MINI_MM_PER_PX, GELSIGHT_MINI_REASON

from tactilevision import InputError, default_calibration_path
from tactilevision.optics import (
    KERNELS,
    DepthReconstructor,
    PhotometricCalibration,
    first_order_kernel,
)
from tactilevision.optics import _reconstructor as rec
from tactilevision.optics import _table_kernel as tk
from tactilevision.optics._table import GradientTable, _read_only

NUMBA = "numba is not installed (the fast extra): the compiled kernel cannot run"


def _has_numba() -> bool:
    try:
        import numba  # noqa: F401
    except ImportError:
        return False
    return True


def _table(seed: int, *, bins: int = 5, cells: int = 4, shape=(40, 52)) -> GradientTable:
    rng = np.random.default_rng(seed)
    n = cells * bins ** 3
    slopes = rng.normal(0, 1, (n, 8)).astype(np.float32)
    offset = (rng.integers(0, cells, shape) * bins ** 3).astype(np.int32)
    ref_inv = (1.0 / rng.uniform(90, 160, (*shape, 3))).astype(np.float32)
    lo, hi = np.full(3, -0.6, np.float32), np.full(3, 0.5, np.float32)
    table = GradientTable(np.zeros(n, np.float32), np.zeros(n, np.float32), offset, bins,
                          lo, hi, ref_inv, slopes=slopes)
    for a in (table.cell_offset, slopes):
        a.setflags(write=False)         # as the reconstructor's shared tables are
    return table


@pytest.mark.skipif(not _has_numba(), reason=NUMBA)
@pytest.mark.parametrize("gain", [False, True])
def test_the_compiled_lookup_reads_each_pixels_plane(gain):
    """Each pixel reads its row's plane at its colour coordinates, computed here in
    float64 from the definition (frame / reference / gain - 1 - lo, times B / (hi - lo),
    clipped to the cells); and the compiled pass equals the OpenCV path."""
    table = _table(5)
    rng = np.random.default_rng(6)
    frame = rng.integers(0, 256, (*table.cell_offset.shape, 3)).astype(np.uint8)
    gx, gy = table.gradients(frame, normalise_gain=gain, kernel="numba")
    assert gx.dtype == gy.dtype == np.float32 and gx.shape == frame.shape[:2]
    ratio = frame * table.ref_inv.astype(np.float64)
    g = np.median(ratio[::8, ::8].reshape(-1, 3), axis=0) if gain else np.ones(3)
    b = table.bins
    u = np.clip((ratio / g - 1 - table.lo) * b / (table.hi - table.lo), 0, b - 1e-3)
    assert 0.05 < np.mean(u == 0) + np.mean(u >= b - 1e-3) < 0.9   # both clips are used
    q = np.floor(u).astype(int)
    row = table.slopes[(q[..., 0] * b + q[..., 1]) * b + q[..., 2] + table.cell_offset]
    near = np.abs(u - np.round(u)).min(-1) > 1e-4       # not on a cell's boundary
    np.testing.assert_allclose(gx[near], (row[..., 0] + (row[..., 2::2] * u).sum(-1))[near],
                               atol=2e-4)
    np.testing.assert_allclose(gy[near], (row[..., 1] + (row[..., 3::2] * u).sum(-1))[near],
                               atol=2e-4)
    ox, oy = table.gradients(frame, normalise_gain=gain, kernel="numpy")
    assert np.mean(gx == ox) > 0.999 and np.mean(gy == oy) > 0.999
    np.testing.assert_allclose(gx, ox, atol=1e-5)


@pytest.mark.skipif(not _has_numba(), reason=NUMBA)
def test_the_compiled_lookup_equals_the_opencv_path_on_gs_sdks_network():
    """On the real GelSight Mini presses, gs_sdk's network in the default engine (a
    first-order table): heights from both kernels agree to float32 rounding."""
    pytest.importorskip("torch", reason="gs_sdk models are torch state dicts")
    if not (GELSIGHT_MINI / "gs_sdk_reference.npz").is_file():
        pytest.skip(GELSIGHT_MINI_REASON)
    ref = np.load(GELSIGHT_MINI / "gs_sdk_reference.npz")
    cal = PhotometricCalibration.from_gs_sdk(
        GELSIGHT_MINI / "model" / "nnmodel.pth", cv2.imread(str(GELSIGHT_MINI / "background.png")),
        mm_per_px=GELSIGHT_MINI_MM_PER_PX)
    fast, slow = (DepthReconstructor(cal, kernel=k) for k in ("numba", "numpy"))
    assert fast._table.order == 1
    for name in ref["presses"][:3]:
        frame = cv2.imread(str(GELSIGHT_MINI / str(name) / "gelsight.png"))
        a, b = fast.gradients(frame), slow.gradients(frame)
        assert np.mean(a[0] == b[0]) > 0.999 and np.mean(a[1] == b[1]) > 0.999
        za, zb = fast(frame), slow(frame)
        assert np.abs(za - zb).max() <= 1e-3 * np.abs(zb).max()


def test_an_unknown_kernel_is_refused_by_name():
    table = _table(1)
    frame = np.full((*table.cell_offset.shape, 3), 128, np.uint8)
    with pytest.raises(InputError, match="kernel must be one of auto, numba, numpy, got 'jit'"):
        table.gradients(frame, kernel="jit")
    with pytest.raises(InputError, match="kernel must be one of"):
        first_order_kernel("fast")
    assert KERNELS == ("auto", "numba", "numpy")
    assert first_order_kernel("numpy") is None


def test_without_numba_auto_falls_back_and_numba_names_the_extra(monkeypatch):
    """numba absent: 'auto' reads by OpenCV and numpy, 'numba' is refused naming the
    extra to install; the OpenCV path gives the same gradients as before."""
    monkeypatch.setattr(tk, "_COMPILED", {})
    monkeypatch.setitem(sys.modules, "numba", None)      # import numba -> ImportError
    assert first_order_kernel("auto") is None
    with pytest.raises(InputError, match=r"tactilevision\[fast\]"):
        first_order_kernel("numba")
    table = _table(2)
    frame = np.random.default_rng(0).integers(0, 256, (*table.cell_offset.shape, 3),
                                              dtype=np.uint8)
    a = table.gradients(frame, kernel="auto")
    b = table.gradients(frame, kernel="numpy")
    np.testing.assert_array_equal(a[0], b[0])
    with pytest.raises(InputError, match="needs numba"):
        table.gradients(frame, kernel="numba")


def test_a_table_of_order_0_never_loads_numba(monkeypatch):
    """An order-0 table is one gather: its frames neither import nor compile numba (the
    shipped GelSight network's table, read with the default kernel='auto'), and 'numba'
    without numba is not refused there."""
    t1 = _table(3)
    table = GradientTable(t1.gx_table, t1.gy_table, t1.cell_offset, t1.bins, t1.lo, t1.hi,
                          np.full((*t1.cell_offset.shape, 3), 1 / 128, np.float32))
    assert table.order == 0
    frame = np.random.default_rng(1).integers(0, 256, (*table.cell_offset.shape, 3),
                                              dtype=np.uint8)
    monkeypatch.setattr(tk, "_COMPILED", {})
    want = table.gradients(frame, kernel="numpy")
    for k in ("auto", "numba"):
        got = table.gradients(frame, kernel=k)
        np.testing.assert_array_equal(got[0], want[0])
    assert tk._COMPILED == {}                 # nothing imported, nothing compiled
    monkeypatch.setitem(sys.modules, "numba", None)
    np.testing.assert_array_equal(table.gradients(frame, kernel="numba")[1], want[1])
    with pytest.raises(InputError, match="kernel must be one of"):
        table.gradients(frame, kernel="jit")


@pytest.mark.skipif(not _has_numba(), reason=NUMBA)
def test_a_kernel_with_no_cache_folder_is_compiled_without_one():
    """numba refuses ``cache=True`` where it can write no cache folder (a read-only
    install, no user cache): the kernel is then compiled without it, not refused."""
    import numba

    tried = []

    class NoLocator:
        types = numba.types

        @staticmethod
        def njit(signature, *, cache=False, **options):
            tried.append(cache)
            if cache:
                raise RuntimeError("cannot cache function '_lookup': no locator available "
                                   "for file '_table_kernel.py'")
            return numba.njit(signature, **options)

    kernel = tk._compile(NoLocator)
    assert tried == [True, False]
    table = _table(4)
    frame = np.random.default_rng(1).integers(0, 256, (*table.cell_offset.shape, 3),
                                              dtype=np.uint8)
    gx = np.empty(frame.shape[:2], np.float32)
    gy = np.empty_like(gx)
    coef = np.concatenate([np.ones(3, np.float32), table._offset]).astype(np.float32)
    kernel(*(_read_only(a) for a in (frame, table._scale_map, coef)), np.float32(table._top),
           table.bins, *table._kernel_in[1:], gx, gy)
    want = table.gradients(frame, normalise_gain=False, kernel="numpy")
    assert np.mean(gx == want[0]) > 0.999 and np.mean(gy == want[1]) > 0.999



def test_a_frame_not_of_uint8_is_read_by_the_opencv_path():
    """The compiled pass reads uint8 frames; a float frame (an already blurred or
    averaged one) is read by OpenCV and numpy whatever the kernel."""
    table = _table(7)
    frame = np.random.default_rng(2).uniform(0, 255, (*table.cell_offset.shape, 3))
    frame = frame.astype(np.float32)
    a = table.gradients(frame, kernel="auto")
    b = table.gradients(frame, kernel="numpy")
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])


def test_the_reconstructor_checks_its_kernel_and_needs_numba_only_for_first_order(
        monkeypatch):
    """An unknown kernel is refused by name before anything is built; without numba,
    'numba' is refused only where a first-order table would use it (the shipped GelSight
    network's table is of order 0, one gather either way)."""
    cal = PhotometricCalibration.load(default_calibration_path("gelsight"))
    real = rec._tabulated
    with pytest.raises(InputError, match="kernel must be one of auto, numba, numpy"):
        DepthReconstructor(cal, kernel="cuda")
    monkeypatch.setattr(tk, "_COMPILED", {})
    monkeypatch.setitem(sys.modules, "numba", None)
    tabulate = []
    monkeypatch.setattr(rec, "_tabulated", lambda *a: tabulate.append(a) or real(*a))
    recon = DepthReconstructor(cal, kernel="numba")
    assert recon._table.order == 0 and recon.kernel == "numba"
    with pytest.raises(InputError, match=r"tactilevision\[fast\]"):
        DepthReconstructor(cal, kernel="numba", table_order=1)
    assert len(tabulate) == 1          # refused before the first-order table was built
