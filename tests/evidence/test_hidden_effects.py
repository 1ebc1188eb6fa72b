"""The claim the loop rests on, checked on records it did not make (tests/truth, the
independent simulator): every hidden effect of the catalogue's that the simulator writes
its own way stands out of the noise, and compare's validation makes it the one confident
suggestion on three noise seeds; without a hidden effect nothing is confident on the same
three. This is make test's evidence tier: the commands end to end are in tests/e2e."""

import pytest
from truth.gear_sim import TruthGear, record
from truth_fits import (ENVELOPE_BAND, HIDDEN, PERIODS, RATE_HZ, SEEDS, STRIKES,
                        assert_one_confident_suggestion, envelope_margin_db, line_margin_db,
                        validated)


@pytest.mark.parametrize("effect", sorted(STRIKES))
def test_bearing_lines_stand_above_the_noise_in_the_envelope(truth_records, effect):
    strikes = [k * STRIKES[effect] for k in (1, 2, 3)]
    margins = {}
    for key in (effect, "none"):
        m = record(TruthGear(), PERIODS, 5, RATE_HZ, clean=truth_records[key])
        margins[key] = envelope_margin_db(m.channels["acc"], RATE_HZ, ENVELOPE_BAND, strikes)
        print(f"{key}: envelope line at {margins[key][0]:.1f} Hz, {margins[key][1]:.1f} dB over "
              "its noise")
    assert margins[effect][1] > 20 and margins["none"][1] < 12


@pytest.mark.parametrize("effect", sorted(set(HIDDEN) - set(STRIKES)))
def test_hidden_lines_stand_above_the_noise(truth_records, effect):
    margins = []
    for channel in ("acc", "disp"):
        freq, margin = line_margin_db(truth_records[effect][channel],
                                      truth_records["none"][channel], 10.0, RATE_HZ, 1575.0)
        print(f"{effect} {channel}: strongest change at {freq:.1f} Hz, {margin:.1f} dB over "
              "the noise")
        margins.append(margin)
    assert max(margins) > 20


@pytest.mark.parametrize("seed", SEEDS)
def test_no_hidden_effect_no_confident_suggestion(gear_fmu, truth_records, effect_fmu_of, seed):
    c = validated(gear_fmu, truth_records["none"], seed, effect_fmu_of)
    assert not [s for s in c.suggested_effects if s.confident], \
        [(s.effect, s.message) for s in c.suggested_effects]
    assert [s for s in c.suggested_effects if s.held_out]  # the misfit pointed somewhere


@pytest.mark.parametrize("effect, seed", [(e, seed) for e in sorted(HIDDEN) for seed in SEEDS])
def test_hidden_effect_is_the_one_confident_suggestion(gear_fmu, truth_records, effect_fmu_of,
                                                       effect, seed):
    assert_one_confident_suggestion(validated(gear_fmu, truth_records[effect], seed,
                                              effect_fmu_of), effect)
