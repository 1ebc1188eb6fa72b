"""Ripples applied to a periodic model's output: a slow speed or torque ripple read from the
model's periodic response without it, instead of simulated over the whole record.

A machine whose speed fluctuates slowly (a torque ripple through the shafts' inertia, a
motor's slip, a drive's speed control; a few hertz against a mesh of hundreds) runs
through the same periodic response as at its mean speed, only at a varying pace: its
angle over the mean speed is ``tau(t) = t + depth/(2 pi f) sin(2 pi f t)`` for a speed
``1 + depth cos(2 pi f t)`` of the mean. A displacement is the periodic response read at
``tau(t)``; an acceleration, its second derivative, is that times the pace squared
(``tau'(t)^2``; the term in ``tau''`` is ``f`` over the line's frequency smaller). Every
kinematic line gets the sidebands of a phase modulation at ``+-f`` (:class:`SpeedRipple`).

A torque ripple ``dT sin(2 pi f t)`` on a mesh whose equations are linear in its torque
(``GearDiag.GearPair``: the contact never lost) adds ``dT sin(2 pi f t)`` times the
response to a unit of steady torque more, which is periodic: the difference of two
periodic responses, at the torque and one step above it, over the step. Slowly: an
acceleration adds ``2 (2 pi f) cos(2 pi f t)`` times that difference's velocity; the line
at ``f`` itself (the static deflection swinging, ``(2 pi f)^2`` times smaller in an
acceleration) is left out. Every kinematic line gets amplitude-modulation sidebands at
``+-f`` (:class:`LoadRipple`).

What a model with the ripple inside it (``GearDiag.Effects.SpeedFluctuation``,
``LoadFluctuation``) computes by integrating the whole record, this reads from one or two
simulated periods, sampled finely enough to be read between their samples. It leaves out
how the structure's own modes answer a line whose frequency or level moves: a speed ripple
within 1-6 % of the integrated model's spectrum near the mesh's mode, a torque ripple
within 0.2 % (``tests/unit/fit/test_ripple.py``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

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


#: A period of the model's response with the ripple off and the given values changed
#: (FMU variable -> value), sampled at :data:`OVERSAMPLE` times the record's rate; None
#: when the response does not repeat.
PeriodOf = Callable[[dict[str, float]], "np.ndarray | None"]


def _periodic_integral(period: np.ndarray, rate_hz: float) -> np.ndarray:
    """The zero-mean integral over time of one period of a periodic signal (rows)."""
    n = period.shape[-1]
    spectrum = np.fft.rfft(period, axis=-1)
    w = 2j * np.pi * np.fft.rfftfreq(n, 1.0 / rate_hz)
    w[0] = 1.0
    spectrum /= w
    spectrum[..., 0] = 0.0
    return np.fft.irfft(spectrum, n=n, axis=-1)


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
    #: it is the whole model's: read so only where the model has no part it leaves still
    whole_model = True

    @property
    def variables(self) -> tuple[str, ...]:
        return self.depth_variable, self.freq_variable

    def renamed(self, prefix: str, accelerations: tuple[str, ...]) -> "SpeedRipple":
        """The same ripple with its variables named ``<prefix>.<name>``, on a model whose
        accelerations are the outputs ``accelerations``."""
        return SpeedRipple(f"{prefix}.{self.depth_variable}", f"{prefix}.{self.freq_variable}",
                           accelerations)

    def read(self, period_of: PeriodOf, values: dict[str, float], outputs: tuple[str, ...],
             n_samples: int, sample_rate_hz: float, start_s: float) -> np.ndarray | None:
        """``n_samples`` at ``sample_rate_hz`` of the model's ``outputs`` with the ripple,
        from the model's time ``start_s`` on; depth and frequency from ``values``."""
        period = period_of({self.depth_variable: 0.0})
        if period is None:
            return None
        return self.apply(period, sample_rate_hz * OVERSAMPLE, outputs, n_samples,
                          sample_rate_hz, start_s, values)

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


@dataclass(frozen=True)
class LoadRipple:
    """A torque ripple a model's variables size, applied to its periodic output.

    Attributes:
        amplitude_variable: the ripple's amplitude (N.m) among the model's values
        freq_variable: its frequency (Hz)
        torque_variable: the steady torque the ripple adds to (N.m), stepped by
            ``torque_step`` to find the response to a unit of it
        accelerations: the model outputs that are accelerations; the others displacements
        torque_step: the step, a share of the torque (the equations are linear in it)
    """

    amplitude_variable: str = "dT"
    freq_variable: str = "f_load"
    torque_variable: str = "T"
    accelerations: tuple[str, ...] = ("acc",)
    torque_step: float = 0.1
    #: it is its mesh's alone: the response to its torque is the mesh's, whatever else the
    #: model has
    whole_model = False

    @property
    def variables(self) -> tuple[str, ...]:
        return self.amplitude_variable, self.freq_variable, self.torque_variable

    def renamed(self, prefix: str, accelerations: tuple[str, ...]) -> "LoadRipple":
        """:meth:`SpeedRipple.renamed`'s."""
        return LoadRipple(*(f"{prefix}.{name}" for name in self.variables), accelerations,
                          self.torque_step)

    def read(self, period_of: PeriodOf, values: dict[str, float], outputs: tuple[str, ...],
             n_samples: int, sample_rate_hz: float, start_s: float) -> np.ndarray | None:
        """:meth:`SpeedRipple.read`'s, for a torque ripple."""
        off = {self.amplitude_variable: 0.0}
        step = self.torque_step * values[self.torque_variable] or 1.0
        base = period_of(off)
        above = period_of({**off, self.torque_variable: values[self.torque_variable] + step})
        if base is None or above is None:
            return None
        rate = sample_rate_hz * OVERSAMPLE
        unit = (above - base) / step  # the response to a unit of steady torque, a period
        velocity = _periodic_integral(unit, rate)
        t = start_s + np.arange(n_samples) / sample_rate_hz
        w = 2 * np.pi * values[self.freq_variable]
        amplitude = values[self.amplitude_variable]
        index = np.arange(n_samples) * OVERSAMPLE % base.shape[1]
        out = []
        for i, name in enumerate(outputs):
            ripple = amplitude * np.sin(w * t) * unit[i, index]
            if name in self.accelerations:
                ripple += 2 * w * amplitude * np.cos(w * t) * velocity[i, index]
            out.append(base[i, index] + ripple)
        return np.array(out)


#: What a ripple is (:class:`SpeedRipple`, :class:`LoadRipple`).
Ripple = SpeedRipple | LoadRipple
