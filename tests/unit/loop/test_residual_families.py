"""Residual by kinematic family, and what a non-kinematic line could be."""

import numpy as np
import pytest

from pydiag.gear.effects import EFFECTS
from pydiag.gear.kinematic_map import kinematic_map
from pydiag.gear.kinematics import GearKinematics
from pydiag.loop.residual import (RESIDUAL_GROUPS, bin_groups, describe_non_kinematic,
                                 residual_shares)

KIN = GearKinematics(32, 80, 29.84)


def test_every_bin_goes_to_one_group_and_the_shares_are_energy_shares():
    bin_hz = 1 / (4 * KIN.period_s)  # four fundamental periods
    freqs = bin_hz * np.arange(1, 20_000)
    lines = kinematic_map(KIN, freqs[-1])
    measured = np.full(freqs.size, 0.01)
    model = measured.copy()
    at = {f: int(round(f / bin_hz)) - 1 for f in (KIN.f_mesh_hz, KIN.f_mesh_hz - 3 * KIN.f_pinion_hz,
                                                   2 * KIN.f_gear_hz, 123.456)}
    for k in at.values():
        measured[k] = 1.0
    model[at[KIN.f_mesh_hz]] = 1.0  # the model has the mesh line only
    groups = bin_groups(freqs, lines, bin_hz, measured, margin=0.1)
    named = [RESIDUAL_GROUPS[groups[k]] for k in at.values()]
    assert named == ["mesh_harmonics", "pinion_orders", "gear_orders", "non_kinematic"]
    shares = residual_shares(groups, measured, model)
    n_mesh = int(np.sum(groups == RESIDUAL_GROUPS.index("mesh_harmonics")))
    total = 4 + 0.01 ** 2 * (freqs.size - 4)
    assert shares["mesh_harmonics"]["measured"] == pytest.approx((1 + 1e-4 * (n_mesh - 1)) / total)
    assert shares["mesh_harmonics"]["residual"] == 0.0
    # three lines the model lacks, each (1 - 0.01)^2: a third of the residual each
    for group in ("pinion_orders", "gear_orders", "non_kinematic"):
        assert shares[group]["residual"] == pytest.approx(1 / 3)
    assert sum(s["measured"] for s in shares.values()) == pytest.approx(1.0)
    assert "error" not in shares["mesh_harmonics"]  # no bins scored: no share of the error
    # the error's bins: the mesh line, the gear order and a broadband bin; its share of the
    # error is over those alone, with Eq. 12's weights (the missing gear line, 1 - 0.01,
    # against a broadband bin the model has right)
    scored = np.zeros(freqs.size, dtype=bool)
    scored[[at[KIN.f_mesh_hz], at[2 * KIN.f_gear_hz], 5]] = True
    shares = residual_shares(groups, measured, model, scored)
    assert shares["gear_orders"]["error"] == pytest.approx(1.0)
    assert shares["pinion_orders"]["error"] == shares["mesh_harmonics"]["error"] == 0.0
    assert sum(s["error"] for s in shares.values()) == pytest.approx(1.0)


def test_a_non_kinematic_line_is_described_and_claimed_by_no_signature_that_misses_it():
    text = describe_non_kinematic(150.0, KIN, 0.1)
    assert text.startswith("not kinematic: 5.03x pinion, 12.6x gear") and "3x 50 Hz mains" in text
    ripple = EFFECTS["load_fluctuation"].weight
    assert ripple(None, 7.5, KIN) == 1.0  # the ripple itself
    assert ripple(None, KIN.f_mesh_hz + 7.5, KIN) == 1.0  # its mesh sideband
    assert ripple(None, 150.0, KIN) == 0.0  # neither: another source
