"""An FMU as a plant: load once, set parameters, simulate, return the sensor signal.

One extracted FMU and one instance serve every evaluation (the instance is reset
between runs): re-extracting and re-instantiating per call is slow and, with some
vendor FMUs, leaks. Not thread-safe; use one plant per process.

Two engines: ``"native"`` integrates FMI 2.0 and 3.0 Model-Exchange FMUs without event
indicators in compiled code (:mod:`pydiag.fmu.native_engine`); ``"fmpy"`` runs fmpy's
``simulate_fmu`` (CVode for ME, the FMU's own solver for CS) and handles every FMU.
``"auto"`` picks native when it applies and builds, fmpy otherwise, and switches to fmpy
for good if the FMU turns out to have events (a time event, or a step event asked for
at a completed integrator step).

Default tolerances differ because the solvers do: against a tight reference (fmpy at
rtol 1e-11), Table 1 case 1's acceleration was off by 26 % of its peak with fmpy/CVode
at rtol 1e-6 (CVode's absolute tolerance is rtol x nominal, and the acceleration is a
small difference of large forces), 0.45 % at 1e-8; the native engine was off by
1.7e-5 at 1e-6. So the defaults are 1e-6 (native) and 1e-8 (fmpy); see bench/speed.py.
A plant whose runs only rank candidates (a swarm's) may ask the native engine for a looser
tolerance where none was asked for (``native_tolerance``); fmpy keeps its 1e-8, since
CVode is off by a quarter of the peak already at 1e-6.
"""

from __future__ import annotations

import shutil
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import fmpy
import numpy as np

from pydiag.core.errors import PlantError
from pydiag.core.termination import deferred
from pydiag.fmu import native_engine
from pydiag.fmu.archive import check_binary, safe_extract
from pydiag.fmu.description import (outputs_of, read_model_description, require_settable,
                                    variables_of)

#: Simulation engines (see the module docstring).
ENGINES = ("auto", "native", "fmpy")
#: Simulated start-up discarded before an analysed window, unless an adapter says otherwise.
DEFAULT_WARMUP_S = 0.05
#: The native engine's relative tolerance when none is asked for (module docstring).
NATIVE_TOLERANCE = 1e-6
#: ... and fmpy's (CVode).
FMPY_TOLERANCE = 1e-8


@dataclass(frozen=True)
class PlantSpec:
    """Everything needed to open an :class:`FmuPlant`, here or in another process."""

    fmu_path: str
    sensors: tuple[str, ...]
    sample_rate_hz: float
    fixed_values: dict = field(default_factory=dict)
    relative_tolerance: float | None = None
    engine: str = "auto"
    cs_step_s: float | None = None
    native_tolerance: float = NATIVE_TOLERANCE

    def open(self) -> "FmuPlant":
        return FmuPlant(self.fmu_path, self.sensors, self.sample_rate_hz,
                        self.relative_tolerance, self.fixed_values, self.engine, self.cs_step_s,
                        self.native_tolerance)


class FmuPlant:
    """Simulate an FMU's sensor output for given parameter values.

    Args:
        fmu_path: the FMU file
        sensors: names of the output variables to return (one row each)
        sample_rate_hz: output sample rate of :meth:`simulate`
        relative_tolerance: solver tolerance; None: ``native_tolerance`` with the native
            engine, :data:`FMPY_TOLERANCE` with fmpy (see above)
        fixed_values: start values applied to every run (e.g. from an adapter)
        engine: "auto", "native" or "fmpy" (see the module docstring)
        cs_step_s: Co-Simulation only: largest communication step; runs sub-step between
            output samples when it is smaller than 1/sample_rate_hz
        native_tolerance: the native engine's tolerance when ``relative_tolerance`` is None
    """

    def __init__(self, fmu_path: str | Path, sensors: tuple[str, ...],
                 sample_rate_hz: float = 10_000.0,
                 relative_tolerance: float | None = None,
                 fixed_values: dict[str, float] | None = None, engine: str = "auto",
                 cs_step_s: float | None = None,
                 native_tolerance: float = NATIVE_TOLERANCE) -> None:
        if engine not in ENGINES:
            raise PlantError(f"engine must be one of {', '.join(ENGINES)}, got {engine!r}")
        self.fmu_path = Path(fmu_path)
        if not sample_rate_hz > 0:
            raise PlantError(f"sample rate must be positive, got {sample_rate_hz}")
        self.sample_rate_hz = float(sample_rate_hz)
        self._requested_tolerance = relative_tolerance
        if not native_tolerance > 0:
            raise PlantError(f"the native tolerance must be positive, got {native_tolerance}")
        self.relative_tolerance = relative_tolerance or native_tolerance
        self.model_description, self.validation_warnings = read_model_description(self.fmu_path)
        self.variables = variables_of(self.model_description)
        self.sensors = tuple(sensors)
        if not self.sensors:
            raise PlantError("at least one sensor output is needed")
        for sensor in self.sensors:
            if sensor not in self.variables:
                raise PlantError(f"sensor '{sensor}' is not a variable of {self.fmu_path.name}; "
                                 f"outputs are: {', '.join(self.outputs()) or 'none'}")
        self.fixed_values = dict(fixed_values or {})
        self._check_settable(self.fixed_values)
        self._fmi_type = ("ModelExchange" if self.model_description.modelExchange is not None
                          else "CoSimulation")
        with deferred():  # a TERM meanwhile is raised once the name is kept, for close()
            self._unzipdir = tempfile.mkdtemp(prefix="pydiag_fmu_")
        try:
            safe_extract(self.fmu_path, self._unzipdir)
            check_binary(self._unzipdir, self.model_description, self.fmu_path.name)
        except PlantError:
            shutil.rmtree(self._unzipdir, ignore_errors=True)
            raise
        try:
            self._instance = fmpy.instantiate_fmu(self._unzipdir, self.model_description,
                                                  fmi_type=self._fmi_type)
        except Exception as err:
            shutil.rmtree(self._unzipdir, ignore_errors=True)
            raise PlantError(f"cannot instantiate {self.fmu_path.name}: {err}") from err
        self._fresh = True
        self._last: tuple | None = None  # (values, first, n) and the signals of the last run
        self.substeps = 1
        if self._fmi_type == "CoSimulation" and cs_step_s:
            self.substeps = max(1, int(np.ceil((1.0 / self.sample_rate_hz) / cs_step_s - 1e-9)))
        self._native = None
        self._engine_requested = engine
        if engine != "fmpy":
            self._native = self._native_runner(required=engine == "native")
        self.engine = "native" if self._native is not None else "fmpy"
        if self.engine == "fmpy":
            self._use_fmpy()

    def _use_fmpy(self) -> None:
        self._native = None
        self.engine = "fmpy"
        if self._requested_tolerance is None:
            self.relative_tolerance = FMPY_TOLERANCE

    def _native_runner(self, required: bool):
        try:
            if self._fmi_type != "ModelExchange" or not native_engine.supports(self.model_description):
                raise native_engine.NativeUnavailable(
                    "the native engine runs FMI 2.0/3.0 Model-Exchange FMUs without event "
                    "indicators")
            refs = [self.model_description_variable(s).valueReference for s in self.sensors]
            return native_engine.NativeMeRunner(self._instance, self.model_description, refs,
                                            self.relative_tolerance)
        except native_engine.NativeUnavailable as err:
            if required:
                raise PlantError(f"{self.fmu_path.name}: {err}") from err
            return None

    def model_description_variable(self, name: str):
        for v in self.model_description.modelVariables:
            if v.name == name:
                return v
        raise PlantError(f"{self.fmu_path.name} has no variable '{name}'")

    # ------------------------------------------------------------------ metadata
    def outputs(self) -> list[str]:
        return outputs_of(self.model_description)

    def parameters(self) -> dict[str, float]:
        """Start values of the FMU's parameters."""
        return {n: v.start for n, v in self.variables.items()
                if v.causality == "parameter" and v.start is not None}

    def _check_settable(self, values: dict[str, float]) -> None:
        for name in values:
            require_settable(self.variables, name, f"{self.fmu_path.name}: variable")

    # ------------------------------------------------------------------ simulation
    def simulate(self, parameters: dict[str, float], duration_s: float,
                 start_s: float = 0.0) -> np.ndarray:
        """Sensor signals, shape (n_sensors, n), at ``start_s + n/sample_rate_hz``.

        ``n = round(duration_s * sample_rate_hz)``. The model is always integrated from
        t = 0; ``start_s`` drops the start-up part. A run with the values of the last one
        returns its signals again (a fit that varies only what lies outside the model, a
        transfer path to the sensor, simulates once).
        """
        return self._cached(parameters, int(round(start_s * self.sample_rate_hz)),
                            int(round(duration_s * self.sample_rate_hz)))

    def simulate_periods(self, parameters: dict[str, float], period_samples: int,
                         start_s: float, state_tolerance: float, oversample: int = 1,
                         total: int | None = None) -> np.ndarray:
        """Sensor signals from ``start_s`` over two periods of the model's forcing
        (``period_samples`` each), shape (n_sensors, 2 * period_samples); or over one,
        shape (n_sensors, period_samples), when the native engine finds that the response
        repeats from ``start_s``: every state back at its start after the period, the
        derivatives and outputs the same at the same state a period later, to within
        ``state_tolerance`` of their ranges (:meth:`pydiag.fmu.native_engine.
        NativeMeRunner.run`); half the simulation is saved. fmpy gives no states: always
        two periods. ``oversample``: samples at that many times the plant's rate (a period
        of ``period_samples`` of them), for a signal read between its samples.

        ``total`` (samples, more than two periods): where the states and derivatives
        repeat and the outputs do not (a bearing's strikes added at the sensor, the
        dynamics turning with the period), the whole ``total`` samples, each later one
        read at its own time from the state whole periods earlier, for one period's
        integration (the native engine; ``total`` samples are the record, however made)."""
        if period_samples < 2:
            raise PlantError(f"a period needs at least two samples, got {period_samples}")
        rate = self.sample_rate_hz * oversample
        first = int(round(start_s * rate))
        if total is None or total <= 2 * period_samples or self._native is None:
            return self._cached(parameters, first, 2 * period_samples,
                                (period_samples, state_tolerance), rate)
        return self._cached(parameters, first, total,
                            (period_samples, state_tolerance, True, 2 * period_samples), rate)

    def _cached(self, parameters: dict[str, float], first: int, n: int,
                check: tuple = (0, 0.0), rate_hz: float | None = None
                ) -> np.ndarray:
        """:meth:`_simulate`, or the last run's signals again when it had these values."""
        values = {**self.fixed_values, **parameters}
        self._check_settable(values)
        rate_hz = rate_hz or self.sample_rate_hz
        key = (tuple(sorted(values.items())), first, n, check, rate_hz)
        if self._last is not None and self._last[0] == key:
            return self._last[1].copy()
        y = self._simulate(values, first, n, check, rate_hz)
        self._last = (key, y.copy())
        return y

    def _simulate(self, values: dict[str, float], first: int, n: int,
                  check: tuple = (0, 0.0), rate_hz: float | None = None
                  ) -> np.ndarray:
        """Signals at samples first..first+n-1 at ``rate_hz`` (default the plant's); with a
        ``check`` (period in samples, state tolerance[, free outputs, stop]), the native
        engine may return the first period alone (or, with free outputs, every sample past
        one period's integration, or the stop's first samples: :meth:`simulate_periods`)."""
        rate_hz = rate_hz or self.sample_rate_hz
        stop = (first + n) / rate_hz
        if self._native is not None:
            try:
                return self._simulate_native(values, first, n, check, rate_hz)
            except native_engine.NeedsEvents as err:
                if self._engine_requested == "native":
                    raise PlantError(f"{self.fmu_path.name}: {err}; the native engine does not "
                                     "handle events, use engine fmpy") from err
                self._use_fmpy()
        if not self._fresh:
            self._instance.reset()
        self._fresh = False
        step = 1.0 / (rate_hz * self.substeps)
        try:
            result = fmpy.simulate_fmu(
                self._unzipdir, validate=False, start_time=0.0, stop_time=stop,
                output_interval=step,
                relative_tolerance=self.relative_tolerance, start_values=values,
                output=list(self.sensors), model_description=self.model_description,
                fmu_instance=self._instance, fmi_type=self._fmi_type)
        except Exception as err:
            raise PlantError(f"simulation of {self.fmu_path.name} failed with "
                             f"{values}: {err}") from err
        result = result[::self.substeps]
        if len(result) < first + n:
            reached = float(result["time"][-1]) if len(result) else 0.0
            raise PlantError(f"simulation of {self.fmu_path.name} stopped at t = {reached:.6g} s "
                             f"of {stop:.6g} s with {values}: a failed or discarded step")
        full = np.array([result[s][:first + n] for s in self.sensors], dtype=float)
        self._check_divergence(full, values, step)
        return full[:, first:first + n]

    def _check_divergence(self, y: np.ndarray, values: dict, step: float) -> None:
        """Non-finite output, or output that grows a millionfold over the run: diverged."""
        cs = (f" (Co-Simulation communication step {step:.3g} s: try a smaller cs_step_s)"
              if self._fmi_type == "CoSimulation" else "")
        if not np.all(np.isfinite(y)):
            raise PlantError(f"simulation of {self.fmu_path.name} gave non-finite output with "
                             f"{values}: diverged{cs}")
        quarter = max(1, y.shape[1] // 4)
        early = np.max(np.abs(y[:, :quarter]), axis=1)
        late = np.max(np.abs(y[:, -quarter:]), axis=1)
        if np.any((late > 1e6 * early) & (late > 1e-300)):
            raise PlantError(f"simulation of {self.fmu_path.name} output grows without bound "
                             f"with {values}: diverged{cs}")

    def _simulate_native(self, values: dict[str, float], first: int, n: int,
                         check: tuple, rate_hz: float) -> np.ndarray:
        if not self._fresh:
            self._instance.reset()
        self._fresh = False
        try:
            y = self._native.run(values, first / rate_hz, 1.0 / rate_hz, n, *check)
        except native_engine.NeedsEvents:
            raise
        except Exception as err:
            raise PlantError(f"simulation of {self.fmu_path.name} failed with {values}: "
                             f"{err}") from err
        self._fresh = True  # the runner terminates and resets the instance
        return np.ascontiguousarray(y.T)

    def close(self) -> None:
        if getattr(self, "_instance", None) is not None:
            try:
                self._instance.freeInstance()
            except Exception:
                pass
            self._instance = None
        shutil.rmtree(getattr(self, "_unzipdir", ""), ignore_errors=True)

    def __enter__(self) -> "FmuPlant":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __del__(self) -> None:
        self.close()
