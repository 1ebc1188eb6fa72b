"""What an FMU is: FMI version, interfaces, platforms, and which variables can be set when."""

from __future__ import annotations

import zipfile
from dataclasses import dataclass, field
from pathlib import Path

from pydiag.core.errors import PlantError
from pydiag.fmu.description import read_model_description, settability


@dataclass(frozen=True)
class VariableInfo:
    name: str
    type_name: str
    causality: str
    variability: str | None
    start: str | None
    unit: str | None
    settable: str  # "before init", "any time", "no", with the reason in ``note``
    note: str
    description: str | None


@dataclass
class FmuInfo:
    path: str
    fmi_version: str
    model_name: str
    generation_tool: str | None
    interfaces: list[str]
    platforms: list[str]
    event_indicators: int
    warnings: list[str] = field(default_factory=list)
    variables: list[VariableInfo] = field(default_factory=list)


def describe(fmu_path: str | Path) -> FmuInfo:
    path = Path(fmu_path)
    md, warnings = read_model_description(path)
    try:
        with zipfile.ZipFile(path) as z:
            platforms = sorted({n.split("/")[1] for n in z.namelist()
                                if n.startswith("binaries/") and n.count("/") >= 2 and n.split("/")[1]})
            if any(n.startswith("sources/") for n in z.namelist()):
                platforms.append("sources")
    except zipfile.BadZipFile as err:
        raise PlantError(f"{path} is not a zip archive: {err}") from err
    interfaces = [name for name, part in (("ModelExchange", md.modelExchange),
                                          ("CoSimulation", md.coSimulation),
                                          ("ScheduledExecution", getattr(md, "scheduledExecution", None)))
                  if part is not None]
    info = FmuInfo(str(path), md.fmiVersion, md.modelName, md.generationTool, interfaces,
                   platforms, md.numberOfEventIndicators or 0, warnings)
    for v in md.modelVariables:
        settable, note = settability(v.causality, v.variability)
        info.variables.append(VariableInfo(v.name, v.type, v.causality, v.variability,
                                           None if v.start is None else str(v.start), v.unit,
                                           settable, note, v.description))
    return info


def format_info(info: FmuInfo, all_variables: bool = False) -> str:
    lines = [f"{info.path}",
             f"  FMI {info.fmi_version}, {' + '.join(info.interfaces) or 'no interface'}, "
             f"model '{info.model_name}', made by {info.generation_tool or 'unknown tool'}",
             f"  platforms: {', '.join(info.platforms) or 'none'}; event indicators: "
             f"{info.event_indicators}"]
    for w in info.warnings:
        lines.append(f"  warning: {w}")
    shown = [v for v in info.variables if all_variables or v.causality in
             ("parameter", "calculatedParameter", "input", "output")]
    lines.append(f"  {len(info.variables)} variables"
                 + ("" if all_variables else f", {len(shown)} shown (parameters, inputs, outputs)"))
    lines.append(f"  {'name':<28} {'causality':<20} {'variability':<11} {'start':>12} "
                 f"{'unit':<8} settable")
    for v in shown:
        lines.append(f"  {v.name:<28} {v.causality:<20} {v.variability or '':<11} "
                     f"{(v.start or '')[:12]:>12} {(v.unit or ''):<8} {v.settable}"
                     + (f"  ({v.note})" if v.settable == "no" else ""))
    return "\n".join(lines)
