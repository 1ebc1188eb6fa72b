"""batch --machine grows the healthy model once, before any record is judged, by what the
records ask (pydiag.app.batch.grown_first): a record that cannot be read asks nothing (its
row, made next, says why), and a model with no lacking effects is not asked about."""

from pydiag.app.batch import BatchTask, grown_first
from pydiag.loop.machine_model import MachineModel
from pydiag.loop.own_changes import HealthyModel

MODEL = MachineModel("Machine_box", "", ("stage_1",), (), (18, 36))


def task(path, lacking=("bearing_outer_race",)):
    return BatchTask(str(path), "box.fmu", machine="box.toml", model=MODEL,
                     healthy=HealthyModel({}, 0.01, {}, (), lacking))


def test_a_record_that_cannot_be_read_asks_the_healthy_model_nothing(tmp_path):
    asked = []
    tasks = [task(tmp_path / "missing.csv"), task(tmp_path / "gone.csv")]
    assert grown_first(tasks, asked.append, n_workers=1) == tasks
    assert asked == []  # the model is not grown (nor built, nor kept again)


def test_a_healthy_model_that_lacks_nothing_is_not_asked_about(tmp_path):
    def grow(tries):
        raise AssertionError("grown")
    tasks = [task(tmp_path / "missing.csv", lacking=())]
    assert grown_first(tasks, grow, n_workers=1) == tasks
    assert grown_first([], grow) == []
