"""fit_affine: parameters the outputs are affine in, fitted from one simulation more than
there are of them."""

import contextlib
from types import SimpleNamespace

import numpy as np
import pytest

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
                           simulate=simulate, residuals_of=residuals_of,
                           linear_features=lambda y: None, analytic=lambda y: None), calls


def test_the_value_is_found_from_two_simulations():
    p, calls = problem(3.7)
    fit = fit_affine(p)
    fitted, error = fit.values, fit.error
    assert fitted["a"] == pytest.approx(3.7, abs=1e-2)
    assert error < 1e-2 and sorted(calls) == [0.0, 10.0]


def test_a_value_beyond_the_range_stops_at_its_end():
    p, _ = problem(14.0)
    fitted = fit_affine(p).values
    assert fitted["a"] == 10.0


def lines(truth: list[float], high: float = 10.0, linear: bool = False, low: float = 0.0):
    """y(a) = base + sum_j a_j * shape_j (lines at 5, 9 and 13 cycles), measured at
    ``truth``; counts its simulations. ``linear``: the problem gives its features' complex
    values (``FitProblem.linear_features``), and counts the spectra taken of a signal."""
    t = np.linspace(0.0, 1.0, 400, endpoint=False)
    base = np.sin(2 * np.pi * 3 * t)
    shapes = np.array([np.cos(2 * np.pi * k * t) for k in (5, 9, 13)])
    calls = []

    def simulate(plant, x):
        calls.append(tuple(float(v) for v in x))
        return (base + x @ shapes)[None, :]

    measured = np.abs(np.fft.rfft(base + np.array(truth) @ shapes))
    spectra = []

    def residuals_of(y):
        spectra.append(1)
        return np.abs(np.fft.rfft(y[0])) - measured

    def linear_features(y):
        spectra.append(1)
        return [np.fft.rfft(y[0])] if linear else None

    spec = SimpleNamespace(open=lambda: contextlib.nullcontext(None))
    params = tuple(Parameter(f"a{j}", low, high) for j in range(3))
    return SimpleNamespace(parameters=params, spec=spec, simulate=simulate,
                           residuals_of=residuals_of, linear_features=linear_features, analytic=lambda y: None,
                           residuals_of_amplitudes=lambda amps: amps[0] - measured,
                           spectra=spectra), calls


def test_several_values_are_found_from_one_simulation_more_than_parameters():
    p, calls = lines([2.5, 0.0, 7.25])
    fit = fit_affine(p)
    fitted, error = fit.values, fit.error
    assert [fitted[f"a{j}"] for j in range(3)] == pytest.approx([2.5, 0.0, 7.25], abs=1e-2)
    assert error < 1e-2
    assert sorted(calls) == [(0.0, 0.0, 0.0), (0.0, 0.0, 10.0), (0.0, 10.0, 0.0),
                             (10.0, 0.0, 0.0)]


def test_several_values_beyond_the_range_stop_at_its_end():
    p, _ = lines([12.0, 3.0, 0.5])
    fitted = fit_affine(p).values
    assert [fitted[f"a{j}"] for j in range(3)] == pytest.approx([10.0, 3.0, 0.5], abs=1e-2)


def test_features_linear_in_the_signal_are_taken_once_a_simulation():
    """The same fit with a spectrum of each simulation only (not one an evaluation of the
    least squares), for signed coefficients too (their off value, 0, in mid-range; an
    amplitude spectrum of lines apart does not tell a coefficient's sign)."""
    found = {}
    for linear in (False, True):
        p, _ = lines([2.5, -1.0, 7.25], linear=linear, low=-10.0)
        fit = fit_affine(p)
        fitted, error = fit.values, fit.error
        found[linear] = [fitted[f"a{j}"] for j in range(3)]
        assert np.abs(found[linear]) == pytest.approx([2.5, 1.0, 7.25], abs=1e-2)
        assert error < 1e-2
        if linear:
            assert len(p.spectra) == 4  # one a simulation
        else:
            assert len(p.spectra) > 10  # one an evaluation
    assert found[True] == pytest.approx(found[False], abs=1e-6)


@pytest.mark.parametrize("linear", [False, True])
def test_a_parameter_whose_lines_no_feature_sees_stays_off(linear):
    """A shaft's order outside every feature band: the search could leave it anywhere (it
    moves no residual), and the comparison, whose bins do see it, would find a line the
    record has not. Here the features stop below the third line (13 cycles)."""
    p, _ = lines([2.5, 1.0, 7.25], linear=linear)
    cut = 12
    whole, features = p.residuals_of, p.linear_features
    measured = -whole(np.zeros((1, 400)))[:cut]
    p.residuals_of = lambda y: whole(y)[:cut]
    p.residuals_of_amplitudes = lambda amps: amps[0] - measured
    p.linear_features = lambda y: (None if not linear else [f[:cut] for f in features(y)])
    fit = fit_affine(p)
    fitted, error = fit.values, fit.error
    assert fitted["a2"] == 0.0 and fit.unseen == ("a2",)  # off: the low end
    assert [fitted["a0"], fitted["a1"]] == pytest.approx([2.5, 1.0], abs=1e-2)
    assert error < 1e-2


def test_signed_coefficients_are_simulated_off_and_one_at_a_time():
    """Signed ranges: the simulations are all coefficients off (0) and each alone at the
    far end of its range from 0, not every one at its low end at once, where a model
    affine only near 0 (a tooth's lead or lag through the mesh's angle) is far from it;
    an affine model is fitted the same way."""
    p, calls = lines([2.5, -1.0, 7.25], low=-10.0, high=4.0)
    fit = fit_affine(p)
    assert sorted(calls) == [(-10.0, 0.0, 0.0), (0.0, -10.0, 0.0), (0.0, 0.0, -10.0),
                             (0.0, 0.0, 0.0)]
    assert np.abs([fit.values[f"a{j}"] for j in range(3)]) == pytest.approx(
        [2.5, 1.0, 7.25], abs=1e-2)  # an amplitude spectrum does not tell the sign
    assert fit.values["a2"] == pytest.approx(-7.25, abs=1e-2)  # +7.25 is out of range


def modulated(truth_a: float, truth_phi: float):
    """y(a, phi) = base + a (1 + cos(2 pi t - phi)) carrier: a line at 40 cycles whose
    sidebands at 39 and 41 beat with the base's lines there (two lines of other phases, so
    that their amplitudes tell the phase); counts its simulations."""
    t = np.linspace(0.0, 1.0, 400, endpoint=False)
    base = (np.sin(2 * np.pi * 3 * t) + 0.3 * np.cos(2 * np.pi * 39 * t + 0.7)
            + 0.2 * np.cos(2 * np.pi * 41 * t - 2.0))
    carrier = np.cos(2 * np.pi * 40 * t)
    calls = []

    def signal(a, phi):
        return base + a * (1 + np.cos(2 * np.pi * t - phi)) * carrier

    def simulate(plant, x):
        calls.append(tuple(float(v) for v in x))
        return signal(*x)[None, :]

    measured = np.abs(np.fft.rfft(signal(truth_a, truth_phi)))
    spec = SimpleNamespace(open=lambda: contextlib.nullcontext(None))
    params = (Parameter("a", 0.0, 5.0), Parameter("phi", -np.pi, np.pi, periodic=True))
    return SimpleNamespace(parameters=params, spec=spec, simulate=simulate,
                           residuals_of=lambda y: np.abs(np.fft.rfft(y[0])) - measured,
                           linear_features=lambda y: None, analytic=lambda y: None), calls


@pytest.mark.parametrize("phi", [-2.5, 0.4, 2.9])
def test_an_amplitude_modulated_at_a_phase_is_fitted_from_four_simulations(phi):
    """Three simulations at the amplitude's end (the phase at 0, a quarter and a half
    turn) and one off give the outputs at every phase: the fit finds both, simulating
    nothing more."""
    p, calls = modulated(1.7, phi)
    fit = fit_affine(p)
    assert len(calls) == 4 and fit.unseen == ()
    assert fit.values["a"] == pytest.approx(1.7, abs=1e-3)
    assert np.angle(np.exp(1j * (fit.values["phi"] - phi))) == pytest.approx(0.0, abs=1e-3)
    assert -np.pi <= fit.values["phi"] < np.pi and fit.error < 1e-3


def test_two_phases_are_not_fitted_affinely():
    p, _ = modulated(1.0, 0.0)
    p.parameters += (Parameter("psi", -np.pi, np.pi, periodic=True),)
    with pytest.raises(ValueError, match="at most one phase"):
        fit_affine(p)
