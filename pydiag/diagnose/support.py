"""Whether a record supports each fault the fit found: a level is read only from
parameters the record pins down.

A fitted fault parameter can sit far from its healthy value while the record barely
cares: on a real record, of which the pair model explains only a part, fits far apart in
such a parameter may differ in error by less than the last bits of the objective, and
which one the swarm returns then hangs on rounding, and so does a verdict read from it
(the case measured: docs/method.md, section 6; bench/RESULTS.md, section 12).

So each group the classification finds above "none" (:data:`pydiag.gear.classify.GROUPS`)
is tested against the same fit with that group healthy
(:func:`pydiag.gear.classify.healthy`), the other parameters held: the likelihood-ratio
statistic of the record's features,

    D = sum w [(R - mu0)^2 - (R - mu1)^2],   w = 1/V0,

with mu0, mu1 the Rician means of the healthy and fitted models' lines in the record's
noise and V0 the variance around the healthy one (the held-out test's terms,
:func:`pydiag.loop.held_out.held_out_statistic`, on the whole record). If the group were
healthy and the fit had only tuned its k parameters to noise, D would be at most about
chi-square with k degrees of freedom; the group is supported when D exceeds that
distribution's (1 - :data:`~pydiag.loop.held_out.FALSE_ALARM_RATE`) quantile. The
healthy model keeps the other parameters at the fit instead of being fitted again, so D
is at least what a refit would give: a group found unsupported would be unsupported
after a refit too, and one found supported might not be (the test errs towards the
fault, as the classification did without it). One simulation a group found faulty.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from pydiag.fit.problem import FitProblem
from pydiag.gear.classify import group_parameters, healthy
from pydiag.loop.held_out import FALSE_ALARM_RATE, held_out_statistic


@dataclass(frozen=True)
class GroupSupport:
    """The test of one fault group (module docstring): ``statistic`` D against
    ``threshold``, with ``parameters`` the group's fitted parameters."""

    group: str
    parameters: tuple[str, ...]
    statistic: float
    threshold: float

    @property
    def supported(self) -> bool:
        return self.statistic > self.threshold

    def to_dict(self) -> dict:
        return {**asdict(self), "supported": self.supported}


def chi2_quantile(dof: int, false_alarm_rate: float = FALSE_ALARM_RATE) -> float:
    """The (1 - ``false_alarm_rate``) quantile of chi-square with ``dof`` degrees."""
    from scipy.stats import chi2  # here: scipy.stats takes a second to import

    return float(chi2.ppf(1.0 - false_alarm_rate, dof))


def fault_support(problem: FitProblem, estimate: dict[str, float], groups: list[str],
                  prefix: str = "") -> list[GroupSupport]:
    """The test of each of ``groups`` at ``estimate`` (a fit of ``problem``, by parameter
    name), one simulation of ``problem``'s model for the fit and one a group; ``prefix``:
    what the fault parameters' names begin with (a machine's stage: ``"<stage>."``)."""
    if not groups:
        return []
    names = [p.name for p in problem.parameters]
    values = {**problem.fixed_values, **estimate}
    own = unprefixed(values, prefix)
    out = []
    with problem.spec.open() as plant:
        fitted = problem.fitted_features(plant, np.array([estimate[n] for n in names]))
        for group in groups:
            free = tuple(prefix + n for n in group_parameters(group, own)
                         if prefix + n in names)
            if not free:
                continue
            null = {**values, **{prefix + n: v for n, v in healthy(own, group).items()}}
            base = problem.fitted_features(plant, np.array([null[n] for n in names]))
            statistic = 0.0
            for c, model, healthy_model in zip(problem.channels, fitted, base):
                ref = problem.reference[c]
                _, terms, _ = held_out_statistic(ref.amplitude, healthy_model, model,
                                                 ref.noise_power)
                statistic += float(np.sum(terms))
            out.append(GroupSupport(group, free, statistic, chi2_quantile(len(free))))
    return out


def unprefixed(values: dict[str, float], prefix: str) -> dict[str, float]:
    """The values whose names begin with ``prefix``, named without it (a machine's stage's
    fault parameters as a pair's)."""
    return {n[len(prefix):]: v for n, v in values.items() if n.startswith(prefix)}
