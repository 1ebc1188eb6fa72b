"""The model's verdict (`diagnose --machine` with a healthy model and two or more
baselines): the machine file's effects are those `pydiag loop` gave the gearbox
simulator's short box on a healthy record (tests/golden/short_box.loop.toml); each is
refitted held out on a record with a broken output-gear tooth, which the simulator writes
as a dip of the mesh's amplitude once a turn of the output shaft, not as the model's
modulation."""

import json

from conftest import ROOT, run_cli
from truth.gearbox import SHORT_BOX, gearbox_record

from pydiag.io.measurements import write_measurement

HEALTHY_MODEL = ROOT / "tests" / "golden" / "short_box.loop.toml"


def test_the_healthy_models_modulation_names_the_broken_output_gear(tmp_path):
    healthy = []
    for seed in (1, 3, 4):  # the model's own record first, then two healthy repeats
        healthy.append(tmp_path / f"healthy_{seed}.csv")
        write_measurement(healthy[-1], gearbox_record(seed, box=SHORT_BOX))
    broken = tmp_path / "broken.csv"
    write_measurement(broken, gearbox_record(2, faulty_shaft=2, stage=1, box=SHORT_BOX))
    out = tmp_path / "out.json"
    r = run_cli("-m", "pydiag", "diagnose", "--machine", str(HEALTHY_MODEL), "--measurement",
                str(broken), *(a for h in healthy for a in ("--baseline", str(h))),
                "--json", str(out), "--build-dir", str(tmp_path / "build"), "--quiet",
                # a small swarm: the healthy fit polishes from the file's [start] too
                "--particles", "8", "--iterations", "4", "--polish", "60")
    assert r.returncode == 0, r.stderr
    changes = json.loads(out.read_text())["model_changes"]
    assert {(c["stage"], c["effect"]) for c in changes} == {
        ("stage 1", "mesh_stiffness_shape"), ("stage 2", "mesh_modulation"),
        ("stage 2", "mesh_stiffness_shape")}
    changed = [c for c in changes if c["changed"]]
    assert len(changed) == 1 and changed[0]["effect"] == "mesh_modulation", changes
    assert changed[0]["part"] == "gear" and changed[0]["components"] == ["50T gear of stage 2"]
    healthy_m_g, fitted_m_g = changed[0]["values"]["stage_2.m_g"]
    assert fitted_m_g > 1.15 * healthy_m_g  # the gear's modulation deepened
    assert all(c["margin"] < 1 for c in changes if not c["changed"])
    assert "mesh_modulation               stage 2         changed" in r.stdout
    assert ": 50T gear of stage 2" in r.stdout
