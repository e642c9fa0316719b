"""tactilevision fem tables: the options reach the builders (the builds themselves, minutes
each, are tested in test_fem_tables / test_fem_beta_table), and bad options are named."""

from __future__ import annotations

import numpy as np
import pytest

import tactilevision.cli._fem_run as fem
from tactilevision.cli import main
from tactilevision.fem import build_kappa_table


@pytest.fixture
def builders(monkeypatch):
    """The table builders replaced by recorders (the names the command calls); write_table
    records what it was given."""
    calls: dict[str, dict] = {}

    def record(name):
        def build(**kw):
            calls[name] = kw
            return {"table": name}
        return build

    monkeypatch.setattr(fem, "build_kappa_table", record("kappa"))
    monkeypatch.setattr(fem, "build_beta_table", record("beta"))
    monkeypatch.setattr(fem, "write_table",
                        lambda path, table, *, command: calls.setdefault("written", []).append(
                            (path.name, table["table"], command)) or path)
    return calls


def test_options_reach_the_builders(builders, tmp_path, capsys):
    assert main(["fem", "tables", "--quick", "--no-progress", "--jobs", "2",
                 "--out-dir", str(tmp_path)]) == 0
    assert builders["kappa"]["progress"] is False and builders["beta"]["progress"] is False
    assert builders["beta"]["jobs"] == 2 and builders["kappa"]["jobs"] == 2
    assert builders["kappa"]["nu"] == [0.3, 0.45, 0.49]
    assert [w[:2] for w in builders["written"]] == [("kappa_fem.npz", "kappa"),
                                                    ("beta_fem.npz", "beta")]
    assert builders["written"][0][2].startswith("tactilevision fem tables --quick")
    builders.clear()
    assert main(["fem", "tables", "--what", "kappa", "--out-dir", str(tmp_path)]) == 0
    assert builders["kappa"]["progress"] is True and "beta" not in builders


@pytest.mark.parametrize("argv, words", [(["--what", "gamma"], "--what must name"),
                                         (["--what", "beta", "--jobs", "0"], "--jobs must be"),
                                         (["--what", "kappa", "--jobs", "0"], "--jobs must be")])
def test_bad_options_are_named(builders, tmp_path, capsys, argv, words):
    assert main(["fem", "tables", "--out-dir", str(tmp_path), *argv]) == 2
    assert words in capsys.readouterr().err
    assert "written" not in builders


def test_kappa_table_with_two_jobs_is_the_table_with_one():
    """--jobs for kappa: the columns built in two processes are those built in one (and the
    small-strain kappa of a thin bonded layer lies above the half-space's 1, Hayes 1972)."""
    kw = dict(nu=[0.3, 0.49], a_over_h=[0.5, 1.0], contacts=("bonded",), cell=0.25,
              edge_refinements=5, progress=False)
    one = build_kappa_table(**kw, jobs=1)
    two = build_kappa_table(**kw, jobs=2)
    assert two["meta"]["jobs"] == 2
    np.testing.assert_array_equal(one["kappa"], two["kappa"])
    assert np.all(one["kappa"] > 1.0)
