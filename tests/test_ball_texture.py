"""A ball's contact on frames that are not clean, or the press refused with the true reason.

Truth no code of ours drew: Taxim's own renderer (``taxim.Taxim(backend="jax").render``, its
GelSight calibration with the gel made flat, ``tests/_data.flat_gel_taxim``) draws an
indenter whose lower face is the gel's surface under a ball of radius R at contact radius a:
the ball's cap inside a at Sneddon's depth w = (a/2) ln((R + a)/(R - a)), Hertz's sink-in
outside (K. L. Johnson, Contact Mechanics, 1985, eq. 3.42b, scaled to meet the cap at a),
both written out below from the closed forms. Inside a the gel takes the ball's texture:
dimples (spherical recesses on a hexagonal lattice), knurling (crossed grooves) or a print
(an albedo pattern seen through the gel). The press frame may then drift against the
reference: a gain and an offset per channel. The contact radius is a, by construction; the
force at it Sneddon's, P = E*/2 ((a^2 + R^2) ln((R + a)/(R - a)) - 2 a R) on a half-space.

Each case states its right answer: the radius within its stated uncertainty (the shared
error plus twice the random one, as :func:`tactilevision.pipeline.circle_depths` carries
them), or the press refused with the reason that is true of it. Renders are 240 x 320 px
(0.0295 mm/px), a few per test. ``benchmarks/bench_ball_texture.py`` draws such cases at
random seeds.
"""

from __future__ import annotations

import math
import shutil

import cv2
import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.mechanics import Sphere
from tactilevision.optics import (
    MAX_SECTORS_BEYOND_RIM,
    MAX_SECTORS_BEYOND_UNSTEADY_RIM,
    MIN_RIM_CONTRAST,
    MIN_RIM_IN_FRAME,
    PAD_SHARE,
    PROFILE_SHOULDER,
    STEADY_RIM_CONTRAST,
    STEADY_RIM_SHARE,
    colour_edge_circle,
    drift_free_change,
    find_contact_circle,
    profile_radius,
    rim_drop,
    rim_fall_share,
    rim_in_frame,
    sectors_beyond_rim,
)
from tactilevision.pipeline import E_PLAUSIBLE_MPA, calibrate_dead_weights, circle_depths

S = 0.0295                    # mm per px (Taxim's GelSight)
SHAPE = (240, 320)
G = 9.80665
KINDS = ("smooth", "dimples", "knurl", "printed")


# ---------------------------------------------------------------------------- closed forms
def sneddon_depth(a: float, R: float) -> float:
    """Sneddon's depth of a rigid sphere at contact radius a on a half-space, mm."""
    return 0.5 * a * math.log((R + a) / (R - a))


def sneddon_force(a: float, R: float, E: float, nu: float = 0.5) -> float:
    """Sneddon's force of a rigid sphere at contact radius a on a half-space, N (MPa mm^2)."""
    return E / (1 - nu * nu) / 2 * ((a * a + R * R) * math.log((R + a) / (R - a)) - 2 * a * R)


def gel_surface(shape, centre, a: float, R: float) -> tuple[np.ndarray, float, np.ndarray]:
    """The gel's depression under the ball (mm, down positive), its depth w and each pixel's
    distance from the centre (mm): the cap inside a, Hertz's sink-in outside."""
    rows, cols = np.indices(shape, dtype=np.float64)
    r = np.hypot(cols - centre[0], rows - centre[1]) * S
    w = sneddon_depth(a, R)
    edge = w - (R - math.sqrt(R * R - a * a))
    out = np.empty(shape)
    inside = r < a
    out[inside] = w - (R - np.sqrt(R * R - r[inside] ** 2))
    ro = r[~inside]
    out[~inside] = edge * ((2 * a * a - ro ** 2) * np.arcsin(a / ro)
                           + a * np.sqrt(ro ** 2 - a * a)) / (np.pi * a * a / 2)
    return out, w, r


def texture(kind: str, shape, centre, rng: np.random.Generator
            ) -> tuple[np.ndarray, np.ndarray | None]:
    """A ball's texture about `centre`: the height it takes off the ball's surface (mm) and,
    for a print, the relative albedo it puts on the frame."""
    rows, cols = np.indices(shape, dtype=np.float64)
    x, y = (cols - centre[0]) * S, (rows - centre[1]) * S
    th = rng.uniform(0, np.pi)
    xr, yr = x * np.cos(th) + y * np.sin(th), -x * np.sin(th) + y * np.cos(th)
    if kind == "dimples":          # 0.6 to 1.3 mm wide, 20 to 60 um deep, a hexagonal lattice
        width, depth = rng.uniform(0.6, 1.3), rng.uniform(0.02, 0.06)
        pitch = width * rng.uniform(1.05, 1.3)
        ox, oy = rng.uniform(0, pitch, 2)
        row = pitch * math.sqrt(3) / 2
        nearest = np.full(shape, np.inf)
        j0 = np.floor((yr + oy) / row)
        for dj in (-1, 0, 1, 2):
            j = j0 + dj
            shift = 0.5 * (j % 2)
            i = np.round((xr + ox) / pitch - shift)
            for di in (-1, 0, 1):
                nearest = np.minimum(nearest, np.hypot(xr - ((i + di + shift) * pitch - ox),
                                                       yr - (j * row - oy)))
        rd = width / 2
        big = (rd * rd + depth * depth) / (2 * depth)         # the dimple's sphere
        return np.where(nearest < rd, np.sqrt(np.maximum(big * big - nearest ** 2, 0))
                        - (big - depth), 0.0), None
    if kind == "knurl":            # crossed grooves 0.35 to 0.9 mm apart, 15 to 40 um deep
        p, depth = rng.uniform(0.35, 0.9), rng.uniform(0.015, 0.04)
        u = np.abs(((xr + yr) / p) % 1 - 0.5) * 2
        v = np.abs(((xr - yr) / p) % 1 - 0.5) * 2
        return depth * np.clip(1 - 3 * np.minimum(u, v), 0, 1), None
    if kind == "printed":          # a checker 0.5 to 1.5 mm, 3 to 10 % of the brightness
        p, amp = rng.uniform(0.5, 1.5), rng.uniform(0.03, 0.10)
        pat = np.sign(np.sin(2 * np.pi * xr / p)) * np.sign(np.sin(2 * np.pi * yr / p))
        return np.zeros(shape), amp * cv2.GaussianBlur(pat.astype(np.float32), (0, 0), 1.0)
    return np.zeros(shape), None


def to8(rgb) -> np.ndarray:
    """Taxim's RGB in [0, 1] as an 8-bit BGR frame."""
    return cv2.cvtColor((np.clip(np.asarray(rgb), 0, 1) * 255).round().astype(np.uint8),
                        cv2.COLOR_RGB2BGR)


def render_press(sim, reference: np.ndarray, *, kind: str, a: float, R: float, centre,
                 gain=(1.0, 1.0, 1.0), offset=(0.0, 0.0, 0.0), seed: int = 0,
                 shape=SHAPE) -> np.ndarray:
    """One press drawn by Taxim: the ball (radius R, mm, texture `kind`) at contact radius
    a (mm) about `centre` (px), the frame then drifted by `gain` and `offset` per BGR
    channel, and 1.5 grey levels of camera noise."""
    rng = np.random.default_rng(seed)
    u, w, r = gel_surface(shape, centre, a, R)
    dz, albedo = texture(kind, shape, centre, rng)
    inside = r < a
    img = to8(sim.render(w - u + np.where(inside, dz, 0.0), press_depth=w)).astype(np.float64)
    if albedo is not None:
        img = np.where(inside[..., None], img * (1 + albedo[..., None]), img)
    img = img * np.asarray(gain) + np.asarray(offset) + rng.normal(0, 1.5, img.shape)
    return np.clip(np.rint(img), 0, 255).astype(np.uint8)


def render_reference(sim, shape=SHAPE, seed: int = 1) -> np.ndarray:
    """Taxim's untouched gel with 1.5 grey levels of noise."""
    ref = to8(sim.render(np.full(shape, 5.0), press_depth=None)).astype(np.float64)
    ref += np.random.default_rng(seed).normal(0, 1.5, ref.shape)
    return np.clip(np.rint(ref), 0, 255).astype(np.uint8)


def true_rim_in_frame(centre, a: float, shape=SHAPE) -> float:
    """Share of the true circle's rim inside the image."""
    return rim_in_frame(centre, a / S, shape)


def stated_bound_px(circle, R: float, h: float) -> float:
    """The circle's stated 95 % bound on its radius, px: the shared error plus twice the
    random one (:func:`tactilevision.pipeline.circle_depths`)."""
    d = circle_depths(circle, Sphere(R), mm_per_px=S, thickness_mm=h, nu=0.5, law="linear")
    return d.radius_bias_px + 2 * d.radius_sd_px


# ---------------------------------------------------------------------------- fixtures
@pytest.fixture(scope="module")
def sim():
    pytest.importorskip("taxim", reason="Taxim's renderer is in the test extra")
    pytest.importorskip("jax", reason="Taxim's jax backend is in the test extra")
    from _data import flat_gel_taxim

    with flat_gel_taxim() as s:
        yield s


@pytest.fixture(scope="module")
def reference(sim):
    return render_reference(sim)


# ---------------------------------------------------------------------------- cases
@pytest.mark.slow
def test_dimpled_ball_covering_the_pad_under_a_drift(sim, reference):
    """The issue's failure, scaled to Taxim's pad: a dimpled ball (0.6 to 1.3 mm dimples, 20
    to 60 um deep) whose contact spans 2.8 of the pad's 7.1 mm height, the frame 12 % darker
    and tinted against the reference. Right answer: the radius within its stated bound and
    the centre within 5 % of it (the optics' ``detect_contact_circle``, whose first circle
    is a blob of strong colour change, puts it on a patch of dimples 2.3 mm off: see
    docs/validation/ball.md)."""
    a, R, centre = 2.7, 6.5, (166.3, 118.7)
    frame = render_press(sim, reference, kind="dimples", a=a, R=R, centre=centre,
                         gain=(0.88, 0.9, 0.86), offset=(6.0, -4.0, 9.0), seed=11)
    c = find_contact_circle(frame, reference)
    assert c.trusted, c.problems
    err = abs(c.radius_px - a / S)
    assert err <= stated_bound_px(c, R, 2 * R), (c.radius_px, a / S)
    assert np.hypot(*(c.centre_px - centre)) < 0.05 * a / S
    # its colour edge lies on the same circle, a little outside the contact
    cc, rc, _, _ = colour_edge_circle(frame, reference)
    assert np.hypot(*(cc - centre)) < 0.05 * a / S and 0.95 < rc * S / a < 1.15


@pytest.mark.parametrize("kind,a,R,centre,gain,offset,seed", [
    ("knurl", 1.9, 4.2, (88.0, 131.0), (1.0, 1.0, 1.0), (0.0, 0.0, 0.0), 3),
    ("printed", 1.4, 3.1, (227.0, 140.0), (1.1, 1.15, 1.12), (-8.0, 3.0, 0.0), 5),
    ("smooth", 1.1, 2.2, (292.0, 75.0), (0.85, 0.85, 0.85), (0.0, 0.0, 0.0), 7),
])
def test_texture_drift_and_off_centre_read_right(sim, reference, kind, a, R, centre, gain,
                                                 offset, seed):
    """Knurling on a large contact; a print under a warm drift; a smooth ball 15 % darker
    whose rim runs past the image's right edge (76 % of it in view). Right answer: the
    radius within its stated bound."""
    assert true_rim_in_frame(centre, a) >= 0.75
    frame = render_press(sim, reference, kind=kind, a=a, R=R, centre=centre, gain=gain,
                         offset=offset, seed=seed)
    c = find_contact_circle(frame, reference)
    assert c.trusted, c.problems
    assert abs(c.radius_px - a / S) <= stated_bound_px(c, R, 2 * R), (c.radius_px, a / S)


def test_a_contact_mostly_off_the_image_is_refused_as_cut(sim, reference):
    """A contact whose centre lies 12 px beyond the image's left edge: a third of its rim
    in view. Right answer: refused, because the image's edge cuts it."""
    a, R, centre = 1.5, 3.2, (-12.0, 120.0)
    assert true_rim_in_frame(centre, a) < 0.45
    frame = render_press(sim, reference, kind="dimples", a=a, R=R, centre=centre, seed=13)
    c = find_contact_circle(frame, reference)
    assert not c.trusted
    assert c.rim_in_frame < MIN_RIM_IN_FRAME
    assert "cut by the image's edge" in c.problems[0]


def test_a_large_contact_cut_by_the_edge_is_not_read_as_a_circle_inside_it(sim, reference):
    """A dimpled contact 136 px in radius whose centre lies 8 px beyond the image's left
    edge (a third of its rim in view; seed 2015 of ``benchmarks/bench_ball_texture.py``,
    which the detector read as a circle 45 % small inside it, tangent to the rim it sees,
    and trusted). Right answer: refused, and what refuses it is that the change does not
    fall past that circle's rim in most directions."""
    a, R, centre = 4.005, 6.272, (-7.71, 69.30)
    assert true_rim_in_frame(centre, a) < 0.4
    frame = render_press(sim, reference, kind="dimples", a=a, R=R, centre=centre, seed=2015)
    c = find_contact_circle(frame, reference)
    assert not c.trusted
    cut = c.rim_in_frame < MIN_RIM_IN_FRAME
    assert cut or c.sectors_beyond_rim > MAX_SECTORS_BEYOND_RIM, c
    assert any("does not fall past its rim" in p or "cut by the image's edge" in p
               for p in c.problems), c.problems


def test_a_contact_covering_the_pad_is_trusted_by_its_drop_past_the_rim(sim, reference):
    """A dimpled contact 115 px in radius centred in the 240 x 320 image (seed 2013 of
    ``benchmarks/bench_ball_texture.py``): beyond 1.6 radii lies 1 % of the image, at its
    corners, where the drift fit (made on the contact too) leaves its own error. Measured
    there, the rim stood 3.0 "pad sigmas" up and the press was refused though its circle
    was 3 px from the truth. Right answer: the circle trusted (its contrast read as the drop
    past the rim in camera sigmas, over :data:`MIN_RIM_CONTRAST`), the radius within 5 %."""
    a, R, centre = 3.3946, 5.3965, (163.47, 120.0)
    yy, xx = np.indices(SHAPE)
    assert np.mean(np.hypot(xx - centre[0], yy - centre[1]) > 1.6 * a / S) < PAD_SHARE
    frame = render_press(sim, reference, kind="dimples", a=a, R=R, centre=centre, seed=2013)
    c = find_contact_circle(frame, reference)
    assert c.trusted, c.problems
    assert c.rim_contrast >= MIN_RIM_CONTRAST
    assert abs(c.radius_px - a / S) < 0.05 * a / S, (c.radius_px, a / S)


def test_a_large_dimpled_contact_is_read_at_its_rim_not_inside(sim, reference):
    """A dimpled contact 111 px in radius on a ball of R = 8.3 mm (seed 2332 of
    ``benchmarks/bench_ball_texture.py``): its tilt is shallow, the radial profile's peak
    broad, and the shoulder within 3 % of the peak lay 10.3 px (9 %) inside the rim,
    outside the stated bound. Right answer: the radius within its stated bound
    (:func:`~tactilevision.pipeline.circle_depths`' shared error plus twice its random
    one), read at a share of the rim's contrast below the peak."""
    a, R, centre = 3.2869, 8.3051, (136.49, 117.02)
    frame = render_press(sim, reference, kind="dimples", a=a, R=R, centre=centre, seed=2332)
    c = find_contact_circle(frame, reference)
    assert c.trusted, c.problems
    d = circle_depths(c, Sphere(R), mm_per_px=S, thickness_mm=2 * R, nu=0.5, law="linear")
    assert abs(c.radius_px - a / S) <= d.radius_bias_px + 2 * d.radius_sd_px, (
        c.radius_px, a / S, d.radius_bias_px, d.radius_sd_px)


def test_a_faint_rim_that_falls_on_every_ray_is_trusted(sim, reference):
    """A knurled contact 73 px in radius under a drift of the light (seed 2021 of
    ``benchmarks/bench_ball_texture.py``): its rim stands 3.9 sigmas of the pad's noise up,
    under :data:`MIN_RIM_CONTRAST`, and it was refused though its circle was 2.6 px from the
    truth. The change falls past its rim on nearly every ray, as a contact's edge does and a
    circle on a texture's edge or the background does not. Right answer: trusted by
    :data:`STEADY_RIM_CONTRAST` and :data:`STEADY_RIM_SHARE`, the radius within its stated
    bound."""
    a, R, centre = 2.1521, 5.2286, (82.49, 98.23)
    frame = render_press(sim, reference, kind="knurl", a=a, R=R, centre=centre,
                         gain=(0.941, 0.960, 0.958), offset=(-9.96, -5.51, 11.32), seed=2021)
    c = find_contact_circle(frame, reference)
    assert c.trusted, c.problems
    assert STEADY_RIM_CONTRAST <= c.rim_contrast < MIN_RIM_CONTRAST
    assert c.rim_fall_share >= STEADY_RIM_SHARE
    assert abs(c.radius_px - a / S) <= stated_bound_px(c, R, 2 * R), (c.radius_px, a / S)


def test_a_circle_inside_a_cut_contact_is_refused_by_its_sectors_and_rays(sim, reference):
    """A printed contact 72 px in radius whose centre lies near the image's corner, 31 % of
    its rim in view (seed 2714 of ``benchmarks/bench_ball_texture.py``, under a drift): a
    circle 39 px in radius, inside the contact and wholly in the image, stood 6.6 sigmas up
    and was trusted though 45 % small. The change does not fall past it in half of its
    sectors, nor on a fifth of its rays. Right answer: refused
    (:data:`MAX_SECTORS_BEYOND_UNSTEADY_RIM`), never read as a radius."""
    a, R = 2.118128612310012, 4.603590692500594
    centre = (20.17612758874508, 234.0862845658034)
    gain = (1.0765355076155967, 1.0748915306601017, 1.1178164021266013)
    offset = (6.211202877445881, 0.20126552846652146, 2.494725447215851)
    frame = render_press(sim, reference, kind="printed", a=a, R=R, centre=centre, gain=gain,
                         offset=offset, seed=2714)
    c = find_contact_circle(frame, reference)
    assert not c.trusted
    assert c.rim_fall_share < STEADY_RIM_SHARE
    assert MAX_SECTORS_BEYOND_UNSTEADY_RIM < c.sectors_beyond_rim <= MAX_SECTORS_BEYOND_RIM
    assert any("does not fall past its rim" in p for p in c.problems), c.problems


def test_profile_radius_reads_a_broad_peak_at_its_knee():
    """A closed-form radial profile: the change rises to a broad peak of 12 grey levels at
    90 px, eases to 11.4 at 110 px, then falls to 2 by 120 px (the rim at the knee, 110 px).
    3 % of the peak would stop at 0.36 below it, about 103 px; the shoulder at
    :data:`PROFILE_SHOULDER` of the contrast (0.75 below) reads the knee. A shoulder
    outside (0, 1) is refused."""
    yy, xx = np.indices((300, 300))
    r = np.hypot(xx - 150.0, yy - 150.0)
    level = np.interp(r, [0.0, 90.0, 110.0, 120.0, 400.0], [8.0, 12.0, 11.4, 2.0, 2.0])
    change = np.repeat((level / math.sqrt(3.0))[..., None], 3, axis=2).astype(np.float32)
    radius, _, contrast = profile_radius(change, (150.0, 150.0), 115.0, n_boot=0)
    assert 12.0 - PROFILE_SHOULDER * 10.0 < 11.4      # the knee's level is within the rule
    assert radius == pytest.approx(110.0, abs=1.0)
    assert contrast == pytest.approx(9.4, abs=0.3)
    with pytest.raises(InputError, match="shoulder must lie in"):
        profile_radius(change, (150.0, 150.0), 115.0, shoulder=1.5)


def test_rim_drop_on_a_disc():
    """A disc of colour change 30 grey levels (each channel) out to 62 px and none past
    64 px: its rim drops by 30 * sqrt(3) (the change's magnitude); a circle wholly off the
    image has no rays to read (NaN)."""
    yy, xx = np.indices((240, 320))
    r = np.hypot(xx - 160.0, yy - 120.0)
    level = np.clip((64.0 - r) / 2.0, 0.0, 1.0) * 30.0
    change = np.repeat(level[..., None], 3, axis=2).astype(np.float32)
    assert rim_drop(change, (160.0, 120.0), 60.0) == pytest.approx(30.0 * math.sqrt(3.0),
                                                                   rel=1e-4)
    assert rim_drop(change, (160.0, 120.0), 30.0) == pytest.approx(0.0, abs=1e-3)
    assert np.isnan(rim_drop(change, (-200.0, 120.0), 20.0))


def test_rim_fall_share_on_a_disc_half_a_disc_and_noise():
    """The share of rays on which the change falls past a rim: 1 on a disc's rim; 1/2 on a
    circle whose change fills only half of it (the other half neither falls nor rises); near
    1/2 on a circle drawn on noise alone (360 rays, 1/2 +- 0.08 at 3 sigmas of a binomial
    share, the rays' samples being correlated); NaN for a circle off the image."""
    yy, xx = np.indices((240, 320))
    r = np.hypot(xx - 160.0, yy - 120.0)
    level = np.clip((64.0 - r) / 2.0, 0.0, 1.0) * 30.0
    disc = np.repeat(level[..., None], 3, axis=2).astype(np.float32)
    assert rim_fall_share(disc, (160.0, 120.0), 60.0) == 1.0
    half = np.where((xx < 160)[..., None], disc, 0.0).astype(np.float32)
    assert rim_fall_share(half, (160.0, 120.0), 60.0) == pytest.approx(0.5, abs=0.01)
    noise = np.random.default_rng(3).normal(0.0, 2.0, (240, 320, 3)).astype(np.float32)
    assert rim_fall_share(noise, (160.0, 120.0), 60.0) == pytest.approx(0.5, abs=0.08)
    assert np.isnan(rim_fall_share(disc, (-200.0, 120.0), 20.0))


def test_sectors_beyond_rim_on_a_disc_and_inside_it():
    """A disc of colour change 60 px in radius falling to nothing past it: no sector holds
    its level past the rim (0). A circle of 30 px tangent to the disc's rim from inside:
    past its rim the disc goes on in every direction but where it touches (most sectors)."""
    yy, xx = np.indices((240, 320))
    r = np.hypot(xx - 160.0, yy - 120.0)
    level = np.clip((64.0 - r) / 8.0, 0.0, 1.0) * 30.0
    change = np.repeat(level[..., None], 3, axis=2).astype(np.float32)
    assert sectors_beyond_rim(change, (160.0, 120.0), 60.0) == 0.0
    inside = sectors_beyond_rim(change, (190.0, 120.0), 30.0)
    assert MAX_SECTORS_BEYOND_RIM < inside < 1.0
    assert np.isnan(sectors_beyond_rim(change, (-200.0, 120.0), 20.0))   # nothing in view


def test_a_contact_over_most_of_the_pad_is_found_not_called_no_contact(sim, reference):
    """A smooth ball whose contact (a = 3.2 mm, 109 px) covers most of the 240 x 320 image,
    the frame 11 to 13 % brighter and tinted. The no-contact gate measured its noise on the
    quieter half of the image, which here lies inside the contact (the ball's cap): it
    refused the press as "no contact found". Right answer: a circle found on the contact,
    radius and centre within 5 % (whether its rim is then trusted is the contrast check's
    call, not the gate's)."""
    a, R, centre = 3.21, 5.24, (152.1, 114.6)
    frame = render_press(sim, reference, kind="smooth", a=a, R=R, centre=centre,
                         gain=(1.135, 1.108, 1.122), offset=(-2.9, -7.0, 7.1), seed=532)
    c = find_contact_circle(frame, reference)
    assert abs(c.radius_px - a / S) < 0.05 * a / S, (c.radius_px, a / S)
    assert np.hypot(*(c.centre_px - centre)) < 0.05 * a / S
    assert not any("no contact" in p for p in c.problems)


def test_a_drifted_noisy_frame_without_contact_is_no_contact(reference):
    """The reference again under a gain, an offset and 1.5 grey levels of fresh camera
    noise: no contact, whatever the noise gate reads its noise from."""
    rng = np.random.default_rng(3)
    frame = reference * np.array([1.1, 1.05, 0.95]) + np.array([3.0, -4.0, 5.0])
    frame = np.clip(np.rint(frame + rng.normal(0, 1.5, frame.shape)), 0, 255).astype(np.uint8)
    with pytest.raises(InputError, match="no contact found"):
        find_contact_circle(frame, reference)


def test_drift_free_change_takes_off_a_gain_and_offset():
    """A frame that is the reference with another exposure and white balance (a gain and an
    offset per channel) and a small square press: the drift leaves under 3 grey levels off
    the press (99th percentile; the noise and rounding alone leave 2), where the old median
    rule left the gain's share of the pad's shading (over 8 levels here); the press stays."""
    rng = np.random.default_rng(0)
    yy, xx = np.mgrid[0:120, 0:160]
    ref = np.stack([80 + 60 * np.exp(-((xx - 60) ** 2 + (yy - 50) ** 2) / 3000.0)] * 3, -1)
    ref = ref * np.array([1.0, 1.1, 0.9])
    frame = ref * np.array([1.25, 1.2, 0.82]) + np.array([-4.0, 2.0, 6.0])
    frame[40:60, 90:110] += 30.0
    to8u = lambda im: np.clip(np.rint(im + rng.normal(0, 0.5, im.shape)), 0,  # noqa: E731
                              255).astype(np.uint8)
    ref8, frame8 = to8u(ref), to8u(frame)
    change = drift_free_change(frame8, ref8, sigma=0)
    off = np.ones(ref.shape[:2], bool)
    off[35:65, 85:115] = False
    assert np.percentile(np.abs(change[off]), 99) < 3.0
    assert np.all(np.abs(change[45:55, 95:105] - 30.0) < 4)
    median_rule = frame8.astype(float) - ref8
    median_rule -= np.median(median_rule.reshape(-1, 3), axis=0)
    assert np.percentile(np.abs(median_rule[off]), 99) > 8.0


def test_no_contact_and_bad_input_are_named(reference):
    with pytest.raises(InputError, match="no contact found"):
        find_contact_circle(reference, reference)
    with pytest.raises(InputError, match="reference"):
        find_contact_circle(reference, reference[:-1])
    with pytest.raises(InputError, match="frame"):
        find_contact_circle(reference[..., 0], reference)


# ---------------------------------------------------------------------------- the session
def dead_weight_folder(sim, reference, folder, presses) -> None:
    """A dead-weight folder (``tactilevision.io.read_dead_weights``): one Taxim frame per
    press ``(kind, a, centre, mass_kg, gain, offset)`` of a ball of R = 2 mm on a 4 mm gel
    (R/h = 0.5, the sphere table's thickest)."""
    (folder / "frames").mkdir(parents=True)
    cv2.imwrite(str(folder / "reference.png"), reference)
    rows = ["frame,mass_kg,mass_std_kg"]
    for i, (kind, a, centre, mass, gain, offset) in enumerate(presses):
        frame = render_press(sim, reference, kind=kind, a=a, R=2.0, centre=centre, gain=gain,
                             offset=offset, seed=20 + i)
        cv2.imwrite(str(folder / "frames" / f"{i:02d}.png"), frame)
        rows.append(f"{i:02d}.png,{mass:.6g},0.0001")
    (folder / "weights.csv").write_text("\n".join(rows) + "\n")
    (folder / "session.toml").write_text(
        f"[sensor]\nmm_per_px = {S}\ngel_thickness_mm = 4.0\n\n"
        '[indenter]\nradius_mm = 2.0\nshape = "sphere"\ncontact = "frictionless"\n')


@pytest.fixture(scope="module")
def weights(sim, reference, tmp_path_factory):
    """Five dimpled presses at E = 0.3 MPa, the third drifted; the fourth's mass recorded
    100 times too large (a load in the wrong unit: it needs some 20 MPa at its circle's
    depth); the fifth mostly off the image (40 % of its rim in view)."""
    E, drift = 0.3, ((0.9, 0.92, 0.88), (5.0, -3.0, 4.0))
    plain = ((1.0, 1.0, 1.0), (0.0, 0.0, 0.0))
    spec = [(0.8, (110.0, 100.0), 1, plain), (1.0, (200.0, 130.0), 1, plain),
            (1.2, (160.0, 120.0), 1, drift), (0.9, (170.0, 110.0), 100, plain),
            (1.0, (-10.0, 120.0), 1, plain)]
    presses = [("dimples", a, c, k * sneddon_force(a, 2.0, E) / G, *d) for a, c, k, d in spec]
    folder = tmp_path_factory.mktemp("texture") / "w"
    dead_weight_folder(sim, reference, folder, presses)
    return folder, presses


@pytest.mark.slow
def test_dead_weights_refuse_the_wrong_force_and_the_cut_press(weights):
    """Right answers: presses 0 to 2 read within their stated bounds; press 3 refused
    because its force contradicts its (right) circle; press 4 refused by its circle (60 % of
    its rim is off the image: no circle in the frame can be trusted, whether the one found
    is cut or stands on the background). Each reason in the calibration's rejections."""
    folder, presses = weights
    cal = calibrate_dead_weights(folder, nu=0.5, law="linear")
    reasons = {r.press: r.reason for r in cal.rejected}
    assert reasons.pop(3) == "force contradicts the circle"
    assert reasons.pop(4) in ("contact cut by the image's edge", "contact circle not trusted")
    assert not reasons
    detail = next(r.detail for r in cal.rejected if r.press == 3)
    assert f"outside the {E_PLAUSIBLE_MPA[0]:g} to {E_PLAUSIBLE_MPA[1]:g} MPa" in detail
    assert list(cal.used) == [0, 1, 2]
    d = cal.depths
    a_true = np.array([presses[i][1] for i in cal.used]) / S
    sd_px, shared_px = d.depth_std_mm / (d.dw_da * S), d.depth_shared_mm / (d.dw_da * S)
    assert np.all(np.abs(d.radii_px - a_true) <= shared_px + 2 * sd_px), (d.radii_px, a_true)


def test_a_narrower_modulus_range_refuses_and_a_bad_one_is_named(weights, tmp_path):
    folder, _ = weights
    copy = tmp_path / "w"
    shutil.copytree(folder, copy)
    with pytest.raises(InputError, match="e_range_mpa"):
        calibrate_dead_weights(copy, law="linear", e_range_mpa=(1.0, 0.5))
    with pytest.raises(InputError, match="e_range_mpa"):
        calibrate_dead_weights(copy, law="linear", e_range_mpa="wide")
    # the gel is 0.3 MPa: a range above it refuses every press, each saying why
    with pytest.raises(InputError, match="force contradicts the circle"):
        calibrate_dead_weights(copy, law="linear", e_range_mpa=(2.0, 10.0))
