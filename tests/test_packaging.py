"""pydiag is an installable package: a wheel with both packages, the compiled engine's
sources and the `pydiag` command; a fresh environment gets a working CLI from it."""

import shutil
import subprocess
import sys
import zipfile

import pytest
from conftest import ROOT


def scratch_copy(tmp_path):
    """The files a build reads, copied, so the build leaves nothing in the checkout."""
    src = tmp_path / "src"
    src.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, src / name)
    for package in ("pydiag", "fmu_build"):
        shutil.copytree(ROOT / package, src / package,
                        ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    return src


def test_wheel_holds_the_packages_the_engine_sources_and_the_command(tmp_path):
    src = scratch_copy(tmp_path)
    res = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps",
                          "--no-build-isolation", "--quiet", "-w", str(tmp_path / "dist"), str(src)],
                         capture_output=True, text=True)
    assert res.returncode == 0, res.stderr[-2000:]
    (wheel,) = (tmp_path / "dist").glob("gear_diag-*.whl")
    with zipfile.ZipFile(wheel) as z:
        names = set(z.namelist())
        entry_points = next(z.read(n).decode() for n in names if n.endswith("entry_points.txt"))
    assert {"pydiag/app/cli.py", "pydiag/fit/problem.py", "fmu_build/__init__.py",
            "pydiag/fmu/native/me_driver.c", "pydiag/fmu/native/dop853_coefficients.h"} <= names
    assert "pydiag = pydiag.app.cli:main" in entry_points
    assert not any(n.startswith("tests/") for n in names)


@pytest.mark.slow
def test_fresh_environment_installs_and_runs_the_command(tmp_path):
    """Downloads the pinned dependencies from the package registry."""
    subprocess.run([sys.executable, "-m", "venv", str(tmp_path / "env")], check=True)
    pip = tmp_path / "env" / "bin" / "pip"
    res = subprocess.run([str(pip), "install", "--quiet", "--disable-pip-version-check",
                          str(scratch_copy(tmp_path))], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr[-2000:]
    res = subprocess.run([str(tmp_path / "env" / "bin" / "pydiag"), "--help"], cwd=tmp_path,
                         capture_output=True, text=True)
    assert res.returncode == 0 and "diagnose" in res.stdout, res.stderr


def test_the_install_pins_are_pyprojects():
    """make venv installs requirements.txt without resolving (--no-deps): it must hold every
    pin of pyproject.toml, its extras too, at the same version, and pin all it lists."""
    import re
    import tomllib
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    wanted = project["dependencies"] + [d for extra in project["optional-dependencies"].values()
                                         for d in extra]
    lines = [ln.strip() for ln in (ROOT / "requirements.txt").read_text().splitlines()
             if ln.strip() and not ln.startswith("#")]
    assert lines[-1] == "-e ."
    pins = {}
    for ln in lines[:-1]:
        name, _, version = ln.partition("==")
        assert version, f"{ln!r} is not pinned"
        pins[re.sub(r"[-_.]+", "-", name).lower()] = version
    for dep in wanted:
        name, _, version = dep.partition("==")
        assert pins.get(re.sub(r"[-_.]+", "-", name).lower()) == version, dep
