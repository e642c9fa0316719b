"""read_ramp and fit_ramp: force-depth ramps drawn with known truth (contact point, baseline,
E, nu), from a closed-form test indenter (no table of ours in the loop) and from the flat
punch's small-strain law (the shipped kappa table)."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.io import Ramp, read_ramp
from tactilevision.mechanics import FlatPunch, Indenter, RampFit, fit_ramp


@dataclass(frozen=True)
class LayeredBall(Indenter):
    """Hertz with a nu-dependent first-order layer term: P = 4/3 E/(1 - nu^2) R^1/2 w^3/2
    (1 + k(nu) chi + k(nu)^2 chi^2), chi = sqrt(R w)/h, k = 0.88 + 1.3 (nu - 0.3) (the
    first-order coefficient of a bonded layer grows with nu, 0.88 to 1.14: Dimitriadis
    et al. 2002's alpha_0 through 1.133 at nu = 0.5). Copied from test_indenter_fit.py."""

    radius_mm: float
    shape: ClassVar[str] = "layered_ball"
    contacts: ClassVar[tuple[str, ...]] = ("frictionless",)
    observes: ClassVar[str] = "nothing (a test law)"

    def reach_mm(self, thickness_mm, law="neo_hookean"):
        return 0.5 * thickness_mm

    def force(self, depth_mm, *, E_mpa, nu, thickness_mm, law="neo_hookean", contact=None):
        w = np.asarray(depth_mm, float)
        chi = np.sqrt(self.radius_mm * w) / thickness_mm
        k = 0.88 + 1.3 * (nu - 0.3)
        return (4 / 3 * E_mpa / (1 - nu**2) * np.sqrt(self.radius_mm) * w**1.5
                * (1 + k * chi + k**2 * chi**2))

    def contact_radius(self, depth_mm, *, nu, thickness_mm, law="neo_hookean", contact=None):
        return np.sqrt(self.radius_mm * np.asarray(depth_mm, float))


BALL, H_BALL = LayeredBall(3.0), 2.0          # reach 1.0 mm
PUNCH, H_PUNCH = FlatPunch(2.5), 3.0          # law='linear': no reach
#: (indenter, h, law, E, nu, deepest depth) of each case.
CASES = {"ball": (BALL, H_BALL, "neo_hookean", 0.5, 0.5, 0.9),
         "punch": (PUNCH, H_PUNCH, "linear", 0.2, 0.5, 0.3)}


def draw(case: str, *, seed: int = 0, n: int = 400, start: float = -0.1,
         depth: float | None = None, back: int = 0, nu: float | None = None,
         noise: float = 0.002, F0: float = 0.03) -> tuple[np.ndarray, np.ndarray, float]:
    """A ramp of `n` points evenly spaced from `start` to z0 + depth, then `back` points of
    unloading; force F0 + the indenter's at the case's E and nu + `noise` N sd. Returns
    (displacement, force, true z0), z0 drawn in [0.13, 0.14) mm."""
    ind, h, law, E, nu0, deep = CASES[case]
    rng = np.random.default_rng(1000 + seed)
    z0 = 0.13 + 0.01 * rng.random()
    z = np.linspace(start, z0 + (deep if depth is None else depth), n)
    if back:
        z = np.r_[z, z[-2::-1][:back]]
    w = z - z0
    g = np.zeros(z.size)
    g[w > 0] = ind.force(w[w > 0], E_mpa=E, nu=nu0 if nu is None else nu, thickness_mm=h,
                         law=law)
    return z, F0 + g + noise * rng.standard_normal(z.size), z0


def fit(case: str, z: np.ndarray, P: np.ndarray, **kw) -> RampFit:
    ind, h, law, *_ = CASES[case]
    return fit_ramp(z, P, ind, thickness_mm=h, law=law, **kw)


@pytest.mark.slow
@pytest.mark.parametrize("case", ["ball", "punch"])
def test_contact_point_and_E_from_noisy_ramps(case):
    """20 ramps of 400 points, 2 mN force noise, 0.23 mm of approach and a 30 mN baseline:
    the contact point within 5 um and E within 3 % of the truth in every one, the baseline
    within 2 mN, and both intervals holding the truth in at least 18 of the 20."""
    E_true = CASES[case][3]
    err_z, err_E, cover_z, cover_E = [], [], 0, 0
    for seed in range(20):
        z, P, z0 = draw(case, seed=seed)
        f = fit(case, z, P)
        err_z.append(f.contact_point_mm - z0)
        err_E.append(f.E_mpa / E_true - 1)
        cover_z += f.contact_point_ci_mm[0] <= z0 <= f.contact_point_ci_mm[1]
        cover_E += f.E_ci95_mpa[0] <= E_true <= f.E_ci95_mpa[1]
        assert f.baseline_n == pytest.approx(0.03, abs=0.002)
        assert f.n_points == z.size and f.n_dropped == 0
        assert f.rmse_n == pytest.approx(0.002, rel=0.2)
    assert np.max(np.abs(err_z)) < 0.005
    assert np.max(np.abs(err_E)) < 0.03
    assert cover_z >= 18 and cover_E >= 18


def test_flat_punch_leaves_nu_to_the_statement():
    """A flat punch's small-strain force is linear in depth whatever nu: the ramp cannot
    identify nu, and E is reported at the stated one (E / (1 - nu^2) is what it measures)."""
    z, P, z0 = draw("punch", seed=3)
    f = fit("punch", z, P, nu=0.45)
    assert not f.nu_identified and f.nu == 0.45
    kappa_ratio = (PUNCH.force(1.0, E_mpa=1.0, nu=0.45, thickness_mm=H_PUNCH, law="linear")
                   / PUNCH.force(1.0, E_mpa=1.0, nu=0.5, thickness_mm=H_PUNCH, law="linear"))
    assert f.E_mpa == pytest.approx(0.2 / kappa_ratio, rel=0.01)
    assert f.contact_point_mm == pytest.approx(z0, abs=0.002)


def test_wrong_stated_nu_is_corrected_with_the_contact_point():
    """Ball ramps of nu = 0.45 fitted at the default nu = 0.5: the ramp identifies nu, the
    contact point is profiled over nu too, and nu, z0 and E land on the truth (profiled at
    the stated nu alone, z0 moved by several um and E by 10 %), their intervals holding it
    in at least 9 of 10 ramps."""
    cover = np.zeros(3, int)
    for seed in range(10):
        z, P, z0 = draw("ball", seed=seed, nu=0.45)
        f = fit("ball", z, P)
        assert f.nu_identified
        assert f.nu == pytest.approx(0.45, abs=0.015)
        assert f.contact_point_mm == pytest.approx(z0, abs=0.005)
        assert f.E_mpa == pytest.approx(0.5, rel=0.05)
        assert any("profiled over nu" in note for note in f.notes)
        cover += [f.nu_ci95[0] <= 0.45 <= f.nu_ci95[1],
                  f.contact_point_ci_mm[0] <= z0 <= f.contact_point_ci_mm[1],
                  f.E_ci95_mpa[0] <= 0.5 <= f.E_ci95_mpa[1]]
    assert np.all(cover >= 9)


def test_unloading_and_points_past_the_reach_are_dropped():
    """A ball ramp to 1.3 mm past contact (the reach is 1.0 mm) and back down 100 points:
    the unloading and the points past the reach are dropped and said; what is left gives
    the truth, and the same fit as the loading part cut by hand at the reach."""
    z, P, z0 = draw("ball", seed=1, depth=1.3, back=100)
    f = fit("ball", z, P)
    assert f.n_points + f.n_dropped == z.size
    past = int(np.sum(z[:-100] - z0 > 1.0))
    assert 100 + past <= f.n_dropped <= 100 + past + 10
    assert any("unloading" in n and "100 point" in n for n in f.notes)
    assert any("reach" in n and "dropped" in n for n in f.notes)
    assert f.depth_mm.max() <= 1.0 and f.depth_mm.min() > 0 and f.force_n.min() > 0
    assert f.contact_point_mm == pytest.approx(z0, abs=0.005)
    assert f.E_mpa == pytest.approx(0.5, rel=0.03)
    cut = z[:-100] <= f.contact_point_ci_mm[0] + 0.99
    g = fit("ball", z[:-100][cut], P[:-100][cut])
    assert g.contact_point_mm == pytest.approx(f.contact_point_mm, abs=0.002)


def test_long_approach_and_long_ramp_are_resampled():
    """2 mm of approach (twice the reach) and 1500 points: the contact point is found, and
    the contact part reaches the fit of E as at most 200 presses evenly spaced in depth."""
    z, P, z0 = draw("ball", seed=2, start=-2.0, n=1500)
    f = fit("ball", z, P)
    assert f.contact_point_mm == pytest.approx(z0, abs=0.005)
    assert f.E_mpa == pytest.approx(0.5, rel=0.03)
    assert f.depth_mm.size <= 200 and f.indenter_fit.n_presses == f.depth_mm.size
    assert np.ptp(np.diff(f.depth_mm)) < 0.5 * np.median(np.diff(f.depth_mm))
    assert any("averaged in" in n for n in f.notes)


def test_max_depth_and_json():
    z, P, z0 = draw("ball", seed=4)
    f = fit("ball", z, P, max_depth_mm=0.4)
    assert f.depth_mm.max() <= 0.4
    assert any("max_depth_mm" in n for n in f.notes)
    assert f.contact_point_mm == pytest.approx(z0, abs=0.005)
    d = json.loads(json.dumps(f.to_json_dict()))
    assert d["contact_point_mm"] == pytest.approx(f.contact_point_mm)
    assert d["indenter_fit"]["E_mpa"] == pytest.approx(f.E_mpa)
    assert len(d["depth_mm"]) == f.depth_mm.size


def _write(path, header: str, rows: list[str]):
    path.write_text("\n".join([header, *rows]) + "\n")
    return path


def test_read_ramp_reads_what_was_written(tmp_path):
    z, P, z0 = draw("punch", seed=5, n=60)
    p = _write(tmp_path / "ramp.csv", "time_s,displacement_mm,force_n,note",
               [f"{0.1 * i:.1f},{float(a)!r},{float(b)!r},x"
                for i, (a, b) in enumerate(zip(z, P, strict=True))])
    ramp = read_ramp(p)
    assert isinstance(ramp, Ramp) and len(ramp) == 60
    assert np.array_equal(ramp.displacement_mm, z) and np.array_equal(ramp.force_n, P)
    assert ramp.time_s[-1] == pytest.approx(5.9)
    assert list(ramp.line_numbers[:2]) == [2, 3]
    f = fit_ramp(ramp.displacement_mm, ramp.force_n, PUNCH, thickness_mm=H_PUNCH, law="linear",
                 source=ramp.path)
    assert f.contact_point_mm == pytest.approx(z0, abs=0.005)
    p2 = _write(tmp_path / "r2.csv", "force_n,displacement_mm", [f"{i},{i}" for i in range(10)])
    assert read_ramp(p2).time_s is None


@pytest.mark.parametrize(("header", "rows", "match"), [
    ("displacement_mm,fz_n", [f"{i},{i}" for i in range(12)],
     r"line 1: missing required column\(s\) force_n"),
    ("displacement_mm,force_n", [f"{i},{i}" for i in range(3)] + ["3,abc"]
     + [f"{i},{i}" for i in range(4, 12)], r"line 5, column force_n: 'abc' is not a number"),
    ("displacement_mm,force_n", [f"{i},{i}" for i in range(5)] + ["inf,5"]
     + [f"{i},{i}" for i in range(6, 12)], r"line 7, column displacement_mm: 'inf' is not a "
                                           "finite"),
    ("displacement_mm,force_n", [f"{i},{i}" for i in range(5)] + [",5"]
     + [f"{i},{i}" for i in range(6, 12)], r"line 7, column displacement_mm: empty cell"),
    ("displacement_mm,force_n", [f"{i},{i}" for i in range(9)], r"has 9 data row\(s\)"),
    ("displacement_mm,force_n,time_s", [f"{i},{i},{i}" for i in range(5)] + ["5,5,1"]
     + [f"{i},{i},{i}" for i in range(6, 12)], r"line 7, column time_s: 1 s is earlier"),
])
def test_read_ramp_refuses_bad_files_naming_them(tmp_path, header, rows, match):
    p = _write(tmp_path / "bad.csv", header, rows)
    with pytest.raises(InputError, match=match) as err:
        read_ramp(p)
    assert str(p) in str(err.value)
    assert str(err.value).count(". ") == 0   # one sentence


def _ramp_file(tmp_path, z, P):
    rows = [f"{float(a)!r},{float(b)!r}" for a, b in zip(z, P, strict=True)]
    return read_ramp(_write(tmp_path / "ramp.csv", "displacement_mm,force_n", rows))


@pytest.mark.parametrize(("what", "match"), [
    ("unloading only", "has no loading part"),
    ("stage still", "has no loading part"),
    ("no contact", "has no contact"),
    ("past the reach", "fewer than 5 points lie between its contact point and 1 mm"),
    ("tiny max depth", r"0\.002 mm past it \(max_depth_mm\)"),
    ("starts in contact", "starts in contact"),
])
def test_fit_ramp_refuses_what_it_cannot_fit_naming_the_file(tmp_path, what, match):
    rng = np.random.default_rng(7)
    z, P, _ = draw("ball", seed=6, n=200)
    kw = {}
    if what == "unloading only":
        z, P = z[::-1], P[::-1]
    elif what == "stage still":
        z = 1.0 + 1e-4 * rng.standard_normal(z.size)
    elif what == "no contact":
        P = 0.03 + 0.002 * rng.standard_normal(z.size)
    elif what == "past the reach":   # the stage jumps from the approach to past the reach
        z = np.r_[np.linspace(-1.0, 0.0, 30), np.linspace(1.2, 2.0, 30)]
        P = (0.03 + BALL.force(np.maximum(z, 0), E_mpa=0.5, nu=0.5, thickness_mm=H_BALL)
             + 0.002 * rng.standard_normal(z.size))
    elif what == "tiny max depth":
        kw["max_depth_mm"] = 0.002
    elif what == "starts in contact":
        z, P, _ = draw("ball", seed=6, n=200, start=0.25)
    ramp = _ramp_file(tmp_path, z, P)
    with pytest.raises(InputError, match=match) as err:
        fit("ball", ramp.displacement_mm, ramp.force_n, source=ramp.path, **kw)
    assert str(ramp.path) in str(err.value)


def test_fit_ramp_checks_its_arguments():
    z, P, _ = draw("ball", n=50)
    with pytest.raises(InputError, match="force_n must have shape"):
        fit_ramp(z, P[:-1], BALL, thickness_mm=H_BALL)
    with pytest.raises(InputError, match="thickness_mm"):
        fit_ramp(z, P, BALL, thickness_mm=0)
    with pytest.raises(InputError, match="max_depth_mm"):
        fit_ramp(z, P, BALL, thickness_mm=H_BALL, max_depth_mm=-1)
    with pytest.raises(InputError, match="confidence"):
        fit_ramp(z, P, BALL, thickness_mm=H_BALL, confidence=1.5)


@pytest.mark.slow
def test_fit_ramp_on_the_command_line(tmp_path):
    """``tactilevision fit RAMP.csv --ramp`` with the geometry in the sidecar: the contact
    point and E of a flat-punch ramp (small-strain law, kappa of the FEM table); without the
    sidecar, one sentence naming what is missing, exit 2."""
    z, P, z0 = draw("punch", seed=3)
    rows = [f"{float(a)!r},{float(b)!r}" for a, b in zip(z, P, strict=True)]
    path = _write(tmp_path / "ramp.csv", "displacement_mm,force_n", rows)
    cmd = [sys.executable, "-m", "tactilevision", "fit", str(path), "--ramp", "--law", "linear"]
    r = subprocess.run(cmd, capture_output=True, text=True)
    assert r.returncode == 2
    assert "thickness_mm not given and no session.toml next to it" in r.stderr
    (tmp_path / "session.toml").write_text("[sensor]\ngel_thickness_mm = 3.0\n"
                                           "[indenter]\nradius_mm = 2.5\n")
    r = subprocess.run([*cmd, "--json", str(tmp_path / "ramp.json")], capture_output=True,
                       text=True)
    assert r.returncode == 0, r.stderr
    obj = json.loads((tmp_path / "ramp.json").read_text())
    assert obj["contact_point_mm"] == pytest.approx(z0, abs=0.005)
    assert obj["E_mpa"] == pytest.approx(0.2, rel=0.03)
    assert "contact point z0" in r.stdout
