"""A gear pair as a pythonfmu Co-Simulation FMU (FMI 2.0): a third exporter.

It integrates the same SDOF mesh with fixed-step RK4 inside ``do_step``; names differ
again (fault knob ``Fault_Amplitude``, output ``Accel``). Built by the ``pythonfmu``
command from SOURCE.
"""

from pathlib import Path

from fmus import build_pythonfmu

SOURCE = '''
import math
from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real


class PyGear(Fmi2Slave):
    author = "gear-diag tests"
    description = "SDOF gear mesh, one faulty pinion tooth, RK4 inside do_step"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.Fault_Amplitude = 0.1
        self.Np = 14.0
        self.Ng = 21.0
        self.Speed = 25.0
        self.Accel = 0.0
        self.x = None
        self.v = 0.0
        for name in ("Fault_Amplitude", "Np", "Ng", "Speed"):
            self.register_variable(Real(name, causality=Fmi2Causality.parameter,
                                        variability=Fmi2Variability.tunable))
        self.register_variable(Real("Accel", causality=Fmi2Causality.output))

    def _acc(self, t, x, v):
        f_mesh = self.Np * self.Speed
        c = math.cos(2 * math.pi * f_mesh * t)
        sigma = c / math.sqrt(0.9 + 0.1 * c * c)
        tooth = math.floor(f_mesh * t + 0.25) % self.Np
        a = self.Fault_Amplitude if tooth < 0.5 else 0.1
        k = 2e8 * (1 + a * sigma)
        return (50 / 0.03 - 1000.0 * v - k * x) / 0.5

    def do_step(self, t, dt):
        if self.x is None:
            self.x = 50 / 0.03 / (2e8 * (1 + self.Fault_Amplitude))
        n = 5
        h = dt / n
        x, v = self.x, self.v
        for i in range(n):
            s = t + i * h
            k1x, k1v = v, self._acc(s, x, v)
            k2x, k2v = v + h / 2 * k1v, self._acc(s + h / 2, x + h / 2 * k1x, v + h / 2 * k1v)
            k3x, k3v = v + h / 2 * k2v, self._acc(s + h / 2, x + h / 2 * k2x, v + h / 2 * k2v)
            k4x, k4v = v + h * k3v, self._acc(s + h, x + h * k3x, v + h * k3v)
            x += h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x)
            v += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
        self.x, self.v = x, v
        self.Accel = self._acc(t + dt, x, v)
        return True
'''

ADAPTER = """
[simulation]
warmup_s = 0.02

[kinematics]
n_pinion = {parameter = "Np"}
n_gear = {parameter = "Ng"}
f_pinion_hz = {parameter = "Speed"}

[[sensor]]
channel = "acc"
variable = "Accel"

[[fault_parameter]]
variable = "Fault_Amplitude"
role = "a_f"
low = 0.1
high = 0.9
"""


def build(folder: Path) -> Path:
    return build_pythonfmu(folder, "PyGear", SOURCE)
