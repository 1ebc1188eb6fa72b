"""The bounded-parameter type and the error hierarchy."""

import inspect

import pytest

from pydiag.core import errors
from pydiag.core.errors import PydiagError, UsageError
import numpy as np

from pydiag.core.parameters import Parameter, fmu_values, snap


@pytest.mark.parametrize("low,high,scale,message", [
    (0.5, 0.5, 1.0, "low < high"), (0.9, 0.1, 1.0, "low < high"),
    (0.0, float("inf"), 1.0, "finite"), (float("nan"), 1.0, 1.0, "finite"),
    (0.0, 1.0, 0.0, "non-zero"), (0.0, 1.0, float("nan"), "non-zero"),
])
def test_bad_bounds_and_scales_are_usage_errors(low, high, scale, message):
    with pytest.raises(UsageError, match=message):
        Parameter("k", low, high, scale=scale)


def test_estimates_map_to_fmu_variables_with_their_scale():
    params = (Parameter("a_f", 0.1, 0.9, "tooth.amp"), Parameter("ecc", 0.0, 50.0, "e", 1e-6))
    assert params[0].fmu_variable == "tooth.amp" and Parameter("x", 0, 1).fmu_variable == "x"
    assert fmu_values(params, {"a_f": 0.3, "ecc": 10.0, "other": 2}) == {
        "tooth.amp": 0.3, "e": pytest.approx(1e-5), "other": 2.0}


def test_a_stepped_parameter_starts_and_snaps_on_its_multiples():
    """A tooth's index: the multiples in range are its starts, any position moves to the
    nearest one (inside the range; a periodic index wraps, its high end being its low)."""
    second = Parameter("tooth2", 0.5, 13.5, step=1.0)
    gear = Parameter("tooth_g", 0.0, 21.0, periodic=True, step=1.0)
    smooth = Parameter("d", 0.0, 0.6)
    assert second.starts() == [float(k) for k in range(1, 14)]
    assert gear.starts() == [float(k) for k in range(21)] and smooth.starts() == []
    xs = np.array([[0.51, 20.7, 0.123], [13.49, -0.4, 0.5], [4.5001, 10.2, 0.0]])
    snapped = snap((second, gear, smooth), xs)
    assert snapped.tolist() == [[1.0, 0.0, 0.123], [13.0, 0.0, 0.5], [5.0, 10.0, 0.0]]
    assert xs[0, 0] == 0.51  # a copy
    assert snap((second, smooth), np.array([7.6, 0.3])).tolist() == [8.0, 0.3]


def test_every_project_error_is_a_pydiag_error():
    classes = [c for _, c in inspect.getmembers(errors, inspect.isclass)
               if issubclass(c, Exception) and c.__module__ == errors.__name__]
    assert len(classes) >= 9
    assert all(issubclass(c, PydiagError) for c in classes), classes
    assert not issubclass(ValueError, PydiagError)
