"""Whose is a line that two shafts' TSAs share: a shaft's rise in its residual that
another shaft's change accounts for.

Whatever repeats with a shaft lands in another shaft's TSA on the orders where their
harmonics meet: where the PHM09 box's output turns once in five input turns, every input
order is an output order too, so a broken output tooth rises in the input's TSA on every
one of its orders (at full strength: the input's TSA keeps it whole, and so a fifth of the
tooth's energy). The line itself does not say whose it is; the slower shaft's orders
beside it do: the output's own change at the line is read as the mean of its change at the
two neighbouring output orders its residual keeps (a local fault's lines cover every order
alike). A change ``b`` added to a line the record already holds at power ``a`` changes that
line's power by as much as ``b + 2 sqrt(a b)`` (in phase) and no more: the other shaft's
change accounts for that much of a line's rise, and never more than the rise itself
(:func:`explained_rise`). What it does not account for is the shaft's own.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from pydiag.gear.machine import Machine
from pydiag.gear.machine_indicators import ShaftRecord, residual_mask


def shared_orders(machine: Machine, shaft: int, other: int, samples_per_rev: int,
                  other_samples_per_rev: int) -> tuple[np.ndarray, np.ndarray]:
    """The orders of shaft ``shaft``'s residual (a TSA of ``samples_per_rev`` samples)
    that are harmonics of shaft ``other``'s turn too, and the same lines in ``other``'s
    orders (a TSA of ``other_samples_per_rev``): with ``shaft`` turning p/q times as fast
    as ``other`` (lowest terms), its every q-th order, p/q of it there."""
    ratio = machine.shaft_ratio(shaft) / machine.shaft_ratio(other)
    here = np.flatnonzero(residual_mask(machine, shaft, samples_per_rev))
    here = here[here % ratio.denominator == 0]
    there = here // ratio.denominator * ratio.numerator
    inside = there < other_samples_per_rev // 2
    return here[inside], there[inside]


def beside(power: np.ndarray, kept: np.ndarray, orders: np.ndarray) -> np.ndarray:
    """The mean power of each of ``orders``' two neighbours that ``kept`` holds (a shaft's
    residual), nan where it holds neither."""
    sides = np.stack([orders - 1, np.minimum(orders + 1, power.size - 1)])
    weight = kept[sides].astype(float)
    total = (power[sides] * weight).sum(axis=0)
    count = weight.sum(axis=0)
    return np.where(count > 0, total / np.maximum(count, 1), np.nan)


def _power(records: Sequence[ShaftRecord], channel: str) -> np.ndarray:
    """The mean of ``records``' power by order in ``channel``, to the highest order all
    hold (records at slightly different speeds hold slightly different numbers)."""
    size = min(len(r.power[channel]) for r in records)
    return np.mean([np.asarray(r.power[channel][:size]) for r in records], axis=0)


def explained_rise(machine: Machine, record: Sequence[ShaftRecord],
                   baselines: Sequence[Sequence[ShaftRecord]], shaft: int,
                   others: Sequence[int]) -> tuple[dict[str, float], tuple[int, ...]]:
    """Channel -> how much of shaft ``shaft``'s residual energy rise the ``others``' own
    change accounts for (module docstring; signal units squared), and which of them
    account for some; ``record``: a record's shafts, ``baselines``: each baseline's.
    Nothing where a record or a baseline was kept without its TSA's power by order."""
    if any(not r.power for r in (*record, *(s for b in baselines for s in b))):
        return {}, ()
    out, by = {}, set()
    for channel in record[shaft].power:
        seen = [record[shaft], *(b[shaft] for b in baselines)]
        size = min(len(r.power[channel]) for r in seen)
        now, before = _power(seen[:1], channel)[:size], _power(seen[1:], channel)[:size]
        allowed = np.zeros(size)
        for j in others:
            other = [record[j], *(b[j] for b in baselines)]
            other_size = min(len(r.power[channel]) for r in other)
            here, there = shared_orders(machine, shaft, j, 2 * size - 1, 2 * other_size - 1)
            if not here.size:
                continue
            kept = residual_mask(machine, j, 2 * other_size - 1)
            added = (beside(_power(other[:1], channel)[:other_size], kept, there)
                     - beside(_power(other[1:], channel)[:other_size], kept, there))
            added = np.maximum(np.nan_to_num(added), 0.0)
            allowed[here] += added + 2 * np.sqrt(before[here] * added)
            if np.any(added > 0):
                by.add(j)
        out[channel] = float(np.sum(np.clip(now - before, 0.0, allowed)))
    return out, tuple(sorted(by))
