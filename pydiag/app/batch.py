"""Diagnose many measurements: locally in worker processes, or on a Dask cluster.

With ``indicators`` set to a shaft, each row also holds the condition indicators of
:mod:`pydiag.gear.indicators` (one column each, ``channel:name`` for several channels), so
a fleet's records can be trended in one table.

With a machine file of several stages (``batch --machine``), every stage of every record
is diagnosed (:mod:`pydiag.diagnose.stages`), against the ``--baseline`` records when given:
a column group a stage, and with baselines every component's state (``<component>:state``)
and the faulty ones in one column (``faulty``). Without an FMU of one's own, by the machine's
own model, built once before the tasks (a task carries it and the FMU's path); with two
or more --baseline files, its healthy model too, fitted (or found kept) once before the
tasks, whose changes are a column (``model``) and join the components' states, as
``diagnose`` joins them. The effects that model lacks a record asks for are asked of every
record first (its indicators alone), and the model grown by all of them once
(:func:`grown_first`), so that each record is judged against the same model whatever the
order its tasks finish in.

Every measurement is one task; inside a task the estimator runs in a single process
(the parallelism is across measurements). A measurement that fails becomes a row with
``status = "error"`` and its message, never a crashed batch. Rows come back in input
order; the same seed gives the same rows on any number of workers or machines.
"""

from __future__ import annotations

import dataclasses
import glob
import os
import signal
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterable

from pydiag.core.errors import MeasurementError, PydiagError, UsageError
from pydiag.core.measurement import Measurement
from pydiag.core.termination import deferred, raise_once, stop_pool
from pydiag.fit.estimator import FaultEstimator
from pydiag.fit.build import ProblemSettings, build_problem
from pydiag.gear.classify import SEVERITIES
from pydiag.gear.indicators import condition_indicators
from pydiag.gear.kinematics import GearKinematics
from pydiag.gear.machine_file import load_machine
from pydiag.gear.machine_indicators import MachineRecord
from pydiag.gear.machine import Machine
from pydiag.io.readers import is_measurement_file, read_measurement
from pydiag.io.outputs import atomic_output
from pydiag.loop.machine_model import MachineModel, machine_fmu
from pydiag.loop.own_changes import HealthyModel
from pydiag.diagnose.diagnosis import diagnose
from pydiag.diagnose.stages import asked_tries, diagnose_machine, diagnose_machine_model
from pydiag.model.adapter import load_adapter

ROW_COLUMNS = ("measurement", "status", "message", "fault_mode", "severity", "error",
               "evaluations", "elapsed_s")


@dataclass(frozen=True)
class BatchTask:
    """One measurement to diagnose; plain data, so it pickles to any worker."""

    measurement: str
    fmu: str
    estimator: dict = field(default_factory=dict)  # FaultEstimator settings
    channels: tuple[str, ...] | None = None  # NAME or NAME=OUTPUT specs
    sample_rate_hz: float | None = None
    adapter: str | None = None  # path of an adapter TOML
    problem: ProblemSettings = ProblemSettings()  # how a record becomes a fit problem
    units: tuple[str, ...] | None = None  # UNIT or NAME=UNIT specs
    indicators: str | None = None  # the shaft whose condition indicators are columns too
    sensitivities: tuple[tuple[str, str], ...] = ()  # (NAME, sensitivity such as 100mV/g)
    machine: str | None = None  # a machine file of several stages: every stage diagnosed
    baselines: tuple[MachineRecord, ...] = ()  # its healthy records, seen through it
    input_hz: float | None = None  # its nominal input speed
    model: MachineModel | None = None  # the machine's own model, built at ``fmu``
    healthy: HealthyModel | None = None  # that model fitted to the first baseline
    library: tuple[str, str] | None = None  # (Modelica root, build folder) of effect models


def find_measurements(spec: str) -> list[str]:
    """A folder (its files of a format pydiag reads), a glob pattern, or one file; sorted,
    at least one."""
    path = Path(spec)
    if path.is_dir():
        paths = sorted(str(p) for p in path.iterdir() if p.is_file() and is_measurement_file(p))
    else:
        paths = sorted(glob.glob(spec))
    if not paths:
        raise MeasurementError(f"no measurement files match {spec}")
    return paths


def diagnose_task(task: BatchTask) -> dict:
    """Diagnose one measurement; every failure is reported in the row."""
    started = time.perf_counter()
    row: dict = {"measurement": task.measurement}
    try:
        m = _read(task, task.measurement)
        adapter = load_adapter(task.adapter) if task.adapter else None
        if task.machine:
            row.update(_machine_row(task, m, adapter))
            row["elapsed_s"] = time.perf_counter() - started
            return row
        problem = build_problem(task.fmu, m, adapter, **task.problem.keywords())
        result = diagnose(problem, FaultEstimator(n_workers=1, **task.estimator))
        facts = {k: v for k, v in result.facts.items()
                 if k not in ("nominal_speed_hz", "gains")}
        gains = {f"gain:{c}": g for c, g in result.facts.get("gains", {}).items()}
        row.update(status="ok", message="; ".join(result.warnings),
                   fault_mode=result.fault_mode,
                   severity=result.severity, error=result.error,
                   evaluations=result.fit.evaluations, **result.parameters,
                   tooth_contrast=result.tooth_contrast, **facts, **gains)
        if task.indicators:
            kin = problem.kinematics
            nominal = GearKinematics(kin.n_pinion, kin.n_gear, problem.speed.nominal_hz
                                     if problem.speed is not None else kin.f_pinion_hz)
            row.update(condition_indicators(m, nominal, task.problem.tracking,
                                            task.indicators).columns())
    except PydiagError as err:
        row.update(status="error", message=str(err))
    except Exception as err:  # a broken FMU must not take the batch down
        row.update(status="error", message=f"{type(err).__name__}: {err}")
    row["elapsed_s"] = time.perf_counter() - started
    return row


def _read(task: BatchTask, path: str) -> Measurement:
    return read_measurement(path, task.sample_rate_hz,
                            list(task.channels) if task.channels else None,
                            list(task.units) if task.units else None, dict(task.sensitivities))


def _machine_row(task: BatchTask, m: Measurement, adapter) -> dict:
    """Every stage of a machine's record (:func:`pydiag.diagnose.stages.diagnose_machine`): a
    column group a stage (``<stage>:fault_mode``, ...); the row's own fault mode is the
    first stage's that is not healthy, its severity and error the highest; with baselines,
    each component's state and the faulty ones (module docstring)."""
    estimator = FaultEstimator(n_workers=1, **task.estimator)
    machine = load_machine(task.machine)
    if task.model is not None:  # every stage at once, by the machine's own model
        result = diagnose_machine_model(task.fmu, task.model, m, machine, task.input_hz,
                                        task.problem, estimator, task.baselines, task.healthy,
                                        _effect_models(task))
    else:
        result = diagnose_machine(task.fmu, m, machine, task.input_hz, task.problem,
                                  estimator, task.baselines, adapter)
    row: dict = {"status": "ok", "message": "; ".join(result.warnings),
                 **{k: v for k, v in result.speed.to_dict().items()
                    if k != "nominal_speed_hz"}}
    modes = [st.fault_mode for st in result.stages]
    row["fault_mode"] = next((f for f in modes if f != "healthy"), "healthy")
    row["severity"] = max((st.severity for st in result.stages), key=_severity_rank)
    row["error"] = max(st.fit.error for st in result.stages)
    row["evaluations"] = sum(st.fit.fit.evaluations for st in result.stages)
    for st in result.stages:
        row.update({f"{st.name}:fault_mode": st.fault_mode, f"{st.name}:severity": st.severity,
                    f"{st.name}:suspect": st.suspect, f"{st.name}:error": st.fit.error,
                    f"{st.name}:tooth_contrast": st.fit.tooth_contrast})
        if st.verdict is not None:
            row[f"{st.name}:change_db"] = max(abs(st.verdict.pinion.change_db),
                                              abs(st.verdict.gear.change_db))
    if task.healthy is not None:  # the healthy model's changes, the largest first
        row["model"] = "; ".join(f"{c.effect} on {c.stage}: {c.fault} ({c.margin:.2f} x)"
                                 + (f", {', '.join(c.components)}" if c.components else "")
                                 for c in result.model_changes if c.changed)
    if result.components:  # judged against baselines: every gear, bearing and shaft
        row["faulty"] = "; ".join(f"{v.component.name}: {v.state}"
                                  for v in result.components if v.faulty)
        row.update({f"{v.component.name}:state": v.state for v in result.components})
    return row


def _effect_models(task: BatchTask) -> Callable[[Machine], str] | None:
    """The FMU of the machine with an effect more, built in ``task.library`` (found there:
    the batch built those a record asks for before its tasks, :func:`grown_first`)."""
    if task.library is None:
        return None
    root, build = (Path(p) for p in task.library)
    return lambda machine: str(machine_fmu(machine, root, build)[1].fmu)


def asked_task(task: BatchTask) -> frozenset[tuple[str, str]]:
    """The (stage, effect) tries of its healthy model's lacking effects that ``task``'s
    record asks for (:func:`pydiag.diagnose.stages.asked_tries`); none for a record that
    cannot be read or judged (its row says why)."""
    if task.model is None or task.healthy is None or not task.healthy.lacking:
        return frozenset()
    try:
        m = _read(task, task.measurement)
        return frozenset(asked_tries(task.model, m, load_machine(task.machine),
                                     task.input_hz, task.healthy, task.baselines,
                                     task.problem))
    except Exception:  # the record's row, made next, says what is wrong with it
        return frozenset()


def grown_first(tasks: list[BatchTask], grow: Callable[[set[tuple[str, str]]], HealthyModel],
                scheduler: str | object = "local", n_workers: int | None = None,
                progress: Callable[[int, int], None] | None = None) -> list[BatchTask]:
    """``tasks`` with their healthy model grown once by every lacking try any of their
    records asks for (``grow``: the model with those tries held on its own records), asked
    of every record first (:func:`asked_task`, spread as :func:`run_batch` spreads): each
    record is then judged against the same model, whatever the order records are done in
    or the workers they are done on."""
    healthy = tasks[0].healthy if tasks else None
    if healthy is None or not healthy.lacking:
        return tasks
    asked = run_batch(tasks, scheduler, n_workers, progress, work=asked_task)
    tries = set().union(*asked)
    if not tries - set(healthy.held):
        return tasks
    grown = grow(tries)
    return [dataclasses.replace(t, healthy=grown) for t in tasks]


def _severity_rank(severity: str) -> int:
    """The paper's classes in order; "unknown" (no diagnosis, a changed stage the model
    cannot class) below them all."""
    return SEVERITIES.index(severity) if severity in SEVERITIES else -1


def run_batch(tasks: Iterable[BatchTask], scheduler: str | object = "local",
              n_workers: int | None = None,
              progress: Callable[[int, int], None] | None = None,
              work: Callable[[BatchTask], object] = diagnose_task) -> list:
    """``work`` of each task (its row: :func:`diagnose_task`), in the order of ``tasks``.

    ``scheduler``: "local" (a process pool of ``n_workers``, default all cores), a Dask
    scheduler address ("tcp://host:port"), or a ``dask.distributed.Client``.
    """
    tasks = list(tasks)
    if scheduler == "local":
        workers = n_workers or os.cpu_count() or 1
        if workers == 1:
            return _collect(tasks, work, progress)
        pool = ProcessPoolExecutor(workers, initializer=_die_with_parent)
        try:
            with deferred():  # the first submits start the workers
                futures = [pool.submit(_task_in_worker, work, t) for t in tasks]
            rows = _collect(futures, lambda f: f.result(), progress)
        except BaseException:  # Ctrl-C, SIGTERM: stop the workers now, not after their tasks
            stop_pool(pool)
            raise
        pool.shutdown()
        return rows
    client, owned = _dask_client(scheduler)
    try:
        futures = client.map(work, tasks, pure=False)
        return _collect(futures, lambda f: f.result(), progress)
    finally:
        if owned:
            client.close()


class _WorkerTerminated(BaseException):
    """SIGTERM in a local worker: unwinds the task (its cleanup runs), then the worker ends."""


#: SIGTERM in a local worker unwinds its task; the TERMs that follow while it does (the
#: executor's, once another worker has ended; the parent's death signal) wait for it.
_worker_terminated = raise_once(_WorkerTerminated)


def _task_in_worker(work: Callable[[BatchTask], object], task: BatchTask) -> object:
    """``work`` of ``task`` in a local worker, which ends on SIGTERM once the task's own
    cleanup has run (the executor would otherwise wait for its next task forever)."""
    try:
        return work(task)
    except _WorkerTerminated:
        os._exit(143)


def _die_with_parent() -> None:
    """A local worker ends on SIGTERM, and is sent one when the batch's main process dies,
    whatever killed it (Linux prctl PR_SET_PDEATHSIG; elsewhere nothing): its task's own
    workers and run folder go with it (:mod:`pydiag.fmu.isolation`)."""
    import ctypes
    signal.signal(signal.SIGTERM, _worker_terminated)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the main process's to handle
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG = 1
    except (OSError, AttributeError):
        return
    if os.getppid() == 1:  # the parent died before the call: follow it
        os.kill(os.getpid(), signal.SIGTERM)


def _collect(items, result, progress) -> list[dict]:
    """``result(item)`` for each item in order, reporting progress."""
    rows = []
    for i, item in enumerate(items):
        rows.append(result(item))
        if progress:
            progress(i + 1, len(items))
    return rows


def _dask_client(scheduler) -> tuple[object, bool]:
    try:
        from dask.distributed import Client
    except ImportError as err:
        raise UsageError("a Dask scheduler needs the 'distributed' package") from err
    if isinstance(scheduler, Client):
        return scheduler, False
    if not (isinstance(scheduler, str) and scheduler.startswith("tcp://")):
        raise UsageError(f"--scheduler must be 'local' or tcp://HOST:PORT, got {scheduler!r}")
    try:
        return Client(scheduler, timeout="10s"), True
    except OSError as err:
        raise UsageError(f"cannot reach the Dask scheduler at {scheduler}: {err}") from err


#: The results table's formats, by the name's extension.
RESULT_SUFFIXES = (".parquet", ".csv")


def check_results_name(out: str | Path) -> None:
    """A results table is named .parquet or .csv (its format): else a UsageError."""
    if Path(out).suffix.lower() not in RESULT_SUFFIXES:
        raise UsageError(f"--out {out}: the results table is written as Parquet or CSV; name "
                         f"it .parquet or .csv")


def write_results(rows: list[dict], out: str | Path, force: bool = False) -> Path:
    """Write the rows as Parquet (or CSV for a .csv name) under the output policy."""
    import pandas as pd

    check_results_name(out)
    out = Path(out)
    frame = pd.DataFrame(rows)
    for col in ROW_COLUMNS:
        if col not in frame:
            frame[col] = None
    with atomic_output(out, force) as tmp:
        if out.suffix.lower() == ".csv":
            frame.to_csv(tmp, index=False)
        else:
            frame.to_parquet(tmp, index=False)
    return out
