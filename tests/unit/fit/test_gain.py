"""The model's level at a sensor: a gain, or a curve with a node at every mesh harmonic."""

import numpy as np
import pytest

from pydiag.fit.gain import (apply_curve, curve_basis, curve_nodes, fitted_curve,
                             fitted_gain)
from pydiag.gear.kinematics import GearKinematics, Surroundings, OtherStage


def test_the_nodes_are_every_stages_mesh_harmonics_and_close_ones_are_one():
    pair = GearKinematics(32, 80, 30.0)  # mesh 960 Hz
    assert curve_nodes(pair, 2500.0) == pytest.approx([960.0, 1920.0, 2880.0])
    # a second stage of 48/80 on the gear shaft (12 Hz): mesh 576 Hz; its 5th harmonic
    # (2880 Hz) falls on the first stage's 3rd, and is one node with it; each stage's
    # harmonics reach the first at or above the top
    box = GearKinematics(32, 80, 30.0, surroundings=Surroundings(
        stages=(OtherStage("output stage", 48, 80, 32 / 80, "idler", "output"),)))
    nodes = curve_nodes(box, 2900.0)
    assert nodes == pytest.approx([576.0, 960.0, 1152.0, 1728.0, 1920.0, 2304.0, 2880.0,
                                    3456.0, 3840.0])


def test_the_basis_is_a_partition_of_unity_flat_beyond_the_end_nodes():
    nodes = np.array([100.0, 200.0, 400.0])
    f = np.array([10.0, 100.0, 150.0, 300.0, 400.0, 900.0])
    basis = curve_basis(f, nodes)
    assert basis.sum(axis=1) == pytest.approx(np.ones(f.size))
    assert basis[0] == pytest.approx([1, 0, 0]) and basis[-1] == pytest.approx([0, 0, 1])
    assert basis[2] == pytest.approx([0.5, 0.5, 0]) and basis[3] == pytest.approx([0, 0.5, 0.5])


def test_a_curve_the_record_has_is_fitted_and_a_gain_is_its_least_squares_level():
    rng = np.random.default_rng(1)
    f = np.sort(rng.uniform(0.0, 3000.0, 400))
    nodes = np.array([960.0, 1920.0, 2880.0])
    basis = curve_basis(f, nodes)
    model = rng.uniform(0.1, 1.0, f.size)
    truth = np.array([2.0, 0.5, 3.0])
    assert fitted_curve(model, (basis @ truth) * model, basis) == pytest.approx(truth)
    assert fitted_gain(model, 2.0 * model) == pytest.approx(2.0)
    assert fitted_gain(np.zeros(3), np.ones(3)) == 1.0
    assert fitted_gain(model, -model) == 0.0


def test_a_signal_through_the_curve_has_each_line_scaled_by_the_curve_there():
    fs, n = 8000.0, 8000  # 1 Hz bins
    t = np.arange(n) / fs
    freqs = (500.0, 1500.0, 2500.0)
    x = sum(np.cos(2 * np.pi * f * t) for f in freqs)
    nodes, values = np.array([1000.0, 2000.0, 3000.0]), np.array([2.0, 4.0, 1.0])
    y = apply_curve(x, fs, nodes, values)
    amplitude = 2 * np.abs(np.fft.rfft(y)) / n
    assert [amplitude[int(f)] for f in freqs] == pytest.approx([2.0, 3.0, 2.5])
