"""A fault group is classified only when the record pins it down
(:mod:`pydiag.loop.support`): a transmission error that an acceleration record barely
sees is read as healthy, one the record shows is kept."""

import dataclasses

import pytest
from conftest import NAMES, noisy_measurement

from pydiag.fit.estimator import FitResult
from pydiag.fit.problem import build_problem
from pydiag.gear.paper_cases import case
from pydiag.loop.diagnosis import classified
from pydiag.loop.support import fault_support


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


def test_only_the_groups_asked_for_are_tested_each_against_its_healthy_model(gear_fmu):
    problem = acc_only(gear_fmu, 1)
    assert fault_support(problem, dict(case(1).parameters), []) == []
    # the fit at the healthy values themselves: no evidence either way
    [same] = fault_support(problem, dict(case(1).parameters), ["transmission_error"])
    assert same.statistic == 0.0 and not same.supported
