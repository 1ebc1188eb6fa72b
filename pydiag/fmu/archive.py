"""Safe extraction of FMU archives.

An FMU is a zip file from somewhere else. Before anything is written, every entry is
checked: no absolute paths or drive letters, no ``..`` components, no symbolic links, at
most ``MAX_ENTRIES`` entries, at most ``MAX_TOTAL_BYTES`` unpacked, no entry that
inflates by more than ``MAX_RATIO`` (zip bombs), and no archive above
``RATIO_FLOOR_BYTES`` unpacked that inflates by more than ``MAX_ARCHIVE_RATIO`` as a
whole (many small, highly compressible entries: 1000 entries of 1 MiB of zeros are a
1.2 MB FMU that unpacks to 1 GiB per worker). An FMU's binaries and XML compress 3-20
times (our GearPair.fmu: 4.2). Sizes are enforced while inflating, so a forged size
header does not help. Then the binary for this platform must exist.
"""

from __future__ import annotations

import os
import stat
import zipfile
from pathlib import Path, PurePosixPath

from pydiag.core.errors import UnsafeArchive

MAX_ENTRIES = 10_000
MAX_TOTAL_BYTES = 1 << 29  # 512 MiB
MAX_RATIO = 1000  # uncompressed / compressed, for entries above 1 MiB
MAX_ARCHIVE_RATIO = 100  # uncompressed / compressed, for the whole archive ...
RATIO_FLOOR_BYTES = 32 << 20  # ... when it unpacks to more than 32 MiB
CHUNK = 1 << 20


def _check_name(name: str) -> None:
    if name.startswith(("/", "\\")) or (len(name) > 1 and name[1] == ":"):
        raise UnsafeArchive(f"entry '{name}' has an absolute path")
    parts = PurePosixPath(name.replace("\\", "/")).parts
    if ".." in parts:
        raise UnsafeArchive(f"entry '{name}' points outside the archive ('..')")


def safe_extract(fmu_path: str | Path, dest: str | Path, max_total_bytes: int = MAX_TOTAL_BYTES,
                 max_entries: int = MAX_ENTRIES, max_ratio: float = MAX_RATIO) -> None:
    fmu_path, dest = Path(fmu_path), Path(dest).resolve()
    try:
        archive = zipfile.ZipFile(fmu_path)
    except (zipfile.BadZipFile, OSError) as err:
        raise UnsafeArchive(f"{fmu_path.name} is not a readable zip archive: {err}") from err
    with archive:
        infos = archive.infolist()
        if len(infos) > max_entries:
            raise UnsafeArchive(f"{len(infos)} entries, more than the limit of {max_entries}")
        declared = 0
        for info in infos:
            _check_name(info.filename)
            mode = info.external_attr >> 16
            if stat.S_ISLNK(mode):
                raise UnsafeArchive(f"entry '{info.filename}' is a symbolic link")
            target = (dest / info.filename).resolve()
            if dest not in target.parents and target != dest:
                raise UnsafeArchive(f"entry '{info.filename}' points outside the archive")
            declared += info.file_size
            if info.file_size > CHUNK and info.file_size > max_ratio * max(info.compress_size, 1):
                raise UnsafeArchive(f"entry '{info.filename}' inflates {info.file_size} bytes "
                                    f"from {info.compress_size}: a zip bomb")
        if declared > max_total_bytes:
            raise UnsafeArchive(f"archive unpacks to {declared} bytes, more than the limit of "
                                f"{max_total_bytes}")
        packed = max(sum(i.compress_size for i in infos), 1)
        if declared > RATIO_FLOOR_BYTES and declared > MAX_ARCHIVE_RATIO * packed:
            raise UnsafeArchive(f"archive unpacks to {declared} bytes from {packed} "
                                f"({declared / packed:.0f} times): a zip bomb")
        written = 0
        for info in infos:
            target = dest / info.filename
            if info.is_dir():
                target.mkdir(parents=True, exist_ok=True)
                continue
            target.parent.mkdir(parents=True, exist_ok=True)
            with archive.open(info) as src, open(target, "wb") as out:
                while chunk := src.read(CHUNK):
                    written += len(chunk)
                    if written > max_total_bytes or (written > RATIO_FLOOR_BYTES and
                                                     written > MAX_ARCHIVE_RATIO * packed):
                        raise UnsafeArchive(f"archive unpacks to more than its {declared} "
                                            "declared bytes (sizes were forged)")
                    out.write(chunk)
            if info.filename.startswith("binaries/"):
                os.chmod(target, 0o755)


def platform_dirs(model_description) -> tuple[str, list[str]]:
    """(the binaries/ folder this machine needs, the folders an FMU may use) for its FMI version."""
    from fmpy import platform, platform_tuple

    if model_description.fmiVersion.startswith("3"):
        return platform_tuple, [platform_tuple]
    return platform, [platform]


def check_binary(unzipdir: str | Path, model_description, fmu_name: str) -> None:
    """One-line error naming the platforms the FMU has when this one is missing."""
    from fmpy import sharedLibraryExtension

    needed, _ = platform_dirs(model_description)
    ids = [i.modelIdentifier for i in (model_description.modelExchange,
                                       model_description.coSimulation) if i is not None]
    binaries = Path(unzipdir) / "binaries"
    if any((binaries / needed / f"{mid}{sharedLibraryExtension}").exists() for mid in ids):
        return
    have = sorted(p.name for p in binaries.iterdir() if p.is_dir()) if binaries.is_dir() else []
    has_source = (Path(unzipdir) / "sources").is_dir()
    raise UnsafeArchive(f"{fmu_name} has no binary for this platform ({needed}); it has: "
                        f"{', '.join(have) or 'no binaries'}"
                        + ("; it ships sources, which pydiag does not compile" if has_source else ""))


def usable_cache(fmu_path: str | Path) -> bool:
    """Whether a cached FMU pydiag built (``fmu_path``) is whole: a zip archive that holds
    its model description. A file left by a build cut short, or damaged since, is not: it
    is built again, not read."""
    import zipfile

    try:
        with zipfile.ZipFile(fmu_path) as z:
            return "modelDescription.xml" in z.namelist() and z.testzip() is None
    except (OSError, zipfile.BadZipFile):
        return False
