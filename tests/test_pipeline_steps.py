"""The main job run step by step, as docs/guide/calibrate.md shows it: each step's
result can be looked at, and the steps in order give what calibrate_session gives; the
calibration folder written by write_calibration reads back through CalibrationResult."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tactilevision import InputError
from tactilevision.contact import certify_session
from tactilevision.io import read_session
from tactilevision.pipeline import (
    CalibrationResult,
    DepthState,
    Fitter,
    calibrate_session,
    read_material,
    take_off_zero,
    vernier_rule,
    with_shared_depth,
    write_calibration,
)

SAMPLE = Path(__file__).resolve().parents[1] / "sample_frames" / "gelsight_session"


@pytest.fixture(scope="module")
def whole():
    return calibrate_session(SAMPLE, relaxation="off")


def test_the_steps_in_order_give_what_calibrate_session_gives(whole):
    session = read_session(SAMPLE)
    cert = certify_session(session)                      # decode, sync, certify
    assert len(cert.presses) == len(whole.certification.presses)
    assert cert.clock_offset_s == pytest.approx(whole.certification.clock_offset_s)
    session, cert, zero, notes = take_off_zero(session, cert, "auto")
    assert zero is not None and notes
    cfg = session.config
    presses = cert.presses
    force = np.array([p.force_n for p in presses])
    w0 = np.array([p.w0_mm for p in presses])
    closure = np.array([p.closure_mm for p in presses])
    fit_at = Fitter(force, thickness_mm=cfg.gel_thickness_mm,
                    radius_mm=cfg.indenter_radius_mm, beta_table="fem")
    st = DepthState(depth=w0 + closure, std=np.array([p.closure_std_mm for p in presses]),
                    bulge=np.zeros_like(w0), bevel_n=np.zeros_like(w0), notes=[])
    vernier_rule(st, presses, cert, cfg, fit_at, force, nu_start=0.48, max_rounds=8,
                 nu_tol=2e-4)
    np.testing.assert_allclose(st.depth, whole.depth_mm, rtol=1e-12)
    fit = st.fit
    if st.shared is not None:
        fit = with_shared_depth(fit, fit_at, st.depth, st.std, force - st.bevel_n, *st.shared)
    assert fit.E_mpa == pytest.approx(whole.fit.E_mpa, rel=1e-12)
    assert fit.nu == pytest.approx(whole.fit.nu, rel=1e-12)
    assert fit.E_ci95_mpa == pytest.approx(whole.fit.E_ci95_mpa, rel=1e-12)
    truth = json.loads((SAMPLE / "truth.json").read_text())
    assert fit.E_ci95_mpa[0] <= truth["E_mpa"] <= fit.E_ci95_mpa[1]


def test_the_folder_written_reads_back(whole, tmp_path):
    out = tmp_path / "cal"
    written = write_calibration(whole, out, report=False)
    assert written.folder == out
    back = CalibrationResult.load(out)
    assert back.E_mpa == pytest.approx(whole.fit.E_mpa, rel=1e-12)
    assert back.nu_ci95 == pytest.approx(whole.fit.nu_ci95, rel=1e-12)
    assert back.n_presses == len(whole.certification.presses)
    assert [r["press"] for r in back.rejected] == [r.press for r in
                                                   whole.certification.rejected]
    np.testing.assert_allclose(back.measurements["depth_mm"], whole.depth_mm, rtol=1e-5)  # 6 digits
    assert back.thickness_mm == whole.session.config.gel_thickness_mm
    assert back.holds is not None and back.holds["press"].size > 0
    E, nu, obj = read_material(out / "fit.json")
    assert (E, nu) == (back.E_mpa, back.nu) and obj["depth_rule"] == "vernier"
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".")) == sorted(
        ["fit.json", "holds.csv", "measurements.csv", "rejected.csv", "session.toml"])


@pytest.mark.parametrize("content, words", [
    ("not json", "is not valid JSON"), ("[1, 2]", "is not a JSON object"),
    ('{"E_mpa": "x", "nu": 0.4}', "no numeric E_mpa and nu")])
def test_a_broken_fit_json_is_named(tmp_path, content, words):
    bad = tmp_path / "fit.json"
    bad.write_text(content)
    with pytest.raises(InputError, match=words) as exc:
        read_material(bad)
    assert str(bad) in str(exc.value)


def test_a_folder_without_fit_json_is_named(tmp_path):
    with pytest.raises(InputError, match=r"has no fit\.json"):
        CalibrationResult.load(tmp_path)
    (tmp_path / "rejected.csv").write_text("press,reason,detail,t_frame_s,bevel_snr\nx,a,b,c,\n")
    with pytest.raises(InputError, match=r"rejected.csv, line 2"):
        CalibrationResult.load(tmp_path, require_fit=False)
