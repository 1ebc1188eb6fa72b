"""Fixes to the modelDescription.xml CasADi writes, so that fmpy's validation passes.

- ``<UnitDefinitions>``: CasADi writes ``unit`` attributes without declaring the units;
  fmpy rejects that ("unit kg is not defined").
- ``variableNamingConvention``: CasADi declares "structured" but names its helper
  variables ``__assign__der(v)__``, which that convention forbids; "flat" allows any name.
- ``<InitialUnknown>``: FMI 3.0 (2.4.8) lists as initial unknowns every output,
  calculated parameter, continuous state and state derivative whose ``initial`` is not
  "exact"; CasADi leaves out the states (and the calculated parameters the parameter
  stage adds). Added entries have no ``dependencies`` attribute: they may depend on every
  known, which is always true. Entries are ordered by value reference.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET

from fmu_build.errors import ModelicaBuildError


def add_unit_definitions(model_description: str) -> str:
    """Insert a <UnitDefinitions> element declaring every unit the variables use."""
    units = sorted(set(re.findall(r'\bunit="([^"]+)"', model_description)))
    if not units or "<UnitDefinitions>" in model_description:
        return model_description
    block = "    <UnitDefinitions>\n" + "".join(
        f'        <Unit name="{u}"/>\n' for u in units) + "    </UnitDefinitions>\n"
    # FMI 3.0 order: ModelExchange/CoSimulation, then UnitDefinitions, ..., ModelVariables.
    anchor = model_description.index("    <ModelVariables>")
    return model_description[:anchor] + block + model_description[anchor:]


def complete_for_fmi(model_description: str) -> str:
    """Naming convention and initial unknowns, as the module docstring says."""
    text = model_description.replace('variableNamingConvention="structured"',
                                     'variableNamingConvention="flat"', 1)
    root = ET.fromstring(text.encode())
    variables = root.find("ModelVariables")
    structure = root.find("ModelStructure")
    if variables is None or structure is None:
        raise ModelicaBuildError("the model description CasADi wrote has no ModelVariables or "
                                 "ModelStructure")
    states = {v.get("derivative") for v in variables if v.get("derivative") is not None}
    expected = []
    for v in variables:
        vr = v.get("valueReference")
        if v.get("initial", "calculated") == "exact" or v.get("variability") == "constant":
            continue
        if (v.get("causality") in ("output", "calculatedParameter") or vr in states
                or v.get("derivative") is not None):
            expected.append(int(vr))
    listed = {int(u.get("valueReference")) for u in structure.findall("InitialUnknown")}
    missing = [vr for vr in expected if vr not in listed]
    if not missing:
        return text
    entries = re.findall(r"        <InitialUnknown [^>]*/>\n", text)
    merged = sorted(entries + [f'        <InitialUnknown valueReference="{vr}"/>\n'
                               for vr in missing],
                    key=lambda e: int(re.search(r'valueReference="(\d+)"', e).group(1)))
    if entries:
        first = text.index(entries[0])
        rest = text[first:]
        for e in entries:
            rest = rest.replace(e, "", 1)
        return text[:first] + "".join(merged) + rest
    anchor = "    </ModelStructure>"
    if anchor not in text:
        raise ModelicaBuildError("the model description CasADi wrote has no </ModelStructure>")
    return text.replace(anchor, "".join(merged) + anchor, 1)
