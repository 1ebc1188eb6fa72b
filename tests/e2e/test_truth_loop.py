"""compare, validate and discover on records of an independent simulator (tests/truth):
no inverse crime. The base model is GearPair with its stiffness shape (k2, phi2, k4, phi4),
healthy-tooth level a0 and faulty-tooth softening d_f fitted; the simulator's stiffness is
a contact-ratio law in series with the shafts, its faulty tooth a weaker tooth over a
parabolic contact, its speed not constant."""

import json

import numpy as np
import pytest
from conftest import ROOT, run_cli
from truth.gear_sim import TruthGear, pinion_speed_hz, record, simulate_many
from truth_fits import (BASE_PARAMETERS, BEARING, ENVELOPE_BAND, FAST, HIDDEN, OPERATING_POINT,
                        PERIODS, RATE_HZ, RESONANCE_RATE_HZ, RESONANCE_TOP_HZ, STRIKES,
                        assert_one_confident_suggestion, line_margin_db, resonance_clean,
                        resonance_problem, validated)

from pydiag.fit.affine import fit_affine
from pydiag.fit.estimator import FaultEstimator
from pydiag.fit.build import build_problem
from pydiag.gear.effects import EFFECTS
from pydiag.gear.features import FullSpectrumFeaturizer
from pydiag.io.measurements import write_measurement
from pydiag.loop.accumulate import accumulate
from pydiag.loop.compare import compare, refit_with_effect
from pydiag.loop.compose import composed_fmu
from pydiag.loop.discover import discover
from pydiag.loop.effect_fit import EFFECT_REFIT
from pydiag.loop.held_out import held_out
from pydiag.loop.residual import measured_spectra
from pydiag.loop.results import Status
from pydiag.loop.validate import validate

#: The gap the simulator's teeth open at the mesh resonance (truth.RESONANCE).
BACKLASH_M = 5e-6


@pytest.fixture(scope="module")
def resonance_records():
    return {"none": resonance_clean(), "backlash": resonance_clean(BACKLASH_M)}



#: The effects discover tries on the simulator's records (the base has the others).
DISCOVERED = ["gear_eccentricity", "gear_tooth_fault", "second_pinion_tooth_fault",
              "load_fluctuation", "speed_fluctuation", "mesh_stiffness_shape",
              "bearing_outer_race", "bearing_inner_race", "bearing_ball", "housing_sensor",
              "pinion_shaft_orders", "other_shaft_orders", "shaft_swing"]


def assert_discovered_first(found, effect):
    assert "mesh_stiffness_shape" not in [d.effect for d in found]  # already in the model
    assert found[0].effect == effect and found[0].confident, found
    assert all(not d.confident for d in found[1:]), found
    assert np.isfinite(found[0].held_out.delta_bic) and found[0].held_out.delta_bic < 0


#: Hidden effects whose discovery (every catalogue effect tried held out, a bearing's
#: strikes simulated whole) runs in make test-e2e, one of the spectrum's and one of the
#: envelope's; the others' in make test-slow. Every hidden effect is validated on three
#: seeds in make test (tests/evidence). The speed fluctuation's refit frees the base it
#: bent (below); the housing mode's discovery (the costliest: the loop tries every
#: synchronous effect) has its record fitted with a gain curve (below).
DISCOVERED_IN_E2E = ("gear_tooth_fault", "bearing_inner_race")


@pytest.mark.parametrize("effect", [e if e in DISCOVERED_IN_E2E else
                                    pytest.param(e, marks=pytest.mark.slow)
                                    for e in sorted(HIDDEN)])
def test_compare_and_discover_find_the_hidden_effect(gear_fmu, truth_records, effect_fmu_of,
                                                     tmp_path, effect, effects_dir):
    """Seed 5: discover ranks the hidden effect first and alone, and compare's validation,
    given discover's held-out verdicts on the same comparison (the same fits it would
    make), makes it the one confident suggestion."""
    m = record(TruthGear(), PERIODS, 5, RATE_HZ, clean=truth_records[effect])
    problem = build_problem(str(gear_fmu), m, parameters=BASE_PARAMETERS,
                            operating_point=OPERATING_POINT)
    c = compare(problem, FaultEstimator(**FAST))
    base, found = discover(problem, effects=DISCOVERED, modelica_root=ROOT / "modelica",
                           build_dir=effects_dir, base=c)
    assert base is c
    assert_discovered_first(found, effect)
    tried = {d.effect: d.held_out for d in found if d.held_out is not None}
    assert_one_confident_suggestion(validate(problem, c, effect_fmu_of, tried=tried), effect)


@pytest.mark.slow
def test_a_shafts_orders_are_found_where_every_one_is_the_other_shafts_too(gear_fmu,
                                                                           effect_fmu_of):
    """14/42 teeth: every pinion order is a gear order (the PHM09 box's 32/96 stage is
    such a pair), so which shaft makes a line there the spectrum alone does not say. The
    simulator's misaligned coupling (1x-3x of the pinion's angle) stands out of the gear's
    orders around it and is the one confident suggestion; without it nothing is."""
    op = {**OPERATING_POINT, "n_pinion": 14, "n_gear": 42}
    for coupling in (3.0, 0.0):
        g = TruthGear(n_gear=42).with_effects(coupling_acc=coupling)
        m = record(g, PERIODS, 5, RATE_HZ, clean=simulate_many([g], PERIODS * g.period_s,
                                                                RATE_HZ)[0])
        problem = build_problem(str(gear_fmu), m, parameters=BASE_PARAMETERS,
                                operating_point=op)
        c = validate(problem, compare(problem, FaultEstimator(**FAST)), effect_fmu_of)
        confident = [s.effect for s in c.suggested_effects if s.confident]
        assert confident == (["pinion_shaft_orders"] if coupling else []), \
            [(s.effect, round(s.score, 2), s.message) for s in c.suggested_effects]


@pytest.mark.slow
@pytest.mark.parametrize("seed", [5, 6])
def test_a_tilted_gear_is_found_and_a_runout_is_not_taken_for_one(gear_fmu, truth_records,
                                                                   effect_fmu_of, seed):
    """The stiffness modulated once per gear turn lowers the held-out error of a tilted
    gear's record far beyond noise and explains its lines; on a runout's record it is not
    confirmed: the modulation cannot make a runout's transmission error."""
    modulation = EFFECTS["mesh_modulation"]
    verdicts = {}
    for record_of in ("tilt", "gear_eccentricity"):
        m = record(TruthGear(), PERIODS, seed, RATE_HZ, clean=truth_records[record_of])
        problem = build_problem(str(gear_fmu), m, parameters=BASE_PARAMETERS,
                                operating_point=OPERATING_POINT)
        verdicts[record_of] = held_out(problem, compare(problem, FaultEstimator(**FAST)),
                                       modulation, effect_fmu_of(modulation))
    tilt, runout = verdicts["tilt"], verdicts["gear_eccentricity"]
    assert tilt.z > 20 and tilt.explained > 0.5 and tilt.error_effect < tilt.error_base, tilt
    assert runout.z < runout.threshold and not runout.confirmed, runout


@pytest.mark.slow
def test_the_backlash_lines_stand_above_the_noise_at_the_mesh_resonance(resonance_records):
    margins = [line_margin_db(resonance_records["backlash"][channel],
                              resonance_records["none"][channel], 10.0, RESONANCE_RATE_HZ,
                              RESONANCE_TOP_HZ)[1] for channel in ("acc", "disp")]
    print(f"backlash at the mesh resonance: {margins[0]:.1f} dB (acc), {margins[1]:.1f} dB "
          "(disp) over the noise")
    assert max(margins) > 20


@pytest.mark.slow
@pytest.mark.parametrize("seed", [5, 6, 7])
@pytest.mark.parametrize("hidden", ["none", "backlash"])
def test_backlash_at_the_mesh_resonance_is_the_one_confident_suggestion(
        gear_fmu, resonance_records, effect_fmu_of, hidden, seed):
    """A gap the teeth open at the mesh resonance: backlash, and only it, confident; the
    same machine without a gap: nothing confident. (make test-slow: 6 records of 2 s.)"""
    problem = resonance_problem(gear_fmu, resonance_records[hidden], seed)
    c = validate(problem, compare(problem, FaultEstimator(**FAST)), effect_fmu_of)
    confident = [s.effect for s in c.suggested_effects if s.confident]
    assert confident == ([] if hidden == "none" else ["backlash"]), \
        [(s.effect, round(s.score, 2), s.message) for s in c.suggested_effects]


@pytest.mark.slow
@pytest.mark.parametrize("seed", [5, 6, 7])
def test_discover_ranks_backlash_first_at_the_mesh_resonance(gear_fmu, resonance_records,
                                                             tmp_path, seed, effects_dir):
    """Among backlash and the effects whose lines it shares."""
    problem = resonance_problem(gear_fmu, resonance_records["backlash"], seed)
    _, found = discover(problem, FaultEstimator(**FAST),
                        effects=["backlash", "gear_eccentricity", "gear_tooth_fault",
                                 "second_pinion_tooth_fault", "housing_sensor",
                                 "load_fluctuation", "speed_fluctuation"],
                        modelica_root=ROOT / "modelica", build_dir=effects_dir)
    assert found[0].effect == "backlash" and found[0].confident, found
    assert all(not d.confident for d in found[1:]), found


@pytest.mark.slow
@pytest.mark.parametrize("seed", [6, 7])
@pytest.mark.parametrize("effect", sorted(HIDDEN))
def test_discover_ranks_the_hidden_effect_first(gear_fmu, truth_records, tmp_path, effect,
                                                seed, effects_dir):
    """Seeds 6 and 7 in `make test-slow` (seed 5 in `make test`, with compare, above)."""
    m = record(TruthGear(), PERIODS, seed, RATE_HZ, clean=truth_records[effect])
    problem = build_problem(str(gear_fmu), m, parameters=BASE_PARAMETERS,
                            operating_point=OPERATING_POINT)
    _, found = discover(problem, FaultEstimator(**FAST), effects=DISCOVERED,
                        modelica_root=ROOT / "modelica", build_dir=effects_dir)
    assert_discovered_first(found, effect)


def test_without_the_other_shafts_ratio_its_lines_are_not_kinematic_and_nothing_is_confident(
        gear_fmu, truth_records, effect_fmu_of):
    """The motor shaft's record, its speed ratio not given: its lines are named as lines no
    shaft of the pair explains, no effect is confident on them (the torque ripple's and
    the speed fluctuation's signatures do not predict lines there), and the other shaft's
    effect says what it lacks."""
    motor_hz = TruthGear().effects.other_shaft_ratio * TruthGear().f_pinion_hz
    for seed in (5, 6, 7):
        c = validated(gear_fmu, truth_records["other_shaft_orders"], seed, effect_fmu_of,
                      operating_point={"bearing": BEARING})
        assert not [s for s in c.suggested_effects if s.confident], \
            [(s.effect, s.message) for s in c.suggested_effects]
        at_motor = [p for p in c.peaks if p.channel == "acc"
                    and abs(p.freq_hz / motor_hz - round(p.freq_hz / motor_hz)) * motor_hz
                    <= c.bin_hz and 1 <= round(p.freq_hz / motor_hz) <= 3]
        assert at_motor and all(p.family == "unexplained" and "not kinematic" in p.label
                                for p in at_motor), at_motor
        other = next(s for s in c.suggested_effects if s.effect == "other_shaft_orders")
        assert other.message == ("not tried: its lines are not known without the other "
                                 "shaft's speed ratio"), other.message
        assert c.residual_by_family["acc"]["non_kinematic"]["residual"] > 0.05, \
            c.residual_by_family["acc"]
    # discover's way in (held out, whatever compare said): not fitted, its FMU not built
    problem = build_problem(str(gear_fmu), record(TruthGear(), PERIODS, 7, RATE_HZ,
                                                  clean=truth_records["other_shaft_orders"]),
                            parameters=BASE_PARAMETERS, operating_point={"bearing": BEARING})
    h = held_out(problem, c, EFFECTS["other_shaft_orders"], lambda: pytest.fail("built"))
    assert not h.tried and h.message == other.message, h.message


@pytest.mark.slow
def test_a_strong_torque_ripple_is_named_with_its_swing_and_its_form(gear_fmu, effects_dir):
    """A 30 % torque ripple at 0.37x the pinion's speed, on a motor's rotor (0.1 kg m2,
    behind a flexible coupling) whose inertia holds the speed's swing to under 2 %: the
    load's damping modulates the mesh force too, which the catalogue's forms do not make
    beside a swing. Not missed: discover ranks the speed's fluctuation first, with the
    swing's size and frequency, and a verdict that says whether its form explains the
    lines (bench/RESULTS.md section 11)."""
    g = TruthGear(rotor_inertia_kg_m2=0.1).with_effects(torque_ripple=0.3,
                                                       ripple_hz=0.37 * TruthGear().f_pinion_hz)
    m = record(g, PERIODS, 5, RATE_HZ)
    speed = pinion_speed_hz(g, PERIODS * g.period_s, RATE_HZ)
    swing = (speed.max() - speed.min()) / 2 / speed.mean()
    assert 0.005 < swing < 0.02, swing  # a drive train's swing, not a stalling pinion's
    problem = build_problem(str(gear_fmu), m, parameters=BASE_PARAMETERS,
                            operating_point=OPERATING_POINT)
    _, found = discover(problem, FaultEstimator(**FAST), effects=DISCOVERED,
                        modelica_root=ROOT / "modelica", build_dir=effects_dir)
    top = found[0]
    assert top.effect == "speed_fluctuation", found
    fitted = top.held_out.parameters
    assert fitted["ds"] == pytest.approx(swing, rel=0.1), (fitted, swing)
    assert fitted["f_speed"] == pytest.approx(g.effects.ripple_hz, abs=m.duration_s ** -1)
    assert top.confident or top.status is Status.PARTIAL, top.message
    assert top.confident or "form" in top.message, top.message


def test_compare_with_a_speed_fluctuation_frees_the_base_it_bent(gear_fmu, truth_records,
                                                                 effect_fmu_of):
    """The base fit of the ripple's record, without the effect, is bent (the faulty
    tooth's d_f and f_f near 0 to make up for the lines the speed fluctuation moved);
    compare with the effect (``compare --effect``) frees the base parameters with it and
    explains the record. The ripple's discovery held out with the base freed the same way
    (test_compare_and_discover_find_the_hidden_effect) is in make test-slow."""
    m = record(TruthGear(), PERIODS, 5, RATE_HZ, clean=truth_records["speed_fluctuation"])
    problem = build_problem(str(gear_fmu), m, parameters=BASE_PARAMETERS,
                            operating_point={"bearing": BEARING})
    base = compare(problem, FaultEstimator(**FAST))
    effect = EFFECTS["speed_fluctuation"]
    c = refit_with_effect(problem, base, effect, effect_fmu_of(effect))
    assert c.error < 0.2 * base.error, (base.error, c.error)
    assert not [p for p in c.peaks if p.family == "unexplained"], c.peaks
    assert c.parameters["d_f"] > base.parameters["d_f"] + 0.05, (base.parameters, c.parameters)


def test_an_affine_strike_amplitude_is_fitted_from_two_simulations(gear_fmu, truth_records,
                                                                   effect_fmu_of):
    """The outer race's strike amplitude enters acc linearly: its fit from two simulations
    (fit_affine) finds what the swarm and polish find, at an error no larger."""
    m = record(TruthGear(), PERIODS, 5, RATE_HZ, clean=truth_records["bearing_outer_race"])
    problem = build_problem(str(gear_fmu), m, parameters=BASE_PARAMETERS,
                            operating_point={"bearing": BEARING})
    base = compare(problem, FaultEstimator(**FAST))
    effect = EFFECTS["bearing_outer_race"]
    assert effect.affine
    envelope = FullSpectrumFeaturizer(problem.kinematics, base.n_periods,
                                      problem.featurizer.max_freq_hz,
                                      envelope_band_hz=ENVELOPE_BAND)  # as held out scores it
    held = problem.derive(fmu_path=effect_fmu_of(effect), parameters=effect.parameters,
                          fixed_values=problem.fmu_values(base.parameters),
                          featurizer=measured_spectra(problem, 0.01, featurizer=envelope).featurizer,
                          fixed_gains=base.gains)
    fit = fit_affine(held)
    fitted, error = fit.values, fit.error
    swarm = FaultEstimator(**EFFECT_REFIT).fit(held)
    assert fitted["A_b"] == pytest.approx(swarm.parameters["A_b"], rel=0.01), (fitted, swarm)
    assert error <= swarm.error * (1 + 1e-6)
    assert effect.parameters[0].low < fitted["A_b"] < effect.parameters[0].high


def test_cli_compare_shows_a_bearing_confirmed_on_the_envelope(gear_fmu, truth_records,
                                                              tmp_path, effects_dir):
    """The command line, whose base fit is GearPair's paper parameters with a channel gain
    (bent here: the gain is 0.09): the outer race is confirmed on the envelope, with that
    gain held, and says so in the text, the JSON and the report; its strike, at the
    measurement's level, is the simulator's."""
    meas = tmp_path / "m.csv"
    write_measurement(meas, record(TruthGear(), PERIODS, 5, RATE_HZ,
                                   clean=truth_records["bearing_outer_race"]))
    out, page = tmp_path / "c.json", tmp_path / "r.html"
    res = run_cli("-m", "pydiag", "compare", "--fmu", str(gear_fmu), "--measurement", str(meas),
                  "--bearing", "9,7.94,39.04", "--json", str(out), "--report", str(page),
                  "--history", str(tmp_path / "h.sqlite"), "--particles", "10",
                  "--iterations", "8", "--polish", "100", "--quiet",
                  "--build-dir", str(effects_dir))
    assert res.returncode == 0, res.stderr
    line = next(ln for ln in res.stdout.splitlines() if "bearing_outer_race" in ln)
    assert "CONFIDENT, confirmed held out" in line and "envelope" in line, line
    data = json.loads(out.read_text())
    found = {s["effect"]: s for s in data["suggested_effects"]}
    assert [k for k, s in found.items() if s["confident"]] == ["bearing_outer_race"], found
    held = found["bearing_outer_race"]["held_out"]
    assert held["envelope_band_hz"] == pytest.approx(ENVELOPE_BAND, rel=1e-4)  # order-tracked
    strike = held["parameters"]["A_b"] * data["gains"]["acc"]  # m/s2 at the sensor
    assert 40 < strike < 90, strike  # the simulator's: 60 m/s2 through another resonance
    assert "confident: confirmed held out" in page.read_text()


@pytest.mark.slow
@pytest.mark.parametrize("validate_after", [False, True])
def test_cli_loop_adds_the_other_shaft_and_the_error_falls(gear_fmu, truth_records,
                                                           effect_fmu_of, tmp_path, effects_dir,
                                                           validate_after):
    """The loop on the command line, on the motor shaft's record: compare, told the motor
    shaft's ratio (--other-shaft 29/17), names its lines and makes other_shaft_orders the
    one confident suggestion; compare of its model (--effect) fits its orders at the
    simulator's amplitudes, the error falls and the history shows it. With
    ``validate_after`` that second compare validates what is left too, and nothing is
    confident: the housing tried on a model whose lines are not all synchronous simulates
    the whole record at every step of its fits (a minute on 2 cores). Both in make
    test-slow; make test-e2e runs the loop on the command line and in the library
    (test_cli_loop_stops_at_its_step_limit..., test_two_hidden_effects...)."""
    meas, db = tmp_path / "m.csv", tmp_path / "h.sqlite"
    write_measurement(meas, record(TruthGear(), PERIODS, 5, RATE_HZ,
                                   clean=truth_records["other_shaft_orders"]))
    common = ["--measurement", str(meas), "--other-shaft", "29/17", "--history", str(db),
              "--particles", "10", "--iterations", "8", "--polish", "100", "--quiet",
              "--build-dir", str(effects_dir)]
    res = run_cli("-m", "pydiag", "compare", "--fmu", str(gear_fmu), "--json",
                  str(tmp_path / "base.json"), *common)
    assert res.returncode == 0, res.stderr
    base = json.loads((tmp_path / "base.json").read_text())
    assert [s["effect"] for s in base["suggested_effects"] if s["confident"]] \
        == ["other_shaft_orders"], base["suggested_effects"]
    assert "2x other shaft" in [p["label"] for p in base["peaks"]]
    assert base["residual_by_family"]["acc"]["other_shaft_orders"]["residual"] > 0.1
    effect_model = effect_fmu_of(EFFECTS["other_shaft_orders"])
    res = run_cli("-m", "pydiag", "compare", "--fmu", effect_model, "--effect",
                  "other_shaft_orders", "--json", str(tmp_path / "with.json"), *common,
                  *([] if validate_after else ["--no-validate"]))
    assert res.returncode == 0, res.stderr
    with_it = json.loads((tmp_path / "with.json").read_text())
    assert with_it["error"] < 0.7 * base["error"], (base["error"], with_it["error"])
    shares = with_it["residual_by_family"]["acc"]["other_shaft_orders"]["residual"]
    assert shares < 0.1 * base["residual_by_family"]["acc"]["other_shaft_orders"]["residual"]
    gain = with_it["gains"]["acc"]
    truth = 3.0 * np.array([0.5, 1.0, 0.25])  # the simulator's 1x-3x, m/s2 at the sensor
    fitted = gain * np.array([with_it["parameters"][f"A_o{k}"] for k in (1, 2, 3)])
    # 1x and 2x within 10 %; 3x, at a quarter of 2x, 0.75 m/s2 against the record's noise,
    # within half (measured: 1.46, 2.93, 0.60 on seed 5)
    assert fitted[:2] == pytest.approx(truth[:2], rel=0.1), fitted
    assert 0.5 * truth[2] < fitted[2] < 1.5 * truth[2], fitted
    if validate_after:
        assert not [s for s in with_it["suggested_effects"] if s["confident"]]
    res = run_cli("-m", "pydiag", "history", "--history", str(db))
    assert res.returncode == 0, res.stderr
    runs = [ln.split() for ln in res.stdout.splitlines()[1:]]
    assert [r[2] for r in runs] == ["GearPair", "OtherShaftOrders"]
    assert float(runs[1][4]) < float(runs[0][4])


def test_two_hidden_effects_are_found_one_after_the_other(gear_fmu, truth_records,
                                                         effect_fmu_of, tmp_path):
    """A gear runout and the motor shaft's orders in one record: the loop accepts the
    runout (the most confident), fits it, then finds the motor shaft confident on the
    model of both (written from the two effects' files), accepts it, and nothing is
    confident after; the error falls at each step."""
    m = record(TruthGear(), PERIODS, 5, RATE_HZ, clean=truth_records["two"])
    problem = build_problem(str(gear_fmu), m, parameters=BASE_PARAMETERS, operating_point={
        **OPERATING_POINT, "other_shaft_ratio": TruthGear().effects.other_shaft_ratio})
    steps, final = accumulate(problem, effect_fmu_of,
                              lambda keys: str(composed_fmu(keys, ROOT / "modelica", tmp_path)),
                              estimator=FaultEstimator(**FAST))
    assert [s.accepted for s in steps] == ["gear_eccentricity", "other_shaft_orders", None], \
        [(s.accepted, s.error) for s in steps]
    assert steps[2].effects == ("gear_eccentricity", "other_shaft_orders")
    assert "GearPairWith" in str(final.spec.fmu_path)
    assert not [s for s in steps[2].comparison.suggested_effects if s.confident]
    assert steps[0].error > steps[1].error > steps[2].error, [s.error for s in steps]
    assert all(s.held_out_error_with < s.held_out_error_base for s in steps[:2])
    assert steps[2].comparison.parameters["ecc_gear"] == pytest.approx(10e-6, rel=0.2)


def test_the_loop_on_a_machine_of_one_stage_finds_a_runout_then_a_ripple(truth_records,
                                                                         tmp_path):
    """`pydiag loop --machine pair.toml` without --fmu, the pair as a machine of one stage
    (no sensors described: the record's acc and disp channels are the model's outputs of
    those names, one gain each), on a record with a gear runout and a torque ripple: the
    runout is accepted first, held out error falling, then the ripple (a speed
    fluctuation: the simulator's ripple moves the shafts' speed) is confident on the model
    with the runout, its held-out error falling again; the fit with the runout is
    below the base's (its line in the displacement lies below every feature band: the
    effect is fitted on the bins the comparison scores)."""
    meas, machine, out = tmp_path / "m.csv", tmp_path / "pair.toml", tmp_path / "loop.json"
    write_measurement(meas, record(TruthGear(), PERIODS, 5, RATE_HZ,
                                   clean=truth_records["runout_ripple"]))
    machine.write_text('name = "pair"\ninput_rpm = 1500\n[[stages]]\npinion_teeth = 14\n'
                       'gear_teeth = 21\n')
    res = run_cli("-m", "pydiag", "loop", "--machine", str(machine), "--measurement",
                  str(meas), "--max-steps", "2", "--json", str(out), "--quiet",
                  "--build-dir", str(tmp_path / "fmus"), "--history", str(tmp_path / "h.sqlite"))
    assert res.returncode == 0, res.stderr
    first, second = json.loads(out.read_text())["steps"]
    assert first["effect"] == "gear_eccentricity on stage 1", first
    assert first["held_out_error_with"] < 0.8 * first["held_out_error_base"]
    assert second["error"] < 0.8 * first["error"]
    ripple = [s for s in second["suggested_effects"] if s["confident"]]
    assert [s["effect"] for s in ripple] == ["speed_fluctuation"], second["suggested_effects"]
    held = ripple[0]["held_out"]
    assert held["error_effect"] < 0.7 * held["error_base"]
    assert held["parameters"]["stage_1.f_speed"] == pytest.approx(
        TruthGear().effects.ripple_hz, abs=0.1)
    assert "stopped at the step limit, confident: speed_fluctuation on stage 1" in res.stdout


#: The simulator's pair as a machine file that places the pinion's bearing (a 6205, the
#: simulator's geometry): a bearing's lines are the machine's, so a stage's model has them.
PAIR_WITH_BEARING = ('name = "pair (its bearing placed)"\ninput_rpm = 1500\n'
                     'shafts = ["pinion", "gear"]\n[[stages]]\npinion_teeth = 14\n'
                     'gear_teeth = 21\n[[bearings]]\nname = "pinion bearing"\n'
                     'shaft = "pinion"\nn_balls = 9\nball_diameter_mm = 7.94\n'
                     'pitch_diameter_mm = 39.04\n')


@pytest.fixture(scope="module")
def machines_dir(tmp_path_factory):
    """Where the machines' models these tests write are built: once for every test of a
    worker that writes the same one."""
    return tmp_path_factory.mktemp("machines")


@pytest.mark.parametrize("hidden", ["bearing_outer_race", "none", pytest.param(
    "bearing_inner_race", marks=pytest.mark.slow)])  # the pair path checks it on three seeds
def test_a_bearing_the_machine_file_places_is_judged_by_the_machines_model(
        truth_records, tmp_path, machines_dir, hidden):
    """`pydiag discover --machine` without --fmu, the pair as a machine of one stage with its
    pinion's bearing: the simulator's race defect (pulses with random slip through a mode
    of its own) is confident on the stage, on the envelope, and the other race is not; on
    the healthy record neither is."""
    meas, machine, out = tmp_path / "m.csv", tmp_path / "pair.toml", tmp_path / "d.json"
    write_measurement(meas, record(TruthGear(), PERIODS, 5, RATE_HZ,
                                   clean=truth_records[hidden]))
    machine.write_text(PAIR_WITH_BEARING)
    res = run_cli("-m", "pydiag", "discover", "--machine", str(machine), "--measurement",
                  str(meas), "--effects", ",".join(STRIKES), "--json", str(out), "--quiet",
                  "--particles", "10", "--iterations", "8", "--polish", "100",
                  "--build-dir", str(machines_dir))
    assert res.returncode == 0, res.stderr
    rows = {r["effect"]: r for r in json.loads(out.read_text())["ranking"]}
    assert set(rows) == set(STRIKES) and {r["stage"] for r in rows.values()} == {"stage 1"}
    confident = [key for key, r in rows.items() if r["confident"]]
    assert confident == ([] if hidden == "none" else [hidden]), rows
    if hidden != "none":
        assert "envelope" in rows[hidden]["message"], rows[hidden]


def test_cli_loop_stops_at_its_step_limit_and_says_what_was_confident(gear_fmu,
                                                                      truth_records,
                                                                      tmp_path):
    """pydiag loop, one comparison allowed: the runout is confident on the two-effect
    record, not accepted, and the line and the JSON say so."""
    meas, out = tmp_path / "m.csv", tmp_path / "loop.json"
    write_measurement(meas, record(TruthGear(), PERIODS, 5, RATE_HZ,
                                   clean=truth_records["two"]))
    res = run_cli("-m", "pydiag", "loop", "--fmu", str(gear_fmu), "--measurement", str(meas),
                  "--other-shaft", "29/17", "--gain", "fixed", "--max-steps", "1", "--json",
                  str(out), "--particles", "4", "--iterations", "3", "--polish", "20",
                  "--quiet", "--build-dir", str(tmp_path / "fmus"), "--history",
                  str(tmp_path / "h.sqlite"))
    assert res.returncode == 0, res.stderr
    assert "step 1: base: error" in res.stdout
    assert f"recorded as run 1 in {tmp_path / 'h.sqlite'}" in res.stdout
    assert "stopped at the step limit, confident: gear_eccentricity (z " in res.stdout, \
        res.stdout  # the most confident first
    data = json.loads(out.read_text())
    assert [s["effect"] for s in data["steps"]] == [None]
    assert data["model_fmu"] == str(gear_fmu)


def test_a_gain_curve_takes_the_housing_mode_one_gain_cannot(gear_fmu, truth_records):
    """The simulator's accelerometer behind a housing mode at 2.5 kHz (between the first
    and second mesh harmonics): one gain a channel leaves the mode's shape over the band
    in the error; a gain curve with a node at every mesh harmonic takes it, and the error
    of the mesh harmonics, which the mode sets, with it."""
    m = record(TruthGear(), PERIODS, 5, RATE_HZ, clean=truth_records["housing_sensor"])
    found = {}
    for curve in (False, True):
        problem = build_problem(str(gear_fmu), m, parameters=BASE_PARAMETERS,
                                operating_point=OPERATING_POINT, fit_gain=True,
                                gain_curve=curve)
        found[curve] = compare(problem, FaultEstimator(**FAST))
    one, curve = found[False], found[True]
    assert curve.error < 0.6 * one.error, (one.error, curve.error)
    mesh = [c.residual_by_family["acc"]["mesh_harmonics"]["error"] * c.error ** 2
            for c in (one, curve)]
    assert mesh[1] < 0.5 * mesh[0], mesh
    assert set(curve.gains) == {"acc", "disp"} and all(g > 0 for g in curve.gains.values())
