import json
import shutil
import subprocess
import sys
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
GEARPAIR_MO = ROOT / "modelica" / "GearDiag" / "GearPair.mo"
BUILT_FMU = ROOT / "build" / "GearPair.fmu"


@pytest.fixture(scope="session", autouse=True)
def _private_data_home(tmp_path_factory):
    """The per-user data and cache folders (compare's default history, the effect FMUs
    it builds) are scratch ones in tests, for this process and every CLI it starts."""
    import os
    os.environ["XDG_DATA_HOME"] = str(tmp_path_factory.mktemp("data_home"))
    os.environ["XDG_CACHE_HOME"] = str(tmp_path_factory.mktemp("cache_home"))


@pytest.fixture(scope="session")
def gear_fmu(tmp_path_factory) -> Path:
    """The GearPair FMU from `make fmu`, or built here when it is missing."""
    if BUILT_FMU.exists():
        return BUILT_FMU
    out = tmp_path_factory.mktemp("fmu") / "GearPair.fmu"
    from fmu_build import build_fmu
    return build_fmu(GEARPAIR_MO, "GearDiag.GearPair", out)


@pytest.fixture(scope="session")
def effects_dir(tmp_path_factory) -> Path:
    """Where the catalogue's effect FMUs are built on first use: `make fmu`'s build/effects
    when every one there is up to date with the Modelica sources (make test builds them
    first), else a folder of this test session. A test that is about building gives its
    own folder."""
    effects = ROOT / "modelica" / "GearDiag" / "Effects"
    newest = max(p.stat().st_mtime for p in (ROOT / "modelica").rglob("*.mo"))
    built = [ROOT / "build" / "effects" / f"{name}.fmu"
             for name in (effects / "package.order").read_text().split()]
    if all(f.exists() and f.stat().st_mtime >= newest for f in built):
        return built[0].parent
    return tmp_path_factory.mktemp("effects")


@pytest.fixture(scope="session")
def effect_fmu_of(effects_dir):
    """The FMU of a catalogue effect (built into ``effects_dir`` on first use), by effect."""
    from pydiag.loop.discover import effect_fmu
    return lambda effect: str(effect_fmu(effect.key, ROOT / "modelica", effects_dir))


def _made_once(tmp_path_factory, name: str, make):
    """``make()``, once a test run: under pytest-xdist the workers share it through a file
    of this run (the first makes it while the others wait)."""
    import os
    run = os.environ.get("PYTEST_XDIST_TESTRUNUID")
    if run is None:
        return make()
    import fcntl
    import pickle
    shared = tmp_path_factory.getbasetemp().parent / f"{name}_{run}.pickle"
    with open(shared.with_suffix(".lock"), "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not shared.exists():
            shared.write_bytes(pickle.dumps(make()))
        return pickle.loads(shared.read_bytes())


class _SimulatedOnFirstUse(Mapping):
    """The independent simulator's records by key, each group of them that shares one
    integration (truth_fits.record_groups) made the first time one of them is asked for,
    once a test run (:func:`_made_once`): a worker makes only those its tests use, and
    waits only for a group another is making."""

    def __init__(self, tmp_path_factory, magnitudes: dict[str, dict]):
        from truth_fits import record_groups
        self._tmp, self._magnitudes = tmp_path_factory, magnitudes
        self._group = {key: keys for keys in record_groups(magnitudes) for key in keys}
        self._made: dict = {}

    def __getitem__(self, key: str):
        if key not in self._made:
            import hashlib

            from truth_fits import clean_records
            keys = self._group[key]
            name = "truth_" + hashlib.sha1(",".join(keys).encode()).hexdigest()[:12]
            self._made.update(_made_once(self._tmp, name,
                                         lambda: clean_records(self._magnitudes, keys)))
        return self._made[key]

    def __iter__(self):
        return iter(self._magnitudes)

    def __len__(self) -> int:
        return len(self._magnitudes)


@pytest.fixture(scope="session")
def truth_records(tmp_path_factory) -> Mapping:
    """The independent simulator's noise-free records at the rig's 25 Hz, by key
    (truth_fits.RECORDS: ``"none"``, each hidden effect alone, the combinations), each
    simulated when a test first asks for it."""
    from truth_fits import RECORDS
    return _SimulatedOnFirstUse(tmp_path_factory, RECORDS)


@pytest.fixture(scope="session")
def hostile_fmu(tmp_path_factory) -> Path:
    """tests/fmus/hostile.py's FMU (it crashes, hangs, returns NaN and fails its steps by
    its parameter's range), built once a test session."""
    pytest.importorskip("pythonfmu")
    from fmus import hostile
    return inspected(hostile.build(tmp_path_factory.mktemp("hostile")))


@pytest.fixture(scope="session")
def housing_fmu(effects_dir) -> Path:
    """GearDiag.Effects.HousingSensor's FMU: the housing mode in Modelica, which no fit uses
    (the effect is a transfer path: pydiag.signal.transfer) but tests hold it to."""
    fmu = effects_dir / "HousingSensor.fmu"
    if not fmu.exists():
        from fmu_build import build_fmu
        build_fmu(ROOT / "modelica" / "GearDiag" / "Effects" / "HousingSensor.mo",
                  "GearDiag.Effects.HousingSensor", fmu)
    return fmu


@pytest.fixture
def modelica_copy(tmp_path) -> Path:
    """A scratch copy of the GearDiag package, safe to edit."""
    dst = tmp_path / "modelica"
    shutil.copytree(ROOT / "modelica", dst)
    return dst


def run_cli(*args: str, cwd: Path = ROOT) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, *args], cwd=cwd, capture_output=True, text=True)


def inspected(fmu: Path) -> Path:
    """Every FMU a test builds goes through `pydiag inspect` too, and what inspect says
    agrees with the FMU: it was built here, so it has this machine's binary; its outputs
    cannot be set; its parameters can, before initialisation or at any time."""
    import fmpy

    from pydiag.fmu.inspect import describe, format_info
    info = describe(fmu)
    md = fmpy.read_model_description(str(fmu), validate=False)
    here = fmpy.platform_tuple if md.fmiVersion.startswith("3") else fmpy.platform
    assert here in info.platforms, (here, info.platforms)
    by_name = {v.name: v for v in info.variables}
    assert set(by_name) == {v.name for v in md.modelVariables}
    for v in md.modelVariables:
        if v.causality == "output":
            assert by_name[v.name].settable == "no"
        elif v.causality == "parameter" and v.variability != "constant":
            assert by_name[v.name].settable in ("before init", "any time")
    text = format_info(info)
    assert all(f"  {v.name} " in text for v in md.modelVariables
               if v.causality in ("parameter", "output"))
    return fmu


#: The sensors of the GearDiag models, and the paper's four fault parameters.
SENSORS = ("acc", "disp")
NAMES = ("a_f", "f_f", "f_ate", "f_dte")


def noisy_measurement(fmu, number: int, seed: int, periods: int = 10):
    """A Table 1 case simulated by our own FMU at SNR 10 (acc + disp)."""
    from pydiag.core.measurement import Measurement
    from pydiag.fmu.plant import FmuPlant
    from pydiag.gear.conventions import kinematics_from
    from pydiag.gear.paper_cases import case
    from pydiag.signal.noise import add_white_noise

    with FmuPlant(fmu, SENSORS) as plant:
        kin = kinematics_from(plant.parameters())
        clean = plant.simulate(case(number).parameters, periods * kin.period_s, 0.05)
    rng = np.random.default_rng(1000 * number + seed)
    return Measurement({s: add_white_noise(clean[i], 10.0, rng) for i, s in enumerate(SENSORS)},
                       10_000.0)


def write_csv(path, header, rows, meta=None):
    lines = ([f"# meta: {json.dumps(meta)}"] if meta else []) + [",".join(header)]
    lines += [",".join(str(v) for v in row) for row in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


def children(pid: int) -> set[int]:
    """The direct children of a process (Linux /proc)."""
    found: set[int] = set()
    for task in Path(f"/proc/{pid}/task").glob("*"):
        try:
            found |= {int(p) for p in (task / "children").read_text().split()}
        except OSError:
            pass
    return found


def alive(pid: int) -> bool:
    """Running or sleeping; a zombie waiting for PID 1 to reap it is not alive."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state not in ("Z", "X")


#: The tests that take the longest (the loops on the independent simulator and on a real
#: record, up to a minute each on 2 cores), by name, longest first, and then their files:
#: collected first, so that under xdist none of them starts last and runs alone.
LONGEST_FIRST = ("test_the_loop_on_a_machine_of_one_stage", "test_the_loop_with_its_defaults",
                 "test_cli_loop_adds", "test_compare_with_a_speed_fluctuation",
                 "test_a_fit_written_as_the_machine_files_start", "test_cli_compare_shows",
                 "test_compare_and_discover_find", "test_hidden_effect_is_the_one_confident",
                 "test_no_hidden_effect", "test_two_hidden_effects",
                 "test_compare_fits_the_machines_model", "test_truth_loop.py",
                 "test_machine_model.py", "test_compare_loop.py", "test_phm09_machine.py",
                 "test_shared_records.py", "test_stages.py")


def pytest_collection_modifyitems(session, config, items):
    def rank(item) -> int:
        return next((i for i, key in enumerate(LONGEST_FIRST)
                     if item.name.startswith(key) or item.path.name == key), len(LONGEST_FIRST))
    items.sort(key=rank)
