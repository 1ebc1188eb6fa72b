"""What pydiag does to a machine file the user owns: `accept` appends an effect where the
file is (through a link, into its target; its mode kept; a read-only file refused; lines
another process appends meanwhile kept; its line ends and byte-order mark kept), and the
loop's `[start]` rewrite finds the table under any spacing TOML allows. The file is read
whatever an editor left in it, and a bad one is one clear error."""

import os
import stat
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pydiag.core.errors import MachineError, OutputError
from pydiag.gear.machine_file import load_machine
from pydiag.loop.machine_edits import accept, record_start

BOX = ('name = "box"  # the user\'s comment\ninput_rpm = 1500\n'
       '[[stages]]\nname = "first"\npinion_teeth = 18\ngear_teeth = 36\n'
       '[[stages]]\nname = "second"\npinion_teeth = 20\ngear_teeth = 50\n')


@pytest.fixture
def box(tmp_path) -> Path:
    path = tmp_path / "box.toml"
    path.write_text(BOX)
    return path


def test_accept_through_a_symbolic_link_edits_its_target(box, tmp_path):
    link = tmp_path / "link.toml"
    link.symlink_to(box)
    accept(link, "gear_tooth_fault", "2")
    assert link.is_symlink()
    assert [e.key for e in load_machine(box).effects] == ["gear_tooth_fault"]


def test_accept_keeps_hard_links_and_the_files_mode(box, tmp_path):
    other = tmp_path / "other.toml"
    os.link(box, other)
    box.chmod(0o600)
    accept(box, "gear_eccentricity", "first")
    assert os.path.samefile(box, other) and other.read_text().startswith(BOX)
    assert [e.key for e in load_machine(other).effects] == ["gear_eccentricity"]
    assert stat.S_IMODE(box.stat().st_mode) == 0o600


def test_a_read_only_machine_file_is_refused_and_left_as_it_was(box):
    box.chmod(0o444)
    with pytest.raises(OutputError, match="is read-only"):
        accept(box, "gear_tooth_fault", "1")
    assert box.read_text() == BOX and stat.S_IMODE(box.stat().st_mode) == 0o444


def test_lines_another_process_appends_meanwhile_are_kept(box):
    """A writer appends 3,000 comment lines while accept edits the file three times."""
    writer = subprocess.Popen([sys.executable, "-c", f"""
import os, time
fd = os.open({str(box)!r}, os.O_WRONLY | os.O_APPEND)
for i in range(3000):
    os.write(fd, b"# appended %d\\n" % i)
    if i % 100 == 0:
        time.sleep(0.005)
"""])
    try:
        time.sleep(0.02)
        for key, stage in (("gear_tooth_fault", "1"), ("gear_eccentricity", "2"),
                           ("mesh_modulation", "1")):
            accept(box, key, stage)
    finally:
        writer.wait(30)
    text = box.read_text()
    assert sum(line.startswith("# appended ") for line in text.splitlines()) == 3000
    assert len(load_machine(box).effects) == 3


def test_accept_writes_the_files_own_line_ends_and_keeps_its_byte_order_mark(box):
    box.write_bytes(b"\xef\xbb\xbf" + BOX.replace("\n", "\r\n").encode())
    accept(box, "gear_tooth_fault", "second")
    raw = box.read_bytes()
    assert raw.startswith(b"\xef\xbb\xbf") and b"\n" not in raw.replace(b"\r\n", b"")
    assert load_machine(box).effects[0].stage == 1


def test_a_stage_named_with_any_character_takes_an_effect(tmp_path):
    path = tmp_path / "box.toml"
    path.write_text(BOX.replace('"second"', '"sortie 🙂 \\"B\\""'), encoding="utf-8")
    accept(path, "gear_tooth_fault", 'sortie 🙂 "B"')
    assert load_machine(path).effects[0].stage == 1
    with pytest.raises(MachineError, match="no stage '²'"):
        accept(path, "gear_eccentricity", "²")


def test_the_start_table_is_found_under_any_spacing(box):
    box.write_text(BOX + '\n[ start ]  # an earlier fit\n"first.a_f" = 0.2\n')
    record_start(box, {"first.a_f": 0.3})
    text = box.read_text()
    assert "[ start ]" not in text and text.count("[start]") == 1
    assert load_machine(box).fit_start() == {"first.a_f": 0.3}
    # the loop's order: an effect accepted after the table, then the table again
    accept(box, "gear_tooth_fault", "first")
    record_start(box, {"first.a_f": 0.4})
    machine = load_machine(box)
    assert [e.key for e in machine.effects] == ["gear_tooth_fault"]
    assert machine.fit_start() == {"first.a_f": 0.4}


@pytest.mark.parametrize("teeth, said", [
    ("inf", "a whole number of at least 2"), ("nan", "a whole number of at least 2"),
    ("1", "a gear of one tooth"), ("18.5", "a whole number of at least 2")])
def test_teeth_that_are_no_gears_are_refused(tmp_path, teeth, said):
    path = tmp_path / "box.toml"
    path.write_text(BOX.replace("pinion_teeth = 18", f"pinion_teeth = {teeth}"))
    with pytest.raises(MachineError, match=said):
        load_machine(path)


def test_a_byte_order_mark_and_deep_nesting_are_read_or_refused_in_one_line(tmp_path):
    path = tmp_path / "box.toml"
    path.write_bytes(b"\xef\xbb\xbf" + BOX.encode())
    assert load_machine(path).name == "box"
    path.write_text(BOX + "x = " + "[" * 5000 + "]" * 5000 + "\n")
    with pytest.raises(MachineError, match="nested too deeply"):
        load_machine(path)
