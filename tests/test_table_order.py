"""Gradient tables of first order: a value and its slopes along the colour axes per
colour cell, read as the plane through them (GradientTable.slopes, tabulate_mlp(order=1),
PhotometricCalibration.table_order)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from _data import ROOT

from tactilevision import InputError, default_calibration_path
from tactilevision.optics import (
    DepthReconstructor,
    MLPGradientModel,
    PhotometricCalibration,
    cell_position_inputs,
    mlp_inputs,
)
from tactilevision.optics import _reconstructor as rec
from tactilevision.optics._ball import gradients_from_normals
from tactilevision.optics._features import channel_medians
from tactilevision.optics._table import GradientTable, _cell_slopes

FRAME = ROOT / "sample_frames" / "gelsight_ball" / "frames" / "press_01.png"


def test_first_order_table_reads_the_plane_through_each_cell():
    """Each pixel reads its row's plane, its value at the colour origin plus the slopes
    times the pixel's colour coordinates, computed here from the definition in numpy."""
    rng = np.random.default_rng(3)
    bins, cells, shape = 4, 3, (12, 16)
    n = cells * bins ** 3
    slopes = rng.normal(0, 1, (n, 8)).astype(np.float32)
    offset = (rng.integers(0, cells, shape) * bins ** 3).astype(np.int32)
    ref_inv = np.full((*shape, 3), 1 / 128, np.float32)
    lo, hi = np.full(3, -0.5, np.float32), np.full(3, 0.5, np.float32)
    table = GradientTable(np.zeros(n, np.float16), np.zeros(n, np.float16), offset, bins,
                          lo, hi, ref_inv, slopes=slopes)
    assert table.order == 1
    frame = rng.integers(40, 220, (*shape, 3)).astype(np.uint8)
    gx, gy = table.gradients(frame, normalise_gain=False)
    u = np.clip((frame / 128.0 - 1 + 0.5) * bins, 0, bins - 1e-3)
    q = np.floor(u).astype(int)
    row = slopes[(q[..., 0] * bins + q[..., 1]) * bins + q[..., 2] + offset]
    want_x = row[..., 0] + (row[..., 2::2] * u).sum(-1)
    want_y = row[..., 1] + (row[..., 3::2] * u).sum(-1)
    assert gx.dtype == np.float32
    np.testing.assert_allclose(gx, want_x, atol=1e-4)
    np.testing.assert_allclose(gy, want_y, atol=1e-4)


def _network_at_exact_colour(cal, recon, frame, cell_px):
    """The network at each pixel's own colour change, fed its position cell (what a table
    approximates, up to the colour cells alone)."""
    ref_inv = recon._ref_inv
    ratio = frame.astype(np.float32) * ref_inv
    gain = np.median(ratio[::8, ::8].reshape(-1, 3), axis=0)
    change = (ratio / gain - 1.0).reshape(-1, 3)
    ref_cell, x_cell, y_cell = cell_position_inputs(1.0 / ref_inv, cell_px)
    nxy = MLPGradientModel(cal.onnx_bytes).normals(mlp_inputs(
        change.astype(np.float32), ref_cell.reshape(-1, 3), x_cell.ravel(), y_cell.ravel(),
        cal.shape))
    gx, gy = gradients_from_normals(nxy[:, 0], nxy[:, 1])
    return gx.reshape(cal.shape), gy.reshape(cal.shape)


@pytest.mark.slow
def test_first_order_error_falls_as_the_square_of_the_colour_cell(tmp_path, monkeypatch):
    """On the shipped GelSight network and a real ball press, against the network at each
    pixel's exact colour (fed the table's position cells): halving the colour cell halves
    the error of an order-0 table and quarters that of a first-order one, and a
    first-order table of 16 cells (an eighth of the cells) is closer than an order-0
    table of 32."""
    monkeypatch.setenv("TACTILEVISION_CACHE", str(tmp_path))
    monkeypatch.setattr(rec, "_TABLES", type(rec._TABLES)())
    cal = PhotometricCalibration.load(default_calibration_path("gelsight"))
    frame = cv2.imread(str(FRAME))
    _, _, cell_px = rec.table_domain(cal)
    lo, hi = rec.table_domain(cal)[:2]
    err = {}
    for order, bins in ((0, 16), (0, 32), (1, 8), (1, 16)):
        recon = DepthReconstructor(cal, table_order=order, table_bins=bins)
        assert recon._table.order == order
        if not err:
            want = _network_at_exact_colour(cal, recon, frame, cell_px)
            ratio = frame.astype(np.float32) * recon._ref_inv
            gain = np.median(ratio[::8, ::8].reshape(-1, 3), axis=0)
            inside = np.all((ratio / gain - 1 > lo) & (ratio / gain - 1 < hi), axis=-1)
            inside &= np.hypot(*want) > 0.05                       # the contact's slopes
            assert inside.sum() > 2000
        gx, gy = recon.gradients(frame)
        err[order, bins] = float(np.sqrt(np.mean(((gx - want[0]) ** 2
                                                  + (gy - want[1]) ** 2)[inside])))
    assert 1.5 < err[0, 16] / err[0, 32] < 2.7
    assert err[1, 8] / err[1, 16] > 3.0
    assert err[1, 16] < 0.85 * err[0, 32]        # 0.023 against 0.031 when written


def test_table_order_is_saved_loaded_and_checked(tmp_path):
    """The calibration's table order survives save and load, a bad one in a file is named,
    and the reconstructor refuses a bad order or number of colour cells."""
    cal = PhotometricCalibration.load(default_calibration_path("gelsight"))
    assert cal.table_order == 0
    cal.table_order = 1
    path = cal.save(tmp_path / "cal.npz")
    assert PhotometricCalibration.load(path).table_order == 1
    import json

    with np.load(path) as data:
        arrays = dict(data)
    meta = json.loads(arrays["meta"].tobytes())
    meta["table_order"] = 2
    arrays["meta"] = np.frombuffer(json.dumps(meta).encode(), np.uint8)
    bad = tmp_path / "bad.npz"
    np.savez(bad, **arrays)
    with pytest.raises(InputError, match=r"bad\.npz.*'table_order' must be 0 or 1"):
        PhotometricCalibration.load(bad)
    with pytest.raises(InputError, match="table_order must be 0 or 1"):
        DepthReconstructor(cal, table_order=2)
    with pytest.raises(InputError, match="table_bins must be an integer of at least 2"):
        DepthReconstructor(cal, table_bins=1)


@pytest.mark.slow
def test_first_order_table_is_cached_on_disk_apart_from_order_zero(tmp_path, monkeypatch):
    """A first-order tabulation is read back from the disk cache with its slopes (same
    gradients, the network not evaluated again); an order-0 file is not taken for it."""
    monkeypatch.setenv("TACTILEVISION_CACHE", str(tmp_path))
    monkeypatch.setattr(rec, "_TABLES", type(rec._TABLES)())
    cal = PhotometricCalibration.load(default_calibration_path("gelsight"))
    frame = cv2.imread(str(FRAME))
    first = DepthReconstructor(cal, table_order=1).gradients(frame)
    zero = DepthReconstructor(cal, table_order=0).gradients(frame)
    files = sorted((tmp_path / "optics").glob("mlp_table_*.npz"))
    assert len(files) == 2
    calls = []
    tabulate = rec.tabulate_mlp
    monkeypatch.setattr(rec, "tabulate_mlp", lambda *a, **k: calls.append(1) or tabulate(*a, **k))
    rec._TABLES.clear()
    again = DepthReconstructor(cal, table_order=1).gradients(frame)
    assert not calls
    np.testing.assert_array_equal(again[0], first[0])
    assert not np.array_equal(zero[0], first[0])
    ref_inv = next(iter(rec._TABLES.values())).ref_inv
    order0 = [f for f in files if "slopes" not in np.load(f).files]
    assert len(order0) == 1 and rec._read_table(order0[0], ref_inv, 16, order=1) is None


@pytest.mark.parametrize("n", [1199, 1200])
def test_the_frame_gain_is_the_median_of_each_channel(n):
    """The per-channel gain's partitioned median equals np.median along the pixels."""
    x = np.random.default_rng(n).uniform(0.5, 1.5, (n, 3)).astype(np.float32)
    np.testing.assert_array_equal(channel_medians(x), np.median(x, axis=0))


def test_a_first_order_row_is_the_plane_through_its_cells_centre():
    """The rows built from the network's seven values a cell (centre, and half a cell
    either side along each axis) give back the centre value at the centre and the chords'
    slopes, for a curved function of the colour coordinates q (in cells)."""
    bins = 5
    r = np.arange(bins ** 3)
    centre = np.stack([r // (bins * bins), (r // bins) % bins, r % bins], 1) + 0.5

    def g(q):                          # gx and gy: curved along every axis
        return (0.3 + 0.2 * q[:, 0] - 0.1 * q[:, 1] ** 2 + 0.05 * q[:, 2] ** 3,
                -0.4 + 0.01 * q[:, 0] * q[:, 1] + 0.3 * q[:, 2])

    pts = [centre] + [centre + s * 0.5 * np.eye(3)[c] for c in range(3) for s in (-1, 1)]
    gx = np.stack([g(p)[0] for p in pts])
    gy = np.stack([g(p)[1] for p in pts])
    rows = _cell_slopes(gx.astype(np.float32), gy.astype(np.float32), bins)
    at_centre_x = rows[:, 0] + (rows[:, 2::2] * centre).sum(1)
    at_centre_y = rows[:, 1] + (rows[:, 3::2] * centre).sum(1)
    np.testing.assert_allclose(at_centre_x, gx[0], atol=2e-5)
    np.testing.assert_allclose(at_centre_y, gy[0], atol=2e-5)
    np.testing.assert_allclose(rows[:, 4], gx[4] - gx[3], atol=1e-6)     # dgx/dq_1
