"""A fault group is classified only when the record pins it down
(:mod:`pydiag.diagnose.support`): a transmission error that an acceleration record barely
sees is read as healthy, one the record shows is kept."""

import dataclasses

import pytest
from conftest import NAMES, noisy_measurement

from pydiag.fit.estimator import FitResult
from pydiag.fit.build import build_problem
from pydiag.gear.paper_cases import case
from pydiag.diagnose.diagnosis import classified
from pydiag.diagnose.support import fault_support


def acc_only(gear_fmu, number: int):
    m = noisy_measurement(gear_fmu, number, 0)
    return build_problem(str(gear_fmu), dataclasses.replace(m, channels={"acc": m.channels["acc"]}))


def fit(parameters: dict[str, float]) -> FitResult:
    return FitResult({n: parameters[n] for n in NAMES}, 0.05, 1, 0.0, [0.05])


def test_a_transmission_error_the_record_barely_sees_is_not_counted(gear_fmu):
    problem = acc_only(gear_fmu, 1)  # healthy: no transmission error
    estimate = {**case(1).parameters, "f_ate": 0.1}  # "early" on the paper's scale
    result = classified(problem, fit(estimate))
    assert (result.fault_mode, result.te_severity) == ("healthy", "none")
    [test] = result.support
    assert test.group == "transmission_error" and not test.supported
    assert test.parameters == ("f_ate", "f_dte") and test.threshold == pytest.approx(9.21, abs=0.01)
    assert result.to_dict()["fault_support"][0]["supported"] is False


def test_a_transmission_error_and_a_tooth_the_record_shows_are_kept(gear_fmu):
    te = classified(acc_only(gear_fmu, 5), fit(case(5).parameters))  # TE early
    assert (te.fault_mode, te.severity) == ("transmission_error", "early")
    assert [t.supported for t in te.support] == [True]
    tooth = classified(acc_only(gear_fmu, 2), fit(case(2).parameters))  # tooth early
    assert (tooth.fault_mode, tooth.severity) == ("tooth_fault", "early")
    assert [t.group for t in tooth.support if t.supported] == ["tooth"]


def test_the_statistic_weighs_the_fit_against_the_record(gear_fmu):
    """On a healthy record a larger fitted transmission error is refuted more strongly; on
    a record with one, the true level is supported more than half or twice it."""
    def statistic(problem, parameters, scale):
        estimate = {**parameters, "f_ate": scale * parameters["f_ate"],
                    "f_dte": scale * parameters["f_dte"]}
        [test] = fault_support(problem, estimate, ["transmission_error"])
        return test.statistic

    healthy = acc_only(gear_fmu, 1)
    levels = {**case(1).parameters, "f_ate": 0.1, "f_dte": 0.1}
    falling = [statistic(healthy, levels, s) for s in (0.5, 1.0, 2.0)]
    assert falling[0] < 0 and falling == sorted(falling, reverse=True), falling
    te = acc_only(gear_fmu, 5)
    half, true, twice = (statistic(te, case(5).parameters, s) for s in (0.5, 1.0, 2.0))
    assert true > max(half, twice) and true > 9.21, (half, true, twice)
