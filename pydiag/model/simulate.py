"""Records made by an FMU: what ``pydiag simulate`` writes, and test and benchmark data."""

from __future__ import annotations

import numpy as np

from pydiag.core.errors import PlantError, UsageError
from pydiag.core.measurement import Measurement
from pydiag.fmu.description import outputs_of, read_model_description
from pydiag.fmu.plant import DEFAULT_WARMUP_S, PlantSpec
from pydiag.gear.conventions import default_sensors, kinematics_from, kinematics_to_dict
from pydiag.model.adapter import Adapter, check_against_fmu
from pydiag.signal.noise import add_white_noise

#: ``metadata["source"]`` of a record made here.
SIMULATED_SOURCE = "pydiag simulate"
#: Default record length of a gear model, in fundamental periods.
DEFAULT_PERIODS = 10


def fmu_outputs(fmu_path: str) -> list[str]:
    """The FMU's output variables; an FMU without any cannot be a sensor."""
    md, _ = read_model_description(fmu_path)
    outputs = outputs_of(md)
    if not outputs:
        raise PlantError(f"{fmu_path} has no output variables to use as a sensor")
    return outputs


def plant_spec_for(fmu: str, sample_rate_hz: float, adapter: Adapter | None = None,
                   sensors: tuple[str, ...] | None = None) -> PlantSpec:
    """How to run ``fmu`` as a sensor: as the adapter says, else for ``sensors`` (default:
    the GearDiag sensors among its outputs, else every output)."""
    if adapter is not None:
        if sensors:
            raise UsageError("give the sensors in the adapter or with --sensor, not both")
        return adapter.plant_spec(fmu, sample_rate_hz)
    return PlantSpec(str(fmu), tuple(sensors or default_sensors(fmu_outputs(fmu))), sample_rate_hz)


def simulate_measurement(fmu: str, values: dict[str, float], duration_s: float | None,
                         sample_rate_hz: float, snr: float | None, seed: int,
                         sensors: tuple[str, ...] | None = None,
                         adapter: Adapter | None = None) -> Measurement:
    """A (noisy) record of the FMU at parameter ``values``.

    Channels are named by the adapter, else by the outputs (default: the GearDiag sensors
    among them). ``duration_s`` None: ``DEFAULT_PERIODS`` fundamental periods of a gear
    model, else the adapter's window, else 1 s. ``snr``: signal/noise power ratio per
    channel, None for a noiseless record. The metadata hold the operating point the
    record was made at (with ``values`` applied).
    """
    spec = plant_spec_for(fmu, sample_rate_hz, adapter, sensors)
    if adapter is not None:
        channels = [(s.channel, s.scale) for s in adapter.sensors]
        warmup_s = adapter.warmup_s
    else:
        channels = [(s, 1.0) for s in spec.sensors]
        warmup_s = DEFAULT_WARMUP_S
    with spec.open() as plant:
        operating_point = {**plant.parameters(), **plant.fixed_values, **values}
        if adapter is not None:
            check_against_fmu(adapter, plant.variables)
            kin = adapter.resolve_kinematics(operating_point)
        else:
            kin = kinematics_from(operating_point)
        if duration_s is None:
            duration_s = (DEFAULT_PERIODS * kin.period_s if kin else
                          adapter.window_s if adapter and adapter.window_s else 1.0)
        if not duration_s > 0:
            raise UsageError(f"--duration must be positive, got {duration_s}")
        y = plant.simulate(values, duration_s, warmup_s)
        meta = {"source": SIMULATED_SOURCE, "fmu": plant.fmu_path.name, "set": values,
                "snr": snr, "seed": seed, "warmup_s": warmup_s}
        if kin:
            meta["kinematics"] = kinematics_to_dict(kin)
    rng = np.random.default_rng(seed)
    signals = {}
    for i, (name, scale) in enumerate(channels):
        clean = scale * y[i]
        signals[name] = add_white_noise(clean, snr, rng) if snr is not None else clean
    return Measurement(signals, sample_rate_hz, meta)
