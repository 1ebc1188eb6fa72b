"""held_out of an effect the model has (``own``): its parameters polished on half A from
the base fit's values and scored on half B against them. Plumbing, on records of the
model itself (no diagnosis is claimed here; what it finds on the gearbox simulator's
records is bench/CHANGELOG.md's, 2026-11-29)."""

import numpy as np
import pytest
from conftest import SENSORS

from pydiag.core.measurement import Measurement
from pydiag.fit.build import build_problem
from pydiag.fit.estimator import FaultEstimator
from pydiag.fmu.plant import FmuPlant
from pydiag.gear.conventions import kinematics_from
from pydiag.gear.effects import EFFECTS
from pydiag.loop.compare import compare
from pydiag.loop.effect_fit import EFFECT_REFIT, refit_own
from pydiag.loop.held_out import held_out
from pydiag.model.adapter import gear_default
from pydiag.signal.noise import add_white_noise

SHAPE = EFFECTS["mesh_stiffness_shape"]
#: The healthy pair's stiffness wave, as a baseline's fit would have it.
HEALTHY = {"a_f": 0.0, "f_f": 0.0, "f_ate": 0.1, "f_dte": 0.1,
           "k2": 0.10, "phi2": 0.5, "k4": 0.03, "phi4": -1.0}


def record(fmu, values: dict[str, float], seed: int) -> Measurement:
    """Ten fundamental periods of the pair at ``values``, SNR 20 on each channel."""
    with FmuPlant(fmu, SENSORS) as plant:
        kin = kinematics_from(plant.parameters())
        clean = plant.simulate(values, 10 * kin.period_s, 0.05)
    rng = np.random.default_rng(seed)
    return Measurement({s: add_white_noise(clean[i], 20.0, rng)
                        for i, s in enumerate(SENSORS)}, 10_000.0)


def seen_through_healthy(fmu, values: dict[str, float], seed: int):
    """(problem, comparison) of a record of the pair at ``values``, seen through the
    healthy fit: its parameters held at HEALTHY's."""
    problem = build_problem(str(fmu), record(fmu, values, seed),
                            parameters=gear_default(list(SENSORS)).fault_parameters
                            + SHAPE.parameters)
    return problem, compare(problem, None, parameters=HEALTHY)


@pytest.mark.parametrize("k2, changed", [(0.10, False), (0.13, True)])
def test_a_record_that_asks_for_other_values_of_an_effect_the_model_has(gear_fmu, k2,
                                                                         changed):
    """A record of the healthy wave: the refit keeps its depth, and the record does not
    ask for other values. One whose wave is 30 % deeper: the refit finds the depth, and
    the held-out test is confident that the record asks for it."""
    problem, base = seen_through_healthy(gear_fmu, {**HEALTHY, "k2": k2}, seed=3)
    h = held_out(problem, base, SHAPE, "unused", FaultEstimator(**EFFECT_REFIT), own=True)
    assert h.tried and h.parameters["k2"] == pytest.approx(k2, abs=0.02), h
    assert h.confirmed is changed, (h.z, h.explained, h.message)


def test_an_effect_the_model_lacks_cannot_be_refitted_as_its_own(gear_fmu):
    problem, base = seen_through_healthy(gear_fmu, HEALTHY, seed=3)
    bare = problem.derive(parameters=tuple(p for p in problem.parameters
                                           if p.name not in {"k2", "phi2", "k4", "phi4"}))
    with pytest.raises(ValueError, match="not in the model"):
        refit_own(bare, base, SHAPE, problem.featurizer, FaultEstimator(**EFFECT_REFIT))
