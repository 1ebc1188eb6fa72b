"""The run history: an unusable file is refused before any work, never after it."""

import pytest

from pydiag.core.errors import OutputError
from pydiag.loop import history


def test_a_file_that_is_not_a_history_is_refused_and_kept(tmp_path):
    notes = tmp_path / "notes.txt"
    notes.write_text("my notes, not a database\n" * 100)
    with pytest.raises(OutputError, match="cannot use .*notes.txt as the run history"):
        history.check(notes)
    assert notes.read_text().startswith("my notes")
    with pytest.raises(OutputError, match="is a folder"):
        history.check(tmp_path)


def test_checking_a_new_history_creates_nothing(tmp_path):
    history.check(tmp_path / "h.sqlite")
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(OutputError, match="does not exist"):
        history.check(tmp_path / "no" / "h.sqlite")


def test_history_plot_follows_the_output_policy(tmp_path):
    rows = [{"id": 1, "error": 0.5, "model_name": "GearPair", "fmu": "a.fmu"},
            {"id": 2, "error": 0.1, "model_name": "WithRunout", "fmu": "b.fmu"}]
    out = history.plot(rows, tmp_path / "h.png")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(OutputError, match="exists"):
        history.plot(rows, out)
    assert history.plot(rows, tmp_path / "h.svg").read_text().lstrip().startswith("<?xml")
