"""A gear pair exported directly with CasADi's DaeBuilder (no Modelica, no fmu_build),
with its own variable names: a second exporter for the adapter tests.

Same physics as GearDiag.GearPair, but speed in rpm, teeth as z1/z2, the fault knobs
named tooth_amp / tooth_shape / runout / profile_err, sensors housing_acc / probe_disp,
and the static start written as an explicit parameter the adapter must set.
"""

import contextlib
import os
import shutil
import tempfile
from pathlib import Path

import casadi as ca

ADAPTER = """
[simulation]
warmup_s = 0.05

[kinematics]
n_pinion = {parameter = "z1"}
n_gear = {parameter = "z2"}
f_pinion_hz = {parameter = "rpm", scale = 0.016666666666666666}

[[sensor]]
channel = "acc"
variable = "housing_acc"

[[sensor]]
channel = "disp"
variable = "probe_disp_um"
scale = 1e-6

[[fault_parameter]]
variable = "tooth_amp"
role = "a_f"
low = 0.1
high = 0.9

[[fault_parameter]]
variable = "runout_um"
role = "f_ate"
low = 0.0
high = 1.0
scale = 50.0
"""


def build(out: Path) -> Path:
    import fmpy

    dae = ca.DaeBuilder("VendorGear")
    t = dae.add("time", "independent", "continuous", {})

    def par(name, value, unit=None, desc=None):
        opts = {"start": value}
        if unit:
            opts["unit"] = unit
        if desc:
            opts["description"] = desc
        return dae.add(name, "parameter", "tunable", opts)

    amp_h = par("healthy_amp", 0.1)
    amp_f = par("tooth_amp", 0.1, desc="faulty tooth stiffness amplitude")
    shape = par("tooth_shape", 0.1)
    runout = par("runout_um", 0.0, "um", "pinion runout")
    profile = par("profile_err_um", 0.0, "um")
    z1 = par("z1", 14.0)
    par("z2", 21.0)  # read by the adapter's [kinematics]; the equations use n_ap below
    rpm = par("rpm", 1500.0, "rpm")
    m, k0, c = par("mass", 0.5, "kg"), par("k_mesh", 2e8, "N/m"), par("damping", 1000.0, "N.s/m")
    force = par("load", 50 / 0.03, "N")
    x = dae.add("dx", "local", "continuous", {"start": 0.0, "nominal": 1e-5, "unit": "m",
                                               "description": "deflection minus static"})
    v = dae.add("vel", "local", "continuous", {"start": 0.0, "nominal": 1e-3})
    f_p = rpm / 60
    f_mesh = z1 * f_p
    # lcm(z1, z2)/z1 for the defaults (14, 21): 3 assembly phases
    n_ap = 3.0
    cs = ca.cos(2 * ca.pi * f_mesh * t)
    sigma = cs / ca.sqrt((1 - shape) + shape * cs * cs)
    tooth = ca.fmod(ca.floor(f_mesh * t + 0.25), z1)
    a = ca.if_else(tooth < 0.5, amp_f, amp_h)
    k = k0 * (1 + a * sigma)
    e = 1e-6 * (runout * ca.sin(2 * ca.pi * f_p * t)
                + profile * ca.sin(2 * ca.pi * f_mesh / n_ap * t))
    x_static = force / (k0 * (1 + amp_f))  # start: faulty tooth in mesh, sigma(0) = 1
    acc = (force - c * v - k * (x + x_static - e)) / m
    dae.eq(dae.der(x), v)
    dae.eq(dae.der(v), acc)
    dae.eq(dae.add("housing_acc", "output", "continuous", {"unit": "m/s2"}), acc)
    dae.eq(dae.add("probe_disp_um", "output", "continuous", {"unit": "um"}), 1e6 * (x + x_static))
    out = Path(out).resolve()
    with tempfile.TemporaryDirectory() as work, contextlib.chdir(work):
        files = dae.export_fmu({"no_warning": True, "with_serialization": False})
        md = Path("modelDescription.xml")
        text = md.read_text()
        units = sorted(set(__import__("re").findall(r'unit="([^"]+)"', text)))
        block = "    <UnitDefinitions>\n" + "".join(f'        <Unit name="{u}"/>\n' for u in units)
        md.write_text(text.replace("    <ModelVariables>", block + "    </UnitDefinitions>\n"
                                   "    <ModelVariables>"))
        files = dae.compile_fmu(files, {"include_dirs": [os.path.join(
            os.path.dirname(fmpy.__file__), "c-code")]})
        shutil.move(dae.pack_fmu(files, {"path": "VendorGear.fmu"}), out)
    return out
