import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
GEARPAIR_MO = ROOT / "modelica" / "GearDiag" / "GearPair.mo"
BUILT_FMU = ROOT / "build" / "GearPair.fmu"


@pytest.fixture(scope="session")
def gear_fmu(tmp_path_factory) -> Path:
    """The GearPair FMU from `make fmu`, or built here when it is missing."""
    if BUILT_FMU.exists():
        return BUILT_FMU
    out = tmp_path_factory.mktemp("fmu") / "GearPair.fmu"
    from fmu_build import build_fmu
    return build_fmu(GEARPAIR_MO, "GearDiag.GearPair", out)


@pytest.fixture
def modelica_copy(tmp_path) -> Path:
    """A scratch copy of the GearDiag package, safe to edit."""
    dst = tmp_path / "modelica"
    shutil.copytree(ROOT / "modelica", dst)
    return dst


def run_cli(*args: str, cwd: Path = ROOT) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, *args], cwd=cwd, capture_output=True, text=True)


def inspected(fmu: Path) -> Path:
    """Every FMU a test builds goes through `pydiag inspect` too (issue: inspect runs on all)."""
    from pydiag.fmu.inspect import describe, format_info
    info = describe(fmu)
    assert info.interfaces and "platforms:" in format_info(info)
    return fmu
