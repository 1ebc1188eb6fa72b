"""The independent simulators: a gear pair's dynamics (:mod:`truth.gear_sim`) and a
gearbox's vibration written from its shafts' angles (:mod:`truth.gearbox`). They share
nothing with the models pydiag fits: their kinematics, their faults and their noise are
their own, and they import nothing of pydiag's but the record type they write
(``tests/test_truth_independence.py``). What the tests fit to them is
``tests/truth_fits.py``'s."""
