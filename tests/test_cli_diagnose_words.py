"""diagnose's summary line says its verdict in words: no Python None or [] (issue 86)."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from tactilevision.cli._diagnose_run import _verdict_words


@pytest.mark.parametrize(("missing", "equivalent", "covariate", "expected"), [
    (None, (), None, "no missing effect named"),
    (None, (), "temperature_c", "no missing effect named; unexplained covariate temperature_c"),
    ("stiffness_step:press", ("stiffness_step:time_s",), None,
     "missing effect stiffness_step:press (equivalent: stiffness_step:time_s)"),
    ("force_offset", (), None, "missing effect force_offset"),
])
def test_the_verdict_reads_as_words(missing, equivalent, covariate, expected):
    diag = SimpleNamespace(missing_effect=missing, equivalent_effects=equivalent,
                           unexplained_covariate=covariate)
    words = _verdict_words(diag)
    assert words == expected
    assert "None" not in words and "[]" not in words
