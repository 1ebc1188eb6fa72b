"""Safe extraction: hostile archives are refused before anything is written."""

import stat
import zipfile

import pytest

from pydiag.core.errors import UnsafeArchive
from pydiag.fmu.archive import safe_extract

# ---------------------------------------------------------------------- adapters

MINIMAL = {"sensor": [{"variable": "y"}], "fault_parameter": [{"variable": "k", "low": 0, "high": 1}],
           "spectrum": {"window_s": 1.0, "max_freq_hz": 10.0}}






# ---------------------------------------------------------------------- CasADi, other names


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
