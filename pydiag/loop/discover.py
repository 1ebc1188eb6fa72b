"""Try every effect of the catalogue and rank them: which missing physics explains the
measurement, held out?

For each effect: build its FMU from ``modelica/GearDiag/Effects`` (cached, rebuilt when a
Modelica file is newer; an effect whose parameters are the base model's own uses the
base FMU), fit its parameters on half of the record's periods and score it on the other
half (:func:`pydiag.loop.validate.held_out`). The ranking is by the held-out z: how far
the effect lowers the error on data it was not fitted to, in standard deviations of what
noise alone would do. The Bayesian information criterion on the fitted half (dBIC < 0:
worth its parameters if the residual were white noise) is printed beside it; a misfit of
the model's form is not white noise, so BIC alone is not the ranking.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Callable

from fmu_build import ModelicaBuildError as BuildError
from fmu_build import build_fmu

from pydiag.core.errors import PydiagError, UsageError
from pydiag.fit.estimator import FaultEstimator
from pydiag.fit.problem import FitProblem
from pydiag.gear.effects import EFFECTS, model_file
from pydiag.gear.kinematic_map import Bearing
from pydiag.loop.compare import Comparison, compare
from pydiag.loop.validate import held_out, in_model, outcompeted

#: The Modelica library of a source checkout (an installed wheel does not carry it).
MODELICA_ROOT = Path(__file__).resolve().parents[2] / "modelica"


@dataclass
class Discovery:
    effect: str
    status: str  # "ok", or the error that stopped this effect
    z: float  # held-out improvement, in noise standard deviations
    delta_bic: float  # on the fitted half
    error: float  # held out, with the effect
    error_reduction: float  # 1 - error / base error, held out
    added_parameters: int
    parameters: dict[str, float]
    confident: bool = False
    verdict: str = ""


def effect_fmu(key: str, modelica_root: Path, build_dir: Path) -> Path:
    """The effect's FMU, built unless an up-to-date one exists. An ``in_base`` effect has
    none: its FMU is the base model's."""
    effect = EFFECTS[key]
    if effect.in_base:
        raise ValueError(f"{key} frees parameters of the base model: it has no FMU of its own")
    out = Path(build_dir) / f"{effect.model.rsplit('.', 1)[1]}.fmu"
    sources = list(Path(modelica_root).rglob("*.mo"))
    if not sources:
        raise UsageError(f"no Modelica library at {modelica_root}; give --modelica")
    newest = max(p.stat().st_mtime for p in sources)
    if not out.exists() or out.stat().st_mtime < newest:
        build_fmu(model_file(effect, modelica_root), effect.model, out)
    return out


def discover(problem: FitProblem, estimator: FaultEstimator | None = None,
             bearing: Bearing | None = None, effects: list[str] | None = None,
             modelica_root: Path = MODELICA_ROOT, build_dir: Path = Path("build/effects"),
             progress: Callable[[str], None] | None = None,
             effect_estimator: FaultEstimator | None = None) -> tuple[Comparison, list[Discovery]]:
    """Compare the base model (``problem``), then try every effect held out and rank them.

    ``estimator`` fits the base model, ``effect_estimator`` each effect's parameters
    (default: :data:`pydiag.loop.compare.EFFECT_REFIT`). Effects whose parameters the base
    model already fits are left out. As in validation, at most one effect is confident
    among those that claim the same peaks (the largest z).
    """
    unknown = [key for key in effects or () if key not in EFFECTS]
    if unknown:
        raise UsageError(f"unknown effect(s) {', '.join(unknown)}; known: {', '.join(EFFECTS)}")
    base = compare(problem, estimator, bearing)
    found = []
    for key in effects or list(EFFECTS):
        effect = EFFECTS[key]
        if in_model(problem, effect):
            continue
        if progress:
            progress(key)
        k = len(effect.parameters)
        try:
            fmu = (problem.spec.fmu_path if effect.in_base
                   else str(effect_fmu(key, modelica_root, build_dir)))
            h = held_out(problem, base, effect, fmu, effect_estimator, bearing)
        except (PydiagError, BuildError) as err:  # one effect that cannot be built or fitted is a row
            found.append(Discovery(key, f"{type(err).__name__}: {err}", float("-inf"),
                                   float("inf"), float("nan"), float("nan"), k, {}))
            continue
        found.append(Discovery(key, "ok", h.z, h.delta_bic, h.error_effect,
                               1 - h.error_effect / h.error_base if h.error_base > 0 else 0.0,
                               k, h.parameters, h.confident, h.verdict))
    found.sort(key=lambda d: -d.z)
    beaten = outcompeted({d.effect: d.z for d in found if d.confident},
                         {s.effect: s.competing for s in base.suggested_effects})
    for d in found:
        if d.effect in beaten:
            d.confident, d.verdict = False, beaten[d.effect]
    return base, found


def as_dict(base: Comparison, found: list[Discovery]) -> dict:
    return {"base_error": base.error, "criterion": "held-out z (dBIC on the fitted half beside it)",
            "ranking": [asdict(d) for d in found]}
