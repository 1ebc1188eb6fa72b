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

An effect none of whose lines is among the bins the test scores (the synchronous lines
and the peaks of the fitted half) has no residual to explain and could not be
confident: it is not fitted, and its row says so (bearing strikes on a record whose
bearing lines are all in the noise, a ripple on a record with no line between the
shaft orders).

Effects are fitted side by side, one per core (each in a process of its own): an
effect's fit keeps a core busy only part of the time (its least-squares polish asks for
one simulation at a time), so running them one after another with all cores each left
about a fifth of the machine idle (bench/RESULTS.md, section 11). Each
effect's fit may use every core (its swarm's particles, its polish's Jacobian columns):
when the others are done, the last one's polish runs on all of them. The effects that
are not synchronous with the shafts (``Effect.synchronous``: their records are simulated
whole, the others' over one period) start first, those that also refit the base
parameters (``Effect.reshapes_base``) before them, and a synchronous one that refits the
base from two starts (``Effect.free_start``) among them. The ranking does not depend on
how many run at once, nor on the order.
"""

from __future__ import annotations

import hashlib
import math
import multiprocessing as mp
import os
import threading
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from collections.abc import Mapping
from pathlib import Path
from typing import Callable

import fmu_build
from fmu_build import ModelicaBuildError as BuildError

from pydiag.core.errors import PydiagError, UsageError
from pydiag.core.termination import deferred, stop_pool
from pydiag.fit.estimator import FaultEstimator
from pydiag.fit.problem import FitProblem
from pydiag.fmu.archive import usable_cache
from pydiag.gear.effect import Effect, model_file
from pydiag.gear.effects import EFFECTS
from pydiag.loop.builds import each_built
from pydiag.loop.compare import compare
from pydiag.loop.competition import mark_settled, settle
from pydiag.loop.effect_fit import EFFECT_REFIT, in_model
from pydiag.loop.held_out import envelope_band, halves, held_out
from pydiag.loop.results import Comparison, Status, Suggestion

#: The Modelica library of a source checkout (an installed wheel does not carry it).
MODELICA_ROOT = Path(__file__).resolve().parents[2] / "modelica"


def default_build_dir(modelica_root: Path) -> Path:
    """Where effect FMUs are built unless told: a per-user cache,
    ``$XDG_CACHE_HOME/pydiag/effects/<library>`` (by default under ``~/.cache``), one
    folder for each Modelica library (a hash of its path); never the current folder."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    library = hashlib.sha256(str(Path(modelica_root).resolve()).encode()).hexdigest()[:12]
    return Path(base) / "pydiag" / "effects" / library


def check_modelica_root(modelica_root: Path) -> None:
    """UsageError unless ``modelica_root`` holds the GearDiag effects (before any work)."""
    effects = Path(modelica_root) / "GearDiag" / "Effects"
    if not (effects / "package.order").is_file():
        raise UsageError(f"no Modelica library of effects at {modelica_root} (it needs "
                         "GearDiag/Effects/package.order); give --modelica the folder that "
                         "holds GearDiag")


def effect_fmu(key: str, modelica_root: Path, build_dir: Path | None = None) -> Path:
    """The effect's FMU, built unless an up-to-date one exists (in ``build_dir``, default
    :func:`default_build_dir`). An effect without ``Effect.own_fmu`` has none: it is
    fitted on the base model's FMU."""
    effect = EFFECTS[key]
    if not effect.own_fmu:
        raise ValueError(f"{key} is fitted on the base model's FMU: it has no FMU of its own")
    out = Path(build_dir or default_build_dir(modelica_root)) / \
        f"{effect.model.rsplit('.', 1)[1]}.fmu"
    sources = list(Path(modelica_root).rglob("*.mo"))
    if not sources:
        raise UsageError(f"no Modelica library at {modelica_root}; give --modelica")
    newest = max(p.stat().st_mtime for p in sources)
    if not out.exists() or out.stat().st_mtime < newest or not usable_cache(out):
        out.parent.mkdir(parents=True, exist_ok=True)
        # renamed when whole; of this thread: two may build one effect's model at once
        partial = out.with_name(f".{out.stem}.{os.getpid()}.{threading.get_ident()}.fmu")
        try:
            fmu_build.build_fmu(model_file(effect, modelica_root), effect.model, partial)
            os.replace(partial, out)
        finally:
            partial.unlink(missing_ok=True)
    return out


def failed_row(key: str, err: Exception, started: float, stage: str | None = None
               ) -> Suggestion:
    """The row of an effect (on ``stage`` of a machine's model) that could not be built or
    fitted."""
    return Suggestion(key, status=Status.FAILED, message=f"{type(err).__name__}: {err}",
                      n_parameters=len(EFFECTS[key].parameters),
                      elapsed_s=time.perf_counter() - started, stage=stage)


def held_out_row(problem: FitProblem, base: Comparison, effect: Effect, fmu: str,
                 estimator: FaultEstimator, memo: dict | None = None,
                 stage: str | None = None, own: bool = False) -> Suggestion:
    """``effect`` (on ``stage`` of a machine's model) held out, as a row; an effect that
    cannot be fitted is a row too; ``own``: :func:`~pydiag.loop.held_out.held_out`'s."""
    started = time.perf_counter()
    try:
        h = held_out(problem, base, effect, fmu, estimator, memo=memo, own=own)
    except PydiagError as err:
        return failed_row(effect.key, err, started, stage)
    return Suggestion(effect.key, status=h.status, message=h.message, held_out=h,
                      n_parameters=len(effect.parameters),
                      elapsed_s=time.perf_counter() - started, confident=h.confirmed,
                      stage=stage)


def _try_effect(problem: FitProblem, base: Comparison, key: str, fmu: str,
                estimator: FaultEstimator, memo: dict | None = None) -> Suggestion:
    """:func:`held_out_row` of the effect ``key``. Takes the effect's key, not the effect:
    it runs in a worker process."""
    return held_out_row(problem, base, EFFECTS[key], fmu, estimator, memo)


def shared_halves(problem: FitProblem, base: Comparison, keys: list[str],
                  estimator: FaultEstimator, catalogue: Mapping[str, Effect] = EFFECTS) -> dict:
    """What every effect's held-out test shares (:class:`pydiag.loop.held_out.Halves`), made
    once here for the workers; empty when it cannot be made (each effect's row then says
    why). The base polished free, which every effect that frees the base is scored
    against, is made here too when two or more such effects may need it. ``catalogue``:
    the effects as the model names them (a machine's stage's)."""
    try:
        bands = {envelope_band(problem, catalogue[key]) for key in keys}
        shared = {band: halves(problem, base, band, with_base_signals=True) for band in bands}
        freeing = [key for key in keys if catalogue[key].reshapes_base
                   and not catalogue[key].unknown_lines(problem.kinematics)]
        if len(freeing) >= 2:
            band = envelope_band(problem, catalogue[freeing[0]])
            shared[band].free_base(estimator, dict(base.parameters))
        return shared
    except PydiagError:
        return {}


def discovery_cost(effect: Effect) -> int:
    """How long an effect's held-out fit takes, in rough units, so the longest start first
    and the short ones fill the cores at the end: one that is not synchronous is simulated
    over the whole record (twice the weight), unless it is a ripple read from periods of
    the model (``Effect.ripple``), the others over one period; one that reshapes the base
    is polished with the base parameters free as well, and one with a free start polished
    so twice."""
    return (2 * (not effect.synchronous and effect.ripple is None) + effect.reshapes_base
            + (effect.free_start is not None))


def side_by_side(call: Callable[[object, FaultEstimator], tuple[Callable, tuple]],
                 tasks: list, estimator: FaultEstimator,
                 progress: Callable[[Suggestion], None] | None) -> list[Suggestion]:
    """The row of each task, in the tasks' order: ``call(task, estimator)`` says the
    function and its arguments, run one task a core (``estimator.n_workers``, default all
    cores), each fit free to use every core (module docstring); in this process when one
    core is given or in a daemonic process, which may not start children. ``progress``
    gets each row as it is done."""
    cores = estimator.n_workers or os.cpu_count() or 1
    jobs = min(cores, len(tasks))
    if jobs <= 1 or mp.current_process().daemon:
        rows = []
        for task in tasks:
            function, args = call(task, estimator)
            rows.append(function(*args))
            if progress:
                progress(rows[-1])
        return rows
    one = estimator.replace(n_workers=cores, progress=None)
    done: dict[int, Suggestion] = {}
    pool = ProcessPoolExecutor(jobs)
    try:
        running = {}
        with deferred():  # the first submits fork the workers: a TERM then is not lost
            for i, task in enumerate(tasks):
                function, args = call(task, one)
                running[pool.submit(_in_worker, function, args)] = i
        for future in as_completed(running):
            done[running[future]] = future.result()
            if progress:
                progress(done[running[future]])
    except BaseException:  # Ctrl-C, SIGTERM: stop the fits now, not after every queued one
        stop_pool(pool)
        raise
    pool.shutdown()
    return [done[i] for i in range(len(tasks))]


def _in_worker(function: Callable, args: tuple):
    """``function(*args)`` in a worker of :func:`side_by_side`'s pool, which ends once a
    stop (a SIGTERM's exception, Ctrl-C) has unwound the task and its cleanup has run:
    the executor would otherwise keep the worker for its next task."""
    try:
        return function(*args)
    except Exception:
        raise
    except BaseException:
        os._exit(143)


def discover(problem: FitProblem, estimator: FaultEstimator | None = None,
             effects: list[str] | None = None,
             modelica_root: Path = MODELICA_ROOT, build_dir: Path | None = None,
             progress: Callable[[Suggestion], None] | None = None,
             effect_estimator: FaultEstimator | None = None,
             base: Comparison | None = None) -> tuple[Comparison, list[Suggestion]]:
    """Compare the base model (``problem``), then try every effect held out and rank them.

    ``estimator`` fits the base model (unless ``base``, its comparison, is given),
    ``effect_estimator`` each effect's parameters (default:
    :data:`pydiag.loop.effect_fit.EFFECT_REFIT`); the effect estimator's ``n_workers``
    (default: all cores) is the number of cores the effects share, one effect per core,
    each fit free to use them all (module docstring). Effects whose parameters the base
    model already fits are left out. ``progress`` gets each effect's row as it is done.
    Competitors are settled as in validation (:func:`pydiag.loop.competition.settle`).
    """
    unknown = [key for key in effects or () if key not in EFFECTS]
    if unknown:
        raise UsageError(f"unknown effect(s) {', '.join(unknown)}; known: {', '.join(EFFECTS)}")
    base = base or compare(problem, estimator)
    keys = [key for key in effects or list(EFFECTS) if not in_model(problem, EFFECTS[key])]
    keys.sort(key=lambda key: -discovery_cost(EFFECTS[key]))  # the longest first
    effect_estimator = effect_estimator or FaultEstimator(**EFFECT_REFIT)

    def build(key: str) -> str | Suggestion:
        started = time.perf_counter()
        try:
            return (str(effect_fmu(key, modelica_root, build_dir))
                    if EFFECTS[key].own_fmu else problem.spec.fmu_path)
        except (PydiagError, BuildError) as err:  # its row, not built again
            return failed_row(key, err, started)

    fmus: dict[str, str] = {}
    found: list[Suggestion] = []
    # built in this process, side by side: two workers must not build one FMU at once
    for key, built in zip(keys, each_built(build, keys, effect_estimator.n_workers)):
        if isinstance(built, Suggestion):
            found.append(built)
            if progress:
                progress(built)
        else:
            fmus[key] = built
    keys = [key for key in keys if key in fmus]
    memo = shared_halves(problem, base, keys, effect_estimator)
    found += side_by_side(lambda key, estimator: (_try_effect, (
        problem, base, key, fmus[key], estimator, memo)), keys, effect_estimator, progress)
    found.sort(key=lambda d: math.inf if math.isnan(d.z) else -d.z)  # those not tried last
    mark_settled(found, settle({d.effect: d.held_out for d in found if d.held_out is not None},
                               {s.effect: s.competing for s in base.suggested_effects},
                               {key for key in keys if EFFECTS[key].reshapes_base}))
    return base, found


def as_dict(base: Comparison, found: list[Suggestion]) -> dict:
    """Plain data for JSON."""
    return {"base_error": base.error, "criterion": "held-out z (dBIC on the fitted half beside it)",
            "ranking": [d.ranking_row() for d in found]}
