"""Try every effect of the catalogue and rank them: which missing physics explains the
measurement best for the parameters it adds?

For each effect: build its FMU from ``modelica/GearDiag/Effects`` (cached, rebuilt when a
Modelica file is newer), refit its parameters (:func:`pydiag.loop.compare.refit_with_effect`)
and compare on the same bins as the base model. Ranking by the Bayesian information
criterion relative to the base model,

    dBIC = n ln(RSS_effect / RSS_base) + k ln(n),

with n the bins scored (all channels), RSS the weighted squared residual of Eq. (12)
(``error_raw``^2 times the same measured power, which cancels) and k the effect's added
parameters. BIC rather than AIC: its ln(n) penalty grows with the hundreds of bins
compared, so an effect must explain real structure, not noise, to rank first. Negative
dBIC means the effect is worth its parameters.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from fmu_build import ModelicaBuildError as BuildError
from fmu_build import build_fmu

from pydiag.core.errors import PydiagError, UsageError
from pydiag.fit.estimator import FaultEstimator
from pydiag.fit.problem import FitProblem
from pydiag.gear.effects import EFFECTS, model_file
from pydiag.gear.kinematic_map import Bearing
from pydiag.loop.compare import Comparison, compare, refit_with_effect

#: The Modelica library of a source checkout (an installed wheel does not carry it).
MODELICA_ROOT = Path(__file__).resolve().parents[2] / "modelica"


@dataclass
class Discovery:
    effect: str
    status: str  # "ok", or the error that stopped this effect
    delta_bic: float
    error: float
    error_reduction: float  # 1 - error / base error
    added_parameters: int
    parameters: dict[str, float]


def effect_fmu(key: str, modelica_root: Path, build_dir: Path) -> Path:
    """The effect's FMU, built unless an up-to-date one exists."""
    effect = EFFECTS[key]
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
    """Compare the base model (``problem``), then refit and rank every effect.

    ``estimator`` fits the base model, ``effect_estimator`` each effect's parameters
    (default: :data:`pydiag.loop.compare.EFFECT_REFIT`).
    """
    unknown = [key for key in effects or () if key not in EFFECTS]
    if unknown:
        raise UsageError(f"unknown effect(s) {', '.join(unknown)}; known: {', '.join(EFFECTS)}")
    base = compare(problem, estimator, bearing)
    n = base.n_error_bins * len(base.spectra)
    found = []
    for key in effects or list(EFFECTS):
        if progress:
            progress(key)
        k = len(EFFECTS[key].parameters)
        try:
            fmu = effect_fmu(key, modelica_root, build_dir)
            c = refit_with_effect(problem, base, EFFECTS[key], str(fmu), effect_estimator, bearing)
        except (PydiagError, BuildError) as err:  # one effect that cannot be built or fitted is a row
            found.append(Discovery(key, f"{type(err).__name__}: {err}", float("inf"),
                                   float("nan"), float("nan"), k, {}))
            continue
        ratio = max(c.error_raw, 1e-12) ** 2 / max(base.error_raw, 1e-12) ** 2
        found.append(Discovery(key, "ok", float(n * np.log(ratio) + k * np.log(n)), c.error,
                               1 - c.error / base.error if base.error > 0 else 0.0, k,
                               {p.name: c.parameters[p.name] for p in EFFECTS[key].parameters}))
    found.sort(key=lambda d: d.delta_bic)
    return base, found


def as_dict(base: Comparison, found: list[Discovery]) -> dict:
    return {"base_error": base.error, "criterion": "BIC", "ranking": [asdict(d) for d in found]}
