"""The Modelica library and build folder of the command line (``--modelica``,
``--build-dir``), and the models built from them: a machine's own, an effect's."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Callable

from pydiag.core.errors import UsageError
from pydiag.gear.effect import Effect
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
    given = getattr(args, "build_dir", None)
    build = Path(given) if given else default_build_dir(root)
    try:
        build.mkdir(parents=True, exist_ok=True)
        writable = os.access(build, os.W_OK | os.X_OK)
    except OSError as err:
        writable, why = False, err.strerror or str(err)
    else:
        why = "not writable"
    if not writable:
        where = "--build-dir" if given else "the cache (under $XDG_CACHE_HOME or ~/.cache)"
        raise UsageError(f"cannot build models in {build} ({why}): {where} must be a "
                         "writable folder" + ("" if given else "; give --build-dir FOLDER"))
    return root, build


def effect_models(args) -> tuple[Callable[[Effect], str], Callable[[tuple[str, ...]], str]]:
    """(an effect's FMU, the FMU of several effects), built on first use (:func:`library`)."""
    root, build = library(args)
    return (lambda e: str(effect_fmu(e.key, root, build)),
            lambda keys: str(composed_fmu(keys, root, build)))


def machine_models(args) -> Callable[[Machine], tuple[MachineModel, BuiltModel]]:
    """A machine's own model, as written and as built (:func:`library`)."""
    root, build = library(args)
    return lambda machine: machine_fmu(machine, root, build)


def machine_fmus(args) -> Callable[[Machine], str]:
    """A machine's own model's FMU, by the machine (:func:`machine_models`): what the
    effect a fit tries on a stage is tried on (the machine with one effect more)."""
    machines = machine_models(args)
    return lambda machine: str(machines(machine)[1].fmu)
