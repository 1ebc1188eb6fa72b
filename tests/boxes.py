"""The simulator's test boxes (:mod:`truth.gearbox`) as pydiag's machines: what a test tells
pydiag of the box it recorded, written from the teeth alone."""

from pydiag.gear.machine_file import machine_from_dict
from truth.gearbox import BOX, SHORT_BOX, Box


def machine_of(box: Box):
    """The pydiag machine of ``box``: its name and its stages' teeth, nothing else."""
    return machine_from_dict({"name": box.name,
                              "stages": [{"pinion_teeth": p, "gear_teeth": g}
                                         for p, g in box.teeth]})


MACHINE = machine_of(BOX)
SHORT_MACHINE = machine_of(SHORT_BOX)
