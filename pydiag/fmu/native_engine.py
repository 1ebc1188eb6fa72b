"""Compiled integration of Model-Exchange FMUs (FMI 2.0 and 3.0): the step loop runs in C.

fmpy's ``simulate_fmu`` calls back into Python for every right-hand side and output
point. Here fmpy still instantiates, sets parameters and initialises, but the whole
integration and the output sampling run in ``native/me_driver.c`` through the FMU's own
function pointers, with DOP853 (8th order with 7th-order dense output, the default) or
Dormand-Prince 5(4) (steps landing on the output grid). The driver is compiled with the
system C compiler on first use and cached under ``$XDG_CACHE_HOME/pydiag``
(``~/.cache/pydiag``) by source hash; where that cache cannot be written, compiled for the
process alone.

Only FMUs without event indicators qualify (:func:`supports`). An FMU that schedules a
time event at initialisation or asks for an event at a completed step raises
:class:`NeedsEvents`; :class:`pydiag.fmu.plant.FmuPlant` then falls back to fmpy's CVode,
which handles events.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

SOURCE = Path(__file__).with_name("native") / "me_driver.c"
HEADER = SOURCE.with_name("dop853_coefficients.h")
METHODS = {"dop853": 8, "dopri5": 5}
ERRORS = {-1: "an FMI call failed", -2: "the step size underflowed",
          -3: "non-finite derivatives or outputs", -4: "too many steps",
          -5: "out of memory", -6: "the FMU asked to terminate", -7: "unknown method",
          -8: "the FMU asked for an event", -9: "unknown FMI version"}
PD_EVENT = -8
FUNCTIONS = {
    2: ("fmi2SetTime", "fmi2SetContinuousStates", "fmi2GetDerivatives", "fmi2GetReal",
        "fmi2CompletedIntegratorStep"),
    3: ("fmi3SetTime", "fmi3SetContinuousStates", "fmi3GetContinuousStateDerivatives",
        "fmi3GetFloat64", "fmi3CompletedIntegratorStep"),
}


class NativeUnavailable(Exception):
    """The native driver cannot be built or used here; fall back to fmpy.

    Internal control flow: the plant catches it (or turns it into a PlantError when the
    native engine was required), so it never reaches the user."""


class NeedsEvents(NativeUnavailable):
    """The FMU has events after all (time events, step events): fall back to fmpy."""


def fmi_major(model_description) -> int | None:
    major = model_description.fmiVersion.split(".")[0]
    return int(major) if major in ("2", "3") else None


def supports(model_description) -> bool:
    return (fmi_major(model_description) in FUNCTIONS
            and model_description.modelExchange is not None
            and model_description.numberOfEventIndicators == 0)


def _cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "pydiag"


_LIBRARY: ctypes.CDLL | None = None


def load_driver() -> ctypes.CDLL:
    """The compiled driver (built once per source version)."""
    global _LIBRARY
    if _LIBRARY is not None:
        return _LIBRARY
    source = SOURCE.read_bytes() + HEADER.read_bytes()
    lib_path = _cache_dir() / f"me_driver-{hashlib.sha256(source).hexdigest()[:16]}.so"
    if lib_path.exists():
        lib = ctypes.CDLL(str(lib_path))
    else:
        try:
            lib_path.parent.mkdir(parents=True, exist_ok=True)
            with tempfile.TemporaryDirectory(dir=lib_path.parent) as tmp:
                tmp_lib = _compiled(Path(tmp) / lib_path.name)
                os.replace(tmp_lib, lib_path)  # atomic: parallel workers may race here
            lib = ctypes.CDLL(str(lib_path))
        except OSError:  # a cache that cannot be written (read-only, a file): built for
            with tempfile.TemporaryDirectory() as tmp:  # this process alone, then loaded
                lib = ctypes.CDLL(str(_compiled(Path(tmp) / lib_path.name)))
    f = lib.pd_integrate
    vp, dp = ctypes.c_void_p, ctypes.POINTER(ctypes.c_double)
    f.argtypes = [vp, ctypes.c_int, vp, vp, vp, vp, vp, ctypes.c_int, dp, ctypes.c_double,
                  ctypes.c_double,
                  ctypes.c_double, ctypes.c_int, ctypes.c_int, ctypes.POINTER(ctypes.c_uint32),
                  dp, ctypes.c_double, ctypes.c_double, ctypes.c_double, ctypes.c_long,
                  ctypes.c_int, ctypes.POINTER(ctypes.c_long), ctypes.POINTER(ctypes.c_long),
                  ctypes.c_int, ctypes.c_double, dp, dp, ctypes.c_int, dp,
                  ctypes.POINTER(ctypes.c_int)]
    f.restype = ctypes.c_int
    _LIBRARY = lib
    return lib


def _compiled(lib_path: Path) -> Path:
    """The driver compiled to ``lib_path``."""
    cc = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc")
    if cc is None:
        raise NativeUnavailable("no C compiler found")
    res = subprocess.run([cc, "-O2", "-shared", "-fPIC", "-I", str(SOURCE.parent), "-o",
                          str(lib_path), str(SOURCE), "-lm"], capture_output=True, text=True)
    if res.returncode != 0:
        raise NativeUnavailable(f"compiling the driver failed: {res.stderr.strip()[:300]}")
    return lib_path


class NativeMeRunner:
    """Runs one fmpy ``FMU2Model`` or ``FMU3Model`` instance with the compiled driver.

    Args:
        instance: an instantiated fmpy Model-Exchange model (FMI 2.0 or 3.0)
        model_description: its model description
        output_refs: value references of the Float64 outputs to sample
        relative_tolerance: error tolerance of the integrator
        method: "dop853" or "dopri5"
    """

    def __init__(self, instance, model_description, output_refs: list[int],
                 relative_tolerance: float, method: str = "dop853") -> None:
        if method not in METHODS:
            raise NativeUnavailable(f"method must be one of {list(METHODS)}, got {method!r}")
        self.method = METHODS[method]
        if not supports(model_description):
            raise NativeUnavailable("only FMI 2.0/3.0 Model-Exchange FMUs without event "
                                    "indicators")
        self.fmi_version = fmi_major(model_description)
        self.lib = load_driver()
        self.instance = instance
        self.md = model_description
        self.nx = len(model_description.derivatives)
        self.refs = (ctypes.c_uint32 * len(output_refs))(*output_refs)
        self.ny = len(output_refs)
        self.rtol = relative_tolerance
        dll = instance.dll
        try:
            self.pointers = [ctypes.cast(getattr(dll, name), ctypes.c_void_p).value
                             for name in FUNCTIONS[self.fmi_version]]
        except AttributeError as err:
            raise NativeUnavailable(f"the FMU's binary lacks a function: {err}") from err
        self.n_rhs = 0
        self.n_steps = 0

    def run(self, start_values: dict, first_output_s: float, interval_s: float,
            n_out: int, check_at: int = 0, check_tolerance: float = 0.0,
            free_outputs: bool = False, stop_at: int = 0) -> np.ndarray:
        """Outputs at ``first_output_s + k*interval_s``, k < n_out, shape (n_out, n_outputs).

        ``check_at`` (0 < check_at < n_out): the outputs a period of the forcing apart;
        when the response repeats from output 0 (every state back at output
        ``check_at``, the derivatives and outputs the same one period later, each within
        ``check_tolerance`` of its range: the driver's header), the run stops there and
        the period's ``check_at`` rows are returned. ``free_outputs``: when the states and
        derivatives repeat and the outputs do not (a strike added at the sensor at a rate
        of its own), the integration stops there too and every later output is read at
        its own time from the period's states: all ``n_out`` rows are returned.
        ``stop_at`` (check_at < stop_at < n_out): a run whose response does not repeat
        stops after that many rows, which are returned."""
        inst = self.instance
        if self.fmi_version == 3:
            inst.enterInitializationMode(tolerance=self.rtol, startTime=0.0)
            self._apply(start_values)
            inst.exitInitializationMode()
            while True:  # event iteration at t = 0 (no state events later: no indicators)
                need_update, terminate, _, _, next_defined, _ = inst.updateDiscreteStates()
                if terminate:
                    raise RuntimeError("the FMU terminated during initialisation")
                if not need_update:
                    break
        else:
            inst.setupExperiment(tolerance=self.rtol, startTime=0.0)
            self._apply(start_values)  # FMI 2: before initialisation, as fmpy does
            inst.enterInitializationMode()
            inst.exitInitializationMode()
            while True:
                need_update, terminate, _, _, next_defined, _ = inst.newDiscreteStates()
                if terminate:
                    raise RuntimeError("the FMU terminated during initialisation")
                if not need_update:
                    break
        if next_defined:
            self._stop()
            raise NeedsEvents("the FMU schedules time events")
        inst.enterContinuousTimeMode()
        x = np.zeros(max(self.nx, 1))
        if self.nx:
            inst.getContinuousStates(x.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), self.nx)
        out = np.empty((n_out, self.ny))
        n_rhs, n_steps = ctypes.c_long(0), ctypes.c_long(0)
        work = np.zeros(7 * max(self.nx, 1) + 5 * self.ny)
        mismatch, returned = ctypes.c_double(np.inf), ctypes.c_int(0)
        dptr = ctypes.POINTER(ctypes.c_double)
        free = free_outputs and 0 < check_at < n_out and self.nx > 0
        store = np.empty(check_at * self.nx) if free else None
        # DOP853 interpolates outputs, so its steps are free; Dormand-Prince lands on the grid.
        h_max = interval_s if self.method == 5 else first_output_s + n_out * interval_s
        rc = self.lib.pd_integrate(
            inst.component, self.fmi_version, *self.pointers, self.nx, x.ctypes.data_as(dptr), 0.0,
            first_output_s, interval_s, n_out, self.ny, self.refs, out.ctypes.data_as(dptr),
            self.rtol, 1e-12, h_max, 10_000_000, self.method, ctypes.byref(n_rhs),
            ctypes.byref(n_steps), int(check_at), float(check_tolerance),
            work.ctypes.data_as(dptr), None if store is None else store.ctypes.data_as(dptr),
            int(stop_at), ctypes.byref(mismatch), ctypes.byref(returned))
        self.n_rhs += n_rhs.value
        self.n_steps += n_steps.value
        self._stop()
        if rc == PD_EVENT:
            raise NeedsEvents("the FMU asked for an event at a completed step")
        if rc != 0:
            raise RuntimeError(f"native integration failed: {ERRORS.get(rc, rc)}")
        if returned.value == 1:
            return out[:check_at]
        if returned.value == 0 and 0 < check_at < stop_at < n_out:
            return out[:stop_at]
        return out

    def _apply(self, start_values: dict) -> None:
        from fmpy.simulation import apply_start_values

        unset = apply_start_values(self.instance, self.md, start_values)
        if unset:
            raise ValueError(f"could not set {', '.join(unset)}")

    def _stop(self) -> None:
        self.instance.terminate()
        self.instance.reset()
