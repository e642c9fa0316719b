"""A ball as its own gauge: depths from the contact circles of rendered presses whose truth no
code of ours drew. A rigid sphere on a thick gel (a half-space): Sneddon's closed form gives
the depth and force at each contact radius a (I. N. Sneddon, Int. J. Eng. Sci. 3:47, 1965:
w = (a/2) ln((R + a)/(R - a)), P = E*/2 ((a^2 + R^2) ln((R + a)/(R - a)) - 2 a R)); the gel's
surface is the ball's cap inside a and Hertz's sink-in outside (K. L. Johnson, Contact
Mechanics, 1985, eq. 3.42, continuous at a), shaded by the Taxim authors' table for the
real GelSight; the layer's first-order correction (Dimitriadis et al., Biophys. J.
82:2798, 2002) is 1.5 % at most here."""

from __future__ import annotations

import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.mechanics import Sphere, fit_indenter
from tactilevision.pipeline import ball_press_depths
from tactilevision.sim import taxim_shading

R, H, PAD, E = 2.0, 100.0, 1000.0, 0.2       # ball, thick gel, its pad (mm), modulus (MPa)


def sneddon(a):
    """Depth (mm) and force (N) of a rigid sphere at contact radius a on the half-space,
    nu = 0.5, times the layer's first-order term 1 + 1.133 sqrt(R w)/h in the force."""
    lg = np.log((R + a) / (R - a))
    w = 0.5 * a * lg
    P = 0.5 * E / 0.75 * ((a * a + R * R) * lg - 2 * a * R)
    return w, P * (1 + 1.133 * np.sqrt(R * w) / H)


def surface(shape, centre, a, mm_per_px):
    """Depth of the gel's surface (mm, into the gel): the sphere's cap inside a (at Sneddon's
    w), Hertz's sink-in outside, (w_edge / (pi a^2 / 2)) ((2 a^2 - r^2) asin(a/r) +
    a sqrt(r^2 - a^2)), scaled to meet the cap at a."""
    rows, cols = np.indices(shape, dtype=np.float64)
    r = np.hypot(cols - centre[0], rows - centre[1]) * mm_per_px
    w = sneddon(a)[0]
    edge = w - (R - np.sqrt(R * R - a * a))          # the cap's depth at r = a
    out = np.empty(shape)
    inside = r < a
    out[inside] = w - (R - np.sqrt(R * R - r[inside] ** 2))
    ro = r[~inside]
    out[~inside] = edge * ((2 * a * a - ro ** 2) * np.arcsin(a / ro)
                           + a * np.sqrt(ro ** 2 - a * a)) / (np.pi * a * a / 2)
    return out


@pytest.fixture(scope="module")
def session():
    table, ref = taxim_shading("gelsight")
    rng = np.random.default_rng(7)
    a = np.repeat(np.linspace(0.6, 1.2, 7), 3)            # contact radii, mm
    frames = []
    for ai in a:
        centre = (rng.uniform(200, 440), rng.uniform(140, 340))
        frames.append(table.render(surface(table.shape, centre, ai, table.mm_per_px),
                                   ref, noise_dn=2.0, rng=rng))
    w, P = sneddon(a)
    return np.stack(frames), ref, table.mm_per_px, w, P


def test_contact_circles_certify_the_depths(session):
    """Depths from the circles through our FEM's a(w) against Sneddon's: every press's error
    within its stated shared bound plus two of its sds (the detector's error carried in
    pixels: 1.5 px either part), the scatter not above the stated sds, and E's interval
    holding the truth. At the true depths the FEM's law gives E within 0.5 % (measured
    0.07 %); through the circles E is 9 % high (within 12 % asserted): the detector puts
    these 20 to 40 px circles 1.5 to 3.7 % inside the contact, the depths 4 to 9 % shallow,
    inside the stated bounds (8 to 14 %)."""
    frames, ref, s, w, P = session
    ball = Sphere(R, pad_radius_mm=PAD)
    d = ball_press_depths(frames, ref, ball, mm_per_px=s, thickness_mm=H, nu=0.5,
                          law="linear", contact="frictionless")
    err = d.depth_mm - w
    assert np.all(np.abs(err) < d.depth_shared_mm + 2 * d.depth_std_mm)
    z = (err - err.mean()) / d.depth_std_mm
    assert z.std() < 1.5, z.std()
    fit = fit_indenter(d.depth_mm, P, ball, thickness_mm=H, nu=0.5,
                       law="linear", contact="frictionless", depth_std_mm=d.depth_std_mm,
                       depth_shared_mm=d.depth_shared_mm)
    assert fit.E_mpa == pytest.approx(E, rel=0.12)
    assert fit.E_ci95_mpa[0] <= E <= fit.E_ci95_mpa[1]
    exact = fit_indenter(w, P, ball, thickness_mm=H, nu=0.5, law="linear",
                         contact="frictionless")
    assert exact.E_mpa == pytest.approx(E, rel=0.005)


def test_a_circle_off_the_image_is_refused(session):
    frames, ref, s, _, _ = session
    table, _ = taxim_shading("gelsight")
    edge = table.render(surface(table.shape, (10.0, 240.0), 1.0, s), ref)
    with pytest.raises(InputError, match="press 9: its contact circle"):
        ball_press_depths(np.stack([frames[0], edge]), ref, Sphere(R, pad_radius_mm=PAD),
                          mm_per_px=s, thickness_mm=H, law="linear",
                          names=["press 8", "press 9"])
