"""The validation report regenerates (issue 86, item 2): ``benchmarks/report.py`` writes one
page per subject into docs/validation/report/. Here, cheaply and without running a
benchmark: every link from a docs page into the report reaches a page and, where it names
one, a heading; each page carries the header the runner writes (commit, machine, date,
run time, command); the runner's registry, the pages and the navigation agree; the
runner's tables, pages, index and failure handling work on a tiny fake subject."""

from __future__ import annotations

import importlib.util
import io
import re
import sys
import unicodedata
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
REPORT = DOCS / "validation" / "report"


def _load_runner():
    """benchmarks/report.py as a module (registered: its dataclasses look themselves up)."""
    name = "tactilevision_benchmarks_report"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, ROOT / "benchmarks" / "report.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return sys.modules[name]


report = _load_runner()

#: A Markdown link's target: ``](path.md#anchor)`` (no scheme).
LINK = re.compile(r"\]\(([^)\s:]+?\.md)(#[^)\s]*)?\)")


def slug(text: str) -> str:
    """Python-Markdown's toc slugify (the ids MkDocs gives headings)."""
    text = unicodedata.normalize("NFKD", text).encode("ascii", "ignore").decode("ascii")
    text = re.sub(r"[^\w\s-]", "", text).strip().lower()
    return re.sub(r"[-\s]+", "-", text)


def anchors(page: Path) -> set[str]:
    text = re.sub(r"```.*?```", "", page.read_text(encoding="utf-8"), flags=re.S)
    heads = re.findall(r"^#{1,6}\s+(.+?)\s*#*\s*$", text, re.M)
    return {slug(re.sub(r"[`*_]|\[([^\]]*)\]\([^)]*\)", r"\1", h)) for h in heads}


def report_links() -> list[tuple[str, str, str]]:
    """(citing page, target, anchor) of every link of a docs page into the report."""
    found = []
    for page in sorted(DOCS.rglob("*.md")):
        if "generated" in page.parts:
            continue
        for m in LINK.finditer(page.read_text(encoding="utf-8")):
            target = (page.parent / m.group(1)).resolve()
            if target.parent == REPORT.resolve():
                found.append((page.relative_to(ROOT).as_posix(),
                              target.relative_to(ROOT).as_posix(), (m.group(2) or "")[1:]))
    return found


def subject_pages() -> list[Path]:
    return sorted(p for p in REPORT.glob("*.md") if p.name != "index.md")


def test_the_report_is_cited():
    links = report_links()
    assert len({t for _, t, _ in links}) >= len(subject_pages())    # the index at least
    assert any(not c.startswith("docs/validation/report/") for c, _, _ in links), \
        "no page outside the report cites it"


@pytest.mark.parametrize(("page", "target", "anchor"), report_links(),
                         ids=lambda v: str(v))
def test_a_cited_table_exists(page, target, anchor):
    path = ROOT / target
    assert path.is_file(), f"{page} cites {target}, which the report does not hold"
    if anchor:
        assert anchor in anchors(path), f"{page} cites {target}#{anchor}: no such heading"


@pytest.mark.parametrize("page", subject_pages(), ids=lambda p: p.stem)
def test_a_page_says_where_it_came_from(page):
    text = page.read_text(encoding="utf-8")
    head = report.read_header(text)
    assert set(head) == set(report.HEADER_FIELDS), head
    assert re.fullmatch(r"`[0-9a-f]{7,40}`( dirty \(\d+ files changed\))?", head["commit"])
    assert re.search(r"\d+ CPUs.*Python 3\.\d+", head["machine"])
    assert re.fullmatch(r"20\d\d-[01]\d-[0-3]\d [0-2]\d:[0-5]\d UTC", head["date"])
    assert re.fullmatch(r"\d+\.\d s", head["run time"])
    assert head["command"].startswith(f"`python benchmarks/report.py --subjects {page.stem}")
    assert text.startswith("# ") and "\n| " in text         # a title and a table


def test_registry_pages_and_nav_agree():
    pages = {p.stem for p in subject_pages()}
    assert set(report.SUBJECTS) == pages, (
        f"subjects without a page: {sorted(set(report.SUBJECTS) - pages)}; "
        f"pages of no subject: {sorted(pages - set(report.SUBJECTS))}")
    nav = (ROOT / "mkdocs.yml").read_text().split("\nnav:", 1)[1]
    for name in ["index", *report.SUBJECTS]:
        assert f"validation/report/{name}.md" in nav, f"{name}.md is not in mkdocs.yml's nav"
    index = (REPORT / "index.md").read_text(encoding="utf-8")
    for name in report.SUBJECTS:
        assert f"]({name}.md)" in index, f"the report's index does not list {name}"


def _fake(quick: bool):
    return report.Result([report.Table("A | table", ["x", "y (mm)"],
                                       [["one", 0.123456], [2, None]], note="a\n note")],
                         summary="What it found.")


def _broken(quick: bool):
    raise RuntimeError("no data")


FAKE = report.Subject("fake", "A fake subject", "What it measures.", ("python fake.py",), _fake)
BROKEN = report.Subject("broken", "A broken subject", "It fails.", (), _broken)


def test_format_table():
    text = report.format_table(_fake(False).tables[0])
    assert text == ("## A | table\n\n| x | y (mm) |\n|---|---|\n| one | 0.1235 |\n"
                    "| 2 | – |\n\na note\n")
    assert report.cell("a|b") == "a\\|b" and report.cell(True) == "yes"
    with pytest.raises(ValueError, match="2 columns"):
        report.format_table(report.Table("t", ["a", "b"], [[1]]))


def test_render_page_and_read_its_header():
    meta = {"commit": "`abc1234`", "machine": "Linux x86_64, 2 CPUs, Python 3.11.7",
            "date": "2030-01-02 03:04 UTC", "run time": "1.0 s",
            "command": "`python benchmarks/report.py --subjects fake`"}
    text = report.render_page(FAKE, _fake(False), meta)
    assert text.startswith("# A fake subject\n")
    assert report.read_header(text) == meta
    assert "What it found." in text and "`python fake.py`" in text
    with pytest.raises(ValueError, match="header"):
        report.render_page(FAKE, _fake(False), {**meta, "date": ""})
    assert report.command_for("x", True, Path("o")) == \
        "python benchmarks/report.py --subjects x --quick --out o"


def test_run_subjects_writes_pages_and_index_and_survives_a_failure(tmp_path):
    log = io.StringIO()
    registry = {"fake": FAKE, "broken": BROKEN}
    failed = report.run_subjects(["broken", "fake"], quick=True, out=tmp_path,
                                 registry=registry, log=log)
    assert list(failed) == ["broken"] and "no data" in failed["broken"]
    assert "broken: FAILED" in log.getvalue() and "fake: done" in log.getvalue()
    assert not (tmp_path / "broken.md").exists()
    page = (tmp_path / "fake.md").read_text()
    head = report.read_header(page)
    assert head["command"] == f"`python benchmarks/report.py --subjects fake --quick " \
                              f"--out {tmp_path.as_posix()}`"
    index = (tmp_path / "index.md").read_text()
    assert "[fake](fake.md)" in index and "broken" not in index
    assert head["date"] in index


def test_the_link_check_catches_a_missing_heading():
    assert slug("Dimitriadis et al. (2002), eq. (12)") == "dimitriadis-et-al-2002-eq-12"
    assert slug("Hertz's half-space") == "hertzs-half-space"
    heads = anchors(REPORT / "sphere_closed_forms.md")
    assert "hertzs-half-space" in heads and "no-such-table" not in heads
    m = LINK.search("see [report](../validation/report/x.md#a-b) and")
    assert m and m.group(1) == "../validation/report/x.md" and m.group(2) == "#a-b"


def _row(kind: str, verdict: str | None = None, holds: str = "flat", named: bool = False,
         ci: tuple[float, float] | None = None, fit_data: str | None = None) -> dict:
    """One row as ``bench_loop.one`` returns it, with only what ``_loop_reads`` reads."""
    return {"kind": kind, "verdict": verdict, "unexplained": None, "E_after_ci": ci,
            "E_named_truth": 0.2, "fit_data": fit_data,
            "holds": {"verdict": holds, "named": named, "decay_rate_per_s": -0.1 if named
                      else 0.001, "smallest_rate_per_s": 0.01}}


def test_the_loops_reads_count_silence_holds_and_intervals():
    """report mark_verdicts' tables of the null's silence, the holds and E after a right
    verdict, on hand-made rows whose counts are known."""
    rows = [(_row("null"), "yes"), (_row("null", "force_offset"), "no"),
            (_row("offset"), "yes"),
            (_row("relaxation", "viscoelastic_relaxation", "relaxing", True, (0.18, 0.22),
                  "holds"), "yes"),
            (_row("damage", "stiffness_step:time_s", ci=(0.21, 0.25), fit_data="crossings"),
             "yes"),
            (_row("spatial", "spatial_nonuniformity", ci=(0.19, 0.21), fit_data="crossings"),
             "yes")]
    silent, fits = report._loop_reads(rows)
    got = {r[0].split(":")[0]: r[1] for r in silent.rows}
    assert got["nothing hidden"] == "1 of 2" and got["a relaxing gel (g 0.25, tau 0.7 s)"] \
        == "1 of 1"
    assert got["every other log"] == "5 of 5"
    assert silent.rows[2][2] == "-10.00 to -10.00"
    by = {r[0]: r[1:] for r in fits.rows}
    assert by["the crossing forces (`fit --crossings --effects`)"] == [2, "1 of 2"]
    assert by["the holds (`fit --holds`)"] == [1, "1 of 1"]
