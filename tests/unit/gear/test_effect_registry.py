"""The effect catalogue, the Modelica package and the Makefile name the same effects, and
each fitted parameter's range searched (the catalogue's, written there alone) lies where
its Modelica declaration says the model holds (docs/effects.md: an effect is one Modelica
file and one catalogue entry)."""

import math
import re
import subprocess
from pathlib import Path

import pytest

from pydiag.gear.effect import GEAR, PARTS, PINION
from pydiag.gear.effects import EFFECTS

ROOT = Path(__file__).resolve().parents[3]
LIBRARY = ROOT / "modelica" / "GearDiag"
DECLARATION = r"parameter\s+(?:Real|Integer)\s+{name}\s*(?:\(([^)]*)\))?\s*="


def package_order() -> list[str]:
    return (LIBRARY / "Effects" / "package.order").read_text().split()


def declaration(effect, variable: str) -> dict[str, float] | None:
    """min and max of ``variable`` where the effect's model (or what it extends) declares it."""
    own = [] if effect.in_base else [LIBRARY / "Effects" / f"{effect.model.rsplit('.', 1)[1]}.mo"]
    base = [LIBRARY / "GearPair.mo", LIBRARY / "Interfaces" / "PartialMeshLaw.mo"]
    for path in own + sorted((LIBRARY / "Components").glob("*.mo")) + base:
        m = re.search(DECLARATION.format(name=re.escape(variable)), path.read_text())
        if m:
            attrs = dict(re.findall(r"(\w+)\s*=\s*([^,]+)", m.group(1) or ""))
            return {k: float(v) for k, v in attrs.items() if k in ("min", "max")}
    return None


def test_the_package_lists_every_effect_model_of_the_catalogue_and_no_other():
    models = {e.model.rsplit(".", 1)[1] for e in EFFECTS.values() if not e.in_base}
    assert sorted(package_order()) == sorted(models)  # once each (a gear bearing's shares)
    for name in package_order():
        text = (LIBRARY / "Effects" / f"{name}.mo").read_text()
        assert re.search(rf"^model {name}\b", text, re.M), name
    for e in EFFECTS.values():
        assert e.model.startswith("GearDiag."), e.key
        assert e.in_base == (e.model == "GearDiag.GearPair"), e.key


def test_make_builds_the_effects_the_package_lists():
    out = subprocess.run(["make", "-s", "--no-print-directory", "-f", "Makefile", "-f", "-",
                          "print-effects"], cwd=ROOT, input="print-effects:\n\t@echo $(EFFECTS)\n",
                         capture_output=True, text=True, check=True).stdout
    assert out.split() == package_order()


@pytest.mark.parametrize("key", sorted(EFFECTS))
def test_each_range_searched_lies_where_the_model_holds(key):
    """The catalogue writes the range a fit searches; the Modelica declaration writes where
    the model holds (its ``min``/``max``: an amplitude not negative, a relative loss at most
    1, a contact ratio between 1 and 2). Each parameter is declared, and its search lies
    within; an angle (one turn) and a tooth's index (the wheel's teeth) are searched over
    what the kinematics give."""
    effect = EFFECTS[key]
    for p in effect.parameters:
        declared = declaration(effect, p.fmu_variable)
        assert declared is not None, f"{key}: {p.fmu_variable} is not declared in {effect.model}"
        if p.periodic or p.step is not None:
            continue
        assert "min" in declared, (key, p.name, "no lower bound where the model holds")
        assert declared["min"] <= p.low < p.high <= declared.get("max", math.inf), \
            (key, p.name, declared, (p.low, p.high))



def test_every_fault_of_a_part_is_sized_by_its_own_amplitudes():
    """An effect that is a fault of a part of its stage names the parameters that size it
    (its own, none a phase); a ripple and a housing mode size no part of the stage (the
    drive, the sensor's path). Another shaft's orders size the other shaft (in a machine,
    the shaft no pinion of the stage's sits on: the output shaft's only judge)."""
    for key, effect in EFFECTS.items():
        names = {p.name: p for p in effect.parameters}
        assert all(name in names and not names[name].periodic and part in PARTS
                   for name, part in effect.parts), key
    without = {k for k, e in EFFECTS.items() if not e.parts}
    assert without == {"load_fluctuation", "speed_fluctuation", "housing_sensor"}


def test_the_part_is_that_of_the_sizing_parameter_that_grew_most():
    modulation = EFFECTS["mesh_modulation"]
    assert modulation.part_of({"m_p": 0.24, "m_g": -0.04, "phi_g": 3.0}) == PINION
    assert modulation.part_of({"m_p": 0.01, "m_g": 0.05}) == GEAR
    assert modulation.part_of({"m_p": 0.05, "m_g": -0.01}) == PINION  # a fall names none
    # the record asks mostly for less modulation: a part that grew by less (a rounding's
    # worth) names nothing
    assert modulation.part_of({"m_p": -0.0084, "m_g": 0.00004}) is None
    assert EFFECTS["pinion_shaft_orders"].part_of({"A_s1": -150.0, "A_s2": -99.0}) is None
    assert EFFECTS["speed_fluctuation"].part_of({"ds": 0.01}) is None
