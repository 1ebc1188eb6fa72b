"""Transfer paths between a machine's parts and a sensor, applied to a model's output.

A housing accelerometer sees the mesh force through the housing's structural modes. That
path is linear, so on a model output that repeats each fundamental period (the periodic
steady state a gear model is simulated to) it is exact as a product of spectra: the output's
spectrum times the path's frequency response, no mode integrated in the model. What a
model with the mode inside it computes only after the mode's transient has died away
(seconds for a light mode at a low frequency) costs one FFT here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def mode_accelerance(freq_hz: np.ndarray, f_n_hz: float, zeta: float) -> np.ndarray:
    """The housing's acceleration per unit mesh acceleration at ``freq_hz`` (complex), for
    one mode of natural frequency ``f_n_hz`` (Hz) and damping ratio ``zeta`` driven by the
    mesh force, of the mesh's modal mass: ``-s^2 / (s^2 + 2 zeta w_n s + w_n^2)`` at
    ``s = 2j pi f``. 1 (sign apart) far above the mode, ``1/(2 zeta)`` at it, ``(f/f_n)^2``
    below: the model ``GearDiag.Components.HousingMode``, in whose equations the mesh
    acceleration is ``-F/m``."""
    s = 2j * np.pi * np.asarray(freq_hz, dtype=float)
    w_n = 2 * np.pi * f_n_hz
    return -s * s / (s * s + 2 * zeta * w_n * s + w_n * w_n)


def through_response(signal: np.ndarray, sample_rate_hz: float, response) -> np.ndarray:
    """``signal`` (any unit, ``sample_rate_hz``) passed through the frequency response
    ``response(freq_hz) -> complex``, circularly: exact for a signal of whole periods of a
    periodic one, an approximation at the window's edges otherwise."""
    x = np.asarray(signal, dtype=float)
    spectrum = np.fft.rfft(x)
    spectrum *= response(np.fft.rfftfreq(x.size, 1.0 / sample_rate_hz))
    return np.fft.irfft(spectrum, n=x.size)


@dataclass(frozen=True)
class HousingMode:
    """One housing mode between the mesh and the sensor of one model output.

    Attributes:
        output: the model output the sensor sees through the mode (an FMU variable)
        f_variable: the name of its natural frequency (Hz) among the fitted values
        zeta_variable: the name of its damping ratio among the fitted values
    """

    output: str = "acc"
    f_variable: str = "f_housing"
    zeta_variable: str = "zeta_housing"

    @property
    def variables(self) -> tuple[str, str]:
        return self.f_variable, self.zeta_variable

    def apply(self, signal: np.ndarray, sample_rate_hz: float,
              values: dict[str, float]) -> np.ndarray:
        """``signal`` (the mesh's acceleration) as the housing's sensor sees it, the mode
        at ``values[f_variable]`` Hz with damping ratio ``values[zeta_variable]``."""
        f_n, zeta = values[self.f_variable], values[self.zeta_variable]
        return through_response(signal, sample_rate_hz,
                                lambda f: mode_accelerance(f, f_n, zeta))
