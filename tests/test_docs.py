"""The documentation builds: MkDocs with warnings as errors (broken links, unknown pages,
docstrings the API reference cannot parse), the gallery's examples run on the sample data."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_docs_build_strict(tmp_path):
    pytest.importorskip("mkdocs", reason="the docs extra (MkDocs) is not installed")
    pytest.importorskip("mkdocs_gallery", reason="the docs extra (mkdocs-gallery) is not installed")
    pytest.importorskip("mkdocstrings", reason="the docs extra (mkdocstrings) is not installed")
    # a copy, so that the gallery's generated pages never land in the working tree
    src = tmp_path / "repo"
    src.mkdir()
    for name in ("sample_frames", "tactilevision"):
        (src / name).symlink_to(ROOT / name)
    shutil.copy(ROOT / "mkdocs.yml", src / "mkdocs.yml")
    for name in ("docs", "examples"):      # without a local build's gallery cache
        shutil.copytree(ROOT / name, src / name,
                        ignore=shutil.ignore_patterns("generated", "__pycache__"))
    env = dict(os.environ, MPLBACKEND="Agg", NO_MKDOCS_2_WARNING="1")
    run = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-q",
                          "-d", str(tmp_path / "site")], cwd=src, env=env,
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stdout[-4000:] + run.stderr[-4000:]
    site = tmp_path / "site"
    for page in ("index.html", "guide/calibrate/index.html", "formats/index.html",
                 "method/index.html", "api/mechanics/index.html", "generated/gallery/index.html"):
        assert (site / page).is_file(), page
    api = (site / "api" / "mechanics" / "index.html").read_text()
    assert "fit_indentation" in api and "diagnose" in api
    gallery = site / "generated" / "gallery" / "images"
    assert len(list(gallery.glob("mkd_glr_plot_*.png"))) >= 3       # the examples ran
