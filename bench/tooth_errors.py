"""Every tooth of both gears a little off: a tooth-error effect tried held out on real records.

The form `bench/error_budget.py --bounds` says could bring a PHM09 stage near 0.5 held out:
each gear's tooth-by-tooth errors, a Fourier series in its angle of the orders 1..Z/2 that
say all of a sequence of Z teeth (GearDiag.Components.ToothSequence). Two ways into the
pair (``--form``):

- ``lag`` (the default): each tooth a little early or late, the mesh's angle leading by
  both sequences (GearPair's ``t_angle``), coefficients in tooth pitches, +-0.05: a
  pitch error modulates the mesh's phase, sidebands round every mesh harmonic;
- ``displacement``: each tooth a little high or low, added to the pair's transmission
  error (``e_extra``), in m, +-50 um. Slow against the mesh, the teeth's deflection
  follows it (x - e barely changes), so it makes sidebands only through the mesh's
  dynamics;
- ``stiffness``: each tooth a little stiffer or softer, the mesh stiffness scaled by 1 +
  both sequences (as GearDiag.Effects.MeshModulation scales it once a turn), +-0.05;
- ``lag+orders``: ``lag`` and each shaft's own orders 1-10 at the sensor
  (GearDiag.Components.ShaftOrders, as the catalogue's shaft orders), fitted with it and
  claiming those orders too;
- ``lag+stiffness``: ``lag`` and ``stiffness`` at once, each with sequences of its own
  (``k``-prefixed for the stiffness): a modulation of the mesh's phase and of its size at
  the same orders, whose sidebands add on one side of a mesh line and cancel on the other
  (the comb ``spur 2_30hz_High_1`` leaves, heavier below its output mesh: RESULTS 13).

The model is written here and built with the library (``build/bench/<name>.mo``): it is
not in the catalogue. As an effect it is affine in its coefficients (``lag``: near 0,
where :func:`pydiag.fit.affine.fit_affine` linearises it, one simulation a coefficient,
then least squares), and it claims the sidebands of either shaft round every mesh
harmonic (at a shaft's own low orders a tooth's error makes only a small quasi-static
motion).

For each record (each stage of ``examples/phm09_spur.toml`` on its own for PHM09, the
speed from the meshes, as ``error_budget`` takes them; GearPair with the gain curve as
the base): the base fit's error, the
effect held out as the loop tries one (:func:`pydiag.loop.held_out.held_out`: z, the
share of its lines' residual explained, the held-out error base -> with it, the
coefficients at a bound), and the bound of its form from half A's lines
(:func:`error_budget.sequence_bound`, the gain curve's nodes): with the shafts' own orders
tied to the sequence, as the model has them, and free; and each gear's fitted sequence
read back tooth by tooth (half A's fit): the tooth farthest from the others, its value and
how many robust spreads of the others that is (a chipped tooth should stand out), and its
largest orders (a few low ones: the shaft's angle swinging over its turn rather than its
teeth).

Usage:
    .venv/bin/python bench/tooth_errors.py [--form lag|displacement|stiffness|lag+orders|lag+stiffness]
        [--extent X]
        [--orders N]
        [--phm09 ../shared/data/phm09]
        [--records "spur 1_30hz_High_1,spur 2_30hz_High_1"] [--gfd ../shared/data/gfd
        --gfd-records h30hz0,b30hz90]
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from error_budget import (gfd_problems, half_lines, phm09_problems,  # noqa: E402
                          sequence_bound)

from pydiag.core.parameters import Parameter  # noqa: E402
from pydiag.fit.estimator import FaultEstimator  # noqa: E402
from pydiag.fit.gain import curve_nodes  # noqa: E402
from pydiag.gear.effect import Effect  # noqa: E402
from pydiag.loop.compare import compare  # noqa: E402
from pydiag.loop.compose import built_fmu  # noqa: E402
from pydiag.loop.held_out import held_out  # noqa: E402

#: Orders of each gear's series in the model: a gear of up to twice as many teeth.
ORDERS = 48
_ARRAYS = "\n".join(
    f'  parameter Real {c}_{g}[{ORDERS}] = zeros({ORDERS}) "{gear}\'s sequence, {kind} '
    f'coefficients";' for g, gear in (("p", "Pinion"), ("g", "Gear"))
    for c, kind in (("c", "cosine"), ("s", "sine")))
_PARTS = f"""  parameter Real f_wheel(unit="Hz") = f_mesh/Ng "Gear shaft speed";
  GearDiag.Components.ToothSequence pinion_teeth(n = {ORDERS}, f_shaft = f_pinion,
    t_angle = time, c = c_p, s = s_p) "The pinion's teeth";
  GearDiag.Components.ToothSequence wheel_teeth(n = {ORDERS}, f_shaft = f_wheel,
    t_angle = time, c = c_g, s = s_g) "The gear's teeth";"""
#: The forms (module docstring): the model's name, its source, each coefficient's range,
#: its unit and the scale to the FMU's.
FORMS = {
    "lag": ("ToothLagTrial", f"""within GearDiag;
model ToothLagTrial "Each tooth of both gears a little early or late (bench/tooth_errors.py)"
  // the mesh's angle leads by the teeth's sequences, in tooth pitches
  extends GearDiag.GearPair(t_angle = time + (pinion_teeth.e + wheel_teeth.e)/f_mesh);
{_ARRAYS}
{_PARTS}
end ToothLagTrial;
""", 0.05, "pitch", 1.0),
    "displacement": ("ToothErrorsTrial", f"""within GearDiag;
model ToothErrorsTrial "Each tooth of both gears a little high or low (bench/tooth_errors.py)"
  // the teeth's sequences, in m, added to the pair's transmission error
  extends GearDiag.GearPair(e_extra = pinion_teeth.e + wheel_teeth.e);
{_ARRAYS}
{_PARTS}
end ToothErrorsTrial;
""", 50.0, "um", 1e-6),
    "stiffness": ("ToothStiffnessTrial", f"""within GearDiag;
model ToothStiffnessTrial "Each tooth of both gears a little stiffer or softer (bench/tooth_errors.py)"
  // the mesh stiffness (its mean and the wave a*sigma) scaled by 1 + both sequences, as
  // MeshModulation scales it once a turn
  extends GearDiag.GearPair(k_mod = (1 + a*sigma)*(pinion_teeth.e + wheel_teeth.e));
{_ARRAYS}
{_PARTS}
end ToothStiffnessTrial;
""", 0.05, "of the stiffness", 1.0),
    "lag+orders": ("ToothLagOrdersTrial", f"""within GearDiag;
model ToothLagOrdersTrial "Each tooth of both gears a little early or late, and both shafts' own orders (bench/tooth_errors.py)"
  extends GearDiag.GearPair(t_angle = time + (pinion_teeth.e + wheel_teeth.e)/f_mesh,
    acc_sensor = der(v) + pinion_orders.a + wheel_orders.a);
{_ARRAYS}
{_PARTS}
  GearDiag.Components.ShaftOrders pinion_orders(f_shaft = f_pinion, t_angle = time)
    "The pinion shaft's own orders 1-10 at the sensor";
  GearDiag.Components.ShaftOrders wheel_orders(f_shaft = f_wheel, t_angle = time)
    "The gear shaft's own orders 1-10 at the sensor";
end ToothLagOrdersTrial;
""", 0.05, "pitch", 1.0),
}
_STIFFNESS_ARRAYS = _ARRAYS.replace("parameter Real c_", "parameter Real kc_").replace(
    "parameter Real s_", "parameter Real ks_").replace("sequence, ", "stiffness sequence, ")
FORMS["lag+stiffness"] = ("ToothLagStiffnessTrial", f"""within GearDiag;
model ToothLagStiffnessTrial "Each tooth of both gears a little early or late, and a little stiffer or softer (bench/tooth_errors.py)"
  extends GearDiag.GearPair(t_angle = time + (pinion_teeth.e + wheel_teeth.e)/f_mesh,
    k_mod = (1 + a*sigma)*(pinion_stiffness.e + wheel_stiffness.e));
{_ARRAYS}
{_STIFFNESS_ARRAYS}
{_PARTS}
  GearDiag.Components.ToothSequence pinion_stiffness(n = {ORDERS}, f_shaft = f_pinion,
    t_angle = time, c = kc_p, s = ks_p) "The pinion's teeth's stiffness";
  GearDiag.Components.ToothSequence wheel_stiffness(n = {ORDERS}, f_shaft = f_wheel,
    t_angle = time, c = kc_g, s = ks_g) "The gear's teeth's stiffness";
end ToothLagStiffnessTrial;
""", 0.05, "pitch (lag) or of the stiffness", 1.0)
#: The shafts' own orders of ``lag+orders`` (GearDiag.Components.ShaftOrders): their
#: number and each amplitude's range at the sensor, m/s2 (the catalogue's shaft orders').
SHAFT_ORDERS, MAX_ORDER_M_S2 = 10, 5000.0


def effect(form: str, extent: float | None = None, most: int | None = None) -> Effect:
    """The form's effect: its coefficients (in +-``extent``, default the form's; each
    gear's orders up to ``most``, default Z/2), claiming the sidebands of either shaft (and
    with the shafts' orders, those), affine."""
    name, _, default, _, scale = FORMS[form]
    extent = extent or default
    kinds = ("c", "s", "kc", "ks") if form == "lag+stiffness" else ("c", "s")
    coefficients = [(f"{c}_{g}", g, k) for g in "pg" for c in kinds for k in range(1, ORDERS + 1)]
    order = {f"{array}{k}": (g, k) for array, g, k in coefficients}  # name -> gear, order
    parameters = tuple(Parameter(f"{array}{k}", -extent, extent, variable=f"{array}[{k}]",
                                 scale=scale) for array, _, k in coefficients)
    orders = form.endswith("+orders")
    if orders:
        parameters += tuple(Parameter(f"A_{g}{k}", 0.0, MAX_ORDER_M_S2,
                                      variable=f"{shaft}_orders.A_{k}")
                            for g, shaft in (("p", "pinion"), ("g", "wheel"))
                            for k in range(1, SHAFT_ORDERS + 1))

    def orders_of_its_teeth(peaks, bin_hz, kin):  # 1..Z/2 of each gear; the rest stay 0
        if kin is None:
            return {}
        half = {"p": min(kin.n_pinion // 2, most or ORDERS),
                "g": min(kin.n_gear // 2, most or ORDERS)}
        return {name: None for name, (g, k) in order.items() if k > half[g]}

    claimed = ("mesh_sb_pinion", "mesh_sb_gear") + (("pinion", "gear") if orders else ())

    def sidebands(line, freq, kin):  # and with the shafts' orders, those
        return 1.0 if line is not None and line.family in claimed else 0.0
    return Effect(f"tooth_{form}", f"GearDiag.{name}", f"each tooth of both gears ({form})",
                  parameters, sidebands, orders_of_its_teeth, affine=True)


def most_off_tooth(values: dict[str, float], gear: str, teeth: int) -> str:
    """The tooth of ``gear`` ("p" or "g") whose value of the fitted sequence (sampled at each
    tooth's angle, from the model's origin) is farthest from the median of the teeth, and
    by how many robust spreads of the others (1.4826 x their median absolute deviation)."""
    n = np.arange(teeth)
    w = 2 * np.pi * n / teeth
    sequence = sum(values.get(f"c_{gear}{k}", 0.0) * np.cos(k * w)
                   + values.get(f"s_{gear}{k}", 0.0) * np.sin(k * w)
                   for k in range(1, teeth // 2 + 1))
    off = sequence - np.median(sequence)
    worst = int(np.argmax(np.abs(off)))
    rest = np.delete(off, worst)
    spread = 1.4826 * np.median(np.abs(rest - np.median(rest)))
    return f"{worst} ({off[worst]:+.3g}, {abs(off[worst]) / spread:.1f})"


def largest_orders(values: dict[str, float], gear: str, teeth: int, most: int = 3) -> str:
    """The ``most`` orders of ``gear``'s fitted sequence with the largest amplitude
    (``hypot(c_k, s_k)``), and the share of the sequence's power they hold."""
    amplitude = np.array([np.hypot(values.get(f"c_{gear}{k}", 0.0), values.get(f"s_{gear}{k}", 0.0))
                          for k in range(1, teeth // 2 + 1)])
    top = np.argsort(-amplitude)[:most]
    share = np.sum(amplitude[top] ** 2) / max(np.sum(amplitude ** 2), 1e-300)
    return ", ".join(f"{k + 1}: {amplitude[k]:.2g}" for k in top) + f" ({share:.0%})"


def row(name: str, problem, tried_effect: Effect, fmu: str) -> str:
    kin = problem.kinematics
    t0 = time.perf_counter()
    base = compare(problem, FaultEstimator(seed=0))
    tried = held_out(problem, base, tried_effect, fmu)
    seconds = time.perf_counter() - t0
    fitted = len(tried_effect.bounds([], 0.0, kin))
    halves = half_lines(problem)
    nodes = curve_nodes(kin, problem.featurizer.max_freq_hz)
    bounds = " / ".join(f"{halves.on_b(sequence_bound(problem, halves, nodes, free)):.3f}"
                        for free in (False, True)) if halves else "-"
    at_bound = (f"{len(tried.at_bound)} ({', '.join(tried.at_bound[:4])}"
                f"{', ...' if len(tried.at_bound) > 4 else ''})" if tried.at_bound else "0")
    return (f"| {name} | {kin.n_pinion}/{kin.n_gear} | {fitted} | {base.error:.3f} | "
            f"{tried.error_base:.3f} -> {tried.error_effect:.3f} | {tried.z:.1f} | "
            f"{tried.explained:.2f} | {at_bound} | {tried.status.value} | {bounds} | "
            f"{most_off_tooth(tried.parameters, 'p', kin.n_pinion)} | "
            f"{most_off_tooth(tried.parameters, 'g', kin.n_gear)} | "
            f"{largest_orders(tried.parameters, 'p', kin.n_pinion)} | "
            f"{largest_orders(tried.parameters, 'g', kin.n_gear)} | {seconds:.0f} |")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--phm09", type=Path, default=ROOT.parent / "shared" / "data" / "phm09")
    ap.add_argument("--records", default="spur 1_30hz_High_1,spur 2_30hz_High_1")
    ap.add_argument("--gfd", type=Path, help="also the GFD records of this folder")
    ap.add_argument("--gfd-records", default="h30hz0,b30hz90")
    ap.add_argument("--form", choices=list(FORMS), default="lag")
    ap.add_argument("--extent", type=float,
                    help="each coefficient's range, +-this (default: the form's)")
    ap.add_argument("--orders", type=int,
                    help="each gear's orders up to this only (default: Z/2, every tooth)")
    args = ap.parse_args()
    paths = [(phm09_problems, args.phm09 / f"{name}.zip") for name in args.records.split(",")]
    if args.gfd:
        paths += [(gfd_problems, args.gfd / f"{name}.csv.gz")
                  for name in args.gfd_records.split(",")]
    missing = [str(p) for _, p in paths if not p.exists()]
    if missing:
        print(f"tooth_errors: no record {', '.join(missing)}", file=sys.stderr)
        return 2
    t0 = time.perf_counter()
    name, source, extent, unit, _ = FORMS[args.form]
    extent = args.extent or extent
    fmu = built_fmu(name, source, ROOT / "modelica", ROOT / "build" / "bench")
    print(f"{platform.machine()}, Python {platform.python_version()}; {args.form}: "
          f"coefficients in +-{extent:g} {unit}; the model built or found in "
          f"{time.perf_counter() - t0:.1f} s: {fmu.fmu}\n")
    print("| record, stage | teeth | coefficients | error | held out, base -> with it | z | "
          "explained | at a bound | verdict | its form's bound held out, own orders tied / "
          f"free | the pinion's most off tooth ({unit}, spreads) | the gear's | the "
          "pinion's largest orders (share of its sequence's power) | the gear's | s |")
    print("|---" * 15 + "|")
    for problems, path in paths:
        for label, problem in problems(path, gain_curve=True).items():
            print(row(label, problem, effect(args.form, extent, args.orders), str(fmu.fmu)),
                  flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
