"""``tactilevision fit``: exit status, stderr sentences, JSON values (formats.md §3)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from _data import load_benchmark

from tactilevision.cli import main
from tactilevision.mechanics import fit_indentation

ROOT = Path(__file__).resolve().parent.parent
SAMPLE = ROOT / "sample_frames" / "paper_line6"
DEPTHS = (0.15, 0.30, 0.40, 0.50, 0.60)
SESSION = "[sensor]\ngel_thickness_mm = 3.0\n\n[indenter]\nradius_mm = 2.5\n"


def line6(w: float) -> float:
    """Force on the paper's line (6), N."""
    return w * (5.2662 * w / 3.0 + 3.4943)


def write_table(folder: Path, text: str | None = None, session: str | None = SESSION) -> Path:
    """Write measurements.csv (default: the paper's line at the five depths) and session.toml."""
    if text is None:
        text = "press,depth_mm,force_n,hold_s\n" + "".join(
            f"{i},{w},{line6(w):.6f},{'' if i == 2 else 1.5}\n" for i, w in enumerate(DEPTHS))
    csv = folder / "measurements.csv"
    csv.write_text(text)
    if session is not None:
        (folder / "session.toml").write_text(session)
    return csv


# These tests check the paper's method on the paper's numbers: they run with
# --beta-table paper unless they name a table (the FEM default is tested below).
PAPER = ["--beta-table", "paper"]


def _paper(argv: list[str]) -> list[str]:
    return argv if argv[:1] != ["fit"] or "--beta-table" in argv else [*argv, *PAPER]


def run_json(argv: list[str], capsys) -> dict:
    assert main([*_paper(argv), "--json", "-"]) == 0
    return json.loads(capsys.readouterr().out)


def error_line(argv: list[str], capsys) -> str:
    """Run, expect exit status 2 and one sentence on stderr; return it."""
    assert main(_paper(argv)) == 2
    cap = capsys.readouterr()
    lines = cap.err.strip().splitlines()
    assert len(lines) == 1, cap.err
    assert lines[0].startswith("tactilevision fit: error: ")
    assert cap.out == ""
    return lines[0]


# ------------------------------------------------------------------ success


def test_json_paper_line(tmp_path, capsys):
    csv = write_table(tmp_path)
    d = run_json(["fit", str(csv), "--a-over-h", "0.8"], capsys)
    assert d["nu"] == pytest.approx(0.4797, abs=1e-3)
    assert d["E_mpa"] == pytest.approx(0.1981, rel=0.01)
    assert d["c_n_per_mm"] == pytest.approx(3.4943, abs=1e-4)
    assert d["beta"] == pytest.approx(1.5071, abs=1e-4)
    assert d["n_presses"] == 5
    assert d["effects"] == ["large_deformation"]
    assert d["effect_params"]["beta"] == d["beta"]
    assert len(d["E_ci95_mpa"]) == 2 and len(d["nu_ci95"]) == 2
    assert d["rmse_n"] == pytest.approx(0.0, abs=1e-5)
    assert d["a_over_h"] == 0.8 and d["beta_table"] == "paper"
    assert d["thickness_source"].endswith("session.toml [sensor] gel_thickness_mm")


def test_json_default_uses_exact_a_over_h(tmp_path, capsys):
    csv = write_table(tmp_path)
    d = run_json(["fit", str(csv)], capsys)
    w = np.array(DEPTHS)
    lib = fit_indentation(w, [float(f"{line6(x):.6f}") for x in w], thickness_mm=3.0,
                          radius_mm=2.5, beta_table="paper")
    assert d["a_over_h"] == pytest.approx(2.5 / 3.0)
    assert d["E_mpa"] == pytest.approx(lib.E_mpa, rel=1e-12)
    assert d["E_mpa"] < 0.1981 * 0.97  # kappa at 0.8333 > kappa at 0.8


def test_summary_and_json_file(tmp_path, capsys):
    csv = write_table(tmp_path)
    out = tmp_path / "fit.json"
    assert main(["fit", str(csv), "--effects", "large_deformation", *PAPER,
                 "--json", str(out)]) == 0
    text = capsys.readouterr().out
    for word in ("E  =", "nu =", "95% CI", "c = ", "beta = ", "C10", "D1", "R^2",
                 "the paper's relation (7)", "Hayes 1972"):
        assert word in text
    d = json.loads(out.read_text())
    assert d["n_presses"] == 5 and math.isfinite(d["E_mpa"])
    assert not (tmp_path / "fit.json.tmp").exists()


def test_geometry_from_options_without_session(tmp_path, capsys):
    csv = write_table(tmp_path, session=None)
    d = run_json(["fit", str(csv), "--thickness-mm", "3", "--radius-mm", "2.5",
                  "--a-over-h", "0.8"], capsys)
    assert d["nu"] == pytest.approx(0.4797, abs=1e-3)
    assert d["thickness_source"] == d["radius_source"] == "argument"


def test_options_override_session(tmp_path, capsys):
    csv = write_table(tmp_path, session="[sensor]\ngel_thickness_mm = 9.0\n")
    d = run_json(["fit", str(csv), "--thickness-mm", "3.0", "--radius-mm", "2.5"], capsys)
    assert d["thickness_mm"] == 3.0


def test_deep_press_warns_but_fits(tmp_path, capsys):
    rows = "".join(f"{w},{line6(w):.6f}\n" for w in (0.15, 0.3, 0.6, 0.9))
    csv = write_table(tmp_path, "depth_mm,force_n\n" + rows)
    assert main(["fit", str(csv), *PAPER, "--json", "-"]) == 0
    cap = capsys.readouterr()
    assert "warning" in cap.err and "w/h = 0.300 > 0.2" in cap.err and str(csv) in cap.err
    assert any("w/h = 0.300" in n for n in json.loads(cap.out)["notes"])


def test_out_of_table_reported_with_exit_3(tmp_path, capsys):
    """A refused fit is reported (summary, JSON) and exits non-zero (issue 54, item 6):
    a script must not take it as a fit."""
    rows = "".join(f"{w},{w * (9.0 * w / 3 + 3.0):.6f}\n" for w in DEPTHS)  # beta = 3
    csv = write_table(tmp_path, "depth_mm,force_n\n" + rows)
    assert main([*_paper(["fit", str(csv)]), "--json", "-"]) == 3
    d = json.loads(capsys.readouterr().out)
    assert d["out_of_table"] is True and d["E_mpa"] is None and d["nu"] is None
    assert "nu in [0.30, 0.50)" in d["out_of_table_message"]
    assert main(["fit", str(csv), *PAPER]) == 3
    cap = capsys.readouterr()
    assert "OUT OF TABLE" in cap.out and "exit status 3" in cap.err


def test_help(capsys):
    with pytest.raises(SystemExit) as info:
        main(["fit", "--help"])
    assert info.value.code == 0
    out = capsys.readouterr().out
    for opt in ("--thickness-mm", "--radius-mm", "--beta-table", "--effects", "--a-over-h",
                "--json"):
        assert opt in out


# ---------------------------------------------------------------- bad input


@pytest.mark.parametrize("text, expected", [
    ("depth_mm,weight\n0.15,0.5\n", ["line 1", "missing required column(s) force_n"]),
    ("press,force_n\n0,0.5\n", ["line 1", "depth_mm"]),
    ("depth_mm,force_n\n0.15,0.56\n0.30,abc\n", ["line 3", "column force_n", "'abc'"]),
    ("depth_mm,force_n,hold_s\n0.15,0.56,1\n0.3,1.2,1.5s\n", ["line 3", "column hold_s",
                                                               "'1.5s'"]),
    ("depth_mm,force_n\n0.15,0.56\n0.30,\n", ["line 3", "column force_n", "empty cell"]),
    ("depth_mm,force_n\n0.15,0.56\n-0.30,1.2\n", ["line 3", "depth_mm", "positive"]),
    ("depth_mm,force_n\n0.15,0.56\n0,1.2\n", ["line 3", "depth_mm", "positive"]),
    ("depth_mm,force_n\n0.15,0.56\n0.30,1.2,7\n", ["line 3", "3 cells", "header has 2"]),
    ("depth_mm,force_n\n", ["no data rows"]),
    ("", ["empty"]),
    ("depth_mm,force_n,depth_mm\n0.1,0.2,0.3\n", ["line 1", "'depth_mm' appears twice"]),
    ("depth_mm,force_n\n0.3,1.2\n0.3,1.21\n", ["two depths"]),
])
def test_bad_table(tmp_path, capsys, text, expected):
    csv = write_table(tmp_path, text)
    msg = error_line(["fit", str(csv)], capsys)
    assert str(csv) in msg
    for part in expected:
        assert part in msg


def test_missing_file(tmp_path, capsys):
    msg = error_line(["fit", str(tmp_path / "nope.csv")], capsys)
    assert "nope.csv" in msg and "not found" in msg


@pytest.mark.parametrize("session, expected", [
    (None, ["no session.toml", "thickness_mm", "--thickness-mm"]),
    ("[sensor]\ngel_thickness_mm = 3.0\n", ["session.toml", "missing key [indenter] radius_mm"]),
    ("[indenter]\nradius_mm = 2.5\n", ["session.toml",
                                       "missing key [sensor] gel_thickness_mm"]),
    ("[sensor]\ngel_thickness_mm = 3.0\n[indenter\nradius_mm = 2.5\n",
     ["session.toml", "not valid TOML", "line 3"]),
    ("[sensor]\ngel_thickness_mm = \"3\"\n[indenter]\nradius_mm = 2.5\n",
     ["session.toml", "[sensor] gel_thickness_mm must be a positive number"]),
    ("[sensor]\ngel_thickness_mm = 3.0\n[indenter]\nradius_mm = -2.5\n",
     ["session.toml", "[indenter] radius_mm must be a positive number"]),
])
def test_bad_session(tmp_path, capsys, session, expected):
    csv = write_table(tmp_path, session=session)
    msg = error_line(["fit", str(csv)], capsys)
    for part in expected:
        assert part in msg


def test_missing_radius_only(tmp_path, capsys):
    csv = write_table(tmp_path, session=None)
    msg = error_line(["fit", str(csv), "--thickness-mm", "3"], capsys)
    assert "radius_mm" in msg and "--radius-mm" in msg


@pytest.mark.parametrize("argv, expected", [
    (["--effects", "aging"], ["needs the column(s) day"]),
    (["--effects", "large_deformation,force_drift"], ["needs the column(s) time_s"]),
    (["--effects", "stiffness_trend:day"], ["stiffness_trend:day", "day"]),
    (["--effects", "creep"], ["unknown effect 'creep'", "valid names", "large_deformation",
                              "viscoelastic_relaxation"]),
    (["--thickness-mm", "-3"], ["thickness_mm must be a positive number"]),
    (["--radius-mm", "0"], ["radius_mm must be a positive number"]),
    (["--a-over-h", "3"], ["a_over_h = 3", "[0.2, 2]"]),
    (["--a-over-h", "nan"], ["--a-over-h must be a finite number"]),
])
def test_bad_options(tmp_path, capsys, argv, expected):
    csv = write_table(tmp_path)
    msg = error_line(["fit", str(csv), *argv], capsys)
    for part in expected:
        assert part in msg


def test_error_keeps_previous_json(tmp_path, capsys):
    csv = write_table(tmp_path, "depth_mm,force_n\n0.15,x\n")
    out = tmp_path / "fit.json"
    out.write_text('{"old": true}\n')
    error_line(["fit", str(csv), "--json", str(out)], capsys)
    assert out.read_text() == '{"old": true}\n'
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fit.json", "measurements.csv",
                                                          "session.toml"]


def test_unwritable_json_is_input_error(tmp_path, capsys):
    """A --json path under a file cannot be written: refused before any work (a missing
    folder is created, as for output folders)."""
    csv = write_table(tmp_path)
    (tmp_path / "a_file").write_text("x")
    msg = error_line(["fit", str(csv), "--json", str(tmp_path / "a_file" / "f.json")],
                     capsys)
    assert "cannot write" in msg and "a_file is a file" in msg
    assert main(_paper(["fit", str(csv), "--json", str(tmp_path / "no" / "dir" / "f.json")])
                ) == 0
    assert (tmp_path / "no" / "dir" / "f.json").is_file()


# ------------------------------------------------------------- demo sample


def _generator():
    return load_benchmark("make_paper_line6")


def test_sample_is_what_the_generator_writes():
    gen = _generator()
    assert (SAMPLE / "measurements.csv").read_text() == gen.measurements_csv()
    assert (SAMPLE / "session.toml").read_text() == gen.SESSION_TOML
    assert (SAMPLE / "README.md").read_text() == gen.readme()


def test_sample_fit_near_paper(capsys):
    d = run_json(["fit", str(SAMPLE / "measurements.csv"), "--a-over-h", "0.8"], capsys)
    assert d["n_presses"] == 50
    assert d["nu"] == pytest.approx(0.4797, abs=0.005)
    assert d["E_mpa"] == pytest.approx(0.1981, rel=0.02)
    assert d["nu_ci95"][0] < d["nu"] < d["nu_ci95"][1]


# ------------------------------------------------- the default: FEM tables


def test_default_fem_tables_on_the_papers_line(tmp_path, capsys):
    # the paper's beta = 1.507 is beyond a bonded Neo-Hookean layer at
    # a/h = 0.83 (tests/test_fem_beta_table.py): no E, nu, and the message
    # names the FEM range; exit status 3, as for any out-of-table fit
    csv = write_table(tmp_path)
    assert main(["fit", str(csv), "--json", "-"]) == 3
    d = json.loads(capsys.readouterr().out)
    assert d["beta_table"] == "fem" and d["kappa_source"] == "fem"
    assert d["contact"] == "bonded"
    assert d["out_of_table"] is True and d["nu"] is None
    assert "bonded punch" in d["out_of_table_message"]
    assert d["beta"] == pytest.approx(1.5071, abs=1e-4)


def test_default_fem_tables_recover_a_fem_layer(tmp_path, capsys):
    # presses on the FEM's own force-depth law: kappa_n of the stored table at
    # a/h = 1.2, nu = 0.47 and five of its depths (w/h = 0.04 ... 0.2), P =
    # 2 a E kappa_n w / (1 - nu^2) (eq. 1): the default fit returns E and nu
    from tactilevision.mechanics._fem_tables import _load

    t = _load("beta_fem.npz")
    h, a, E, nu = 2.5, 3.0, 0.15, 0.47
    i, j = list(t["a_over_h"]).index(a / h), list(t["nu"]).index(nu)
    k = np.arange(1, 10, 2)
    w = t["w_over_h"][k] * h
    P = 2 * a * E * t["kappa_n"][0, i, j, k] * w / (1 - nu**2)
    rows = "".join(f"{x:.6f},{f:.10f}\n" for x, f in zip(w, P, strict=True))
    csv = write_table(tmp_path, "depth_mm,force_n\n" + rows,
                      session=f"[sensor]\ngel_thickness_mm = {h}\n\n[indenter]\nradius_mm = {a}\n")
    assert main(["fit", str(csv), "--json", "-"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["E_mpa"] == pytest.approx(E, rel=1e-6) and d["nu"] == pytest.approx(nu, abs=1e-6)
    assert main(["fit", str(csv)]) == 0
    assert "FEM tables, bonded punch" in capsys.readouterr().out


def test_fit_with_an_effect_recovers_it(tmp_path, capsys):
    """--effects adds catalogue effects; the JSON keeps its keys and holds their parameters."""
    rng = np.random.default_rng(4)
    w = np.repeat(DEPTHS, 8)
    wait = rng.uniform(0.3, 20.0, w.size)
    P = line6(w) * (1 + 0.08 * np.exp(-wait / 2.5)) + rng.normal(0, 0.002, w.size)
    rows = "".join(f"{i},{a},{b:.6f},{c:.3f}\n"
                   for i, (a, b, c) in enumerate(zip(w, P, wait, strict=True)))
    csv = write_table(tmp_path, "press,depth_mm,force_n,wait_s\n" + rows)
    plain = run_json(["fit", str(csv)], capsys)
    d = run_json(["fit", str(csv), "--effects", "incomplete_recovery"], capsys)
    for key in ("E_mpa", "nu", "c_n_per_mm", "beta", "E_ci95_mpa", "nu_ci95", "rmse_n",
                "n_presses", "effects", "effect_params"):
        assert key in d
    assert d["effects"] == ["large_deformation", "incomplete_recovery"]
    ep = d["effect_params"]
    assert ep["incomplete_recovery.r"] == pytest.approx(0.08, abs=0.03)
    assert ep["incomplete_recovery.tau_s"] == pytest.approx(2.5, rel=0.3)
    assert d["rmse_n"] < 0.4 * plain["rmse_n"]
    assert d["rmse_n"] == pytest.approx(0.002, rel=0.3)
    ref = fit_indentation(np.array(DEPTHS), line6(np.array(DEPTHS)), thickness_mm=3.0,
                          radius_mm=2.5, beta_table="paper")
    assert d["E_mpa"] == pytest.approx(ref.E_mpa, rel=0.05)
    assert abs(plain["E_mpa"] / ref.E_mpa - 1) > abs(d["E_mpa"] / ref.E_mpa - 1)
    main(["fit", str(csv), "--effects", "incomplete_recovery", *PAPER])
    out = capsys.readouterr().out
    assert "incomplete_recovery.tau_s" in out
    assert "eq. (5) [layer + large_deformation] + incomplete_recovery" in out


def test_unidentified_fit_says_so(tmp_path, capsys):
    """issue 23: viscoelastic_relaxation on a constant hold_s cannot separate c, g and
    tau. The fit is printed and written, but the headline says so, the JSON has
    ``identified: false`` with the parameters named, and the exit status is 3; the
    same table without the effect is identified (exit 0)."""
    from tactilevision.io import write_measurements
    from tactilevision.sim import make_measurement_table

    t = make_measurement_table(None, 3)
    cols = dict(t.columns)
    cols["hold_s"] = np.full(cols["depth_mm"].size, 0.5)
    csv = tmp_path / "m.csv"
    write_measurements(csv, cols, thickness_mm=t.thickness_mm, radius_mm=t.radius_mm)
    out = tmp_path / "fit.json"
    assert main(["fit", str(csv), "--effects", "viscoelastic_relaxation",
                 "--json", str(out)]) == 3
    cap = capsys.readouterr()
    assert "NOT IDENTIFIED by this table" in cap.out
    assert "not identified by these data" in cap.err and "exit status 3" in cap.err
    obj = json.loads(out.read_text())
    assert obj["identified"] is False
    assert "viscoelastic_relaxation.g" in obj["unidentified"]
    assert main(["fit", str(csv), "--json", str(out)]) == 0
    assert json.loads(out.read_text())["identified"] is True
    assert "NOT IDENTIFIED" not in capsys.readouterr().out


def test_a_mark_tables_shared_depth_error_is_not_read_as_a_misfit(tmp_path, capsys):
    """A table as calibrate's mark rule writes it: 5 indenters x 4 presses on the paper's
    line (6), each indenter's depths off by one shared error (15 um, stated as
    depth_indenter_std_mm, counted n = 4 times over in depth_std_mm). Without the
    indenter columns ``fit`` reads the runs along depth as a misfit and widens E's
    interval; with them it does not, and E is the same."""
    rng = np.random.default_rng(5)
    ind = np.repeat(np.arange(5), 4)
    w_true = np.array(DEPTHS)[ind] + rng.uniform(0.0, 0.04, ind.size)
    w = w_true + np.array([0.02, -0.02, 0.015, -0.015, 0.02])[ind]
    P = np.array([line6(v) for v in w_true])
    rows = "".join(f"{i},{g},{a:.6f},0.03,0.03,{b:.6f}\n"
                   for i, (g, a, b) in enumerate(zip(ind, w, P, strict=True)))
    csv = write_table(tmp_path, "press,indenter,depth_mm,depth_std_mm,depth_indenter_std_mm,"
                      "force_n\n" + rows)
    grouped = run_json(["fit", str(csv)], capsys)
    (tmp_path / "plain").mkdir()
    plain_csv = write_table(tmp_path / "plain", "press,depth_mm,depth_std_mm,force_n\n" + "".join(
        f"{i},{a:.6f},0.03,{b:.6f}\n" for i, (a, b) in enumerate(zip(w, P, strict=True))))
    plain = run_json(["fit", str(plain_csv)], capsys)
    assert plain["misfit"]["factor"] > 1.5
    assert grouped["misfit"]["factor"] == 1.0
    assert grouped["E_mpa"] == pytest.approx(plain["E_mpa"], rel=1e-12)
    lo, hi = grouped["E_ci95_mpa"]
    plo, phi = plain["E_ci95_mpa"]
    assert hi - lo < (phi - plo) / 1.5
