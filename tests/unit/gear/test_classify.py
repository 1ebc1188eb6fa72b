import pytest

from pydiag.gear.classify import classify, tooth_contrast
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


def test_with_a0_estimated_the_tooth_is_judged_by_its_contrast_alone():
    """The level was fitted: only a_f/a0 counts, on the paper's scale (a0 = 0.1), and f_f
    (the shape of every tooth's wave then) does not."""
    assert tooth_contrast({"a_f": 0.3, "a0": 0.2}) == pytest.approx(0.5)
    assert tooth_contrast({"a_f": 0.3}) == pytest.approx(2.0)  # a0 the paper's 0.1
    same = classify({"a_f": 0.32, "a0": 0.2, "f_f": 0.9})
    assert same == classify({"a_f": 0.16, "a0": 0.1, "f_f": 0.0})  # contrast 0.6 both
    assert (same.tooth_severity, same.fault_mode) == ("early", "tooth_fault")
    assert classify({"a_f": 0.8, "a0": 0.7, "f_f": 0.95}).tooth_severity == "none"
    assert classify({"a_f": 0.8, "f_f": 0.95}).tooth_severity == "advanced"
