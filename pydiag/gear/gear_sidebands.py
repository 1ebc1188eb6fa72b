"""Which of a shaft's two gears changed: the sidebands of the harmonics of its own mesh.

An idler carries two gears, and its TSA's residual rises with either one's fault. A gear's
fault modulates its own mesh: a chip once a turn, a runout by a swing of its amplitude and
timing; its mesh's harmonics grow sidebands at the shaft's orders. The sidebands around a
harmonic of one mesh that is none of the other's (:data:`SIDEBANDS` orders either side,
away from the other's harmonics and their sidebands, in the residual) are that gear's
own; their energy is judged against the baselines' as a shaft's residual is
(:func:`~pydiag.gear.stage_judge.synchronous_db`: the energy less the noise a TSA keeps
there, its deviation from how many orders hold it), less what the shaft's rise spread
evenly over its residual would put there: a tooth's strike that rings the housing rises
on every order alike, around either mesh, and says nothing of which gear. A gear whose
own sidebands rose beyond their threshold, so counted, changed; one whose own did not,
while the other's did, did not. A gear whose mesh harmonics are all the other's (the PHM
2009 spur idler's 96 teeth against its 48) has none of its own: where the other's rose,
one fault accounts for the shaft and it did not change; else the two are not told apart.
The idler's swing through a runout modulates both its meshes on a real box, so an
eccentric gear raises the other mesh's shared sidebands too: only a gear's own are asked
of (:mod:`pydiag.gear.component_judge` applies this).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from pydiag.gear.machine import Machine
from pydiag.gear.machine_indicators import MachineRecord, residual_mask
from pydiag.gear.stage_judge import synchronous_db

#: The sidebands a gear's own are read at: the first two either side of each harmonic
#: (a runout's and a once-a-turn wobble's strongest).
SIDEBANDS = 2


def own_sidebands(teeth: int, other: int, kept: np.ndarray) -> np.ndarray:
    """Which orders (a mask the size of ``kept``) are the first :data:`SIDEBANDS`
    sidebands either side of a harmonic of a ``teeth`` mesh and within as many of none of
    an ``other`` mesh's harmonics, among the orders ``kept`` (a shaft's residual)."""
    orders = np.arange(kept.size)

    def distance(z: int) -> np.ndarray:  # to the nearest harmonic of a z mesh
        k = np.maximum(np.round(orders / z), 1)
        return np.abs(orders - k * z)
    mine, theirs = distance(teeth), distance(other)
    return (mine >= 1) & (mine <= SIDEBANDS) & (theirs > SIDEBANDS) & kept


def sideband_change(machine: Machine, record: MachineRecord,
                    baselines: Sequence[MachineRecord], shaft: int, teeth: int
                    ) -> tuple[float, float] | None:
    """The change of the energy of the own sidebands of shaft ``shaft``'s ``teeth`` gear
    against the baselines', beyond what the shaft's rise spread evenly over its residual
    puts there (dB, averaged over the channels), and its deviation (dB); None where the
    gear has none (its mesh's harmonics all the other gear's) or a record was kept without
    its TSA's power by order."""
    this = record.shafts[shaft]
    seen = [b.shafts[shaft] for b in baselines]
    if len(this.teeth) != 2 or any(not s.power for s in (this, *seen)):
        return None
    other = this.teeth[1] if this.teeth[0] == teeth else this.teeth[0]
    changes, deviations = [], []
    for channel in this.power:
        size = min(len(s.power[channel]) for s in (this, *seen))
        zone = own_sidebands(teeth, other, residual_mask(machine, shaft, 2 * size - 1))
        count = int(np.count_nonzero(zone))
        if count == 0:
            return None
        energy = [float(np.sum(np.asarray(s.power[channel][:size])[zone])) for s in (this, *seen)]
        noise = [s.noise[channel] * count / max(s.residual_orders, 1) for s in (this, *seen)]
        # what the shaft's synchronous rise, spread evenly over its residual, puts there
        rise = (this.residual_energy[channel] - this.noise[channel]
                - float(np.mean([s.residual_energy[channel] - s.noise[channel] for s in seen])))
        even = max(rise, 0.0) * count / max(this.residual_orders, 1)
        change, deviation = synchronous_db(
            (energy[0] - even, noise[0], count),
            (float(np.mean(energy[1:])), float(np.mean(noise[1:])), len(seen) * count))
        changes.append(change)
        deviations.append(deviation)
    return float(np.mean(changes)), float(np.mean(deviations))
