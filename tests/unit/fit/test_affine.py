"""fit_affine: one parameter the outputs are affine in, fitted from two simulations."""

import contextlib
from types import SimpleNamespace

import numpy as np
import pytest

from pydiag.core.errors import UsageError
from pydiag.core.parameters import Parameter
from pydiag.fit.affine import fit_affine


def problem(truth: float, low: float = 0.0, high: float = 10.0):
    """A model y(a) = base + a * shape, measured at ``truth``; counts its simulations."""
    t = np.linspace(0.0, 1.0, 200)
    base, shape = np.sin(2 * np.pi * 3 * t), np.cos(2 * np.pi * 7 * t)
    calls = []

    def simulate(plant, x):
        calls.append(float(x[0]))
        return (base + x[0] * shape)[None, :]

    def residuals_of(y):  # amplitude residuals, not linear in a: the fit must search
        return np.abs(np.fft.rfft(y[0])) - np.abs(np.fft.rfft(base + truth * shape))

    spec = SimpleNamespace(open=lambda: contextlib.nullcontext(None))
    return SimpleNamespace(parameters=(Parameter("a", low, high),), spec=spec,
                           simulate=simulate, residuals_of=residuals_of), calls


def test_the_value_is_found_from_two_simulations():
    p, calls = problem(3.7)
    fitted, error = fit_affine(p)
    assert fitted["a"] == pytest.approx(3.7, abs=1e-2)
    assert error < 1e-2 and sorted(calls) == [0.0, 10.0]


def test_a_value_beyond_the_range_stops_at_its_end():
    p, _ = problem(14.0)
    fitted, _ = fit_affine(p)
    assert fitted["a"] == 10.0


def test_one_parameter_only():
    p, _ = problem(1.0)
    p.parameters = p.parameters * 2
    with pytest.raises(UsageError, match="one parameter"):
        fit_affine(p)
