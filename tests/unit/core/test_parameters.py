"""The bounded-parameter type and the error hierarchy."""

import inspect

import pytest

from pydiag.core import errors
from pydiag.core.errors import PydiagError, UsageError
from pydiag.core.parameters import Parameter, fmu_values


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


def test_every_project_error_is_a_pydiag_error():
    classes = [c for _, c in inspect.getmembers(errors, inspect.isclass)
               if issubclass(c, Exception) and c.__module__ == errors.__name__]
    assert len(classes) >= 9
    assert all(issubclass(c, PydiagError) for c in classes), classes
    assert not issubclass(ValueError, PydiagError)
