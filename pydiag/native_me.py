"""Compiled integration of FMI 3.0 Model-Exchange FMUs: the step loop runs in C.

fmpy's ``simulate_fmu`` calls back into Python for every right-hand side and output
point. Here fmpy still instantiates, sets parameters and initialises, but the whole
integration (Dormand-Prince 5(4), steps landing on the output grid) and the output
sampling run in ``native/me_driver.c`` through the FMU's own ``fmi3*`` function
pointers, with DOP853 (8th order, the default) or Dormand-Prince 5(4). The driver is compiled with the system C compiler on first use and cached
under ``$XDG_CACHE_HOME/pydiag`` (``~/.cache/pydiag``) by source hash.

Only FMI 3.0 ME FMUs without event indicators qualify; :func:`supports` says which.
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
          -5: "out of memory", -6: "the FMU asked to terminate", -7: "unknown method"}


class NativeUnavailable(Exception):
    """The native driver cannot be built or used here; fall back to fmpy."""


def supports(model_description) -> bool:
    return (model_description.fmiVersion.startswith("3.")
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
    if not lib_path.exists():
        cc = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc")
        if cc is None:
            raise NativeUnavailable("no C compiler found")
        lib_path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(dir=lib_path.parent) as tmp:
            tmp_lib = Path(tmp) / lib_path.name
            res = subprocess.run([cc, "-O2", "-shared", "-fPIC", "-I", str(SOURCE.parent), "-o",
                                  str(tmp_lib), str(SOURCE), "-lm"], capture_output=True, text=True)
            if res.returncode != 0:
                raise NativeUnavailable(f"compiling the driver failed: {res.stderr.strip()[:300]}")
            os.replace(tmp_lib, lib_path)  # atomic: parallel workers may race here
    lib = ctypes.CDLL(str(lib_path))
    f = lib.pd_integrate
    vp, dp = ctypes.c_void_p, ctypes.POINTER(ctypes.c_double)
    f.argtypes = [vp, vp, vp, vp, vp, vp, ctypes.c_int, dp, ctypes.c_double, ctypes.c_double,
                  ctypes.c_double, ctypes.c_int, ctypes.c_int, ctypes.POINTER(ctypes.c_uint32),
                  dp, ctypes.c_double, ctypes.c_double, ctypes.c_double, ctypes.c_long,
                  ctypes.c_int, ctypes.POINTER(ctypes.c_long), ctypes.POINTER(ctypes.c_long)]
    f.restype = ctypes.c_int
    _LIBRARY = lib
    return lib


class NativeMeRunner:
    """Runs one fmpy FMU3Model instance with the compiled driver.

    Args:
        instance: an instantiated fmpy ``FMU3Model``
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
            raise NativeUnavailable("only FMI 3.0 Model-Exchange FMUs without event indicators")
        self.lib = load_driver()
        self.instance = instance
        self.md = model_description
        self.nx = len(model_description.derivatives)
        self.refs = (ctypes.c_uint32 * len(output_refs))(*output_refs)
        self.ny = len(output_refs)
        self.rtol = relative_tolerance
        dll = instance.dll
        self.pointers = [ctypes.cast(getattr(dll, name), ctypes.c_void_p).value for name in (
            "fmi3SetTime", "fmi3SetContinuousStates", "fmi3GetContinuousStateDerivatives",
            "fmi3GetFloat64", "fmi3CompletedIntegratorStep")]
        self.n_rhs = 0
        self.n_steps = 0

    def run(self, start_values: dict, first_output_s: float, interval_s: float,
            n_out: int) -> np.ndarray:
        """Outputs at ``first_output_s + k*interval_s``, k < n_out, shape (n_out, n_outputs)."""
        from fmpy.simulation import apply_start_values

        inst = self.instance
        inst.enterInitializationMode(tolerance=self.rtol, startTime=0.0)
        unset = apply_start_values(inst, self.md, start_values)
        if unset:
            raise ValueError(f"could not set {', '.join(unset)}")
        inst.exitInitializationMode()
        while True:  # event iteration at t = 0 (no events later: no indicators)
            need_update, terminate, *_ = inst.updateDiscreteStates()
            if terminate:
                raise RuntimeError("the FMU terminated during initialisation")
            if not need_update:
                break
        inst.enterContinuousTimeMode()
        x = np.zeros(max(self.nx, 1))
        if self.nx:
            inst.getContinuousStates(x.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), self.nx)
        out = np.empty((n_out, self.ny))
        n_rhs, n_steps = ctypes.c_long(0), ctypes.c_long(0)
        dptr = ctypes.POINTER(ctypes.c_double)
        # DOP853 interpolates outputs, so its steps are free; Dormand-Prince lands on the grid.
        h_max = interval_s if self.method == 5 else first_output_s + n_out * interval_s
        rc = self.lib.pd_integrate(
            inst.component, *self.pointers, self.nx, x.ctypes.data_as(dptr), 0.0,
            first_output_s, interval_s, n_out, self.ny, self.refs, out.ctypes.data_as(dptr),
            self.rtol, 1e-12, h_max, 10_000_000, self.method, ctypes.byref(n_rhs),
            ctypes.byref(n_steps))
        self.n_rhs += n_rhs.value
        self.n_steps += n_steps.value
        inst.terminate()
        inst.reset()
        if rc != 0:
            raise RuntimeError(f"native integration failed: {ERRORS.get(rc, rc)}")
        return out
