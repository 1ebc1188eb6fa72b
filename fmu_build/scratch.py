"""A scratch folder for a build, removed however the build ends: an error, a Ctrl-C, or a
second Ctrl-C while the first one's cleanup runs (SIGINT and SIGTERM are held while the
folder is removed, then delivered)."""

from __future__ import annotations

import contextlib
import shutil
import signal
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path

_HELD = {signal.SIGINT, signal.SIGTERM}


@contextlib.contextmanager
def scratch_folder(prefix: str) -> Iterator[Path]:
    """A new folder under the system's temporary folder, removed when the block ends."""
    folder = Path(tempfile.mkdtemp(prefix=prefix))
    try:
        yield folder
    finally:
        main = threading.current_thread() is threading.main_thread()
        old = signal.pthread_sigmask(signal.SIG_BLOCK, _HELD) if main else None
        try:
            shutil.rmtree(folder, ignore_errors=True)
        finally:
            if old is not None:
                signal.pthread_sigmask(signal.SIG_SETMASK, old)
