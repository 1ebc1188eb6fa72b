"""One policy for every file pydiag writes.

- An existing path is refused unless ``force``; ``force`` replaces a regular file only
  (never a folder, a device or a link target's file type).
- Nothing but the asked-for name is written in the user's folder: the content goes to a
  uniquely named temporary file beside the target (``tempfile``), which is renamed over
  the target when complete and removed on every failure, so an interrupted write leaves
  neither a partial file nor a stray temporary one. One left by a writer killed outright
  (SIGKILL) names its owner and is removed by the next write of the same file.
- :func:`check_output` can be called before a long computation, so that a result is never
  computed only to find that it cannot be written.
- A file the user owns and asked pydiag to edit (a machine file ``accept`` gives an
  effect) is edited where it is, never replaced: :func:`edit_in_place`.
"""

from __future__ import annotations

import codecs
import contextlib
import fcntl
import os
import stat
import tempfile
from pathlib import Path
from typing import Callable, Iterator

from pydiag.core.errors import OutputError
from pydiag.core.leftovers import owner_tag, reclaim
from pydiag.core.termination import deferred


def check_output(path: str | Path, force: bool = False) -> Path:
    """Raise :class:`OutputError` unless ``path`` can be written under the policy."""
    path = Path(path)
    try:
        st = path.stat()
    except FileNotFoundError:
        st = None
    except OSError as err:
        raise OutputError(f"cannot write {path}: {err.strerror or err}") from err
    if st is not None:
        if not force:
            raise OutputError(f"{path} exists; choose another name or pass --force")
        if not stat.S_ISREG(st.st_mode):
            raise OutputError(f"{path} exists and is not a regular file; --force replaces "
                              "regular files only")
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise OutputError(f"cannot write {path}: folder {folder} does not exist")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise OutputError(f"cannot write {path}: folder {folder} is not writable")
    return path


@contextlib.contextmanager
def atomic_output(path: str | Path, force: bool = False) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success it replaces ``path``.

    The caller writes the whole content to the yielded path. Whatever happens inside
    the block, the temporary file does not survive it.
    """
    path = check_output(path, force)
    folder = path.parent if str(path.parent) else Path(".")
    reclaim(folder, f".{path.name}.", ".tmp")  # left by a writer killed outright
    tmp = ""
    try:
        with deferred():  # a TERM meanwhile is raised once the name is kept, for the finally
            fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.{owner_tag()}.", suffix=".tmp",
                                       dir=folder)
            os.close(fd)
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; give what open() would
        yield Path(tmp)
        check_output(path, force)  # nothing appeared at the target in the meantime
        os.replace(tmp, path)
    except OSError as err:
        raise OutputError(f"cannot write {path}: {err.strerror or err}") from err
    finally:
        if tmp:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(tmp)


def _umask() -> int:
    """The process umask, read without changing it (os.umask would set it process-wide)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("Umask:"):
                return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    return 0o022


def write_text(path: str | Path, text: str, force: bool = False) -> Path:
    """Write ``text`` to ``path`` under the output policy, as UTF-8 (what every reader of
    pydiag's text files takes, whatever the locale)."""
    with atomic_output(path, force) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def edit_in_place(path: str | Path, edit: Callable[[str], str]) -> str:
    """Edit the text file ``path`` where it is: ``edit`` takes its text (UTF-8, line ends
    as they are) and returns the new text, which is written into the same file, so a link
    to it (symbolic or hard) still names it and its mode and owner stay. The file is
    locked (``flock``) from the read to the last write, so two edits never interleave;
    when the new text only adds to the end of the old one, only the addition is written,
    appended (``O_APPEND``), so a line another process appends meanwhile is never lost.
    A file without any write bit is refused, even for root; a byte-order mark is kept.
    Returns the new text."""
    path = Path(path)
    try:
        st = path.stat()
    except FileNotFoundError as err:
        raise OutputError(f"{path} not found") from err
    except OSError as err:
        raise OutputError(f"cannot edit {path}: {err.strerror or err}") from err
    if not stat.S_ISREG(st.st_mode):
        raise OutputError(f"{path} is not a regular file; pydiag edits regular files only")
    if not st.st_mode & 0o222:
        raise OutputError(f"{path} is read-only (mode {stat.filemode(st.st_mode)}); make it "
                          "writable for pydiag to edit it")
    try:
        fd = os.open(path, os.O_RDWR | os.O_APPEND)
    except OSError as err:
        raise OutputError(f"cannot edit {path}: {err.strerror or err}") from err
    with os.fdopen(fd, "r+b", buffering=0) as f:
        fcntl.flock(fd, fcntl.LOCK_EX)  # released when the file is closed
        raw = f.read()
        bom = codecs.BOM_UTF8 if raw.startswith(codecs.BOM_UTF8) else b""
        try:
            text = raw[len(bom):].decode("utf-8")
        except UnicodeDecodeError as err:
            raise OutputError(f"{path} is not UTF-8 text: {err}") from err
        new = edit(text)
        with deferred():  # a TERM waits for the write, so the file is never half-written
            try:
                if new.startswith(text):
                    f.write(new[len(text):].encode("utf-8"))
                else:
                    fcntl.fcntl(fd, fcntl.F_SETFL, fcntl.fcntl(fd, fcntl.F_GETFL)
                                & ~os.O_APPEND)
                    f.seek(0)
                    f.write(bom + new.encode("utf-8"))
                    f.truncate()
            except OSError as err:
                raise OutputError(f"cannot edit {path}: {err.strerror or err}") from err
    return new
