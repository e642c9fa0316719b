"""The live pipeline (tactilevision.live): one result per frame under the 'every' policy,
the newest frame under 'latest', the reference taken from the first frames, a clean stop,
and the ``live`` command's annotated video and CSV."""

from __future__ import annotations

import csv
import threading
import time

import cv2
import numpy as np
import pytest
from _data import decoded, quarter_gelsight, write_video

from tactilevision import InputError
from tactilevision.cli import main
from tactilevision.fem import ForceEstimator
from tactilevision.live import Pipeline, auto_reference, open_frames, stream
from tactilevision.optics import DepthReconstructor

SIZE = (160, 120)        # a quarter of GelSight's frame: cheap to process


@pytest.fixture(scope="module")
def sensor(tmp_path_factory):
    """The real GelSight presses at a quarter size, their reference, a LUT calibration."""
    root = tmp_path_factory.mktemp("live")
    ref, presses, cal = quarter_gelsight(SIZE)
    cal.save(root / "optics.npz")
    rng = np.random.default_rng(0)
    rest = [np.clip(ref.astype(int) + rng.integers(-2, 3, ref.shape), 0, 255).astype(np.uint8)
            for _ in range(8)]
    return root, cal, ref, presses, rest


def test_every_frame_in_order_with_the_reconstructors_heights(sensor):
    _, cal, ref, presses, rest = sensor
    frames = rest + [np.roll(presses[i % 4], i, axis=1) for i in range(12)]
    out = list(stream(frames, cal, reference=ref))
    assert [r.index for r in out] == list(range(len(frames)))
    assert all(r.dropped == 0 for r in out)
    recon = DepthReconstructor(cal, reference=ref)
    for f, r in zip(frames, out, strict=True):
        np.testing.assert_array_equal(r.height_mm, recon(f))
        np.testing.assert_array_equal(r.contact, recon.contact_mask(f))
    t = [r.t_capture_s for r in out]
    assert np.all(np.diff(t) >= 0) and all(r.latency_s > 0 for r in out)
    assert out[0].forces is None and out[0].total_force_n is None


def test_auto_reference_leaves_out_a_press_among_the_first_frames(sensor):
    _, cal, ref, presses, rest = sensor
    first = [*rest[:4], presses[0], *rest[4:]]               # a press at frame 4
    made, used = auto_reference(np.stack(first))
    assert not used[4] and used.sum() == len(first) - 1
    assert np.abs(made.astype(int) - ref).max() <= 2        # the noise of the rest frames
    frames = first + presses
    out = list(stream(frames, cal, reference="auto", n_reference=len(first)))
    assert [r.index for r in out] == list(range(len(frames)))     # those frames processed too
    recon = DepthReconstructor(cal, reference=made)
    np.testing.assert_array_equal(out[-1].height_mm, recon(frames[-1]))


def test_latest_policy_drops_stale_frames_and_ends_on_the_newest(sensor):
    _, cal, ref, presses, _ = sensor
    n = 60

    def camera():                          # a 200 frames/s camera
        for i in range(n):
            time.sleep(0.005)
            yield presses[i % 4]

    got = []
    for r in stream(camera(), cal, reference=ref, policy="latest"):
        time.sleep(0.03)                   # a consumer six times slower
        got.append(r)
    idx = [r.index for r in got]
    assert np.all(np.diff(idx) > 0) and idx[-1] == n - 1
    assert sum(r.dropped for r in got) == n - len(got) > n // 2


def test_closing_the_stream_stops_the_capture_thread(sensor):
    _, cal, ref, presses, _ = sensor

    def endless():
        while True:
            yield presses[0]

    it = stream(endless(), cal, reference=ref)
    for _ in range(3):
        next(it)
    it.close()
    time.sleep(0.2)
    assert not any(t.name == "tactilevision-capture" and t.is_alive()
                   for t in threading.enumerate())


def test_forces_follow_the_estimator(sensor):
    _, cal, ref, presses, _ = sensor
    out = list(stream(presses, cal, reference=ref, E_mpa=0.2, nu=0.48, thickness_mm=3.0))
    recon = DepthReconstructor(cal, reference=ref, boundary="contact", level="median")
    est = ForceEstimator(cal.shape, cal.mm_per_px, thickness_mm=3.0, E_mpa=0.2, nu=0.48)
    for f, r in zip(presses, out, strict=True):
        np.testing.assert_allclose(r.total_force_n, est(recon(f)).total_n, rtol=1e-6)
        assert r.total_force_n[2] > 0.05
    with pytest.raises(InputError, match="all of E_mpa, nu and thickness_mm"):
        Pipeline(cal, reference=ref, E_mpa=0.2)


def test_fem_forces_follow_the_fem_estimator_and_draw_node_arrows(sensor):
    """method='fem': the inverse FEM's node forces, as the estimator gives them; on the
    footprint, their totals near the spectral method's (another model of the pad:
    18.8 x 14 mm, free sides, 0.48 mm nodes; measured 0.91 to 0.985 of it); the
    annotation draws its tangential arrows at the nodes."""
    from tactilevision.cli._live_run import annotate

    _, cal, ref, presses, _ = sensor
    kw = dict(reference=ref, E_mpa=0.2, nu=0.48, thickness_mm=3.0, contact="footprint",
              threshold_mm=0.02)
    fem = list(stream(presses, cal, method="fem", **kw))
    spectral = list(stream(presses, cal, **kw))
    recon = DepthReconstructor(cal, reference=ref, boundary="contact", level="median")
    est = ForceEstimator(cal.shape, cal.mm_per_px, thickness_mm=3.0, E_mpa=0.2, nu=0.48,
                         method="fem", contact="footprint", threshold_mm=0.02)
    for f, r, s in zip(presses, fem, spectral, strict=True):
        assert r.forces.forces_n.shape == (30, 40, 3)
        np.testing.assert_allclose(r.total_force_n, est(recon(f)).total_n, rtol=1e-6)
        assert r.total_force_n[2] == pytest.approx(s.total_force_n[2], rel=0.12)
    # normal forces only: no arrow; a tangential force on one node: its arrow, there
    import dataclasses

    r = fem[0]
    plain = annotate(r.frame, r.height_mm, depth_range_mm=0.1)
    assert np.array_equal(annotate(r.frame, r.height_mm, depth_range_mm=0.1, forces=r.forces),
                          plain)
    f = np.zeros_like(r.forces.forces_n)
    f[15, 20, 0] = 0.1                                   # +x at the node (20, 15)
    drawn = annotate(r.frame, r.height_mm, depth_range_mm=0.1,
                     forces=dataclasses.replace(r.forces, forces_n=f))
    rows, cols = np.nonzero(np.any(drawn != plain, axis=2))
    x0 = r.forces.x_mm[20] / cal.mm_per_px + SIZE[0]
    y0 = r.forces.y_mm[15] / cal.mm_per_px
    assert rows.size > 3 and np.all(cols >= SIZE[0])
    assert abs(rows.mean() - y0) < 2 and x0 - 1 <= cols.min() and cols.max() <= x0 + 6
    with pytest.raises(InputError, match="method must be"):
        Pipeline(cal, reference=ref, method="bem")


def _dotted(img: np.ndarray, shift_px: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
    """`img` with dark dots 16 px apart, the dots moved by `shift_px` (x, y)."""
    h, w = img.shape[:2]
    dots = np.zeros((h, w), np.uint8)
    for cy in np.arange(10.0, h - 6, 16):
        for cx in np.arange(10.0, w - 6, 16):   # 4 fractional bits: sub-pixel centres
            cv2.circle(dots, (round((cx + shift_px[0]) * 16), round((cy + shift_px[1]) * 16)),
                       40, 255, -1, cv2.LINE_AA, shift=4)
    return np.clip(np.rint(img * (1 - 0.7 * dots[..., None] / 255.0)), 0, 255).astype(np.uint8)


def test_marker_gel_results_carry_the_lateral_field(sensor):
    """markers=True: each result has the tracks and the lateral field; the dots moved by
    (0.6, -0.4) px read as that shift in mm everywhere, the unmoved frame as zero."""
    _, cal, ref, _, _ = sensor
    moved = (0.6, -0.4)
    ref_d = _dotted(ref.astype(np.float64))
    frames = [ref_d, _dotted(ref.astype(np.float64), moved)]
    out = list(stream(frames, cal, reference=ref_d, markers=True))
    assert all(r.markers is not None and r.lateral_mm.shape == (*ref.shape[:2], 2)
               for r in out)
    assert out[1].markers.valid.sum() >= 0.9 * len(out[1].markers.valid) >= 30
    np.testing.assert_allclose(out[0].lateral_mm, 0.0, atol=0.02 * cal.mm_per_px)
    for k in (0, 1):
        np.testing.assert_allclose(np.median(out[1].lateral_mm[..., k]),
                                   moved[k] * cal.mm_per_px, atol=0.05 * cal.mm_per_px)
    # no markers asked for: no fields; a reference without dots: refused
    (plain,) = stream(frames[:1], cal, reference=ref_d)
    assert plain.lateral_mm is None and plain.markers is None
    with pytest.raises(InputError, match="marker"):
        Pipeline(cal, reference=ref, markers=True)


def test_bad_sources(tmp_path, sensor):
    (tmp_path / "notes.txt").write_text("x")
    with pytest.raises(InputError, match="not a video"):
        open_frames(tmp_path / "notes.txt")
    with pytest.raises(InputError, match="no such file"):
        open_frames(tmp_path / "missing.mp4")
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError, match="holds no"):
        open_frames(tmp_path / "empty")
    _, cal, ref, _, _ = sensor
    with pytest.raises(InputError, match="policy"):
        list(stream([ref], cal, reference=ref, policy="newest"))


def test_cli_live_writes_the_annotated_video_and_the_csv(sensor, tmp_path, capsys):
    root, _, _, presses, rest = sensor
    video = tmp_path / "clip.avi"
    frames = rest + presses * 3
    write_video(video, frames, fps=30.0)
    out, table = tmp_path / "annotated.avi", tmp_path / "totals.csv"
    assert main(["live", str(video), "--calibration", str(root / "optics.npz"),
                 "--reference-frames", "8", "--E-mpa", "0.2", "--nu", "0.48",
                 "--thickness-mm", "3", "--out", str(out), "--csv", str(table),
                 "--no-progress"]) == 0
    said = capsys.readouterr().out
    assert f"live: {len(frames)} frame(s)" in said
    # a file is read ahead: the summary leads with the processing time, and says what its
    # capture-to-result figure is (issue 54, item 4)
    assert "processing median" in said and "mostly its queue, not a latency" in said
    cap = cv2.VideoCapture(str(out))
    n = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
    ok, img = cap.read()
    cap.release()
    assert ok and n == len(frames) and img.shape[:2] == (SIZE[1], 2 * SIZE[0])
    rows = list(csv.DictReader(table.open()))
    assert [int(r["frame"]) for r in rows] == list(range(len(frames)))
    fz = np.array([float(r["fz_n"]) for r in rows])
    assert np.all(fz[len(rest):] > 5 * np.abs(fz[:len(rest)]).max())   # presses vs rest
    assert all(float(r["latency_ms"]) > 0 for r in rows)
    # the processing alone is part of the capture-to-result time, never more
    assert all(0 < float(r["process_ms"]) <= float(r["latency_ms"]) for r in rows)
    assert main(["live", str(tmp_path / "nothing.mp4"), "--calibration",
                 str(root / "optics.npz")]) == 2
    assert "no such file" in capsys.readouterr().err
    # the footprint's threshold as forces checks it: named, nothing written
    bad = tmp_path / "bad.csv"
    assert main(["live", str(video), "--calibration", str(root / "optics.npz"),
                 "--E-mpa", "0.2", "--nu", "0.48", "--thickness-mm", "3",
                 "--threshold-mm", "-0.01", "--csv", str(bad), "--no-progress"]) == 2
    assert "threshold_mm" in capsys.readouterr().err and not bad.exists()


def test_reconstruct_takes_a_video(sensor, tmp_path, capsys):
    root, cal, ref, presses, _ = sensor
    video = tmp_path / "clip.avi"
    write_video(video, [ref, *presses], fps=30.0)
    cv2.imwrite(str(tmp_path / "clip_reference.png"), ref)
    out = tmp_path / "heights"
    assert main(["reconstruct", str(video), "--calibration", str(root / "optics.npz"),
                 "--out", str(out), "--no-images"]) == 0
    assert "reference: " + str(tmp_path / "clip_reference.png") in capsys.readouterr().out
    frames = decoded(video)
    recon = DepthReconstructor(cal, reference=ref)
    for i, f in enumerate(frames):
        np.testing.assert_array_equal(np.load(out / f"clip_{i:05d}_height.npy"), recon(f))
    assert len(list(csv.DictReader((out / "heights.csv").open()))) == 5


def test_forces_takes_a_video(sensor, tmp_path, capsys):
    root, cal, ref, presses, _ = sensor
    video = tmp_path / "clip.avi"
    write_video(video, [ref, *presses], fps=30.0)
    cv2.imwrite(str(tmp_path / "clip_reference.png"), ref)
    assert main(["forces", str(video), "--calibration", str(root / "optics.npz"),
                 "--E-mpa", "0.2", "--nu", "0.48", "--thickness-mm", "3", "--every", "2",
                 "--no-images", "--no-progress"]) == 0
    capsys.readouterr()
    rows = list(csv.DictReader((tmp_path / "clip_forces" / "forces.csv").open()))
    assert [r["frame"] for r in rows] == ["clip.avi#0", "clip.avi#2", "clip.avi#4"]
    assert [float(r["t_s"]) for r in rows] == pytest.approx([0.0, 2 / 30, 4 / 30], abs=1e-4)
    frames = decoded(video)
    recon = DepthReconstructor(cal, reference=ref, boundary="contact", level="median")
    est = ForceEstimator(cal.shape, cal.mm_per_px, thickness_mm=3.0, E_mpa=0.2, nu=0.48,
                         contact="footprint", threshold_mm=0.02, beta=0.0)  # forces' defaults
    for r, i in zip(rows, (0, 2, 4), strict=True):
        assert float(r["fz_n"]) == pytest.approx(float(est(recon(frames[i])).total_n[2]),
                                                 rel=1e-4, abs=1e-5)
