"""The disk caches' key on code: docstrings and comments do not enter it, statements do."""

from pathlib import Path

from tactilevision._cache import code_digest

SOURCE = '''"""Module docstring."""


def f(x):
    """Twice x."""
    return 2 * x  # a comment
'''


def _write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_docstrings_and_comments_leave_the_digest(tmp_path):
    base = code_digest(_write(tmp_path, "a.py", SOURCE))
    edited = SOURCE.replace("Twice x.", "Two times x, as the paper's eq. 3 has it.") \
        .replace("# a comment", "# another comment").replace("Module docstring.", "Other.")
    assert code_digest(_write(tmp_path, "b.py", edited).rename(tmp_path / "a.py")) == base


def test_a_changed_statement_changes_the_digest(tmp_path):
    base = code_digest(_write(tmp_path, "a.py", SOURCE))
    changed = code_digest(_write(tmp_path, "a.py", SOURCE.replace("2 * x", "3 * x")))
    assert changed != base
    assert len(base) == 64 and int(base, 16) >= 0


def test_a_function_of_only_a_docstring_still_hashes(tmp_path):
    text = 'def g():\n    """Nothing but a docstring."""\n'
    d1 = code_digest(_write(tmp_path, "a.py", text))
    d2 = code_digest(_write(tmp_path, "a.py", text.replace("Nothing", "Still nothing")))
    assert d1 == d2
    assert d1 != code_digest(_write(tmp_path, "a.py", "def g():\n    pass\n    return 1\n"))
