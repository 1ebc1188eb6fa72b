"""The drive train's components (GearDiag.Components, connected through
GearDiag.Interfaces.Flange): built by the bridge, simulated, held to the paper's pair and
to what a coupled gearbox does."""

import fmpy
import numpy as np
import pytest

from fmu_build import build_fmu

PACKAGE = "modelica/GearDiag/package.mo"
FAULT = {"a_f": 0.4, "f_f": 0.5, "d_f": 0.2, "k2": 0.05, "f_ate": 0.3, "f_dte": 0.2}


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    from conftest import ROOT
    folder = tmp_path_factory.mktemp("components")
    return {name: build_fmu(ROOT / PACKAGE, f"GearDiag.{name}", folder / f"{name}.fmu")
            for name in ("GearPair", "Examples.PairOnShafts", "Examples.TwoStageGearbox")}


def _simulate(fmu, values, outputs, stop_s, step_s, rtol):
    return fmpy.simulate_fmu(str(fmu), stop_time=stop_s, output_interval=step_s,
                             relative_tolerance=rtol, start_values=values, output=outputs)


def test_a_mesh_between_a_steady_pinion_and_a_gear_inertia_is_the_paper_pair(built):
    """GearMesh with the pinion at its steady speed, the gear's inertia m*r_g^2 and its
    load T*r_g/r_p is GearPair of mass m: the same acceleration and deflection, with a
    faulty tooth, a stiffness shape and both transmission errors, to the solver's
    tolerance (two builds of GearPair itself differ by about as much)."""
    pair = _simulate(built["GearPair"], FAULT, ["acc", "disp"], 0.2, 1e-4, 1e-8)
    parts = _simulate(built["Examples.PairOnShafts"], {f"mesh.{k}": v for k, v in FAULT.items()},
                      ["acc", "disp"], 0.2, 1e-4, 1e-8)
    for out, tol in (("acc", 2e-3), ("disp", 1e-5)):
        scale = np.max(np.abs(pair[out]))
        assert np.max(np.abs(pair[out] - parts[out])) < tol * scale, out
    # and a different fault is a different signal at that tolerance (the check can fail)
    other = _simulate(built["Examples.PairOnShafts"], {"mesh.a_f": 0.2}, ["acc"], 0.2, 1e-4,
                      1e-8)
    assert np.max(np.abs(pair["acc"] - other["acc"])) > 0.05 * np.max(np.abs(pair["acc"]))


def _line(signal, rate_hz, freq_hz):
    x = signal - np.mean(signal)
    amp = np.abs(np.fft.rfft(x)) * 2 / x.size
    return amp[int(round(freq_hz * x.size / rate_hz))]


def test_the_idler_shaft_couples_the_two_stages(built):
    """The first stage's mesh (960 Hz) reaches the second stage's teeth through the idler
    shaft: with the shaft stiff (2e5 N m/rad) it is a tenth of the second stage's own
    mesh line in that stage's deflection; with the shaft 100 times softer (its mode near
    70 Hz, far below 960 Hz) it is isolated, at least ten times weaker. The second stage
    has 47 teeth here, so that no harmonic of its mesh (470 Hz) falls on the first's."""
    rate = 20_000.0
    ratio = {}
    for k_t in (2e5, 2e3):
        r = _simulate(built["Examples.TwoStageGearbox"], {"idler.k_t": k_t, "mesh2.Np": 47},
                      ["acc", "disp_2"], 0.3, 1 / rate, 1e-6)
        x = r["disp_2"][2000:]  # after 0.1 s: the start's transient gone
        ratio[k_t] = _line(x, rate, 960.0) / _line(x, rate, 470.0)
        # the housing sensor sees both stages' meshes
        acc = r["acc"][2000:]
        assert _line(acc, rate, 960.0) > 10 * _line(acc, rate, 1000.0)
        assert _line(acc, rate, 470.0) > 10 * _line(acc, rate, 500.0)
    assert ratio[2e5] > 0.03
    assert ratio[2e5] > 10 * ratio[2e3]


def test_a_tooth_sequence_is_its_fourier_series_in_the_shafts_angle(tmp_path):
    """GearDiag.Components.ToothSequence (array parameters a model binds element by element)
    makes e = sum_k c[k] cos(k w) + s[k] sin(k w), w the shaft's angle, exactly."""
    from conftest import ROOT
    wrapper = tmp_path / "Wrap.mo"
    wrapper.write_text(
        "model Wrap\n"
        "  parameter Real c[3] = {1e-6, 0, 2e-6};\n"
        "  parameter Real s[3] = {0, 3e-6, 0};\n"
        "  GearDiag.Components.ToothSequence teeth(n = 3, f_shaft = 7.0, t_angle = time,\n"
        "    c = c, s = s);\n"
        "  Real x(start = 0, fixed = true);\n"
        "  output Real e = teeth.e;\n"
        "equation\n"
        "  der(x) = -x;\n"
        "end Wrap;\n")
    fmu = build_fmu(wrapper, "Wrap", tmp_path / "Wrap.fmu",
                    library_roots=(ROOT / "modelica",))
    values = {"c[2]": -1e-6, "s[3]": 0.5e-6}
    r = _simulate(fmu, values, ["e"], 0.3, 1e-3, 1e-6)
    w = 2 * np.pi * 7.0 * r["time"]
    c, s = [1e-6, -1e-6, 2e-6], [0.0, 3e-6, 0.5e-6]
    expected = sum(c[k] * np.cos((k + 1) * w) + s[k] * np.sin((k + 1) * w) for k in range(3))
    assert np.max(np.abs(r["e"] - expected)) < 1e-12
