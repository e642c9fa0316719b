"""The ball-on-a-finite-pad sweeps the FEATS sample needs ship in models/ and are read
without a FEM solve (issue: first use in seconds)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import tactilevision.mechanics._indenter as indenter_module
from tactilevision.mechanics import SHIPPED_PAD_SWEEPS, Sphere, fem_table_meta, pad_sweep_key
from tactilevision.mechanics._pad_sweeps import shipped_pad_sweep


def test_every_listed_sweep_ships_complete_to_the_reach():
    for key in SHIPPED_PAD_SWEEPS:
        w, f, a = shipped_pad_sweep(*key)
        assert w[0] == pytest.approx(key[5]) and w[-1] == pytest.approx(0.5)
        assert np.all(np.diff(w) > 0) and np.all(f > 0) and np.all(a > 0)
    assert shipped_pad_sweep(1.875, 0.45, 3.23, "linear", "tied", 0.04) is None
    meta = fem_table_meta("sphere_pad_sweeps.npz")
    assert meta["command"].startswith("tactilevision fem tables") and "pad" in meta["command"]


def test_the_feats_ball_reads_the_shipped_sweep_without_solving(monkeypatch):
    """The FEATS gel's ball (R 7.5 mm, h 4 mm, pad 12.92 mm) at nu 0.5: its force comes
    from the shipped table (a FEM solve would raise here), and the tied contact is stiffer
    than the frictionless at depth, as a no-slip contact must be."""
    def no_solve(*args, **kw):
        raise AssertionError(f"a FEM sweep was run for {args}")

    indenter_module._pad_sweep.cache_clear()
    monkeypatch.setattr(indenter_module, "pad_sweep_result", no_solve)
    ball = Sphere(7.5, pad_radius_mm=12.92)
    w = np.array([0.5, 1.0, 1.5, 2.0])
    key = ball.sweep_key(w / 4.0, 0.5, 4.0, "linear", "tied")
    assert pad_sweep_key(*key) == json.dumps([1.875, 0.5, 3.23, "linear", "tied", 0.04, None,
                                              None])
    tied = ball.force(w, E_mpa=0.4, nu=0.5, thickness_mm=4.0, law="linear", contact="tied")
    slip = ball.force(w, E_mpa=0.4, nu=0.5, thickness_mm=4.0, law="linear",
                      contact="frictionless")
    assert np.all(tied > 0) and tied[-1] > slip[-1]
    indenter_module._pad_sweep.cache_clear()


def _feats() -> tuple[np.ndarray, np.ndarray]:
    from pathlib import Path
    data = np.loadtxt(Path(__file__).resolve().parents[1] / "sample_frames" / "feats"
                      / "force_depth.csv", delimiter=",", skiprows=1)
    return data[:, 0], data[:, 1]


def test_feats_fit_warns_of_its_drift_and_holds_what_diagnose_selects():
    """The real FEATS gel read by fit's defaults (tied, linear, nu 0.5): its apparent E
    drifts 21 %, which fit warns of and holds in E's interval, and that interval holds the
    E of the model diagnose selects; depths shifted 0.05 mm either way (a contact point
    off) are fitted, not refused, and the shift toward the gel is named a depth offset."""
    from tactilevision.diagnosis import diagnose_indenter
    from tactilevision.mechanics import fit_indenter

    ball = Sphere(7.5, pad_radius_mm=12.92)
    w, P = _feats()
    kw = {"thickness_mm": 4.0, "contact": "tied"}
    fit = fit_indenter(w, P, ball, law="linear", **kw)
    assert fit.misfit.drifts and fit.misfit.drift == pytest.approx(-0.21, abs=0.01)
    assert any(n.startswith("warning:") for n in fit.notes)
    chosen = diagnose_indenter(w, P, ball, **kw).ladder[-1].E_mpa
    assert fit.E_ci95_mpa[0] <= chosen <= fit.E_ci95_mpa[1]
    for shift in (-0.05, 0.05):
        f = fit_indenter(w + shift, P, ball, law="linear", **kw)
        assert f.E_ci95_mpa[0] > 0
    d = diagnose_indenter(w - 0.05, P, ball, **kw)
    assert "depth_offset" in d.missing_effects and d.ladder[-1].depth_offset_mm > 0.05
