"""The Examples sections of the public docstrings run and give what they show."""

import doctest
import importlib
import pkgutil

import pytest

import tactilevision

MODULES = sorted(m.name for m in pkgutil.walk_packages(tactilevision.__path__, "tactilevision.")
                 if not m.name.endswith("__main__"))


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.failed == 0
