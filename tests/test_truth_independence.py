"""The independent simulators share nothing with the models pydiag fits (issue 61): they
import nothing of pydiag's but the record type they write, so a bug in pydiag's
kinematics, effects or noise cannot hit the truth and the tool alike."""

import ast
from pathlib import Path

import pytest

TRUTH = Path(__file__).resolve().parent / "truth"
#: What the simulators may take from pydiag: the record they write.
ALLOWED = {"pydiag.core.measurement"}


@pytest.mark.parametrize("path", sorted(TRUTH.glob("*.py")), ids=lambda p: p.name)
def test_the_simulators_import_of_pydiag_only_the_record_they_write(path):
    imported = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module:
            imported.add(node.module)
        elif isinstance(node, ast.Import):
            imported.update(a.name for a in node.names)
    assert {m for m in imported if m.split(".")[0] == "pydiag"} <= ALLOWED, path


def test_the_check_sees_an_import_of_pydiag():
    """Not vacuous: the simulators are read, and a pydiag import in them would be seen."""
    sources = " ".join(p.read_text() for p in TRUTH.glob("*.py"))
    assert "from pydiag.core.measurement import Measurement" in sources
    assert len(list(TRUTH.glob("*.py"))) >= 3


def test_the_simulators_own_way_writes_its_runout_and_pitch_errors_unlike_the_model():
    """`TruthGear.own_way()`: the pinion's runout through the centres' geometry and each
    gear tooth's pitch error shared by the pairs in contact. Against the model's way (one
    sine a shaft turn, one at the assembly order): the pinion's turn line in the deflection
    is the simulator's own size (4 um, not 5), and the pitch pattern, shared tooth by tooth,
    makes harmonics of the assembly order that one sine cannot (the same mesh lines)."""
    import numpy as np
    from truth.gear_sim import TruthGear, simulate

    g = TruthGear()
    periods = 5
    lines = {}
    for name, gear in (("model's", g), ("own", g.own_way())):
        x = simulate(gear, periods * g.period_s, 10_000.0)["disp"]
        amp = 2 * np.abs(np.fft.rfft(x - x.mean())) / x.size
        f_turn = g.f_pinion_hz
        f_assembly = g.f_pinion_hz * g.n_pinion / (np.lcm(g.n_pinion, g.n_gear) // g.n_pinion)
        f_mesh = g.f_pinion_hz * g.n_pinion
        at = {k: amp[int(round(f * periods * g.period_s))] for k, f in (
            ("turn", f_turn), ("assembly 2x", 2 * f_assembly), ("mesh", f_mesh))}
        lines[name] = at
    assert abs(lines["model's"]["turn"] - 5e-6) < 0.3e-6
    assert abs(lines["own"]["turn"] - 4e-6) < 0.3e-6, lines
    assert lines["own"]["assembly 2x"] > 5 * lines["model's"]["assembly 2x"], lines
    assert np.isclose(lines["own"]["mesh"], lines["model's"]["mesh"], rtol=0.1), lines
