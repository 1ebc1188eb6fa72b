"""A speed ripple applied to a periodic model's output: the response read along a
modulated angle.

A machine whose speed fluctuates slowly (a torque ripple through the shafts' inertia, a
motor's slip, a drive's speed control; a few hertz against a mesh of hundreds) runs
through the same periodic response as at its mean speed, only at a varying pace: its
angle over the mean speed is ``tau(t) = t + depth/(2 pi f) sin(2 pi f t)`` for a speed
``1 + depth cos(2 pi f t)`` of the mean. A displacement is the periodic response read at
``tau(t)``; an acceleration, its second derivative, is that times the pace squared
(``tau'(t)^2``; the term in ``tau''`` is ``f`` over the line's frequency smaller). Every
kinematic line gets the sidebands of a phase modulation at ``+-f``. What a model with the
ripple inside it (``GearDiag.Effects.SpeedFluctuation``) computes by integrating the whole
record, this reads from one simulated period, sampled finely enough to be read between its
samples. It leaves out how the structure's own modes answer a line whose frequency moves:
within 1-5 % of the integrated model's spectrum for ``depth`` up to 0.01 near a mode
(``tests/unit/fit/test_speed_ripple.py``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: A period is simulated at this many times the record's sample rate before it is read
#: between its samples (a cubic spline through it): at 1x a gear mesh's acceleration,
#: which has lines up to the record's Nyquist frequency, was read 10-40 % wrong above
#: the first mesh harmonic; at 8x, 0.3-1.5 % (the module's test).
OVERSAMPLE = 8


def modulated_angle(n_samples: int, sample_rate_hz: float, start_s: float, depth: float,
                    freq_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """(angle over the mean speed, s; pace, 1) at samples ``start_s + k/sample_rate_hz``,
    the angle counted from the first sample, for a speed ``1 + depth cos(2 pi freq_hz t)``
    of the mean (``t`` the model's time, from its start)."""
    k = np.arange(n_samples) / sample_rate_hz
    phase = 2 * np.pi * freq_hz * (start_s + k)
    return k + depth / (2 * np.pi * freq_hz) * np.sin(phase), 1.0 + depth * np.cos(phase)


def along_angle(period: np.ndarray, period_rate_hz: float, angle_s: np.ndarray,
                pace: np.ndarray, derivative: int) -> np.ndarray:
    """One period of a periodic signal (sampled at ``period_rate_hz``, its first sample at
    angle 0) read at ``angle_s`` (s over the mean speed), times ``pace`` to the power
    ``derivative`` (0: a displacement; 2: an acceleration)."""
    from scipy.interpolate import CubicSpline  # the command line starts without it

    n = period.size
    spline = CubicSpline(np.arange(n + 1) / period_rate_hz, np.append(period, period[0]),
                         bc_type="periodic")
    y = spline(np.mod(angle_s, n / period_rate_hz))
    return y * pace ** derivative if derivative else y


@dataclass(frozen=True)
class SpeedRipple:
    """A speed ripple a model's variables size, applied to its periodic output.

    Attributes:
        depth_variable: the name of the ripple's depth (share of the mean speed) among the
            model's values
        freq_variable: the name of its frequency (Hz) among them
        accelerations: the model outputs that are accelerations (read times the pace
            squared); the others are displacements
    """

    depth_variable: str = "ds"
    freq_variable: str = "f_speed"
    accelerations: tuple[str, ...] = ("acc",)

    def apply(self, period: np.ndarray, period_rate_hz: float, outputs: tuple[str, ...],
              n_samples: int, sample_rate_hz: float, start_s: float,
              values: dict[str, float]) -> np.ndarray:
        """``n_samples`` at ``sample_rate_hz`` of the model with the ripple, from its
        periodic response without it: ``period`` (one period of each of ``outputs``, a row
        each, at ``period_rate_hz``, from the model's time ``start_s`` on); depth and
        frequency from ``values``."""
        angle, pace = modulated_angle(n_samples, sample_rate_hz, start_s,
                                      values[self.depth_variable], values[self.freq_variable])
        return np.array([along_angle(row, period_rate_hz, angle, pace,
                                     2 if name in self.accelerations else 0)
                         for row, name in zip(period, outputs)])
