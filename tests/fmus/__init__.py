"""FMUs made by other exporters than ours, built by the tests."""

import subprocess
import sys
from pathlib import Path


def build_pythonfmu(folder: Path, name: str, source: str) -> Path:
    """Write ``source`` as ``name``.py and build it with the pythonfmu command."""
    folder = Path(folder)
    script = folder / f"{name}.py"
    script.write_text(source)
    exe = Path(sys.executable).with_name("pythonfmu")
    res = subprocess.run([str(exe), "build", "-f", str(script), "-d", str(folder)],
                         capture_output=True, text=True, cwd=folder)
    if res.returncode != 0:
        raise RuntimeError(f"pythonfmu build failed: {res.stderr[-500:]}")
    return folder / f"{name}.fmu"
