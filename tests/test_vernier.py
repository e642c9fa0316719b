"""The bevel as a vernier: reading the band of contact, the hold, the bulge, the session keys.

Known answers: synthetic profiles of a band of known half-width; bevels
rendered from a gel surface whose contact band follows from the geometry
(the flank meets the surface where ``overshoot - |u| tan(theta)`` crosses
it); a force trace whose stop is known; the FEM's bulge against its own
surface profile and its trend with nu. Sessions rendered by Taxim's own
renderer are in tests/test_vernier_taxim.py.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import erf

from tactilevision import InputError
from tactilevision.contact import (
    BevelGeometry,
    BevelProfile,
    bevel_profile,
    bulge_at,
    hold_end,
    hold_start,
    read_bevel,
)
from tactilevision.contact._certify import MIN_BAND_CONTRAST

S = 0.0295
GEOM = BevelGeometry(offset_mm=9.0, direction_deg=0.0, angle_deg=5.0, length_mm=3.0)


def _band_profile(L: float, crest: float = 0.3, blur: float = 1.0, noise: float = 0.3,
                  seed: int = 0, colours=((-6.0, 2.0, 3.0), (4.0, -1.5, -2.0))) -> BevelProfile:
    """A profile across the crest: two flank plateaus of half-width L, blurred, with noise."""
    rng = np.random.default_rng(seed)
    u = np.arange(-47.0, 47.0 + 1e-9, 0.5)
    k = 1 / (math.sqrt(2) * blur)

    def box(a, b):
        return 0.5 * (erf((u - a) * k) - erf((u - b) * k))

    c_in, c_out = np.array(colours)
    R = (box(crest - L, crest)[:, None] * c_in[None] + box(crest, crest + L)[:, None] * c_out
         + 0.5 + 0.01 * u[:, None])            # a sloping background
    return BevelProfile(u_px=u, colour=R + rng.normal(0, noise, R.shape), coverage=1.0)


@pytest.mark.parametrize("L", [4.0, 8.5, 15.25, 30.0])
def test_read_bevel_finds_the_half_width(L):
    zs = []
    for seed in range(6):
        r = read_bevel(_band_profile(L, seed=seed), GEOM, S)
        assert r.half_width_px == pytest.approx(L, abs=0.3)
        assert r.crest_px == pytest.approx(0.3, abs=0.4)
        assert r.closure_mm == pytest.approx(r.half_width_px * math.tan(math.radians(5)) * S)
        assert r.snr > 20
        zs.append((r.half_width_px - L) / r.half_width_std_px)
    assert np.all(np.abs(zs) < 3)


def test_short_band_reads_with_the_colour_prior():
    colours = np.array([(-6.0, 2.0, 3.0), (4.0, -1.5, -2.0)])
    errs_free, errs_prior = [], []
    for seed in range(10):
        p = _band_profile(2.0, seed=seed, noise=0.5)
        errs_free.append(read_bevel(p, GEOM, S, lines="none").half_width_px - 2.0)
        errs_prior.append(read_bevel(p, GEOM, S, lines="none", flank_colours=colours,
                                     colour_sd=0.1).half_width_px - 2.0)
    assert np.sqrt(np.mean(np.square(errs_prior))) < 0.3
    assert np.sqrt(np.mean(np.square(errs_prior))) <= np.sqrt(np.mean(np.square(errs_free)))


def test_no_band_reads_weak():
    rng = np.random.default_rng(3)
    snrs = []
    for _ in range(20):
        u = np.arange(-47.0, 47.0 + 1e-9, 0.5)
        R = 0.5 + 0.02 * u[:, None] + rng.normal(0, 0.3, (u.size, 3))
        snrs.append(read_bevel(BevelProfile(u, R, 1.0), GEOM, S).snr)
    strong = read_bevel(_band_profile(6.0), GEOM, S).snr
    assert max(snrs) < 8.0 < strong


def test_band_contrast_is_the_flank_colours():
    """The contrast is the band's own colour change (the flanks' -6 and +4 grey levels in the
    first channel: 10 peak to peak), whatever its length once it is a few blurs wide (a
    3 px band blurred by 1 px keeps 0.87 of it, less what the background takes); smooth
    shading with no band (a derivative of a broad Gaussian, 1 grey level peak to peak, as
    Taxim renders a press stopped 0.9 um past w0) stays under the certification's
    threshold, 0.15 of the bands', however it is read."""
    for L in (8.0, 20.0):
        assert read_bevel(_band_profile(L, noise=0.1), GEOM, S).contrast == pytest.approx(
            10.0, rel=0.03)
    assert 6.0 < read_bevel(_band_profile(3.0, noise=0.1), GEOM, S).contrast < 9.0
    u = np.arange(-47.0, 47.0 + 1e-9, 0.5)
    shade = -0.5 * (u / 10.0) * np.exp(0.5 - 0.5 * (u / 10.0) ** 2)
    R = np.stack([shade, 0.2 * shade, -0.1 * shade], axis=1) + 0.5
    rng = np.random.default_rng(1)
    faint = read_bevel(BevelProfile(u, R + rng.normal(0, 0.1, R.shape), 1.0), GEOM, S)
    assert faint.contrast < MIN_BAND_CONTRAST * 10.0


def test_read_bevel_bad_input():
    with pytest.raises(InputError, match="no vernier"):
        read_bevel(_band_profile(5.0), BevelGeometry(9.0, angle_deg=0.0), S)
    a, b = _band_profile(5.0), _band_profile(5.0)
    with pytest.raises(InputError, match="sampled differently"):
        read_bevel([a, BevelProfile(b.u_px[::2], b.colour[::2], 1.0)], GEOM, S)
    with pytest.raises(InputError, match="at least one"):
        read_bevel([], GEOM, S)


def test_bevel_profile_is_clipped_to_the_image():
    """A bevel half out of the image: the part inside is averaged, coverage says how much."""
    frame = np.full((480, 640, 3), 100, np.uint8)
    ref = frame.copy()
    frame[:, 600:, 2] = 130            # a change that ends at column 600
    centre = (640 - 9.0 / S - 2.0, 240.0)   # crest 2 px inside the right edge
    prof = bevel_profile(frame, ref, centre, S, GEOM, reach_px=20.0)
    assert np.all(np.isfinite(prof.colour))
    assert 0.3 < prof.coverage < 0.7
    inside = prof.u_px <= 1.0
    assert np.allclose(prof.colour[inside & (prof.u_px > -15), 2], 30.0, atol=0.5)
    assert np.all(prof.colour[prof.u_px > 2.5] == 0)
    out = bevel_profile(frame, ref, (-500.0, 240.0), S, GEOM, reach_px=20.0)
    assert out.coverage == 0.0 and np.all(out.colour == 0)


def test_rendered_bevel_reads_the_geometry():
    """Bevels rendered (Taxim's GelSight shading) from a flat gel meeting the ridge: the
    band's half-width is overshoot / tan(theta) exactly; the reading is within 0.5 px."""
    pytest.importorskip("taxim")
    import cv2

    from tactilevision.sim import taxim_shading

    table, reference = taxim_shading()
    rng = np.random.default_rng(5)
    errs = []
    for k, overshoot in enumerate((0.015, 0.025, 0.035, 0.045)):
        centre = (140.3 + 7 * k, 230.6 - 11 * k)
        rows, cols = np.indices(table.shape, dtype=np.float64)
        u = (cols - centre[0]) * S - GEOM.offset_mm
        v = (rows - centre[1]) * S
        ridge = np.where(np.abs(v) <= 1.5, overshoot - np.abs(u) * GEOM.tan_theta, -np.inf)
        z = np.maximum(0.0, ridge)
        frames = []
        for _ in range(3):
            img = table.render(z, reference, noise_dn=2.0, rng=rng)
            _, buf = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, 90])
            frames.append(cv2.imdecode(buf, cv2.IMREAD_COLOR))
        profs = [bevel_profile(f, reference, centre, S, GEOM, reach_px=46.0) for f in frames]
        r = read_bevel(profs, GEOM, S, lines="none", blur_px=1.5)
        errs.append(r.half_width_px - overshoot / GEOM.tan_theta / S)
    assert np.max(np.abs(errs)) < 0.5, errs
    assert abs(np.mean(errs)) < 0.3, errs


def test_hold_start_finds_the_stop():
    """An approach at constant speed into a stiffening law, then a hold with relaxation."""
    rng = np.random.default_rng(0)
    t = np.arange(0.0, 2.0, 0.001)
    t_stop = 0.8734
    w = np.clip((t - 0.3) / (t_stop - 0.3), 0, 1) * 0.35
    f = 3.5 * w * (1 + 0.8 * w / 3) - 0.02 * np.clip(t - t_stop, 0, None)
    f += rng.normal(0, 1 / 80, t.size)
    assert hold_start(t, f, 0.0, 2.0) == pytest.approx(t_stop, abs=0.004)
    assert hold_start(t[:10], f[:10], 0.0, 2.0) is None
    assert hold_start(t, -f, 0.0, 2.0) is None          # falling force: no approach
    assert hold_start(t, rng.normal(0, 1 / 80, t.size), 0.0, 2.0) is None   # noise alone


def test_hold_end_finds_the_release_not_the_relaxation():
    """Approach 0.5 s, a 3 s hold that relaxes by a fifth (tau 0.7 s), release in 0.25 s,
    1/80 N of noise at 1 kHz: the hold runs from the stop to the start of the release
    (within 5 ms each), the relaxation is not taken for it; no release, no end."""
    rng = np.random.default_rng(1)
    t = np.arange(0.0, 5.0, 0.001)
    t_stop, t_rel = 0.8, 3.8
    ramp = np.clip((t - 0.3) / 0.5, 0, 1)
    relax = 1 - 0.2 * (1 - np.exp(-np.clip(t - t_stop, 0, None) / 0.7))
    down = 1 - np.clip((t - t_rel) / 0.25, 0, 1)
    f = 2.0 * ramp * relax * down + rng.normal(0, 1 / 80, t.size)
    t0 = hold_start(t, f, 0.0, 5.0)
    assert t0 == pytest.approx(t_stop, abs=0.005)
    assert hold_end(t, f, t0) == pytest.approx(t_rel, abs=0.005)
    held = t < 3.5
    assert hold_end(t[held], f[held], t0) is None


def test_bulge_grows_with_nu_and_decays_with_distance():
    """The FEM bulge: positive, larger for a less compressible gel, smaller further out,
    nearly proportional to w (within 15% over w/h 0.05 to 0.2)."""
    w = np.array([0.15, 0.3, 0.6])
    b45 = bulge_at(9.0, w, thickness_mm=3.0, radius_mm=2.5, nu=0.45)
    b49 = bulge_at(9.0, w, thickness_mm=3.0, radius_mm=2.5, nu=0.49)
    far = bulge_at(12.0, w, thickness_mm=3.0, radius_mm=2.5, nu=0.49)
    assert np.all(b45 > 0) and np.all(b49 > b45) and np.all(far < b49)
    frac = b49 / w
    assert frac.max() / frac.min() < 1.15
    assert 0.01 < frac.mean() < 0.04          # 2 to 3% of w at 3 h for a bonded 0.49 layer
    with pytest.raises(InputError, match="inside the indenter"):
        bulge_at(2.0, w, thickness_mm=3.0, radius_mm=2.5, nu=0.48)
    with pytest.raises(InputError, match="must lie in"):
        bulge_at(9.0, w, thickness_mm=3.0, radius_mm=2.5, nu=0.6)


def test_bulge_between_the_nu_nodes_matches_a_sweep_at_that_nu():
    """Between the FEM sweeps at nu 0.48 and 0.49, the interpolated bulge and land contact
    depth stay within 0.03% of w of a sweep run at nu 0.485 itself."""
    from tactilevision.contact import land_contact_depth, land_contact_depths_mm
    from tactilevision.fem import press_profile

    w = np.array([0.15, 0.3, 0.6])
    prof = press_profile(2.5 / 3.0, 0.485, w_over_h_max=0.22, steps=8, cell=0.5,
                         edge_refinements=5)
    direct = np.array([-float(prof.depth_at(v / 3.0, np.array([2.5]))[0]) * 3.0 for v in w])
    b = bulge_at(7.5, w, thickness_mm=3.0, radius_mm=2.5, nu=0.485)
    assert np.all(np.abs(b - direct) < 3e-4 * w)
    assert np.all(np.abs(b - direct) > 0)        # interpolated, not the same sweep
    wc = land_contact_depths_mm(w, thickness_mm=3.0, radius_mm=2.5, nu=0.485)
    wd = np.array([land_contact_depth(v / 3.0, prof) * 3.0 for v in w])
    assert np.all(np.abs(wc - wd) < 3e-4 * w)


def test_session_keys(tmp_path):
    from tactilevision.io import read_session

    base = """[sensor]
mm_per_px = 0.0295
gel_thickness_mm = 3.0
[indenter]
radius_mm = 2.5
[gauge_block]
depths_mm = [0.15, 0.3]
{extra}
"""
    folder = tmp_path / "s"
    folder.mkdir()
    (folder / "session.toml").write_text(base.format(extra="bevel_angle_deg = 90.0"))
    with pytest.raises(InputError, match=r"bevel_angle_deg is the flank angle.*"
                                         r"bevel_direction_deg"):
        read_session(folder)
    (folder / "session.toml").write_text(base.format(extra='bulge_correction = "yes"'))
    with pytest.raises(InputError, match="bulge_correction must be true or false"):
        read_session(folder)


def test_crest_consistency_closed_form():
    """Crests 0, 1, 2 px: chi2 about their mean is 2 on 2 degrees of freedom, so the Birge
    ratio is 1 at a stated sd of 1 px and 2 at 0.5 px, with p = exp(-chi2 / 2)."""
    from tactilevision.contact import crest_consistency

    r, p = crest_consistency([0.0, 1.0, 2.0], [1.0, 1.0, 1.0])
    assert r == pytest.approx(1.0) and p == pytest.approx(math.exp(-1.0))
    r, p = crest_consistency([0.0, 1.0, 2.0], [0.5, 0.5, 0.5])
    assert r == pytest.approx(2.0) and p == pytest.approx(math.exp(-4.0))
    # weights: a precise crest pulls the mean to itself
    r, _ = crest_consistency([0.0, 3.0, 3.0], [0.01, 1.0, 1.0])
    mean = 6.0 / 10002.0
    assert r == pytest.approx(math.sqrt((1e4 * mean ** 2 + 2 * (3.0 - mean) ** 2) / 2), rel=1e-12)
    assert r < math.sqrt(9.0)          # about the unweighted mean 2 it would be 6 / sqrt(2)
    assert all(math.isnan(v) for v in crest_consistency([0.0, 1.0], [1.0, 1.0]))


def test_crest_check_holds_its_false_alarm_rate_and_sees_narrow_uncertainties():
    """Crests drawn with the stated sd are flagged at the check's 5 % (within Monte Carlo
    error over 4000 sessions of 12 bands); drawn 1.5 times wider, the median Birge ratio is
    1.5 within 5 %."""
    from tactilevision.contact import CREST_CHECK_P, crest_consistency

    rng = np.random.default_rng(3)
    sd = rng.uniform(0.4, 0.6, 12)
    honest = [crest_consistency(rng.normal(0.0, sd), sd) for _ in range(4000)]
    rate = np.mean([p < CREST_CHECK_P for _, p in honest])
    assert abs(rate - CREST_CHECK_P) < 3 * math.sqrt(0.05 * 0.95 / 4000)
    narrow = np.array([crest_consistency(rng.normal(0.0, 1.5 * sd), sd)[0]
                       for _ in range(4000)])
    # the median of sqrt(chi2_11 / 11) is 0.970: times 1.5
    assert np.median(narrow) == pytest.approx(1.5 * 0.970, rel=0.05)


def test_read_bands_are_widened_by_their_crests_scatter():
    """The session check on its presses: crests scattering beyond their stated sd widen every
    read band's closure sd by the Birge ratio and leave unread bands (a uniform over their
    bounds) as they were; consistent crests change nothing. Both say so in the optics."""
    from dataclasses import dataclass

    from tactilevision.contact import crest_consistency
    from tactilevision.contact._vernier_presses import _crest_checked

    @dataclass(frozen=True)
    class Reading:
        crest_px: float
        half_width_std_px: float

    @dataclass(frozen=True)
    class Press:
        band_resolved: bool
        reading: Reading
        closure_std_mm: float

    crests = [-1.5, 1.2, 0.1, -0.9, 1.6, -0.4, 0.8, -1.1]
    presses = [Press(True, Reading(c, 0.45), 0.001) for c in crests]
    presses.append(Press(False, Reading(9.0, 0.45), 0.007))       # unread: not in the check
    optics: dict = {}
    out = _crest_checked(presses, optics)
    ratio, p = crest_consistency(crests, [0.45] * len(crests))
    assert p < 0.05 and ratio > 2.0
    assert optics["read_std_factor"] == pytest.approx(ratio, abs=1e-3)
    assert optics["crest_birge"] == pytest.approx(ratio, abs=1e-3)
    assert [q.closure_std_mm for q in out[:-1]] == pytest.approx([0.001 * ratio] * 8)
    assert out[-1].closure_std_mm == 0.007
    calm = [Press(True, Reading(0.2 * c, 0.45), 0.001) for c in crests]
    optics = {}
    assert _crest_checked(calm, optics) == calm and optics["read_std_factor"] == 1.0
