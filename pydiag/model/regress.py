"""Regression check of an exported FMU against golden spectra.

A golden file records, for a set of cases (parameter values), the amplitude spectrum
of each sensor over a fixed window after start-up: the period-synchronous lines up to
the top band edge when the kinematics are known, else the windowed FFT magnitudes up
to ``max_freq_hz``. A check passes when, for every case and sensor, every amplitude
lies within ``rtol`` times the largest amplitude of that spectrum of its golden value.

The default cases are Table 1's eight when the FMU has the paper's fault parameters (a
machine's model: on its first stage), else one case at the FMU's own defaults: so any
FMU can be blessed and checked. A machine's own model is checked on the machine's
fundamental period (every stage's lines synchronous), which the golden file records as
``synchronous``.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pydiag.core.errors import GoldenError, UsageError
from pydiag.fmu.plant import DEFAULT_WARMUP_S, FmuPlant
from pydiag.gear.conventions import kinematics_from, kinematics_to_dict
from pydiag.gear.features import max_band_freq_hz
from pydiag.gear.kinematics import GearKinematics
from pydiag.gear.machine import Machine
from pydiag.gear.paper_cases import TABLE1
from pydiag.io.outputs import atomic_output
from pydiag.model.adapter import Adapter
from pydiag.model.simulate import plant_spec_for
from pydiag.signal.spectra import amplitude_spectrum, sync_spectrum

GOLDEN_VERSION = 1
DEFAULT_RTOL = 2e-3


@dataclass
class Mismatch:
    case: str
    sensor: str
    freq_hz: float
    golden: float
    actual: float
    allowed: float


@dataclass
class RegressionReport:
    golden: str
    cases: int
    sensors: list[str]
    rtol: float
    mismatches: list[Mismatch] = field(default_factory=list)
    worst_relative: float = 0.0

    @property
    def passed(self) -> bool:
        return not self.mismatches


def default_cases(plant: FmuPlant) -> dict[str, dict[str, float]]:
    """Table 1's eight cases on the FMU's paper fault parameters: its own, else the first
    instance's that has them all (a machine's model: the first stage's, ``stage.f_ate``);
    else one case at the FMU's defaults."""
    names = set(TABLE1[0].parameters)
    have = list(plant.parameters())
    prefixes = [""] + list(dict.fromkeys(n.rsplit(".", 1)[0] + "." for n in have if "." in n))
    for prefix in prefixes:
        if {prefix + n for n in names} <= set(have):
            return {f"case{c.number}": {prefix + k: v for k, v in c.parameters.items()}
                    for c in TABLE1}
    return {"defaults": {}}


@dataclass(frozen=True)
class Synchronous:
    """The window a model with known kinematics is checked on: one fundamental period
    (``period_s``, s; every line a harmonic of its inverse), its lines up to
    ``max_freq_hz`` (Hz)."""

    period_s: float
    max_freq_hz: float

    @classmethod
    def of(cls, kin: GearKinematics) -> "Synchronous":
        """The window of ``kin`` (a pair's, or a stage's of a modelled machine: the
        machine's period and every stage's bands)."""
        return cls(kin.period_s, max_band_freq_hz(kin))


def spectrum_of(plant: FmuPlant, parameters: dict[str, float], sync: Synchronous | None,
                warmup_s: float, window_s: float, max_freq_hz: float) -> dict[str, dict]:
    if sync is not None:
        y = plant.simulate(parameters, sync.period_s, warmup_s)
        out = {}
        for i, s in enumerate(plant.sensors):
            spec = sync_spectrum(y[i], plant.sample_rate_hz, sync.period_s, sync.max_freq_hz)
            out[s] = {"freq_hz": spec.freq_hz.tolist(), "amplitude": spec.amplitude.tolist()}
        return out
    y = plant.simulate(parameters, window_s, warmup_s)
    out = {}
    for i, s in enumerate(plant.sensors):
        freqs, amp = amplitude_spectrum(y[i], plant.sample_rate_hz, "hann")
        keep = freqs <= max_freq_hz
        out[s] = {"freq_hz": freqs[keep].tolist(), "amplitude": amp[keep].tolist()}
    return out


def bless_fmu(fmu_path: str | Path, golden_path: str | Path, adapter: Adapter | None = None,
              sensors: tuple[str, ...] | None = None, sample_rate_hz: float = 10_000.0,
              machine: Machine | None = None, speed_parameter: str | None = None) -> Path:
    """Open the FMU as the adapter says (else: the GearDiag sensors among its outputs, or
    ``sensors``) and :func:`bless` it. The FMU of ``machine``'s own model is blessed on
    the machine's period at the input speed its ``speed_parameter`` (Hz) starts at."""
    with plant_spec_for(str(fmu_path), sample_rate_hz, adapter, sensors).open() as plant:
        kin = None
        if machine is not None:
            values = {**plant.parameters(), **plant.fixed_values}
            if speed_parameter not in values:  # a caller's mix-up, not the user's
                raise ValueError(f"{fmu_path} has no parameter {speed_parameter}: it is not "
                                 f"the model of {machine.name}")
            kin = machine.model_kinematics(values[speed_parameter])
        return bless(plant, golden_path, adapter=adapter, kinematics=kin)


def bless(plant: FmuPlant, golden_path: str | Path, warmup_s: float = DEFAULT_WARMUP_S,
          window_s: float = 0.2, max_freq_hz: float = 2000.0,
          cases: dict[str, dict[str, float]] | None = None,
          adapter: Adapter | None = None, kinematics: GearKinematics | None = None) -> Path:
    """Write (or replace: blessing is the explicit act of accepting new behaviour) the golden file.

    With an adapter, its kinematics (or its [spectrum] window) and warm-up apply, and its
    start values are recorded so that the check sets them too. ``kinematics`` (a
    machine's own model: :meth:`~pydiag.gear.machine.Machine.model_kinematics`) wins over
    both.
    """
    kin = kinematics
    if adapter is not None:
        kin = kin or adapter.resolve_kinematics({**plant.parameters(), **plant.fixed_values})
        warmup_s = adapter.warmup_s
        if kin is None:
            window_s, max_freq_hz = adapter.window_s, adapter.max_freq_hz
    elif kin is None:
        kin = kinematics_from({**plant.parameters(), **plant.fixed_values})
    sync = None if kin is None else Synchronous.of(kin)
    cases = cases if cases is not None else default_cases(plant)
    golden = {
        "version": GOLDEN_VERSION,
        "fmu": plant.fmu_path.name,
        "sensors": list(plant.sensors),
        "sample_rate_hz": plant.sample_rate_hz,
        "start_values": dict(plant.fixed_values),
        "relative_tolerance": plant.relative_tolerance,
        "warmup_s": warmup_s,
        "window_s": window_s,
        "max_freq_hz": max_freq_hz,
        "kinematics": None if kin is None else kinematics_to_dict(kin),
        "synchronous": None if sync is None else dataclasses.asdict(sync),
        "cases": {name: {"parameters": params,
                         "spectra": spectrum_of(plant, params, sync, warmup_s, window_s,
                                                max_freq_hz)}
                  for name, params in cases.items()},
    }
    path = Path(golden_path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_output(path, force=True) as tmp:
        tmp.write_text(json.dumps(golden, indent=1) + "\n")
    return path


def load_golden(golden_path: str | Path) -> dict:
    path = Path(golden_path)
    try:
        golden = json.loads(path.read_text())
    except FileNotFoundError as err:
        raise GoldenError(f"no golden file {path}; create it with --bless") from err
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
        raise GoldenError(f"cannot read golden file {path}: {err}") from err
    if not isinstance(golden, dict) or golden.get("version") != GOLDEN_VERSION:
        version = golden.get("version") if isinstance(golden, dict) else None
        raise GoldenError(f"{path} is not a golden file of version {GOLDEN_VERSION} "
                          f"(found {version if version is not None else 'no version'})")
    return golden


def _synchronous(golden: dict) -> Synchronous | None:
    """The golden file's window: as recorded, else (a file blessed before machines were)
    its pair's kinematics'."""
    if golden.get("synchronous"):
        try:
            return Synchronous(float(golden["synchronous"]["period_s"]),
                               float(golden["synchronous"]["max_freq_hz"]))
        except (TypeError, KeyError, ValueError) as err:
            raise GoldenError(f"the golden file's synchronous window is not a period and a "
                              f"top frequency: {golden['synchronous']!r}") from err
    kin = golden.get("kinematics")
    return None if kin is None else Synchronous.of(kinematics_from(kin))


def check(fmu_path: str | Path, golden_path: str | Path, rtol: float = DEFAULT_RTOL) -> RegressionReport:
    """Simulate the golden cases on ``fmu_path`` and compare."""
    if not (math.isfinite(rtol) and rtol >= 0):
        raise UsageError(f"the tolerance must be a finite number >= 0, got {rtol}")
    golden = load_golden(golden_path)
    sync = _synchronous(golden)
    with FmuPlant(fmu_path, tuple(golden["sensors"]), golden["sample_rate_hz"],
                  golden.get("relative_tolerance"), golden.get("start_values") or None) as plant:
        report = RegressionReport(str(golden_path), len(golden["cases"]), list(plant.sensors), rtol)
        for name, case in golden["cases"].items():
            actual = spectrum_of(plant, case["parameters"], sync, golden["warmup_s"],
                                 golden["window_s"], golden["max_freq_hz"])
            for sensor, ref in case["spectra"].items():
                g = np.asarray(ref["amplitude"])
                a = np.asarray(actual[sensor]["amplitude"])
                scale = float(np.max(np.abs(g))) or 1.0
                if a.shape != g.shape:
                    report.mismatches.append(Mismatch(name, sensor, float("nan"), float(g.size),
                                                      float(a.size), 0.0))
                    continue
                dev = np.abs(a - g)
                report.worst_relative = max(report.worst_relative, float(np.max(dev)) / scale)
                i = int(np.argmax(dev))
                if dev[i] > rtol * scale:
                    report.mismatches.append(Mismatch(name, sensor, ref["freq_hz"][i], float(g[i]),
                                                      float(a[i]), rtol * scale))
    return report
