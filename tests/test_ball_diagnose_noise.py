"""A ball's diagnosis on the fit's noise model: the presses' stated uncertainties weigh every
rung, the circles' shared error is fitted within its bound, and the final model is tested
against what was stated.

Ground truth: presses drawn from the sphere table's small-strain law (nothing missing)
whose depths are read through contact circles with a known bias shared by every press and
a random error per press, both within what the certification states."""

import json
import subprocess
import sys

import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.diagnosis import diagnose_indenter
from tactilevision.mechanics import Sphere

PX = 0.0295          # mm per pixel
BALL, H, E = Sphere(2.0), 2.0, 0.25


def _circle_presses(seed: int, bias_px: float, law: str = "linear", sd_px: float = 0.5,
                    bound_px: float = 1.5):
    """Presses whose depths come from circles off by `bias_px` (shared) and `sd_px`
    (random): depths, forces (2 mN noise), and the stated depth_std and depth_shared."""
    rng = np.random.default_rng(seed)
    w = np.repeat(np.linspace(0.08, 0.7, 8), 3)
    P = BALL.force(w, E_mpa=E, nu=0.5, thickness_mm=H, law=law, contact="frictionless")
    P = P + rng.normal(0.0, 0.002, w.size)
    a = BALL.contact_radius(w, nu=0.5, thickness_mm=H) + PX * (
        bias_px + rng.normal(0.0, sd_px, w.size))
    wm = BALL.depth_from_contact_radius(a, nu=0.5, thickness_mm=H)
    dwda = (BALL.depth_from_contact_radius(a + 1e-4, nu=0.5, thickness_mm=H) - wm) / 1e-4
    return wm, P, dwda * sd_px * PX, dwda * bound_px * PX


@pytest.mark.slow
def test_shared_circle_error_is_not_named_as_physics():
    """Circles all 1.5 px small (the stated bound): read as exact, the ladder names an
    effect (a depth offset) on several seeds; with the fit's noise model it names nothing on
    at least 9 of 10, and lists what the shared error explains as not testable."""
    false_plain, false_noise, untestable = 0, 0, set()
    for seed in range(10):
        w, P, sd, shared = _circle_presses(seed, -1.5)
        plain = diagnose_indenter(w, P, BALL, thickness_mm=H, contact="frictionless")
        d = diagnose_indenter(w, P, BALL, thickness_mm=H, contact="frictionless",
                              depth_std_mm=sd, depth_shared_mm=shared)
        false_plain += plain.missing_effects != ()
        false_noise += d.missing_effects != ()
        untestable |= set(d.not_testable)
        assert d.noise["stated"] and d.noise["shared"]
        assert -1.0 <= d.ladder[-1].shared_shift <= 1.0
    assert false_plain >= 3
    assert false_noise <= 1
    assert "depth_offset" in untestable


def test_finite_strain_still_found_when_the_depths_are_good():
    """Deep presses drawn from the Neo-Hookean table (tied, w/h to 0.4) with small stated
    depth errors: the noise model keeps the power to name large_deformation, and the final
    model's residuals are what the stated uncertainties explain."""
    rng = np.random.default_rng(3)
    w = np.repeat([0.1, 0.2, 0.3, 0.45, 0.6, 0.8], 4)
    P = BALL.force(w, E_mpa=E, nu=0.5, thickness_mm=H, law="neo_hookean", contact="tied")
    u = np.full(w.size, 0.0005)
    wm = w + rng.normal(0.0, 0.0005, w.size)
    P = P + rng.normal(0.0, 0.002, w.size)
    d = diagnose_indenter(wm, P, BALL, thickness_mm=H, contact="tied", depth_std_mm=u,
                          force_std_n=np.full(w.size, 0.002), depth_shared_mm=0.0005)
    assert d.missing_effects[:1] == ("large_deformation",)
    assert d.ladder[-1].E_mpa == pytest.approx(E, rel=0.02)
    t = d.noise["test"]
    assert t is not None and t["p_value"] > 0.001 and t["p_low"] > 0.001
    assert "what the stated uncertainties explain" in d.message


@pytest.mark.parametrize(("scale", "phrase", "key"), [
    (10.0, "larger than the presses' scatter", "p_low"),
    (0.1, "exceed what the stated uncertainties explain", "p_value"),
])
def test_stated_uncertainties_tested(scale, phrase, key):
    """Uncertainties stated ten times too large, or ten times too small, are called so."""
    rng = np.random.default_rng(5)
    w = np.repeat(np.linspace(0.08, 0.7, 8), 3)
    P = BALL.force(w, E_mpa=E, nu=0.5, thickness_mm=H, law="linear", contact="frictionless")
    P = P + rng.normal(0.0, 0.002, w.size)
    d = diagnose_indenter(w, P, BALL, thickness_mm=H, contact="frictionless",
                          force_std_n=np.full(w.size, 0.002 * scale))
    assert d.noise["test"][key] < 0.001
    assert phrase in d.message


def test_bad_uncertainty_names_the_press():
    w, P, sd, _ = _circle_presses(0, 0.0)
    sd[4] = -1e-3
    with pytest.raises(InputError, match="press 4: depth_std_mm"):
        diagnose_indenter(w, P, BALL, thickness_mm=H, depth_std_mm=sd)
    with pytest.raises(InputError, match="depth_shared_rel"):
        diagnose_indenter(w, P, BALL, thickness_mm=H, depth_shared_rel=1.5)


@pytest.mark.slow
def test_cli_diagnose_reads_the_tables_uncertainties(tmp_path):
    """`diagnose` of a ball's table takes its depth_std_mm, depth_shared_mm and force_sem_n
    columns, as `fit` does, and says so in its JSON."""
    w, P, sd, shared = _circle_presses(2, -1.5)
    folder = tmp_path / "s"
    folder.mkdir()
    rows = "".join(f"{a:.6f},{b:.8f},{c:.6f},{d:.6f},0.002\n"
                   for a, b, c, d in zip(w, P, sd, shared, strict=True))
    path = folder / "presses.csv"
    path.write_text("depth_mm,force_n,depth_std_mm,depth_shared_mm,force_sem_n\n" + rows)
    (folder / "session.toml").write_text('[sensor]\ngel_thickness_mm = 2.0\n[indenter]\n'
                                         'shape = "sphere"\nradius_mm = 2.0\n')
    r = subprocess.run([sys.executable, "-m", "tactilevision", "diagnose", str(path),
                        "--json", str(tmp_path / "d.json")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    obj = json.loads((tmp_path / "d.json").read_text())
    assert obj["noise"]["stated"] and obj["noise"]["shared"]
    direct = diagnose_indenter(w, P, BALL, thickness_mm=H, depth_std_mm=sd,
                               depth_shared_mm=shared, force_std_n=np.full(w.size, 0.002))
    assert obj["missing_effects"] == list(direct.missing_effects)
    assert obj["noise"]["test"]["dof"] == w.size - direct.ladder[-1].n_params - 1
    assert obj["ladder"][0]["E_mpa"] == pytest.approx(direct.ladder[0].E_mpa, rel=1e-4)
    assert "shared error" in r.stdout
