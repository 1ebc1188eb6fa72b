"""Failure mode and degradation level from estimated fault parameters.

Thresholds are the midpoints between the levels of the paper's Table 1:

==========  =======  =====  ======  ========
level       healthy  early  medium  advanced
==========  =======  =====  ======  ========
a_f - a0    0        0.1    0.2     0.5
f_f         0.1      0.4    0.6     0.9
f_ate/f_dte 0        0.1    0.2     0.4
==========  =======  =====  ======  ========

so a tooth level comes from a_f - a0 at 0.05 / 0.15 / 0.35 and from f_f at
0.25 / 0.5 / 0.75 (the higher of the two), and a transmission-error level from
max(f_ate, f_dte) at 0.05 / 0.15 / 0.3. The failure mode names which of the two
is above "none"; the severity is the higher of the two levels.

When ``a0`` was estimated as well (a record whose level was fitted, see
:mod:`pydiag.fit.problem`), the absolute amplitudes are not identifiable, their ratio is:
the tooth level then comes from the contrast ``|a_f / a0 - 1|`` put on the paper's scale
(``a0`` = 0.1: a contrast of 1 is the paper's a_f - a0 = 0.1), and not from ``f_f``,
which then is the shape of every tooth's stiffness wave, fitted to the real gear.

The parameters fall in two groups, the tooth's (``a_f``, and ``f_f`` when ``a0`` is
known) and the transmission error's (``f_ate``, ``f_dte``); :func:`healthy` puts one
group at its healthy values, the model that group's level is judged against
(:mod:`pydiag.diagnose.support`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

SEVERITIES = ("none", "early", "medium", "advanced")
FAULT_MODES = ("healthy", "tooth_fault", "transmission_error", "combined")
TOOTH_AMPLITUDE_EDGES = (0.05, 0.15, 0.35)
FORM_FACTOR_EDGES = (0.25, 0.5, 0.75)
TE_EDGES = (0.05, 0.15, 0.3)
DEFAULT_A0 = 0.1
#: The form factor of a healthy gear in the paper's Table 1.
HEALTHY_FORM_FACTOR = 0.1
#: The parameter groups a level is read from, as :class:`Classification` names them.
GROUPS = ("tooth", "transmission_error")


def _level(value: float, edges: tuple[float, ...]) -> int:
    return int(np.searchsorted(edges, value, side="right"))


@dataclass(frozen=True)
class Classification:
    fault_mode: str
    severity: str
    tooth_severity: str
    te_severity: str


def tooth_contrast(parameters: dict[str, float], a0: float = DEFAULT_A0) -> float:
    """|a_f / a0 - 1|: how much the faulty tooth's stiffness variation differs from the
    healthy teeth's, relative to theirs (``a0`` from the parameters when estimated)."""
    a0 = parameters.get("a0", a0)
    return abs(parameters.get("a_f", a0) / a0 - 1.0)


def classify(parameters: dict[str, float], a0: float = DEFAULT_A0) -> Classification:
    """Classify from ``a_f``, ``f_f``, ``f_ate``, ``f_dte`` (missing ones count as healthy),
    or from the tooth contrast when ``a0`` is among the parameters (module docstring)."""
    if "a0" in parameters:
        tooth = _level(DEFAULT_A0 * tooth_contrast(parameters), TOOTH_AMPLITUDE_EDGES)
    else:
        tooth = max(_level(parameters.get("a_f", a0) - a0, TOOTH_AMPLITUDE_EDGES),
                    _level(parameters.get("f_f", 0.0), FORM_FACTOR_EDGES))
    te = _level(max(parameters.get("f_ate", 0.0), parameters.get("f_dte", 0.0)), TE_EDGES)
    mode = FAULT_MODES[(tooth > 0) + 2 * (te > 0)]
    return Classification(mode, SEVERITIES[max(tooth, te)], SEVERITIES[tooth], SEVERITIES[te])


def group_parameters(group: str, parameters: dict[str, float]) -> tuple[str, ...]:
    """The names among ``parameters`` that ``group``'s level is read from (module
    docstring)."""
    names = {"tooth": ("a_f",) if "a0" in parameters else ("a_f", "f_f"),
             "transmission_error": ("f_ate", "f_dte")}[group]
    return tuple(n for n in names if n in parameters)


def healthy(parameters: dict[str, float], group: str, a0: float = DEFAULT_A0
            ) -> dict[str, float]:
    """``parameters`` with ``group`` at its healthy values: the faulty tooth as the others
    (and the paper's healthy form factor when ``a0`` is known), no transmission error."""
    values = {"a_f": parameters.get("a0", a0), "f_f": HEALTHY_FORM_FACTOR,
              "f_ate": 0.0, "f_dte": 0.0}
    return {**parameters, **{n: values[n] for n in group_parameters(group, parameters)}}


def group_level(classification: Classification, group: str) -> str:
    """The level ``classification`` gives ``group``."""
    return {"tooth": classification.tooth_severity,
            "transmission_error": classification.te_severity}[group]
