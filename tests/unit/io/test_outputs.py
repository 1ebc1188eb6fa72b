"""The output policy: nothing the user owns is replaced or left behind unasked."""

import os
import stat

import pytest

from pydiag.core.errors import OutputError
from pydiag.core.measurement import Measurement
from pydiag.io.measurements import write_measurement
from pydiag.io.outputs import atomic_output, check_output, write_text


def test_existing_file_is_refused_without_force_and_replaced_with_it(tmp_path):
    out = tmp_path / "r.json"
    out.write_text("mine")
    with pytest.raises(OutputError, match="exists; choose another name or pass --force"):
        write_text(out, "new")
    assert out.read_text() == "mine"
    write_text(out, "new", force=True)
    assert out.read_text() == "new"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.json"]


def test_force_replaces_regular_files_only(tmp_path):
    folder = tmp_path / "adir"
    folder.mkdir()
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    for target in (folder, fifo):
        with pytest.raises(OutputError, match="not a regular file"):
            write_text(target, "x", force=True)
    assert folder.is_dir() and stat.S_ISFIFO(fifo.stat().st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["adir", "pipe"]


def test_a_failed_write_leaves_neither_partial_file_nor_temporary(tmp_path):
    out = tmp_path / "big.csv"
    with pytest.raises(RuntimeError):
        with atomic_output(out) as tmp:
            tmp.write_text("half")
            raise RuntimeError("interrupted")
    assert list(tmp_path.iterdir()) == []


def test_only_the_asked_name_is_written_and_permissions_follow_the_umask(tmp_path):
    keep = tmp_path / "keep.csv.tmp"
    keep.write_text("the user's own file")
    write_measurement(tmp_path / "keep.csv", Measurement({"a": [1.0, 2.0]}, 10.0))
    assert keep.read_text() == "the user's own file"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.csv", "keep.csv.tmp"]
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE((tmp_path / "keep.csv").stat().st_mode) == 0o666 & ~umask


def test_missing_folder_is_refused_before_any_work(tmp_path):
    with pytest.raises(OutputError, match="does not exist"):
        check_output(tmp_path / "nowhere" / "r.json")
