"""Marker tracking (tactilevision.optics._marker_flow): synthetic dots moved by a
known field, bad input, and the real GelSlim 3.0 set_2020_09 presses.

Synthetic frames: dark anti-aliased dots (radius 3 px, about 20 px apart,
jittered) on a smooth coloured background with camera noise, warped by
``cv2.remap`` with a known smooth displacement field u(x) (a uniform shift plus
an outward Gaussian bulge, up to 2.5 px): the frame at x shows the reference at
p with p + u(p) = x (solved by fixed-point iteration), so a dot that was at p
is at p + u(p), and u(p) is the truth for the track that starts at p.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from _data import GELSLIM, GELSLIM_MM_PER_PX, GELSLIM_REASON

from tactilevision import InputError
from tactilevision.fem import ForceEstimator
from tactilevision.optics import (
    MarkerFlow,
    detect_contact_circles,
    lateral_displacement,
    marker_centres,
    track_markers,
)

H, W = 240, 320
SHIFT = (0.6, -0.4)
BULGE = (3.0, 150.0, 110.0, 35.0)  # amplitude, centre x, centre y, width (px)


def u_true(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The displacement (px) of the gel point at (x, y): a shift plus an outward bulge."""
    amp, cx, cy, s = BULGE
    dx, dy = x - cx, y - cy
    g = amp * np.exp(-(dx * dx + dy * dy) / (2 * s * s)) / s
    return SHIFT[0] + g * dx, SHIFT[1] + g * dy


def background() -> np.ndarray:
    y, x = np.mgrid[0:H, 0:W].astype(np.float64)
    return np.stack([150 + 40 * x / W, 140 + 30 * y / H, 130 + 20 * (x + y) / (W + H)], -1)


def dotted_reference(seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(H, W, 3) uint8 frame with dark dots, and the (M, 2) drawn centres (x, y)."""
    rng = np.random.default_rng(seed)
    centres = np.array([(cx + rng.uniform(-1.5, 1.5), cy + rng.uniform(-1.5, 1.5))
                        for cy in np.arange(12.0, H - 4, 20) for cx in np.arange(12.0, W - 4, 20)])
    dots = np.zeros((H, W), np.uint8)
    for px, py in centres:  # 4 fractional bits: sub-pixel centres
        cv2.circle(dots, (round(px * 16), round(py * 16)), 48, 255, -1, cv2.LINE_AA, shift=4)
    img = background() * (1 - 0.7 * dots[..., None] / 255.0)
    img += rng.normal(0.0, 1.0, img.shape)
    return np.clip(np.rint(img), 0, 255).astype(np.uint8), centres


def warp(reference: np.ndarray) -> np.ndarray:
    """The reference with every point p moved to p + u_true(p)."""
    y, x = np.mgrid[0:H, 0:W].astype(np.float64)
    px, py = x.copy(), y.copy()
    for _ in range(20):
        ux, uy = u_true(px, py)
        px, py = x - ux, y - uy
    return cv2.remap(reference, px.astype(np.float32), py.astype(np.float32), cv2.INTER_CUBIC,
                     borderMode=cv2.BORDER_REFLECT)


@pytest.fixture(scope="module")
def pair():
    ref, centres = dotted_reference()
    return ref, warp(ref), centres


def test_marker_centres_sub_pixel(pair):
    ref, _, drawn = pair
    found = marker_centres(ref)
    assert found.dtype == np.float32 and found.shape == (len(drawn), 2)
    dist = np.min(np.hypot(*(found[:, None, :] - drawn[None]).transpose(2, 0, 1)), axis=1)
    assert dist.max() < 0.15  # measured 0.07 px


def test_track_markers_recovers_known_displacement(pair):
    ref, frame, _ = pair
    flow = track_markers(ref, frame)
    assert isinstance(flow, MarkerFlow)
    assert flow.valid.all()
    assert flow.displacement_px.dtype == np.float32 and flow.valid.dtype == bool
    tx, ty = u_true(*flow.positions_px.astype(np.float64).T)
    err = np.hypot(flow.displacement_px[:, 0] - tx, flow.displacement_px[:, 1] - ty)
    assert np.hypot(tx, ty).max() > 2.0  # the field is not trivial
    assert err.max() < 0.15  # measured 0.067 px
    assert np.sqrt(np.mean(err**2)) < 0.06  # measured 0.028 px
    assert flow.fb_error_px.max() < 0.1


@pytest.mark.parametrize(("method", "rms_px", "max_px"), [("tps", 0.05, 0.15),
                                                            ("linear", 0.10, 0.45)])
def test_lateral_displacement_dense_field(pair, method, rms_px, max_px):
    # measured: tps 0.025 px rms, 0.085 max; linear 0.065 rms, 0.32 max, over
    # the pixels more than 15 px from the border (the dots' hull and a margin)
    ref, frame, _ = pair
    mm = 0.05
    field = lateral_displacement(track_markers(ref, frame), (H, W), mm, method=method)
    assert field.shape == (H, W, 2) and field.dtype == np.float32
    y, x = np.mgrid[0:H, 0:W].astype(np.float64)
    tx, ty = u_true(x, y)
    err = np.hypot(field[..., 0] / mm - tx, field[..., 1] / mm - ty)[15:-15, 15:-15]
    assert np.sqrt(np.mean(err**2)) < rms_px
    assert err.max() < max_px


def test_sign_convention_matches_force_estimator():
    # dots moved right (+x, columns) and down (+y, rows): the field is positive
    # along both, and the estimator's traction points the same way
    ref, _ = dotted_reference(seed=1)
    m = np.float32([[1, 0, 1.5], [0, 1, 0.8]])  # frame(x) = ref(x - shift)
    frame = cv2.warpAffine(ref, m, (W, H), flags=cv2.INTER_CUBIC,
                           borderMode=cv2.BORDER_REFLECT)
    flow = track_markers(ref, frame)
    inner = (flow.positions_px[:, 0] > 10) & (flow.positions_px[:, 1] > 10)
    assert np.allclose(flow.displacement_px[inner & flow.valid], [1.5, 0.8], atol=0.1)
    lat = lateral_displacement(flow, (H, W), 0.1)
    assert np.allclose(np.median(lat.reshape(-1, 2), axis=0), [0.15, 0.08], atol=0.01)
    est = ForceEstimator((H, W), 0.1, thickness_mm=3.0, E_mpa=0.2, nu=0.45, mode="full",
                         contact="field")
    fx, fy, _ = est(np.zeros((H, W), np.float32), lat).total_n
    assert fx > 0 and fy > 0 and fx / fy == pytest.approx(1.5 / 0.8, rel=0.1)


def test_forward_backward_check_flags_tracks_onto_a_blanked_region(pair):
    ref, frame, _ = pair
    rng = np.random.default_rng(5)
    blank = frame.copy()
    box = (slice(60, 120), slice(200, 280))
    # the dots there are gone: only background and camera noise are left
    noisy = background()[box] + rng.normal(0.0, 1.0, (60, 80, 3))
    blank[box] = np.clip(np.rint(noisy), 0, 255).astype(np.uint8)
    flow = track_markers(ref, blank)
    p = flow.positions_px
    inside = (p[:, 0] > 204) & (p[:, 0] < 276) & (p[:, 1] > 64) & (p[:, 1] < 116)
    assert inside.sum() >= 10
    assert not flow.valid[inside].any()
    assert flow.valid[~inside].all()
    # Lucas-Kanade alone keeps most of them (it converges on the noise):
    # the forward-backward check is what rejects them (measured 11 of 12 kept)
    lk_only = track_markers(ref, blank, max_fb_px=1e9)
    assert lk_only.valid[inside].mean() > 0.5
    assert np.all(flow.fb_error_px[inside & lk_only.valid] > 0.5)


def test_lost_tracks_do_not_enter_the_dense_field(pair):
    ref, frame, _ = pair
    flow = track_markers(ref, frame)
    bad = flow.displacement_px.copy()
    bad[::7] = 40.0  # wild values, but marked invalid
    valid = flow.valid.copy()
    valid[::7] = False
    spoiled = MarkerFlow(flow.positions_px, bad, valid, flow.fb_error_px)
    a = lateral_displacement(flow, (H, W), 1.0)
    b = lateral_displacement(spoiled, (H, W), 1.0)
    assert np.abs(a - b)[15:-15, 15:-15].max() < 0.3


# ------------------------------------------------------------------ bad input
def test_bad_inputs_raise_input_error(pair):
    ref, frame, _ = pair
    with pytest.raises(InputError, match="frame must have dtype uint8"):
        marker_centres(ref.astype(np.float32))
    with pytest.raises(InputError, match=r"frame must have shape \(H, W, 3\)"):
        marker_centres(ref[..., 0])
    with pytest.raises(InputError, match="size_px must be an odd integer"):
        marker_centres(ref, size_px=10)
    with pytest.raises(InputError, match=r"frame must have shape \(240, 320, 3\)"):
        track_markers(ref, frame[:200])
    with pytest.raises(InputError, match="reference must have dtype uint8"):
        track_markers(ref.astype(np.float64), frame)
    with pytest.raises(InputError, match="no marker dots found in the reference"):
        track_markers(np.full_like(ref, 128), frame)
    with pytest.raises(InputError, match="positions_px is empty"):
        track_markers(ref, frame, positions_px=np.zeros((0, 2)))
    with pytest.raises(InputError, match="positions_px must have shape"):
        track_markers(ref, frame, positions_px=np.zeros((5, 3)))
    with pytest.raises(InputError, match="max_fb_px must be positive"):
        track_markers(ref, frame, max_fb_px=0)
    flow = track_markers(ref, frame)
    with pytest.raises(InputError, match="mm_per_px must be positive"):
        lateral_displacement(flow, (H, W), -0.1)
    with pytest.raises(InputError, match="method must be 'tps' or 'linear'"):
        lateral_displacement(flow, (H, W), 0.1, method="cubic")
    with pytest.raises(InputError, match=r"shape must be \(H, W\)"):
        lateral_displacement(flow, (H,), 0.1)
    few = MarkerFlow(flow.positions_px, flow.displacement_px,
                     np.arange(len(flow.valid)) < 2, flow.fb_error_px)
    with pytest.raises(InputError, match="3 valid marker tracks for a lateral field, got 2"):
        lateral_displacement(few, (H, W), 0.1)
    nan = flow.displacement_px.copy()
    nan[0] = np.nan
    with pytest.raises(InputError, match="NaN or inf on tracks marked valid"):
        lateral_displacement(MarkerFlow(flow.positions_px, nan, flow.valid, flow.fb_error_px),
                             (H, W), 0.1)
    with pytest.raises(InputError, match=r"flow\.valid must have shape"):
        lateral_displacement(MarkerFlow(flow.positions_px, flow.displacement_px,
                                        flow.valid[:-1], flow.fb_error_px), (H, W), 0.1)


def test_no_markers_gives_empty_centres():
    assert marker_centres(np.full((50, 60, 3), 90, np.uint8)).shape == (0, 2)


# ------------------------------------------------------------------ real frames
@pytest.fixture(scope="module")
def gelslim09():
    if not GELSLIM.is_dir():
        pytest.skip(GELSLIM_REASON)
    from tactilevision.io import read_ball_presses

    ps = read_ball_presses(GELSLIM / "set_2020_09")
    return ps, marker_centres(ps.reference)


def test_gelslim_reference_markers_form_a_regular_grid(gelslim09):
    # ref.jpg shows a grid of about 19 x 14 = 266 dots; those cut by the image
    # border are dropped: 252 found. Nearest neighbours 18 to 24 px apart
    # (median 22.0, interquartile range 11 % of it: the camera's perspective
    # bends the grid a little).
    _, centres = gelslim09
    assert 200 <= len(centres) <= 320
    d = np.hypot(*(centres[:, None] - centres[None]).transpose(2, 0, 1))
    d[np.arange(len(d)), np.arange(len(d))] = np.inf
    nn = d.min(axis=1)
    q25, q50, q75 = np.percentile(nn, [25, 50, 75])
    assert 18.0 <= q50 <= 25.0
    assert (q75 - q25) / q50 < 0.2
    assert nn.min() > 12.0  # no dot found twice


def test_gelslim_presses_push_the_gel_outwards(gelslim09):
    """Every press of set_2020_09: the tracks hold, the motion is at the contact,
    and after removing the contact's mean translation it points outwards.

    Asserted per press: at least 95 % of the tracks valid (measured >= 99.6 %);
    the median motion within 1.5 contact radii at least 3 times that beyond 3
    radii (measured >= 7.2 times); with the mean motion of the tracks within
    1.5 radii subtracted, the median radial component of the tracks between
    0.5 and 1.5 radii positive (measured 0.25 to 2 px, median 1.05 px) and over
    55 % of them outward (measured >= 64 %). Why outward: the gel is a nearly
    incompressible layer bonded to a rigid back, so the ball squeezes it out
    sideways from under the contact. Why the translation is removed: these are
    hand presses with a tangential load (in some the whole contact moves 3 to
    4 px one way). This can fail for a compressible gel or a sticking contact
    (Hertz on a half-space with nu < 0.5 pulls the surface inwards), for a
    misdetected circle, or for a press at the image border.
    """
    ps, centres = gelslim09
    cc, rr = detect_contact_circles(ps.frames, ps.reference)
    radial_medians = []
    for i, frame in enumerate(ps.frames):
        flow = track_markers(ps.reference, frame, positions_px=centres)
        v, d = flow.valid, flow.displacement_px
        rel = flow.positions_px - cc[i]
        r = np.hypot(*rel.T)
        near, far = v & (r < 1.5 * rr[i]), v & (r > 3 * rr[i])
        ring = v & (r > 0.5 * rr[i]) & (r < 1.5 * rr[i])
        assert v.mean() >= 0.95, f"press {ps.names[i]}"
        assert np.median(np.hypot(*d[near].T)) > 3 * np.median(np.hypot(*d[far].T))
        radial = np.sum((d - d[near].mean(axis=0)) * rel, axis=1) / np.maximum(r, 1e-6)
        assert np.median(radial[ring]) > 0, f"press {ps.names[i]}"
        assert np.mean(radial[ring] > 0) > 0.55, f"press {ps.names[i]}"
        radial_medians.append(np.median(radial[ring]))
    assert np.median(radial_medians) > 0.5
    lat = lateral_displacement(flow, ps.reference.shape[:2], GELSLIM_MM_PER_PX)
    assert 0.05 < np.abs(lat).max() < 1.5  # mm: a few px of motion, not a lost track
