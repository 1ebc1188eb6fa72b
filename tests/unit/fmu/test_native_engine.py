"""The compiled Model-Exchange engine agrees with fmpy's simulate_fmu and fails cleanly."""

import numpy as np
import pytest
from conftest import inspected

from fmu_build import build_fmu
from pydiag.core.errors import PlantError
from pydiag.fmu.plant import FmuPlant
from pydiag.gear.paper_cases import TABLE1

SENSORS = ("acc", "disp")
# Both engines converged (rtol 1e-10): sampled signals agree to 2e-4 of their peak
# (measured 9.2e-5, fmpy's share). At its default rtol 1e-6 the native engine stays
# within 1e-4 of that (measured 1.7e-5 and 6.2e-5 in cases 1 and 4).
AGREEMENT = 2e-4
NATIVE_DEFAULT_ACCURACY = 1e-4


@pytest.fixture(scope="module")
def engines(gear_fmu):
    native = FmuPlant(gear_fmu, SENSORS, relative_tolerance=1e-10, engine="native")
    fmpy_ = FmuPlant(gear_fmu, SENSORS, relative_tolerance=1e-10, engine="fmpy")
    yield native, fmpy_
    native.close()
    fmpy_.close()


@pytest.mark.parametrize("case", [TABLE1[0], TABLE1[3], TABLE1[7]], ids=lambda c: f"case{c.number}")
def test_native_equals_fmpy_within_solver_tolerance(engines, case):
    native, fmpy_ = engines
    assert native.engine == "native" and fmpy_.engine == "fmpy"
    a = native.simulate(case.parameters, 0.12, 0.05)
    b = fmpy_.simulate(case.parameters, 0.12, 0.05)
    for i, name in enumerate(SENSORS):
        dev = np.max(np.abs(a[i] - b[i])) / np.max(np.abs(b[i]))
        assert dev < AGREEMENT, f"{name}: {dev:.2e}"


def test_native_default_tolerance_is_accurate(gear_fmu, engines):
    _, fmpy_ = engines
    with FmuPlant(gear_fmu, SENSORS, engine="native") as native:
        assert native.relative_tolerance == 1e-6
        for c in (TABLE1[0], TABLE1[3]):
            a = native.simulate(c.parameters, 0.12, 0.05)
            b = fmpy_.simulate(c.parameters, 0.12, 0.05)
            for i in range(len(SENSORS)):
                assert np.max(np.abs(a[i] - b[i])) / np.max(np.abs(b[i])) < NATIVE_DEFAULT_ACCURACY


def test_native_runs_are_repeatable_and_follow_parameters(gear_fmu):
    with FmuPlant(gear_fmu, SENSORS, engine="native") as plant:
        first = plant.simulate({"a_f": 0.3}, 0.05, 0.0)
        other = plant.simulate({"a_f": 0.6}, 0.05, 0.0)
        again = plant.simulate({"a_f": 0.3}, 0.05, 0.0)
        np.testing.assert_array_equal(first, again)
        assert not np.allclose(first, other)
        # start at the static deflection of the parameters that were set
        assert first[1, 0] == pytest.approx(50 / 0.03 / (2e8 * 1.3), rel=1e-9)


def test_auto_prefers_native_and_agrees_with_forced_fmpy(gear_fmu, tmp_path):
    with FmuPlant(gear_fmu, SENSORS) as plant:
        assert plant.engine == "native"
    mo = tmp_path / "Ev.mo"
    mo.write_text("""model Ev
  Real x(start = 1, fixed = true);
  output Real y;
equation
  der(x) = -x;
  y = x;
end Ev;
""")
    fmu = inspected(build_fmu(mo, "Ev", tmp_path / "Ev.fmu"))
    with FmuPlant(fmu, ("y",), engine="fmpy") as plant:
        assert plant.engine == "fmpy"
        y = plant.simulate({}, 0.5, 0.0)[0]
    with FmuPlant(fmu, ("y",)) as plant:
        assert plant.relative_tolerance == 1e-6
        np.testing.assert_allclose(plant.simulate({}, 0.5, 0.0)[0], y, rtol=0, atol=1e-6)


def test_blow_up_is_a_plant_error(tmp_path):
    mo = tmp_path / "Boom.mo"
    mo.write_text("""model Boom
  parameter Real k = 1;
  Real x(start = 1, fixed = true);
  output Real y;
equation
  der(x) = k*x*x;
  y = x;
end Boom;
""")
    fmu = inspected(build_fmu(mo, "Boom", tmp_path / "Boom.fmu"))
    with FmuPlant(fmu, ("y",), sample_rate_hz=100.0, engine="native") as plant:
        with pytest.raises(PlantError, match="failed"):
            plant.simulate({}, 2.0, 0.0)  # x = 1/(1 - t) blows up at t = 1
        assert plant.simulate({"k": -1.0}, 1.0, 0.0)[0, -1] == pytest.approx(1 / 1.99, rel=1e-5)


# ---------------------------------------------------------------------- events: fall back

def _toy_model(fmi_version: int, event_after_steps: int | None):
    """FMI function pointers of a toy model dx/dt = -x, y = x, in Python (ctypes)."""
    import ctypes as C

    state = {"t": 0.0, "x": 1.0, "steps": 0}
    boolean = C.c_bool if fmi_version == 3 else C.c_int

    def set_time(inst, t):
        state["t"] = t
        return 0

    def set_states(inst, x, n):
        state["x"] = x[0]
        return 0

    def get_derivs(inst, dx, n):
        dx[0] = -state["x"]
        return 0

    def get_outputs(inst, vr, n, values, *n_values):
        values[0] = state["x"]
        return 0

    def completed(inst, no_set_prior, event, terminate):
        state["steps"] += 1
        event[0] = event_after_steps is not None and state["steps"] >= event_after_steps
        terminate[0] = False
        return 0

    get_outputs_type = (C.CFUNCTYPE(C.c_int, C.c_void_p, C.POINTER(C.c_uint32), C.c_size_t,
                                    C.POINTER(C.c_double), C.c_size_t) if fmi_version == 3 else
                        C.CFUNCTYPE(C.c_int, C.c_void_p, C.POINTER(C.c_uint32), C.c_size_t,
                                    C.POINTER(C.c_double)))
    return [
        C.CFUNCTYPE(C.c_int, C.c_void_p, C.c_double)(set_time),
        C.CFUNCTYPE(C.c_int, C.c_void_p, C.POINTER(C.c_double), C.c_size_t)(set_states),
        C.CFUNCTYPE(C.c_int, C.c_void_p, C.POINTER(C.c_double), C.c_size_t)(get_derivs),
        get_outputs_type(get_outputs),
        C.CFUNCTYPE(C.c_int, C.c_void_p, boolean, C.POINTER(boolean), C.POINTER(boolean))(completed),
    ]


@pytest.mark.parametrize("fmi_version", [2, 3])
@pytest.mark.parametrize("event_after_steps", [None, 3])
def test_driver_integrates_and_stops_when_the_fmu_asks_for_an_event(fmi_version,
                                                                   event_after_steps):
    """The C driver with FMI 2 and FMI 3 call signatures: exp(-t) without events; the
    'event' code as soon as CompletedIntegratorStep asks for one."""
    import ctypes as C

    from pydiag.fmu import native_engine as native_me
    callbacks = _toy_model(fmi_version, event_after_steps)
    pointers = [C.cast(f, C.c_void_p).value for f in callbacks]
    x = np.array([1.0])
    out = np.zeros(11)
    refs = (C.c_uint32 * 1)(0)
    n_rhs, n_steps = C.c_long(0), C.c_long(0)
    dptr = C.POINTER(C.c_double)
    rc = native_me.load_driver().pd_integrate(
        1, fmi_version, *pointers, 1, x.ctypes.data_as(dptr), 0.0, 0.0, 0.1, 11, 1, refs,
        out.ctypes.data_as(dptr), 1e-8, 1e-12, 1.0, 100_000, 8, C.byref(n_rhs), C.byref(n_steps),
        0, 0.0, np.zeros(12).ctypes.data_as(dptr), None, 0, C.byref(C.c_double()),
        C.byref(C.c_int()))
    if event_after_steps is None:
        assert rc == 0
        np.testing.assert_allclose(out, np.exp(-0.1 * np.arange(11)), rtol=1e-7)
    else:
        assert rc == native_me.PD_EVENT and n_steps.value == event_after_steps


def test_a_native_tolerance_applies_to_the_native_engine_alone(gear_fmu):
    """``native_tolerance`` (a swarm's plant) loosens the native engine where no
    tolerance is asked for, and nothing else: an asked tolerance wins, and fmpy keeps its
    1e-8 (CVode is off by a quarter of the peak at 1e-6). The looser run really is
    looser: it differs from the default one by more than the default's own error."""
    params = TABLE1[7].parameters
    with FmuPlant(gear_fmu, SENSORS, engine="native", native_tolerance=1e-3) as loose, \
            FmuPlant(gear_fmu, SENSORS, engine="native") as default:
        assert loose.relative_tolerance == 1e-3
        a, b = loose.simulate(params, 0.12, 0.05), default.simulate(params, 0.12, 0.05)
        assert np.max(np.abs(a - b)) > NATIVE_DEFAULT_ACCURACY * np.max(np.abs(b))
    with FmuPlant(gear_fmu, SENSORS, engine="native", relative_tolerance=1e-7,
                  native_tolerance=1e-3) as asked:
        assert asked.relative_tolerance == 1e-7
    with FmuPlant(gear_fmu, SENSORS, engine="fmpy", native_tolerance=1e-3) as fmpy_:
        assert fmpy_.relative_tolerance == 1e-8
    with pytest.raises(PlantError, match="native tolerance must be positive"):
        FmuPlant(gear_fmu, SENSORS, native_tolerance=0.0)


def test_an_fmu_with_events_falls_back_to_fmpy(gear_fmu, monkeypatch):
    """engine auto: the run that meets an event is redone by fmpy, and fmpy (with its own
    default tolerance) serves from then on; engine native: a clear error."""
    from pydiag.fmu import native_engine as native_me

    params = TABLE1[7].parameters
    with FmuPlant(gear_fmu, SENSORS, engine="fmpy") as reference:
        expected = reference.simulate(params, 0.02, 0.01)

    def meets_an_event(self, *args):
        raise native_me.NeedsEvents("the FMU schedules time events")

    monkeypatch.setattr(native_me.NativeMeRunner, "run", meets_an_event)
    with FmuPlant(gear_fmu, SENSORS) as plant:
        assert plant.engine == "native"
        np.testing.assert_array_equal(plant.simulate(params, 0.02, 0.01), expected)
        assert plant.engine == "fmpy" and plant.relative_tolerance == 1e-8
    with FmuPlant(gear_fmu, SENSORS, engine="native") as plant:
        with pytest.raises(PlantError, match="schedules time events.*does not handle events"):
            plant.simulate(params, 0.02, 0.01)


@pytest.mark.parametrize("h_max, returned", [(0.01, True), (1.0, False)])
def test_the_periodicity_check_stops_only_a_run_whose_period_it_sampled_densely(h_max,
                                                                                returned):
    """dx/dt = -x from x = 1, outputs from t = 40 s (the state at rest: e^-40): a period of
    ten outputs (1 s) crossed in 100 steps repeats, and the run stops after it; crossed in
    one or two steps, its forcing is not sampled enough to tell, and the run goes on."""
    import ctypes as C

    from pydiag.fmu import native_engine as native_me
    pointers = [C.cast(f, C.c_void_p).value for f in _toy_model(3, None)]
    x, out = np.array([1.0]), np.zeros(21)
    dptr = C.POINTER(C.c_double)
    mismatch, stopped = C.c_double(), C.c_int()
    rc = native_me.load_driver().pd_integrate(
        1, 3, *pointers, 1, x.ctypes.data_as(dptr), 0.0, 40.0, 0.1, 21, 1, (C.c_uint32 * 1)(0),
        out.ctypes.data_as(dptr), 1e-8, 1e-12, h_max, 100_000, 8, C.byref(C.c_long()),
        C.byref(C.c_long()), 10, 1e-4, np.zeros(12).ctypes.data_as(dptr), None, 0,
        C.byref(mismatch), C.byref(stopped))
    assert rc == 0 and mismatch.value <= 1.0
    assert bool(stopped.value) is returned
