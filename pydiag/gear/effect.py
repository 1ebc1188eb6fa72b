"""What a catalogue effect is (:class:`Effect`): its Modelica model, its parameters, the
signature that points to it and what it needs of the machine; the catalogue itself is
:mod:`pydiag.gear.effects`."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from pydiag.core.parameters import Parameter
from pydiag.gear.faults import CHANGED
from pydiag.gear.kinematic_map import KinematicLine
from pydiag.gear.kinematics import GearKinematics
from pydiag.gear.peaks import Peak
from pydiag.signal.ripple import Ripple
from pydiag.signal.transfer import HousingMode


#: The parts of a stage an effect's parameters can size a fault of (``Effect.parts``).
#: The other shaft is the one the other-shaft effect models: in a machine, the shaft
#: :meth:`~pydiag.gear.machine.Machine.other_shaft` names.
PINION, GEAR, MESH, PINION_SHAFT, GEAR_SHAFT, PINION_BEARING, GEAR_BEARING, OTHER_SHAFT = (
    "pinion", "gear", "mesh", "pinion shaft", "gear shaft", "pinion bearing", "gear bearing",
    "other shaft")
PARTS = (PINION, GEAR, MESH, PINION_SHAFT, GEAR_SHAFT, PINION_BEARING, GEAR_BEARING,
         OTHER_SHAFT)


@dataclass(frozen=True)
class Effect:
    """One catalogue effect (docs/effects.md).

    Attributes:
        key: the name the CLI and the JSON use
        model: its Modelica class (``GearDiag.GearPair`` for one whose parameters are the
            base model's own, ``in_base``)
        description: what it is, in a line
        parameters: what it adds, named as its FMU variables, with the ranges its Modelica
            file declares
        weight: its signature, (line or None, freq_hz, kinematics) -> 0..1: the weight of
            a residual line at ``freq_hz`` (``line``: the kinematic line there) on the pair
            of ``kinematics``
        hint: (peaks, bin_hz, kinematics) -> {name: (low, high), or None: not fitted here}
        in_base: its parameters are the base model's, neutral by default: it frees them in
            the base FMU instead of building a model of its own
        synchronous: every line it makes is an order of the fundamental period, so its
            model is simulated over one period and repeated; False for a bearing's strikes
            or a ripple at a frequency of its own, simulated whole (discover starts those
            first) unless it is a ``ripple`` read from periods of the model or the outputs
            alone see it (read from one period of the states:
            :func:`pydiag.fmu.periodic.simulate_periodic`)
        outputs: the GearPair outputs whose lines it changes (None: all): a housing mode or
            a bearing's strikes ring the acceleration at the sensor, not the mesh's
            displacement, so peaks of disp are no evidence for them
        reshapes_base: it takes energy from the lines the base makes (a speed fluctuation,
            a second faulty tooth, a housing mode), so a base fit without it bent its
            parameters: it is fitted with the base parameters free as well, and the misfit
            the bent base left on any channel is its evidence
        free_start: (top of the analysed band, Hz) -> values of some of its parameters a
            second polish with the base free starts from (a housing mode above the band
            shows only as a tilt, which a fit with the base held makes up for); the better
            polish is kept
        affine: its outputs are affine in its parameters (a strike amplitude, a shaft's
            orders): fitted from one simulation more than it has parameters; but for one
            periodic parameter, a phase they depend on as a first harmonic (where a load
            zone or a cage's turn peaks the strikes), three a parameter then
            (:func:`pydiag.fit.affine.fit_affine`)
        envelope: its lines show in the envelope of the acceleration above the gear's bands
            (a bearing's strikes ringing a structural mode), where held-out validation
            fits and scores it
        machine_values: (kinematics) -> FMU values its model takes from the machine (a
            bearing's geometry, another shaft's ratio) rather than fits
        missing: (kinematics) -> what the machine's description must say for it to have
            lines at all, "" when nothing is missing
        transfer: it is a path between the model's output and the sensor, applied to the
            base model's simulated output (:mod:`pydiag.signal.transfer`) rather than
            built into an FMU of its own: it adds to any model, and costs no integration
            of a stiff or slowly settling mode (its ``model`` is the Modelica model that
            says the same, which a test holds it to)
        ripple: it is a speed or torque ripple its model's values size, read from the
            model's periodic response without it (:mod:`pydiag.signal.ripple`) rather
            than simulated over the whole record (its ``model`` has it inside, which a
            test holds it to)
        parts: (parameter, part) of each parameter that sizes a fault of one part of its
            stage (:data:`PARTS`: the pinion, the gear, both through their mesh, a shaft
            of the pair or the other shaft, the bearing on either shaft); a phase or a
            frequency sizes none, and an effect of the drive or the sensor (a ripple, a
            housing mode) has none
        fault: the state (:mod:`pydiag.gear.faults`) of a part whose fault a record sizes
            beyond the healthy model's: a word, or a rule of the :attr:`parts`'
            parameters' values, (healthy, on the record) -> the word (a shaft's orders
            that rose, a tooth's lost stiffness); "changed" where the effect does not
            tell the fault
    """

    key: str
    model: str
    description: str
    parameters: tuple[Parameter, ...]
    weight: Callable[[KinematicLine | None, float, GearKinematics], float]
    hint: Callable[[list[Peak], float, GearKinematics | None], dict] | None = None
    in_base: bool = False
    synchronous: bool = True
    outputs: tuple[str, ...] | None = None
    reshapes_base: bool = False
    free_start: Callable[[float], dict[str, float]] | None = None
    affine: bool = False
    envelope: bool = False
    machine_values: Callable[[GearKinematics | None], dict[str, float]] | None = None
    missing: Callable[[GearKinematics | None], str] | None = None
    transfer: HousingMode | None = None
    ripple: Ripple | None = None
    parts: tuple[tuple[str, str], ...] = ()
    fault: str | Callable[[tuple[float, ...], tuple[float, ...]], str] = CHANGED

    @property
    def own_fmu(self) -> bool:
        """Whether it is fitted on an FMU of its own (else on the base model's FMU: its
        parameters are the base's, ``in_base``, or a ``transfer`` path's)."""
        return not self.in_base and self.transfer is None

    def changes(self, output: str) -> bool:
        """Whether the effect changes the model output ``output`` (an FMU variable)."""
        return self.outputs is None or output in self.outputs

    def bounds(self, peaks: list[Peak], bin_hz: float,
               kinematics: GearKinematics | None = None) -> tuple[Parameter, ...]:
        """The effect's parameters, bounds narrowed by what the residual peaks (and the gear
        machine's ``kinematics``: :class:`pydiag.gear.kinematics.GearKinematics`) say, if it can;
        those its hint leaves out (None) are not fitted: they keep the FMU's neutral value."""
        narrowed = self.hint(peaks, bin_hz, kinematics) if self.hint else {}
        return tuple(dataclasses.replace(p, low=narrowed[p.name][0], high=narrowed[p.name][1])
                     if p.name in narrowed else p for p in self.parameters
                     if p.name not in narrowed or narrowed[p.name] is not None)

    def values_from(self, kinematics) -> dict[str, float]:
        """FMU values its model takes from the machine's ``kinematics``, not fitted."""
        return self.machine_values(kinematics) if self.machine_values else {}

    def unknown_lines(self, kinematics) -> str:
        """Why ``kinematics`` do not say where its lines are, or "" when they do."""
        missing = self.missing(kinematics) if self.missing else ""
        return f"its lines are not known without {missing}" if missing else ""

    def part_of(self, changes: dict[str, float]) -> str | None:
        """The part whose fault the effect's ``changes`` (parameter -> its change) size:
        that of the sizing parameter that grew most (its :attr:`parts`; amplitudes of one
        effect share their units). Every sizing parameter is an amplitude a fault makes
        larger (a deeper modulation, a softer tooth, a stronger strike, larger orders), so
        one that fell names no fault: None when none grew, when another fell by more (the
        record asks for less of the effect, and a part that barely moved would be named by
        the sign of its rounding), or for an effect that sizes no part."""
        sized = [(changes[name], part) for name, part in self.parts if name in changes]
        size, part = max(sized, key=lambda s: s[0], default=(0.0, None))
        fall = max((-change for change, _ in sized), default=0.0)
        return part if size > 0 and size >= fall else None

    def fault_of(self, values: dict[str, tuple[float, float]]) -> str:
        """The fault the effect names (:attr:`fault`) from ``values``: each sizing
        parameter (:attr:`parts`) -> (healthy value, value on the record); one missing (a
        shaft's order held off) is given to the rule as not a number in its place, so that
        the orders after it keep theirs."""
        if isinstance(self.fault, str):
            return self.fault
        sized = [values.get(name, (math.nan, math.nan)) for name, _ in self.parts]
        return self.fault(tuple(a for a, _ in sized), tuple(b for _, b in sized))

    def neutral_values(self) -> dict[str, float]:
        """FMU values that switch the effect off (each parameter's value nearest zero,
        :attr:`pydiag.core.parameters.Parameter.off`; none for a transfer path, which is
        off when it is not applied)."""
        if self.transfer is not None:
            return {}
        return {p.fmu_variable: p.fmu_value(p.off) for p in self.parameters}


def model_file(effect: Effect, modelica_root) -> Path:
    return Path(modelica_root) / "GearDiag" / "Effects" / f"{effect.model.rsplit('.', 1)[1]}.mo"
