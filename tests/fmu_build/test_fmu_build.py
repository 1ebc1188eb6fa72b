"""The Modelica -> FMU bridge: what it builds, and how it refuses what it cannot."""

import textwrap
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import casadi as ca
import fmpy
import numpy as np
import pytest
from conftest import ROOT, inspected, run_cli

from fmu_build import ModelicaBuildError, build_fmu
from fmu_build.build import ode_system
from fmu_build.model_description import add_unit_definitions

FAULT_PARAMETERS = ["a0", "a_f", "f_f", "f_ate", "f_dte"]


def write_model(folder: Path, text: str, name: str = "M.mo") -> Path:
    path = folder / name
    path.write_text(textwrap.dedent(text))
    return path


def test_gear_fmu_validates_and_exposes_tunable_parameters(gear_fmu):
    md = fmpy.read_model_description(str(gear_fmu), validate=True)  # raises on schema problems
    assert md.fmiVersion == "3.0" and md.modelExchange is not None
    variables = {v.name: v for v in md.modelVariables}
    for name in FAULT_PARAMETERS + ["Np", "Ng", "f_pinion", "m", "c", "K", "T", "r_p",
                                    "xi_max", "gamma_max"]:
        assert variables[name].causality == "parameter", name
        assert variables[name].variability == "tunable", name
        assert variables[name].description, name
    assert variables["K"].unit == "N/m" and variables["f_pinion"].unit == "Hz"
    for out in ("acc", "disp", "stiffness", "mesh_force"):
        assert variables[out].causality == "output"
    units = {u.name for u in md.unitDefinitions}
    assert {"N/m", "kg", "Hz", "m/s2"} <= units


def test_gear_fmu_passes_fmpys_full_validation(gear_fmu):
    """Naming convention, initial unknowns (states, calculated parameters), units."""
    from fmpy.validation import validate_fmu
    assert validate_fmu(str(gear_fmu)) == []


def test_derived_parameters_are_calculated_and_follow_the_free_ones(gear_fmu):
    """N_ap, f_mesh, f_fe, x_static are calculated parameters, computed by the FMU's
    parameter stage: right after each reset with new teeth counts, and again when the
    parameters return to earlier values (one instance throughout, as the plant uses it)."""
    md = fmpy.read_model_description(str(gear_fmu))
    variables = {v.name: v for v in md.modelVariables}
    derived = ["N_ap", "f_mesh", "f_fe", "x_static"]
    for name in derived:
        assert variables[name].causality == "calculatedParameter", name
        assert variables[name].start is None, name
    unzipped = fmpy.extract(str(gear_fmu))
    fmu = fmpy.instantiate_fmu(unzipped, md, fmi_type="ModelExchange")
    refs = [variables[n].valueReference for n in derived]
    try:
        for np_, ng, f_pinion, a_f in ((14, 21, 25.0, 0.1), (14, 28, 25.0, 0.1),
                                       (15, 20, 30.0, 0.5), (14, 21, 25.0, 0.1)):
            fmu.reset()
            fmu.enterInitializationMode()
            fmu.setFloat64([variables[n].valueReference for n in ("Np", "Ng", "f_pinion", "a_f")],
                           [np_, ng, f_pinion, a_f])
            fmu.exitInitializationMode()
            n_ap = np.lcm(np_, ng) / np_
            expected = [n_ap, np_ * f_pinion, np_ * f_pinion / n_ap,
                        50 / 0.03 / (2e8 * (1 + a_f))]
            assert fmu.getFloat64(refs) == pytest.approx(expected, rel=1e-12), (np_, ng)
            fmu.terminate()
    finally:
        fmu.freeInstance()


def test_parameter_stage_refuses_a_wrapper_it_does_not_know():
    from fmu_build.parameter_stage import patch_wrapper
    wrapper = "fmi3ValueReference p_vr[N_P] = {1, 2, 3};\nint evaluate(void* m) { return 0; }\n"
    with pytest.raises(ModelicaBuildError, match="anchor of the parameter stage is missing"):
        patch_wrapper(wrapper, "M", 2, [3])
    with pytest.raises(ModelicaBuildError, match="ordered the FMU's parameters unexpectedly"):
        patch_wrapper(wrapper, "M", 1, [3])


def test_start_follows_parameters_static_equilibrium(gear_fmu):
    """x starts at the static deflection, recomputed from the parameters that are set."""
    for a_f, T in ((0.1, 50.0), (0.5, 80.0)):
        res = fmpy.simulate_fmu(str(gear_fmu), stop_time=1e-3, output_interval=1e-4,
                                start_values={"a_f": a_f, "T": T}, output=["disp", "acc"])
        x_static = T / 0.03 / (2e8 * (1 + a_f))  # formWave(0, f_f) = 1 at theta = 0
        assert res["disp"][0] == pytest.approx(x_static, rel=1e-9)
        assert abs(res["acc"][0]) < 1e-6 * 2e8 * x_static / 0.5  # no start-up jolt


def test_functions_with_algorithms_if_and_for_are_inlined(tmp_path):
    mo = write_model(tmp_path, """
        package P
          function gcd
            input Integer a; input Integer b; output Integer g;
          protected
            Integer x; Integer y; Integer r;
          algorithm
            x := a; y := b;
            for i in 1:30 loop
              if y > 0 then r := mod(x, y); x := y; y := r; end if;
            end for;
            g := x;
          end gcd;
          model M
            parameter Integer a = 42;
            parameter Integer b = 30;
            parameter Real g = gcd(a, b);
            Real x(start = 1, fixed = true);
            output Real y;
          equation
            der(x) = -g*x;
            y = if x > 0.5 then 2*x else -x;
          end M;
        end P;
        """)
    system = ode_system(mo, "P.M")
    rhs, out, x0 = system.functions()
    p = ca.DM([q.value for q in system.parameters])
    assert float(rhs(0, 1.0, p)) == pytest.approx(-6.0)  # gcd(42, 30) = 6
    names = [q.name for q in system.parameters]
    p2 = p.full().ravel().copy()
    p2[names.index("a")], p2[names.index("b")] = 35, 21
    assert float(rhs(0, 1.0, p2)) == pytest.approx(-7.0)  # stays a function of the parameters
    assert float(out(0, 0.8, p)) == pytest.approx(1.6)
    assert float(out(0, 0.2, p)) == pytest.approx(-0.2)


def test_implicit_linear_equations_are_solved_jointly(tmp_path):
    mo = write_model(tmp_path, """
        model L
          parameter Real k = 3;
          Real x(start = 2, fixed = true);
          Real a;
          Real b;
          output Real y;
        equation
          a + b = x;
          a - b = k;
          der(x) = -a;
          y = b;
        end L;
        """)
    system = ode_system(mo, "L")
    rhs, out, _ = system.functions()
    # a = (x + k)/2, b = (x - k)/2
    assert float(rhs(0, 2.0, 3.0)) == pytest.approx(-2.5)
    assert float(out(0, 2.0, 3.0)) == pytest.approx(-0.5)


def test_nonlinear_algebraic_loop_is_reported_with_lines(tmp_path):
    mo = write_model(tmp_path, """
        model N
          Real x(start = 1, fixed = true);
          Real z;
        equation
          z*z + z = x;
          der(x) = -z;
        end N;
        """)
    with pytest.raises(ModelicaBuildError, match=r"M\.mo:6: equation is nonlinear in its only unknown z"):
        ode_system(mo, "N")
    mo = write_model(tmp_path, """
        model N2
          Real x(start = 1, fixed = true);
          Real a;
          Real b;
        equation
          a*b = x;
          a + b = 3;
          der(x) = -a;
        end N2;
        """)
    with pytest.raises(ModelicaBuildError, match=r"nonlinear algebraic loop in .*a, b.*M\.mo:7, .*M\.mo:8"):
        ode_system(mo, "N2")


def test_unsupported_construct_names_it_and_its_line(tmp_path):
    mo = write_model(tmp_path, """
        model W
          Real x(start = 1, fixed = true);
        equation
          der(x) = -x;
        algorithm
          when x < 0.5 then
            terminate("done");
          end when;
        end W;
        """)
    with pytest.raises(ModelicaBuildError) as err:
        ode_system(mo, "W")
    assert "not supported" in str(err.value) or "rumoca" in str(err.value)


def test_array_variables_are_refused_with_location(tmp_path):
    mo = write_model(tmp_path, """
        model A
          Real x[2](each start = 1, each fixed = true);
        equation
          der(x) = -x;
        end A;
        """)
    with pytest.raises(ModelicaBuildError,
                       match=r"M\.mo:3: array variable 'x' is not supported \(only one-dim"):
        ode_system(mo, "A")


ARRAY_MODEL = """
    package T
      model Series "A Fourier series whose coefficients are array parameters"
        parameter Integer n = 3;
        parameter Real c[n] = fill(0, n);
        parameter Real s[n] = zeros(n);
        input Real w;
        output Real y;
      equation
        y = sum(c[k]*cos(k*w) + s[k]*sin(k*w) for k in 1:n);
      end Series;
      model A
        parameter Real a[3] = {1, 2, 3};
        parameter Real b[3] = {0, 0.5, 0};
        Series ser(n = 3, c = a, s = b);
        Series unset(n = 2);
        Real x(start = 0, fixed = true);
      equation
        ser.w = time;
        unset.w = time;
        der(x) = -x + ser.y + a[2] + unset.y;
      end A;
    end T;
    """


def test_array_parameters_are_tunable_elements_through_modifications(tmp_path):
    """One-dimensional array parameters become one scalar parameter an element (``a[2]``),
    an element at a literal index and a ``sum`` reduction are expressions of them, and a
    component's array bound to the model's follows it element by element in the FMU."""
    folder = tmp_path / "T"
    folder.mkdir()
    mo = write_model(folder, ARRAY_MODEL, "package.mo")
    system = ode_system(mo, "T.A")
    free = {p.name: p.value for p in system.parameters}
    assert {k: free[k] for k in ("a[1]", "a[2]", "a[3]", "b[2]", "unset.c[2]", "unset.s[1]")} \
        == {"a[1]": 1.0, "a[2]": 2.0, "a[3]": 3.0, "b[2]": 0.5, "unset.c[2]": 0.0,
            "unset.s[1]": 0.0}
    assert {d.name for d in system.derived} == {f"ser.{c}[{k}]" for c in "cs" for k in (1, 2, 3)}
    fmu = build_fmu(mo, "T.A", tmp_path / "A.fmu")

    def x_end(a2: float) -> float:
        return float(fmpy.simulate_fmu(str(fmu), stop_time=2.0, output=["x"], relative_tolerance=1e-9,
                                       start_values={"a[2]": a2})["x"][-1])

    # a[2] enters as itself and through ser.c[2]: dx/dt gains d (1 + cos 2t), so x(2) gains
    # d times the integral of exp(tau - 2) (1 + cos 2 tau) over 0..2
    tau = np.linspace(0.0, 2.0, 200_001)
    gain = np.trapezoid(np.exp(tau - 2.0) * (1.0 + np.cos(2.0 * tau)), tau)
    assert x_end(5.0) - x_end(2.0) == pytest.approx(3.0 * gain, rel=1e-5)


def test_array_parameter_values_it_cannot_expand_are_refused(tmp_path):
    mo = write_model(tmp_path, """
        model B
          parameter Real k = 2;
          parameter Real a[2] = k*{1, 2};
          Real x(start = 0, fixed = true);
        equation
          der(x) = a[1];
        end B;
        """)
    with pytest.raises(ModelicaBuildError, match=r"M\.mo:4: the value of array parameter 'a'"):
        ode_system(mo, "B")


def test_cli_errors_are_one_line_without_traceback(tmp_path):
    mo = write_model(tmp_path, """
        model Bad
          Real x(start = 1, fixed = true);
        equation
          der(x) = -x + undefinedThing;
        end Bad;
        """)
    res = run_cli("-m", "fmu_build", str(mo), "--model", "Bad", "-o", str(tmp_path / "b.fmu"))
    assert res.returncode == 2
    assert "Traceback" not in res.stderr
    assert res.stderr.startswith("fmu_build: error:") and "undefinedThing" in res.stderr
    assert not (tmp_path / "b.fmu").exists()
    res = run_cli("-m", "fmu_build", str(tmp_path / "nope.mo"), "--model", "X", "-o", "x.fmu")
    assert res.returncode == 2 and "no such Modelica file" in res.stderr


def test_unit_definitions_are_inserted_before_variables():
    md = ('<fmiModelDescription>\n    <ModelExchange modelIdentifier="m"/>\n    <ModelVariables>\n'
          '        <Float64 name="k" unit="N/m"/>\n        <Float64 name="x" unit="m"/>\n'
          '    </ModelVariables>\n</fmiModelDescription>\n')
    root = ET.fromstring(add_unit_definitions(md))
    assert [c.tag for c in root] == ["ModelExchange", "UnitDefinitions", "ModelVariables"]
    assert sorted(u.get("name") for u in root.find("UnitDefinitions")) == ["N/m", "m"]


def test_build_writes_only_the_requested_file(tmp_path, modelica_copy):
    out = tmp_path / "out" / "G.fmu"
    inspected(build_fmu(modelica_copy / "GearDiag" / "GearPair.mo", "GearDiag.GearPair", out))
    assert sorted(p.name for p in out.parent.iterdir()) == ["G.fmu"]
    names = zipfile.ZipFile(out).namelist()
    assert "modelDescription.xml" in names and any(n.startswith("binaries/") for n in names)
    res = fmpy.simulate_fmu(str(out), stop_time=1.0, output_interval=1e-4, output=["acc"])
    assert len(res) == 10001 and np.all(np.isfinite(res["acc"]))


def test_builds_in_threads_at_once_each_give_their_own_model(tmp_path):
    """Builds in threads compile side by side (fmu_build.fmu_export.PYTHON_SIDE): each FMU
    is its own model's, and the process's working folder is where it was."""
    from concurrent.futures import ThreadPoolExecutor
    import os

    def source(rate: int) -> Path:
        folder = tmp_path / f"R{rate}"
        folder.mkdir()
        return write_model(folder, f"""
            model R{rate}
              parameter Real k = {rate};
              Real x(start = 1, fixed = true);
              output Real y;
            equation
              der(x) = -k*x;
              y = x;
            end R{rate};
            """)

    here = os.getcwd()
    rates = [1, 2, 3, 4]
    with ThreadPoolExecutor(2) as pool:
        fmus = list(pool.map(lambda r: build_fmu(source(r), f"R{r}", tmp_path / f"R{r}.fmu"),
                             rates))
    assert os.getcwd() == here
    for rate, fmu in zip(rates, fmus):
        y = fmpy.simulate_fmu(str(inspected(fmu)), stop_time=1.0, output=["y"],
                              relative_tolerance=1e-8)["y"][-1]
        assert y == pytest.approx(np.exp(-rate), rel=1e-5)


@pytest.mark.parametrize("delay_s", [0.6, 1.2, 1.8])
def test_two_ctrl_c_during_a_build_leave_nothing_behind(tmp_path, delay_s):
    """A build interrupted twice, the second during the first one's cleanup, leaves no
    scratch folder, no compiler temporary file and no partial FMU (issue 59.15)."""
    import os
    import signal
    import subprocess
    import sys
    import time

    scratch = tmp_path / "tmp"
    scratch.mkdir()
    out = tmp_path / "out" / "Eccentricity.fmu"
    out.parent.mkdir()
    proc = subprocess.Popen(
        [sys.executable, "-m", "fmu_build", str(ROOT / "modelica" / "GearDiag" / "Effects"
                                               / "GearEccentricity.mo"),
         "--model", "GearDiag.Effects.GearEccentricity", "-o", str(out)],
        cwd=ROOT, env={**os.environ, "TMPDIR": str(scratch)},
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(delay_s)
    proc.send_signal(signal.SIGINT)
    time.sleep(0.02)
    proc.send_signal(signal.SIGINT)
    proc.wait(60)
    assert list(scratch.iterdir()) == []
    assert [p.name for p in out.parent.iterdir()] in ([], [out.name])
