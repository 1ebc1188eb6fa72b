"""Export an OdeSystem as an FMI 3.0 Model-Exchange FMU with CasADi's DaeBuilder.

What CasADi's export would otherwise get wrong or make slow, handled here:

- CasADi's generated C code ignores initial equations, so a state whose start value
  depends on parameters is integrated as ``<name>__delta = <name> - start(p)`` with a
  zero start: setting a parameter moves the start point as the Modelica source says.
- CasADi's FMU evaluates only state derivatives and outputs; local variables would read
  back as 0. Algebraic locals are therefore not exported: declare what a user must see as
  an ``output`` in Modelica. Derived parameters are exported as calculated parameters,
  computed once per parameter set (:mod:`fmu_build.parameter_stage`).
- CasADi's modelDescription.xml fails fmpy's validation (undeclared units, helper names
  the declared naming convention forbids, missing initial unknowns): completed by
  :mod:`fmu_build.model_description` before packing.
- CasADi's shell compiler passes no optimisation flag, so gcc built the model at -O0 and
  a right-hand side call cost 2.6x more (0.76 vs 0.29 us for GearPair, measured with the
  native engine). The binary is compiled here, with ``COMPILER_FLAGS``, each source file
  its own translation unit (CasADi's amalgamation would clash the static names of two
  generated files).
- CasADi, rumoca and CasADi's export (which writes into the process's working folder) are
  not made for threads: :data:`PYTHON_SIDE` lets one build at a time use them. The C
  compile, most of a build's time, runs outside it, so builds in threads compile side by
  side.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import subprocess
import threading
from pathlib import Path

import casadi as ca
from fmpy import platform_tuple, sharedLibraryExtension

from fmu_build import parameter_stage
from fmu_build.errors import ModelicaBuildError
from fmu_build.model_description import add_unit_definitions, complete_for_fmi
from fmu_build.ode_system import OdeSystem
from fmu_build.scratch import scratch_folder

MX = ca.MX
COMPILER_FLAGS = ["-O2", "-pipe"]  # -pipe: no temporary files of gcc's own to leave
#: Held while a build runs rumoca or CasADi or works in the process's working folder (the
#: module docstring): the process's, as that folder is.
PYTHON_SIDE = threading.Lock()


def fmi_headers_dir() -> str:
    import fmpy
    return os.path.join(os.path.dirname(fmpy.__file__), "c-code")


def _opts(unit: str | None, description: str | None, **extra) -> dict:
    opts = {k: v for k, v in extra.items() if v is not None}
    if unit:
        opts["unit"] = unit
    if description:
        opts["description"] = description
    return opts


def to_dae_builder(system: OdeSystem) -> ca.DaeBuilder:
    """The model as a DaeBuilder: free parameters, then derived ones (see parameter_stage)."""
    model_id = model_identifier(system)
    dae = ca.DaeBuilder(model_id)
    t = dae.add("time", "independent", "continuous", {})
    p = [dae.add(q.name, "parameter", "tunable", _opts(q.unit, q.description, start=q.value))
         for q in system.parameters]
    free_values = [q.value for q in system.parameters]
    stage = ca.Function("stage", [ca.vertcat(*[q.symbol for q in system.parameters])],
                        [ca.vertcat(*[d.expr for d in system.derived])])
    d_values = [float(v) for v in ca.DM(stage(free_values)).full().ravel()] if system.derived else []
    d = [dae.add(q.name, "parameter", "tunable", _opts(q.unit, q.description, start=v))
         for q, v in zip(system.derived, d_values)]
    taken = ({q.name for q in system.parameters} | {q.name for q in system.derived}
             | {s.name for s in system.states})
    x_vars = []  # the symbols the FMU integrates
    physical = []  # the physical state value in terms of those symbols
    delta_states = []
    for s in system.states:
        if s.start.is_constant():
            var = dae.add(s.name, "local", "continuous",
                          _opts(s.unit, s.description, start=float(s.start), nominal=s.nominal))
            x_vars.append(var)
            physical.append(var)
        else:
            name = f"{s.name}__delta"
            if name in taken:
                raise ModelicaBuildError(f"name '{name}' is reserved for the start offset of "
                                         f"state '{s.name}'")
            var = dae.add(name, "local", "continuous", _opts(
                s.unit, f"{s.name} minus its parameter-dependent start value", start=0.0,
                nominal=s.nominal))
            x_vars.append(var)
            delta_states.append((s, len(physical)))
            physical.append(None)

    # One SX function for everything, called on the builder's MX symbols.
    params_sx = [*[q.symbol for q in system.parameters], *[q.symbol for q in system.derived]]
    sx_in = [system.time, *[s.symbol for s in system.states], *params_sx]
    starts = ca.Function("starts", params_sx, [s.start for s in system.states])
    p_mx = [*p, *d]
    for _, i in delta_states:
        physical[i] = x_vars[i] + starts(*p_mx)[i]
    outs = [*system.derivatives, *[o.expr for o in system.outputs]]
    f = ca.Function("f", sx_in, outs)
    values = f(t, *physical, *p_mx)
    values = values if isinstance(values, (list, tuple)) else [values]
    n_x = len(system.states)
    for var, rhs in zip(x_vars, values[:n_x]):
        dae.eq(dae.der(var), rhs)
    for o, rhs in zip(system.outputs, values[n_x:]):
        dae.eq(dae.add(o.name, "output", "continuous", _opts(o.unit, o.description)), rhs)
    return dae


def model_identifier(system: OdeSystem) -> str:
    """The FMU's model identifier, from the model's class name: a name CasADi takes for its
    functions (a letter, then letters, digits and single underscores), whatever the class
    is called (``My__Model_`` -> ``My_Model``)."""
    name = re.sub(r"[^A-Za-z0-9]+", "_", system.name.split(".")[-1]).strip("_")
    return name if name[:1].isalpha() else f"Model_{name}".rstrip("_")


@contextlib.contextmanager
def _removed_unless_moved(path: Path):
    """``path`` (the FMU packed beside its target) removed if the block leaves it there."""
    try:
        yield
    finally:
        path.unlink(missing_ok=True)


def _compile(model_id: str, sources: list[str], folder: Path) -> str:
    """Build the FMU's shared library from ``sources`` in ``folder``; returns its file
    name. Runs outside :data:`PYTHON_SIDE`: it reads no working folder of the process's."""
    cc = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc")
    if cc is None:
        raise ModelicaBuildError("no C compiler found (set CC or install gcc)")
    lib = model_id + sharedLibraryExtension
    # the compiler's own temporary files in the build's scratch folder, removed with it
    # even when the compiler is killed
    res = subprocess.run([cc, *COMPILER_FLAGS, "-shared", "-fPIC", "-I", fmi_headers_dir(), "-I",
                          ".", "-o", lib, *sources, "-lm"], capture_output=True, text=True,
                         cwd=folder, env={**os.environ, "TMPDIR": str(folder)})
    if res.returncode != 0:
        raise ModelicaBuildError(f"compiling the FMU failed: {res.stderr.strip()[:500]}")
    return lib


def export_fmu(system: OdeSystem, out_path: str | Path) -> Path:
    """Generate C code, compile it with the system C compiler and pack the FMU."""
    out_path = Path(out_path).resolve()
    out_path.parent.mkdir(parents=True, exist_ok=True)
    model_id = model_identifier(system)
    tmp_out = out_path.with_suffix(".fmu.tmp")
    with scratch_folder("fmu_build_") as work, _removed_unless_moved(tmp_out):
        with PYTHON_SIDE, contextlib.chdir(work):
            dae = to_dae_builder(system)
            try:
                files = dae.export_fmu({"no_warning": True, "with_serialization": False})
            except RuntimeError as err:
                raise ModelicaBuildError(f"CasADi could not export the FMU: "
                                         f"{str(err).strip().splitlines()[-1]}") from err
            md = Path("modelDescription.xml")
            text = add_unit_definitions(md.read_text())
            if system.derived:
                text = parameter_stage.add_to_export(Path("."), model_id, system, files, text)
            sources = [f for f in files if f.endswith(".c")]
            md.write_text(complete_for_fmi(text))
        lib = _compile(model_id, sources, work)
        files[lib] = f"binaries/{platform_tuple}/{lib}"
        with PYTHON_SIDE, contextlib.chdir(work):
            try:
                packed = work / dae.pack_fmu(files, {"path": "model.fmu"})
            except RuntimeError as err:
                raise ModelicaBuildError(f"CasADi could not pack the FMU: "
                                         f"{str(err).strip().splitlines()[-1]}") from err
        shutil.move(packed, tmp_out)
        os.replace(tmp_out, out_path)
    return out_path
