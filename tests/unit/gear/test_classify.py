import pytest

from pydiag.gear.classify import classify
from pydiag.gear.paper_cases import TABLE1


@pytest.mark.parametrize("case", TABLE1, ids=lambda c: f"case{c.number}")
def test_table1_truth_is_classified_as_its_row(case):
    c = classify(case.parameters)
    assert (c.fault_mode, c.severity) == (case.fault_mode, case.severity)


@pytest.mark.parametrize("case", TABLE1, ids=lambda c: f"case{c.number}")
def test_estimates_within_003_of_truth_keep_the_class(case):
    """The thresholds sit at mid-levels, so a 0.03 estimation error cannot flip a class."""
    for sign in (-1, 1):
        shifted = {k: max(0.0, v + sign * 0.03) for k, v in case.parameters.items()}
        c = classify(shifted)
        assert (c.fault_mode, c.severity) == (case.fault_mode, case.severity), shifted


def test_levels_combine():
    c = classify(dict(a_f=0.62, f_f=0.9, f_ate=0.12, f_dte=0.0))
    assert c.fault_mode == "combined" and c.severity == "advanced"
    assert (c.tooth_severity, c.te_severity) == ("advanced", "early")
