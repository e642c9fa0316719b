"""Each package's public face: every name in ``__all__`` resolves, and a name that moved
out of ``tactilevision.mechanics`` (to ``diagnosis`` or ``planning``) is found at its new
home, while the old attribute says where it went."""

from __future__ import annotations

import importlib

import pytest

import tactilevision.mechanics as mechanics

PACKAGES = ("io", "fem", "optics", "contact", "mechanics", "diagnosis", "planning", "viz",
            "sim", "pipeline", "history", "live", "batch")


@pytest.mark.parametrize("name", PACKAGES)
def test_every_public_name_resolves(name):
    mod = importlib.import_module(f"tactilevision.{name}")
    missing = [n for n in mod.__all__ if not hasattr(mod, n)]
    assert missing == []


@pytest.mark.parametrize("name", sorted(mechanics.MOVED))
def test_a_moved_name_lives_at_its_new_home_and_the_old_one_says_so(name):
    home = importlib.import_module(mechanics.MOVED[name])
    assert name in home.__all__ and getattr(home, name) is not None
    with pytest.raises(AttributeError, match=f"moved to {mechanics.MOVED[name]}.{name}"):
        getattr(mechanics, name)
    with pytest.raises(AttributeError, match="has no attribute 'no_such_name'"):
        mechanics.no_such_name  # noqa: B018


def test_the_old_import_fails_with_an_import_error():
    with pytest.raises(ImportError):
        from tactilevision.mechanics import diagnose  # noqa: F401
