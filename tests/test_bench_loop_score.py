"""The rule that scores benchmarks/bench_loop.py's rows (docs/loop.md), on rows whose
right answer is written out here: the Taxim scores the docs quote rest on it."""

from __future__ import annotations

import pytest
from _data import load_benchmark


@pytest.fixture(scope="module")
def score():
    return load_benchmark("bench_loop").score


def _row(kind, verdict=None, fitted=None, equivalent=(), unexplained=None):
    return {"kind": kind, "verdict": verdict, "fitted": fitted,
            "equivalent": list(equivalent), "unexplained": unexplained}


@pytest.mark.parametrize(("row", "want"), [
    (_row("null"), "yes"),
    (_row("null", "force_offset"), "no"),
    (_row("null", fitted="stiffness_trend:time_s", unexplained="time_s"), "no"),
    (_row("offset"), "yes"),                      # calibrate took the F/T zero off
    (_row("offset", "force_offset"), "yes"),
    (_row("spatial"), "no"),
    (_row("spatial", "spatial_nonuniformity"), "yes"),
    (_row("softening", fitted="stiffness_trend:press", unexplained="press"), "yes"),
    (_row("softening", "stiffness_step:press", equivalent=("stiffness_step:time_s",)),
     "shape"),
    (_row("softening", "stiffness_step:press", equivalent=("stiffness_trend:time_s",)),
     "yes"),
    (_row("damage", fitted="stiffness_trend:time_s", unexplained="time_s"), "shape"),
    (_row("damage", "stiffness_step:time_s"), "yes"),
    (_row("damage", "force_drift"), "no"),
    (_row("relaxation", "viscoelastic_relaxation"), "yes"),
    (_row("relaxation"), "no"),
])
def test_each_kind_is_scored_by_what_it_hid(score, row, want):
    assert score(row) == want
