"""A record upsampled once and read at every shaft of a machine (:mod:`pydiag.gear.tracking`)
is tracked exactly as each shaft alone would track it, on a record of :mod:`truth.gearbox`
(written from the shafts' angles)."""

import numpy as np
import pytest
from boxes import MACHINE
from truth.gearbox import INPUT_HZ, gearbox_record

from pydiag.gear.speed import SpeedSettings, estimate_speed
from pydiag.gear.tracking import order_track, track_revolutions, upsampled_record
from pydiag.diagnose.stages import stage_speed


@pytest.fixture(scope="module")
def tracked():
    m = gearbox_record(2)
    estimate = estimate_speed(m, MACHINE.stage_kinematics(0, INPUT_HZ), SpeedSettings("mesh"),
                              machine=MACHINE)
    return m, estimate, upsampled_record(m, estimate)


def test_every_shaft_read_from_one_upsampling_is_as_if_tracked_alone(tracked):
    m, estimate, up = tracked
    for shaft in range(len(MACHINE.shafts)):
        ratio = float(MACHINE.shaft_ratio(shaft))
        alone = track_revolutions(m, estimate, 512, ratio)
        shared = track_revolutions(m, estimate, 512, ratio, upsampled=up)
        assert alone[0] == shared[0] and alone[2] == shared[2]
        np.testing.assert_array_equal(alone[1][0], shared[1][0])
    # a stage's speed is the input's times its ratio, on the same samples: the same reading
    second = stage_speed(estimate, MACHINE, 1)
    np.testing.assert_array_equal(order_track(m, second).channels["acc"],
                                  order_track(m, second, upsampled=up).channels["acc"])


def test_an_upsampling_of_other_samples_is_refused(tracked):
    m, estimate, up = tracked
    shorter = type(up)((up.valid[0] + 1, up.valid[1]), up.channels)
    with pytest.raises(ValueError, match="not this record's"):
        track_revolutions(m, estimate, 512, upsampled=shorter)
