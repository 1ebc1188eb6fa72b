"""What makes a fit untrustworthy, said to the user: a parameter the record pushes to the
top of its range (the model's form or range is wrong there)."""

from types import SimpleNamespace

from pydiag.core.parameters import Parameter
from pydiag.diagnose.diagnosis import fit_warnings


def problem(*parameters: Parameter) -> SimpleNamespace:
    return SimpleNamespace(parameters=parameters, channels=("acc",), speed=None,
                           measurement=SimpleNamespace(metadata={}))


def test_a_parameter_at_the_top_of_its_range_is_named_and_one_at_the_bottom_is_not():
    p = problem(Parameter("f_ate", 0.0, 1.0), Parameter("a_f", 0.1, 0.9),
                Parameter("phase", 0.0, 6.283, periodic=True))
    found = fit_warnings(p, 0.5, {}, {"f_ate": 0.9985, "a_f": 0.1, "phase": 6.28})
    assert found == ["f_ate = 0.9985 is at the top of its range [0, 1]: the record asks for "
                     "more than the model allows (its form or its range is wrong there)"]
    assert fit_warnings(p, 0.5, {}, {"f_ate": 0.98, "a_f": 0.9}) == [
        found[0].replace("f_ate = 0.9985", "a_f = 0.9").replace("[0, 1]", "[0.1, 0.9]")]
    assert fit_warnings(p, 0.5) == []  # no parameters given: nothing to say of them
