"""The sphere from the Hertz limit (issue 84, item 2): below the sphere table's smallest R/h
the closed forms, joined to the table at the seam; one reach; refusals that name the file.

Every expected number here is the closed form's own, written out from its source (Hertz's
P = 4/3 E/(1 - nu^2) R^1/2 w^3/2, Johnson 1985 eq. 4.22-4.23; Sneddon's sphere, 1965;
Dimitriadis et al. 2002 eq. (11)-(12) as printed at nu = 0.5), not a copy of the package's.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from tactilevision import InputError
from tactilevision.cli import main
from tactilevision.mechanics import Sphere, sphere_force_ratio, table_reach
from tactilevision.mechanics._sphere_closed import (
    dimitriadis_coefficients,
    dimitriadis_force_ratio,
)

#: Dimitriadis et al. 2002 as printed at nu = 0.5: eq. (12) bonded, eq. (11) not bonded.
EQ12_BONDED = (1.133, 1.283, 0.769, 0.0975)
EQ11_SLIDING = (0.884, 0.781, 0.386, 0.0048)


def hertz(w, *, E, nu, R):
    """Johnson 1985 eq. 4.22-4.23, a rigid sphere on a half-space, N (mm, MPa)."""
    return 4.0 / 3.0 * E / (1.0 - nu**2) * np.sqrt(R) * np.asarray(w, float) ** 1.5


def eq12(chi):
    c = EQ12_BONDED
    return 1 + c[0] * chi + c[1] * chi**2 + c[2] * chi**3 + c[3] * chi**4


def sneddon(w_over_r):
    """Sneddon 1965's rigid sphere, P / P_Hertz at w/R (R = 1, E* = 1)."""
    a = brentq(lambda x: x / 2 * np.log((1 + x) / (1 - x)) - w_over_r, 1e-12, 1 - 1e-12)
    P = 0.5 * ((a**2 + 1) * np.log((1 + a) / (1 - a)) - 2 * a)
    return P / (4.0 / 3.0 * w_over_r**1.5)


def test_dimitriadis_series_is_the_papers():
    """The general-nu series reproduces eq. (11) and (12) at nu = 0.5 to the printed digits
    (the bonded chi^4 term's sign aside: the module says why)."""
    b, s = dimitriadis_coefficients(0.5, "bonded"), dimitriadis_coefficients(0.5, "sliding")
    assert b[0] == s[0] == 1.0
    np.testing.assert_allclose(b[1:4], EQ12_BONDED[:3], atol=6e-4)
    assert abs(b[4]) == pytest.approx(EQ12_BONDED[3], abs=6e-5)
    np.testing.assert_allclose(s[1:], EQ11_SLIDING, atol=6e-4)
    with pytest.raises(InputError, match="chi"):
        dimitriadis_force_ratio(1.5, 0.5)


def _table(folder: Path, w, P, *, R, h, sem=None) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "presses.csv"
    head = "depth_mm,force_n" + (",force_sem_n" if sem is not None else "")
    rows = [f"{a:.6f},{b:.10f}" + (f",{c:.10f}" if sem is not None else "")
            for a, b, c in zip(w, P, sem if sem is not None else P, strict=True)]
    path.write_text(head + "\n" + "\n".join(rows) + "\n")
    (folder / "session.toml").write_text(
        f'[sensor]\ngel_thickness_mm = {h}\n[indenter]\nshape = "sphere"\nradius_mm = {R}\n')
    return path


def test_hertz_limit_through_fit(tmp_path, capsys):
    """A 2.5 mm ball on a 250 mm gel (R/h = 0.01): presses drawn from Hertz's closed form at
    E = 0.3 MPa, nu = 0.5, 0.5 % force noise; `fit` returns E within 1 % and its interval
    holds it (the thick gel was refused before: R/h outside the table's 0.5 to 20)."""
    E, nu, R, h = 0.3, 0.5, 2.5, 250.0
    w = np.linspace(0.02, 0.10, 8)                 # w/R <= 0.04: Hertz's paraboloid holds
    P = hertz(w, E=E, nu=nu, R=R)
    noisy = P * (1 + 0.005 * np.random.default_rng(1).standard_normal(w.size))
    path = _table(tmp_path / "s", w, noisy, R=R, h=h, sem=0.005 * P)
    out = tmp_path / "fit.json"
    assert main(["fit", str(path), "--law", "linear", "--nu", "0.5", "--json", str(out)]) == 0
    obj = json.loads(out.read_text())
    assert obj["E_mpa"] == pytest.approx(E, rel=0.01)
    lo, hi = obj["E_ci95_mpa"]
    assert lo <= E <= hi


def test_dimitriadis_within_3_percent_inside_its_range():
    """Our small-strain frictionless ball on the bonded layer, table (R/h 0.5 to 4) and closed
    form (R/h 0.05, 0.2), against Hertz times eq. (12) for chi <= 0.3 and w/R <= 0.1 (the
    paraboloid's range; Sneddon's sphere is 1 % below Hertz at w/R = 0.1)."""
    worst = 0.0
    for rh in (0.05, 0.2, 0.5, 1.0, 2.0, 4.0):
        h, R = 1.0, rh
        for w_over_r in (0.005, 0.01, 0.02, 0.05, 0.1):
            w = w_over_r * R
            chi = np.sqrt(R * w) / h
            if chi > 0.3 or w > Sphere(R).reach_mm(h, "linear", "frictionless"):
                continue
            ours = Sphere(R).force(np.array([w]), E_mpa=0.3, nu=0.5, thickness_mm=h,
                                   law="linear", contact="frictionless")[0]
            theirs = hertz(w, E=0.3, nu=0.5, R=R) * eq12(chi)
            worst = max(worst, abs(ours / theirs - 1))
    assert worst < 0.03


@pytest.mark.parametrize("nu", [0.3, 0.5])
def test_table_and_closed_form_join_at_the_seam(nu):
    """At the table's R/h = 0.5: the table against Hertz x Sneddon's sphere x Dimitriadis'
    bonded series (eq. 12 at nu = 0.5, the general series at 0.3) within 1 % up to
    w/h = 0.2 (w/R 0.4, chi 0.32); Hertz x Dimitriadis alone (a paraboloid) within 1 % to
    w/h = 0.04; and just below the seam our answer is the table's (continuous)."""
    w = np.array([0.01, 0.02, 0.04, 0.08, 0.13, 0.2])
    table = sphere_force_ratio(0.5, nu, w, model="linear", contact="frictionless")
    chi = np.sqrt(0.5 * w)
    series = eq12(chi) if nu == 0.5 else sum(
        c * chi**k for k, c in enumerate(dimitriadis_coefficients(nu)))
    closed = series * np.array([sneddon(x / 0.5) for x in w])
    np.testing.assert_allclose(closed, table, rtol=0.01)
    np.testing.assert_allclose(series[:3], table[:3], rtol=0.01)
    for model in ("linear", "neo_hookean"):
        below = sphere_force_ratio(0.5 * (1 - 1e-6), nu, w[:3] * (1 - 1e-6), model=model)
        np.testing.assert_allclose(below, sphere_force_ratio(0.5, nu, w[:3], model=model),
                                   rtol=1e-5)


def test_thick_gel_tends_to_hertz_and_shares_one_reach():
    """At R/h = 0.001 the ratio is Sneddon's sphere (the layer's chi vanishes) within 0.2 %
    (the table's ratio to the closed form at R/h 0.5, 2.8 % at w/R 0.6, is carried scaled
    by (R/h) / 0.5: Sneddon's sphere is exact on the half-space); the reach is
    w <= 0.6 R for the small-strain law, 0.08 R for the finite-strain one, the same figure
    in the fit, the inverse and the table."""
    R, h = 2.5, 2500.0
    ball = Sphere(R)
    w = np.array([0.01, 0.1, 1.0])
    ratio = ball.force(w, E_mpa=1.0, nu=0.5, thickness_mm=h, law="linear") / hertz(
        w, E=1.0, nu=0.5, R=R)
    np.testing.assert_allclose(ratio, [sneddon(x / R) for x in w], rtol=0.002)
    assert ball.reach_mm(h, "linear") == pytest.approx(0.6 * R)
    assert ball.reach_mm(h, "neo_hookean") == pytest.approx(0.08 * R)
    assert table_reach(R / h, "neo_hookean", "tied") * h == pytest.approx(0.08 * R)
    a_top = ball.contact_radius(np.array([0.6 * R]), nu=0.5, thickness_mm=h, law="linear")[0]
    top = ball.depth_from_contact_radius(a_top * (1 - 1e-9), nu=0.5, thickness_mm=h,
                                         law="linear")
    assert float(top) == pytest.approx(0.6 * R, rel=1e-6)
    with pytest.raises(InputError, match="past"):
        ball.depth_from_contact_radius(a_top * 1.001, nu=0.5, thickness_mm=h, law="linear")


@pytest.mark.parametrize(("R", "h", "w", "extra", "match"), [
    (2.5, 250.0, [0.1, 0.3], ("--law", "neo_hookean"), "past the sphere table's reach, 0.2 mm"),
    (2.5, 250.0, [0.5, 1.6], ("--law", "linear"), "past the sphere table's reach, 1.5 mm"),
    (25.0, 1.0, [0.05, 0.1], (), "sphere_fem.npz"),
    (2.5, 250.0, [0.05, 0.1], ("--law", "linear", "--nu", "0.2"), "nu = 0.2"),
])
def test_refusals_name_the_file(tmp_path, capsys, R, h, w, extra, match):
    """Past the reach, R/h past the table, nu outside it: exit 2, one sentence naming the
    measurements table's path."""
    path = _table(tmp_path / "s", w, hertz(w, E=0.3, nu=0.5, R=R), R=R, h=h)
    assert main(["fit", str(path), *extra]) == 2
    err = capsys.readouterr().err
    assert match in err and str(path) in err


@pytest.mark.slow
def test_below_the_seam_the_package_meets_a_direct_fem_solve():
    """Between the Hertz limit and the table's smallest R/h (0.5), at an R/h and nu no rule
    was set on (0.15, 0.45): the package's P/P_Hertz (the closed form carried on from the
    seam) within 1 % of a direct small-strain FEM solve of a sphere, frictionless, to w/R
    0.6, the reach (issue 84: the closed forms join the tables within 1 %)."""
    from tactilevision.fem import sphere_indentation

    w = np.array([0.1, 0.35, 0.6]) * 0.15
    fem = sphere_indentation(0.15, 0.45, w, model="linear", contact="frictionless",
                             profile="sphere", cache=False)
    ours = sphere_force_ratio(0.15, 0.45, w, model="linear", contact="frictionless")
    np.testing.assert_allclose(ours, fem.hertz_ratio, rtol=0.01)
