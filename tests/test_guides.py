"""The guides teach in a page (issue 86): every page of the documentation's "User guide"
section reads in ten minutes (under 2,500 words, as ``wc -w`` counts them) and carries no
measurement's date; the README neither. Evidence with its dates lives on the validation
pages (docs/validation/), which the guides cite."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
MAX_WORDS = 2500
#: An ISO date, or a day or month written with its year (a paper's or a dataset's bare
#: year may stand).
DATE = re.compile(r"\b20\d{2}-[01]\d-[0-3]\d\b|\b(?:January|February|March|April|May|June|"
                  r"July|August|September|October|November|December|Jan|Feb|Mar|Apr|Jun|"
                  r"Jul|Aug|Sep|Sept|Oct|Nov|Dec)\.? (?:[0-3]?\d, )?20\d{2}\b|"
                  r"\b[0-3]?\d (?:January|February|March|April|May|June|July|August|"
                  r"September|October|November|December)\b")


def guide_pages() -> list[Path]:
    """The pages the navigation lists under "User guide" (mkdocs.yml)."""
    nav = (ROOT / "mkdocs.yml").read_text().split("\nnav:", 1)[1]
    section = nav.split("  - User guide:\n", 1)[1].split("\n  - ", 1)[0]
    return [ROOT / "docs" / p for p in re.findall(r":\s*(\S+\.md)\s*$", section, re.M)]


def test_the_user_guide_section_is_read():
    pages = guide_pages()
    assert len(pages) >= 15
    assert all(p.is_file() for p in pages), [p for p in pages if not p.is_file()]


@pytest.mark.parametrize("page", guide_pages(), ids=lambda p: str(p.relative_to(ROOT)))
def test_a_guide_reads_in_ten_minutes(page):
    words = len(page.read_text().split())
    assert words < MAX_WORDS, f"{page.relative_to(ROOT)}: {words} words"


@pytest.mark.parametrize("page", [*guide_pages(), ROOT / "README.md"],
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_no_measurement_date(page):
    found = [m.group(0) for m in DATE.finditer(page.read_text())]
    assert not found, f"{page.relative_to(ROOT)}: {found}"


def test_the_date_pattern_catches_what_it_must():
    for text in ("on 2026-11-24 it read", "measured 24 November", "November 2026",
                 "Nov 24, 2026"):
        assert DATE.search(text), text
    for text in ("Hayes 1972", "ICRA 2023", "doi:10.1109/ICRA48891.2023.10161153"):
        assert not DATE.search(text), text
