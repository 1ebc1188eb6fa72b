"""The states a component is said to be in, and the rules that name a fault from what
changed: the same words whether the indicators judged the component
(:mod:`pydiag.gear.component_judge`, :mod:`pydiag.gear.bearing_judge`) or the machine's
healthy model did (:mod:`pydiag.loop.own_changes`, ``Effect.fault``)."""

from __future__ import annotations

import math
from collections.abc import Sequence

GOOD, CHANGED, NOT_JUDGED = "good", "changed", "not judged"
CHIPPED, BROKEN, ECCENTRIC = "chipped", "broken", "eccentric"
OUTER, INNER, BALL, CAGE = "outer", "inner", "ball", "cage"
IMBALANCE, BENT, LOOSENESS = "imbalance", "bent", "looseness"

#: A tooth that has lost at least this share of its mesh stiffness is "broken", a
#: softer one "chipped": the tooth's contact is mostly gone rather than reduced (a
#: convention of the words, not a threshold fitted to records).
BROKEN_LOSS = 0.5
#: A shaft's order whose amplitude rose by at least this share of the largest rise of its
#: orders counts as risen (:func:`model_shaft_state`).
RISEN_SHARE = 0.5


def shaft_state(rises: Sequence[int]) -> str:
    """A shaft's state from the orders of its turn that rose (ascending): none, good; its
    1x alone, imbalance; its 1x and 2x, bent (or misaligned); three or more, looseness;
    any other, changed."""
    rises = list(rises)
    if not rises:
        return GOOD
    if len(rises) >= 3:
        return LOOSENESS
    if 1 in rises and 2 in rises:
        return BENT
    if rises == [1]:
        return IMBALANCE
    return CHANGED


def model_shaft_state(healthy: Sequence[float], fitted: Sequence[float]) -> str:
    """:func:`shaft_state` of a shaft's orders 1, 2, ... as a model sized them, healthy and
    on the record: an order rose when its amplitude grew by at least :data:`RISEN_SHARE`
    of the largest growth; changed when none grew. An order not sized (not a number: held
    off) did not rise."""
    growth = [b - a for a, b in zip(healthy, fitted)]
    top = max((g for g in growth if math.isfinite(g)), default=0.0)
    if top <= 0:
        return CHANGED
    return shaft_state([k + 1 for k, g in enumerate(growth) if g >= RISEN_SHARE * top])


def tooth_state(healthy: Sequence[float], fitted: Sequence[float]) -> str:
    """A faulty tooth's state from the share of its mesh stiffness it lost as a model sized
    it on the record (the largest of ``fitted`` that is a number): :data:`BROKEN` from
    :data:`BROKEN_LOSS` on, else :data:`CHIPPED`."""
    loss = max((f for f in fitted if math.isfinite(f)), default=0.0)
    return BROKEN if loss >= BROKEN_LOSS else CHIPPED
