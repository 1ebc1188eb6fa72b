"""A parameter stage for CasADi's FMU: derived parameters computed once per parameter set.

CasADi's FMU wrapper has one generated function for derivatives and outputs and calls it
on every right-hand side; derived parameters inlined into it were recomputed on every
call. For GearPair that was half the cost of a call: ``N_ap = lcm(Np, Ng)/Np`` unrolls a
30-step Euclid loop (0.29 vs 0.15 us per call, measured with the native engine). Modelica
tools evaluate parameter bindings once, in a parameter stage; this module gives the FMU
one:

- every derived parameter is an FMU variable of its own (``causality=
  "calculatedParameter"``), an input of the model function instead of an expression in it;
- a second generated function, ``<id>_parameters(p) -> d``, computes them from the free
  parameters, in its own source file (``<id>_parameters.c``);
- the wrapper is patched to call it when, and only when, a free parameter differs from
  the values the derived ones were computed from (a 15-double ``memcmp`` per evaluation
  for GearPair), and to write the results where the model function and ``fmi3GetFloat64``
  read them. Values a caller writes into a calculated parameter are overwritten.

The patch anchors on CasADi 3.8.2's wrapper text; if an anchor is missing the build stops
with an error naming it instead of producing an FMU that computes the wrong thing.
Directional derivatives with respect to parameters do not see the chain through the
derived ones; the model structure CasADi writes declares no parameter dependencies, so
FMI importers do not ask for them.
"""

from __future__ import annotations

import re
from pathlib import Path

import casadi as ca

from fmu_build.errors import ModelicaBuildError
from fmu_build.scratch import scratch_folder
from fmu_build.ode_system import OdeSystem

_STRUCT_ANCHOR = "  // Has any variable been set since last call\n  int up_to_date;\n"
_RESET_ANCHOR = "  // Not evaluated\n  m->up_to_date = 0;\n  // Zero index is negative: No event\n"
_COPY_P = "  for (i = 0; i < N_P; ++i) m->p[i] = m->v[p_vr[i]];\n"
_EVALUATE = "int evaluate(casadi_fmi_memory* m) {\n"


def add_to_export(folder: Path, model_id: str, system: OdeSystem, files: dict[str, str],
                  model_description: str) -> str:
    """Add the stage to the files CasADi's ``export_fmu`` wrote in ``folder``.

    Patches ``<id>_wrap.c`` and ``buildDescription.xml`` in place, writes
    ``<id>_parameters.c`` and adds it to ``files`` (local name -> archive path); returns
    ``model_description`` with the derived parameters made calculated parameters.
    """
    names = [q.name for q in system.derived]
    refs = value_references(model_description, names)
    wrap = folder / f"{model_id}_wrap.c"
    wrap.write_text(patch_wrapper(wrap.read_text(), model_id, len(system.parameters), refs))
    stage_file = f"{stage_function_name(model_id)}.c"
    (folder / stage_file).write_text(stage_source(
        model_id, [q.symbol for q in system.parameters], [q.expr for q in system.derived]))
    files[stage_file] = f"sources/{stage_file}"
    build = folder / "buildDescription.xml"
    build.write_text(add_source_file(build.read_text(), stage_file))
    return mark_calculated(model_description, names)


def stage_function_name(model_id: str) -> str:
    return f"{model_id}_parameters"


def stage_source(model_id: str, free: list[ca.SX], derived: list[ca.SX]) -> str:
    """C source of ``<id>_parameters_eval(const double* p, double* d)``, CasADi-generated."""
    name = stage_function_name(model_id)
    f = ca.Function(name, [ca.vertcat(*free)], [ca.vertcat(*derived)])
    with scratch_folder("fmu_build_stage_") as tmp:
        path = tmp / f"{name}.c"
        gen = ca.CodeGenerator(path.name, {"with_header": False})
        gen.add(f)
        gen.generate(f"{tmp}/")
        code = path.read_text()
    sizes = {k: max(1, int(getattr(f, f"sz_{k}")())) for k in ("arg", "res", "iw", "w")}
    return code + f"""
/* gear-diag: the derived parameters d from the free parameters p (parameter_stage.py). */
int {name}_eval(const casadi_real* p, casadi_real* d) {{
  const casadi_real* arg[{sizes['arg']}];
  casadi_real* res[{sizes['res']}];
  casadi_int iw[{sizes['iw']}];
  casadi_real w[{sizes['w']}];
  arg[0] = p;
  res[0] = d;
  return {name}(arg, res, iw, w, 0);
}}
"""


def _value_references(wrapper: str, array: str) -> list[int]:
    m = re.search(rf"fmi3ValueReference {array}\[\w+\] = \{{([^}}]*)\}};", wrapper)
    if m is None:
        raise ModelicaBuildError(f"CasADi's FMU wrapper has no '{array}' array; the parameter "
                                 "stage supports CasADi 3.8.2's wrapper")
    return [int(v) for v in m.group(1).replace(" ", "").split(",") if v]


def patch_wrapper(wrapper: str, model_id: str, n_free: int, derived_vrs: list[int]) -> str:
    """Add the parameter stage to CasADi's ``<id>_wrap.c``.

    The model's parameter vector is ``[free..., derived...]``; ``derived_vrs`` are the value
    references of the derived ones, in that order.
    """
    p_vr = _value_references(wrapper, "p_vr")
    if p_vr[n_free:] != derived_vrs or len(p_vr) != n_free + len(derived_vrs):
        raise ModelicaBuildError("CasADi ordered the FMU's parameters unexpectedly: free ones "
                                 f"then derived ones {derived_vrs} expected, got {p_vr}")
    for anchor, what in ((_STRUCT_ANCHOR, "memory struct"), (_RESET_ANCHOR, "fmi3Reset"),
                         (_COPY_P, "parameter copy"), (_EVALUATE, "evaluate()")):
        if anchor not in wrapper:
            raise ModelicaBuildError(f"CasADi's FMU wrapper changed: the {what} anchor of the "
                                     "parameter stage is missing (written for CasADi 3.8.2)")
    name = stage_function_name(model_id)
    n_d = len(derived_vrs)
    include = f'#include "{model_id}.h"\n'
    prelude = f"""#include <string.h>
/* gear-diag parameter stage (fmu_build/parameter_stage.py) */
#define PD_N_FREE {n_free}
#define PD_N_DERIVED {n_d}
static const fmi3ValueReference pd_vr[PD_N_DERIVED] = {{{", ".join(map(str, derived_vrs))}}};
int {name}_eval(const casadi_real* p, casadi_real* d);
"""
    refresh = f"""/* gear-diag: recompute the derived parameters when a free one changed. */
static int pd_refresh(casadi_fmi_memory* m) {{
  size_t i;
  if (!m->pd_valid || memcmp(m->pd_p, m->p, sizeof(m->pd_p)) != 0) {{
    if ({name}_eval(m->p, m->pd_d)) return 1;
    memcpy(m->pd_p, m->p, sizeof(m->pd_p));
    m->pd_valid = 1;
  }}
  for (i = 0; i < PD_N_DERIVED; ++i) {{
    m->v[pd_vr[i]] = m->pd_d[i];
    m->p[PD_N_FREE + i] = m->pd_d[i];
  }}
  return 0;
}}
"""
    out = wrapper.replace(include, include + prelude, 1)
    out = out.replace(_STRUCT_ANCHOR, _STRUCT_ANCHOR + "  // gear-diag parameter stage: free "
                      "parameters of the last stage, its results\n  int pd_valid;\n"
                      "  double pd_p[PD_N_FREE];\n  double pd_d[PD_N_DERIVED];\n", 1)
    out = out.replace(_RESET_ANCHOR, _RESET_ANCHOR.replace(
        "  // Zero index", "  m->pd_valid = 0;\n  // Zero index"), 1)
    out = out.replace(_COPY_P, _COPY_P + "  if (pd_refresh(m)) return 1;\n")
    out = out.replace(_EVALUATE, refresh + _EVALUATE, 1)
    return out


def mark_calculated(model_description: str, names: list[str]) -> str:
    """Make the derived parameters ``calculatedParameter``s (not settable, no start)."""
    for name in names:
        pattern = re.compile(rf'<Float64 [^>]*\bname="{re.escape(name)}"[^>]*/>')
        m = pattern.search(model_description)
        if m is None:
            raise ModelicaBuildError(f"derived parameter '{name}' is missing from the model "
                                     "description CasADi wrote")
        element = m.group(0)
        element = element.replace('causality="parameter"', 'causality="calculatedParameter"')
        element = element.replace('initial="exact"', 'initial="calculated"')
        element = re.sub(r' start="[^"]*"', "", element)
        model_description = model_description[:m.start()] + element + model_description[m.end():]
    return model_description


def value_references(model_description: str, names: list[str]) -> list[int]:
    refs = []
    for name in names:
        m = re.search(rf'<Float64 [^>]*\bname="{re.escape(name)}"[^>]*/>', model_description)
        vr = re.search(r'valueReference="(\d+)"', m.group(0)) if m else None
        if vr is None:
            raise ModelicaBuildError(f"derived parameter '{name}' has no value reference in the "
                                     "model description CasADi wrote")
        refs.append(int(vr.group(1)))
    return refs


def add_source_file(build_description: str, file_name: str) -> str:
    anchor = "        </SourceFileSet>"
    if anchor not in build_description:
        raise ModelicaBuildError("CasADi's buildDescription.xml has no SourceFileSet")
    return build_description.replace(
        anchor, f'            <SourceFile name="{file_name}"/>\n' + anchor, 1)
