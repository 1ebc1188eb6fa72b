"""Modelica file + model name -> FMU, the whole pipeline."""

from __future__ import annotations

from pathlib import Path

from fmu_build.flatten import flatten
from fmu_build.fmu_export import PYTHON_SIDE, export_fmu
from fmu_build.ode_system import OdeSystem, build_ode_system


def ode_system(model_file: str | Path, model: str,
               library_roots: tuple[Path, ...] = ()) -> OdeSystem:
    with PYTHON_SIDE:  # rumoca and CasADi, one build at a time (fmu_build.fmu_export)
        return build_ode_system(flatten(model_file, model, library_roots))


def build_fmu(model_file: str | Path, model: str, out_path: str | Path,
              library_roots: tuple[Path, ...] = ()) -> Path:
    """``model`` of ``model_file`` as an FMU at ``out_path``; ``library_roots``: folders
    holding the packages it uses beyond its own library's (a model written outside it)."""
    return export_fmu(ode_system(model_file, model, library_roots), out_path)
