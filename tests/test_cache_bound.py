"""The disk cache is bounded (issue 54, item 9): least recently used files go first once
the cache passes $TACTILEVISION_CACHE_MB; a read marks a file used; ``tactilevision cache
info|clear`` say what it holds and empty it."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from tactilevision import InputWarning
from tactilevision._cache import cache_info, cache_limit_bytes, cache_root, savez_atomic, touch
from tactilevision.cli import main


def _table(root, i):
    path = root / "optics" / f"mlp_table_{i:02d}.npz"
    assert savez_atomic(path, t=np.random.default_rng(i).random(2500))   # 20 kB each
    os.utime(path, (time.time() - 1000 + i, time.time() - 1000 + i))   # written in turn
    return path


def test_twenty_tables_stay_within_the_bound_oldest_first(tmp_path, monkeypatch):
    monkeypatch.setenv("TACTILEVISION_CACHE", str(tmp_path))
    monkeypatch.setenv("TACTILEVISION_CACHE_MB", str(100e3 / 2**20))      # 100 kB
    (tmp_path / "tests").mkdir()
    (tmp_path / "tests" / "render.npz").write_bytes(b"x" * 200_000)      # not counted
    paths = [_table(tmp_path, i) for i in range(3)]
    touch(paths[0])                      # the first one read again: used last
    paths += [_table(tmp_path, i) for i in range(3, 20)]
    info = cache_info(tmp_path)
    assert info["optics"][1] <= 100e3 and info["tests"] == (1, 200_000)
    left = {p.name for p in (tmp_path / "optics").iterdir()}
    assert paths[-1].name in left                  # the newest stays
    assert paths[1].name not in left               # an old one unused goes
    assert paths[0].name in left                   # the one read again outlives its peers
    assert len(left) == 4                          # 4 x 20 kB within 100 kB


def test_cache_info_and_clear(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("TACTILEVISION_CACHE", str(tmp_path))
    monkeypatch.delenv("TACTILEVISION_CACHE_MB", raising=False)
    for i in range(3):
        _table(tmp_path, i)
    assert main(["cache", "info", "--json", "-"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["folders"]["optics"]["files"] == 3 and d["limit_mb"] == 1024
    assert main(["cache", "clear", "--folder", "optics"]) == 0
    assert "removed 3 files" in capsys.readouterr().out
    assert not list((tmp_path / "optics").iterdir())


def test_a_bad_bound_is_warned_and_the_default_used(monkeypatch):
    for bad in ("lots", "-5", "nan"):
        monkeypatch.setenv("TACTILEVISION_CACHE_MB", bad)
        with pytest.warns(InputWarning, match="TACTILEVISION_CACHE_MB"):
            assert cache_limit_bytes() == 1024 * 2**20
    monkeypatch.setenv("TACTILEVISION_CACHE_MB", "0.5")
    assert cache_limit_bytes() == 2**19


def test_the_suite_writes_its_own_cache_never_the_users():
    """Issue 86: the suite's cache is ``~/.cache/tactilevision-suite`` (tests/conftest.py),
    in this worker and in every command a test starts, never the user's default folder."""
    users = Path.home() / ".cache" / "tactilevision"
    suite = Path(os.environ.get("TACTILEVISION_SUITE_CACHE",
                                Path.home() / ".cache" / "tactilevision-suite"))
    child = subprocess.run([sys.executable, "-c", "from tactilevision._cache import "
                            "cache_root; print(cache_root())"],
                           capture_output=True, text=True, timeout=60, check=True)
    assert cache_root() == suite == Path(child.stdout.strip())
    assert suite != users and users not in suite.parents


def test_a_tables_cache_path_covers_the_code_that_tabulates(monkeypatch):
    """A network's disk-cached gradient table is keyed on the code of the tabulation, the
    network's inputs and the gradients from normals, and on every module the tabulation
    imports from the package (the key once held the format number alone, so a changed
    tabulation read tables the old code had written until someone bumped it)."""
    import ast

    import tactilevision.optics._reconstructor as rec
    import tactilevision.optics._table as table_module

    tree = ast.parse(Path(table_module.__file__).read_text())
    imported = {f"{node.module}.py" for node in ast.walk(tree)
                if isinstance(node, ast.ImportFrom) and node.level == 1 and node.module}
    # the LUT and the first-order kernel make other tables, not the network's
    assert imported - {"_lut.py", "_table_kernel.py", "_features.py"} <= set(rec.TABLE_SOURCES)
    assert "_table.py" in rec.TABLE_SOURCES
    key = (b"net", b"ref", (4, 4), (0.0,), (1.0,), 64, False, 40, 0)
    before = rec._table_cache_path(key)
    monkeypatch.setattr(rec, "_table_source_digest", lambda: "0" * 64)
    after = rec._table_cache_path(key)
    assert after != before and after.parent == before.parent
