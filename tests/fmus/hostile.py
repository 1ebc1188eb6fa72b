"""A pythonfmu Co-Simulation FMU that misbehaves on purpose, by parameter range:

    k > 1.6          segfaults its process (SIGSEGV)
    1.4 < k <= 1.6   hangs in doStep
    1.2 < k <= 1.4   outputs NaN
    1.0 < k <= 1.2   fails doStep
    otherwise        y = k sin(2 pi 5 t) + 0.5 sin(2 pi 12 t)
"""

import tomllib
from pathlib import Path

import numpy as np

from fmus import build_pythonfmu
from pydiag.core.measurement import Measurement
from pydiag.fmu.plant import FmuPlant
from pydiag.model.adapter import Adapter, parse_adapter

SOURCE = '''
import math
import os
import signal
import time
from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real


class Hostile(Fmi2Slave):
    description = "misbehaves on purpose"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.k = 0.5
        self.y = 0.0
        self.register_variable(Real("k", causality=Fmi2Causality.parameter,
                                    variability=Fmi2Variability.tunable))
        self.register_variable(Real("y", causality=Fmi2Causality.output))

    def do_step(self, t, dt):
        k = self.k
        if k > 1.6:
            os.kill(os.getpid(), signal.SIGSEGV)
        if k > 1.4:
            time.sleep(3600)
        if k > 1.2:
            self.y = float("nan")
            return True
        if k > 1.0:
            return False
        s = t + dt
        self.y = k * math.sin(2 * math.pi * 5 * s) + 0.5 * math.sin(2 * math.pi * 12 * s)
        return True
'''

ADAPTER = """
[simulation]
warmup_s = 0.0

[spectrum]
window_s = 1.0
max_freq_hz = 20.0

[[sensor]]
channel = "y"
variable = "y"

[[fault_parameter]]
variable = "k"
low = {low}
high = {high}
"""


def build(folder: Path) -> Path:
    return build_pythonfmu(folder, "Hostile", SOURCE)


def adapter(low: float, high: float) -> Adapter:
    """The hostile FMU's adapter, its one fault parameter k searched over [low, high]."""
    return parse_adapter(tomllib.loads(ADAPTER.format(low=low, high=high)), "hostile.toml")


def measurement(fmu: Path, k: float) -> Measurement:
    """1 s of the FMU's y at 100 Hz at ``k``, with a little noise (seed 0)."""
    with FmuPlant(fmu, ("y",), sample_rate_hz=100.0) as plant:
        y = plant.simulate({"k": k}, 1.0, 0.0)[0]
    return Measurement({"y": y + np.random.default_rng(0).normal(0, 0.01, y.size)}, 100.0)
