"""The Modelica library and build folder of the command line (``--modelica``,
``--build-dir``), and the models built from them: a machine's own, an effect's."""

from __future__ import annotations

from pathlib import Path
from typing import Callable

from pydiag.gear.effects import Effect
from pydiag.gear.machine import Machine
from pydiag.loop.compose import BuiltModel, composed_fmu
from pydiag.loop.discover import (MODELICA_ROOT, check_modelica_root, default_build_dir,
                                  effect_fmu)
from pydiag.loop.machine_model import MachineModel, machine_fmu


def library(args) -> tuple[Path, Path]:
    """(the Modelica library root, --modelica, checked here; the build folder, --build-dir,
    default the per-user cache)."""
    root = Path(args.modelica) if getattr(args, "modelica", None) else MODELICA_ROOT
    check_modelica_root(root)
    build = getattr(args, "build_dir", None)
    return root, Path(build) if build else default_build_dir(root)


def effect_models(args) -> tuple[Callable[[Effect], str], Callable[[tuple[str, ...]], str]]:
    """(an effect's FMU, the FMU of several effects), built on first use (:func:`library`)."""
    root, build = library(args)
    return (lambda e: str(effect_fmu(e.key, root, build)),
            lambda keys: str(composed_fmu(keys, root, build)))


def machine_models(args) -> Callable[[Machine], tuple[MachineModel, BuiltModel]]:
    """A machine's own model, as written and as built (:func:`library`)."""
    root, build = library(args)
    return lambda machine: machine_fmu(machine, root, build)
