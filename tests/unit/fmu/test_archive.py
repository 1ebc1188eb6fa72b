"""Safe extraction: hostile archives are refused before anything is written."""

import stat
import zipfile

import pytest

from pydiag.core.errors import UnsafeArchive
from pydiag.fmu.archive import safe_extract


@pytest.mark.parametrize("entries,message", [
    ([("/etc/evil", b"x", None)], "absolute path"),
    ([("binaries/../../evil", b"x", None)], r"outside the archive \('\.\.'\)"),
    ([("link", b"/etc/passwd", stat.S_IFLNK | 0o777)], "symbolic link"),
    ([("bomb.bin", b"\0" * (64 << 20), None)], "zip bomb"),
])
def test_hostile_archives_are_rejected_before_writing(tmp_path, entries, message):
    fmu = make_zip(tmp_path / "evil.fmu", entries)
    dest = tmp_path / "out"
    dest.mkdir()
    with pytest.raises(UnsafeArchive, match=message):
        safe_extract(fmu, dest)
    assert list(dest.iterdir()) == []
    assert not (tmp_path / "evil").exists()


def test_many_small_compressible_entries_are_a_bomb_too(tmp_path):
    """Each 1 MiB entry of zeros is under the per-entry rule; together they are 64 MiB from
    about 64 kB (the issue's case was 1000 of them: 1 GiB per worker)."""
    fmu = make_zip(tmp_path / "zeros.fmu", [(f"resources/z{i}", bytes(1 << 20), None)
                                            for i in range(64)])
    dest = tmp_path / "out"
    dest.mkdir()
    with pytest.raises(UnsafeArchive, match=r"unpacks to 67108864 bytes from \d+ \(\d+ times\): a "
                                            "zip bomb"):
        safe_extract(fmu, dest)
    assert list(dest.iterdir()) == []


def test_an_ordinary_fmu_is_far_from_the_ratio_limit(gear_fmu, tmp_path):
    safe_extract(gear_fmu, tmp_path / "out")
    assert (tmp_path / "out" / "modelDescription.xml").is_file()


def test_total_size_limit(tmp_path):
    fmu = make_zip(tmp_path / "big.fmu", [(f"f{i}", bytes(1000), None) for i in range(20)])
    with pytest.raises(UnsafeArchive, match="more than the limit"):
        safe_extract(fmu, tmp_path / "out", max_total_bytes=10_000)


def make_zip(path, entries):
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        for name, data, mode in entries:
            info = zipfile.ZipInfo(name)
            info.compress_type = zipfile.ZIP_DEFLATED
            if mode is not None:
                info.external_attr = mode << 16
            z.writestr(info, data)
    return path
