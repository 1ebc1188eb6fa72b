"""A machine's baseline kept once (`pydiag baseline`) and judged against later
(`--baseline kept`), on records of :mod:`truth.gearbox` (written from the shafts' angles)."""

import json

from conftest import run_cli
from boxes import MACHINE
from truth.gearbox import INPUT_HZ, gearbox_record

from pydiag.io.measurements import write_measurement


def box(tmp_path) -> tuple:
    """The test box's machine file, a history, and the options that name them."""
    machine = tmp_path / "box.toml"
    machine.write_text(f'name = "{MACHINE.name}"\ninput_rpm = {60 * INPUT_HZ}\n'
                       + "".join(f"[[stages]]\npinion_teeth = {s.pinion_teeth}\n"
                                 f"gear_teeth = {s.gear_teeth}\n" for s in MACHINE.stages))
    db = str(tmp_path / "history.sqlite")
    return machine, db, ("--machine", str(machine), "--speed", "mesh", "--history", db)


def test_a_kept_baseline_judges_as_the_file_it_was_kept_from(tmp_path):
    write_measurement(tmp_path / "healthy.csv", gearbox_record(1))
    write_measurement(tmp_path / "broken.csv", gearbox_record(3, faulty_shaft=2, stage=1))
    machine, db, common = box(tmp_path)
    res = run_cli("-m", "pydiag", "baseline", "--measurement", str(tmp_path / "healthy.csv"),
                  *common)
    assert res.returncode == 0, res.stderr
    assert "kept       : baseline 1 of two-stage test box" in res.stdout
    listed = run_cli("-m", "pydiag", "baseline", "--list", *common)
    assert "healthy.csv" in listed.stdout and "1 kept for two-stage test box" in listed.stdout

    judged = {}
    for how in ("kept", str(tmp_path / "healthy.csv")):
        out = tmp_path / f"{len(judged)}.json"
        res = run_cli("-m", "pydiag", "indicators", "--measurement", str(tmp_path / "broken.csv"),
                      *common, "--baseline", how, "--json", str(out))
        assert res.returncode == 0, res.stderr
        judged[how] = json.loads(out.read_text())
    kept, read = judged.values()
    assert kept["stages"] == read["stages"]
    assert [s["baseline"]["verdict"] for s in kept["stages"]] == ["healthy", "changed"]
    assert kept["baselines"] == [f"kept 1: {read['baselines'][0]}"]

    # at another operating point the kept baseline is not used: said, and nothing judged
    res = run_cli("-m", "pydiag", "indicators", "--measurement", str(tmp_path / "broken.csv"),
                  *common, "--baseline", "kept", "--rpm", str(60 * INPUT_HZ * 1.2))
    assert res.returncode == 2 and res.stdout == ""
    assert "no baseline of machine 'two-stage test box'" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1
    res = run_cli("-m", "pydiag", "baseline", "--forget", "1", *common)
    assert res.returncode == 0 and "forgot baseline 1" in res.stdout, res.stderr
    res = run_cli("-m", "pydiag", "baseline", "--list", *common)
    assert "none kept for two-stage test box" in res.stdout


def test_a_baseline_counts_once_and_a_record_judged_against_itself_is_said(tmp_path):
    """A baseline given twice (or given and kept) counts once, with a warning: a second copy
    would narrow the healthy spread; a record that is one of its baselines is said to be
    judged against itself; a kept baseline's path is stored whole; a --history that does
    not exist is no "none kept"."""
    write_measurement(tmp_path / "healthy.csv", gearbox_record(1))
    write_measurement(tmp_path / "other.csv", gearbox_record(2))
    machine, db, common = box(tmp_path)
    res = run_cli("-m", "pydiag", "baseline", "--measurement", "healthy.csv", *common,
                  cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    listed = run_cli("-m", "pydiag", "baseline", "--list", *common)
    assert str(tmp_path / "healthy.csv") in listed.stdout

    def judged(*baselines: str) -> tuple[dict, str]:
        out = tmp_path / "j.json"
        res = run_cli("-m", "pydiag", "indicators", "--measurement",
                      str(tmp_path / "other.csv"), *common, "--json", str(out), "--force",
                      *[a for b in baselines for a in ("--baseline", b)])
        assert res.returncode == 0, res.stderr
        return json.loads(out.read_text()), res.stderr

    once, said = judged(str(tmp_path / "healthy.csv"))
    assert said == ""
    for twice in ((str(tmp_path / "healthy.csv"), str(tmp_path / ".." / tmp_path.name
                                                       / "healthy.csv")),
                  (str(tmp_path / "healthy.csv"), "kept"),
                  ("kept", str(tmp_path / "healthy.csv"))):  # in either order
        data, said = judged(*twice)
        assert data["stages"] == once["stages"] and len(data["baselines"]) == 1, twice
        assert "counts once" in said or "count once" in said, said
    _, said = judged(str(tmp_path / "other.csv"), str(tmp_path / "healthy.csv"))
    assert "is the record itself" in said
    res = run_cli("-m", "pydiag", "baseline", "--list", "--machine", str(machine),
                  "--history", str(tmp_path / "no" / "such.sqlite"))
    assert res.returncode == 2 and "no such file" in res.stderr, res.stderr
