"""The pinion speed of a real record, and the record order-tracked to that speed.

One concern: the shaft angle over a record, from whatever the record holds (a tacho, the
mesh lines of one pair or of every stage, or nothing but the nominal speed), with how far
it can be trusted (its confidence, its warnings).

A real machine turns at a speed that is only nominal (motor slip moves it with the load)
and drifts within the record, so a synchronous cut at the nominal speed smears the mesh
harmonics. :func:`estimate_speed` finds the shaft angle over the record:

- ``"tacho"``: from a pulse channel (:func:`pydiag.signal.angle.tacho_revolutions`);
- ``"mesh"``: from the mesh harmonics. A harmonic-product search over the Hann spectrum
  finds the speed at which the mesh harmonics line up, within the nominal speed
  +- ``SPEED_SEARCH`` and +- 0.45/Np: beyond half a pinion order at the mesh, the comb of
  sidebands h f_mesh - h f_pinion of a faulty tooth lines up as well as the mesh and can
  pass for it (seen on a simulated tooth fault, Np = 14). The nominal speed must be that
  close (1.4 % for a 32-tooth pinion); otherwise use a tacho. The harmonic that stands
  highest above its band's median is then phase-demodulated in a band of +- half the
  slower shaft's speed (Tukey taper, flat over the inner half), which excludes the
  shaft-order sidebands, so the phase is the shaft angle times h Np; the band is centred
  on the line's power centroid, its mean frequency (a line that drifts peaks at the ends
  of its swing, where it dwells longest). The mean speed is
  the slope of that phase (far below one FFT bin). A speed that swings near the band's
  edge leaves it, and the phase followed is partly another line's: a warning
  (:data:`SWING_SHARE`);
- ``"mesh"`` on a machine of two or more stages (:class:`~pydiag.gear.machine.Machine`):
  one input speed must put every stage's mesh harmonics and their sideband families
  (1 to ``COMB_SIDEBANDS`` orders of both of a stage's shafts) on lines, summed over every
  channel, within +- ``MACHINE_SEARCH``. A sideband taken for a mesh can line up one
  stage's comb with another's (32/96 then 48/80 teeth: 2 % below the truth, mesh 1 minus
  2x idler and mesh 2 minus 1x idler), but then every family's spacing is 2 % short and
  its sidebands miss their lines. The line followed is the one that stands highest over
  the rest of its own band (another stage's lines may fall in it). The estimate's
  ``confidence_db`` says how far the best speed stands over the next distinct one;
- ``"nominal"``: the nominal speed, constant.

The mesh line must stand above the noise: its amplitude over its band's median must
exceed what the largest of the band's bins reaches by chance with probability 1e-3
(Rayleigh noise: ``r^2 ln 2 > ln(bins / 1e-3)``); otherwise the estimate is refused.

``speed_variation_pct`` is 100 (max - min) / mean of the speed averaged over blocks of
``BLOCK_REVS`` pinion revolutions (or over quarters of a shorter record).

The record order-tracked to the speed found: :mod:`pydiag.gear.tracking`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from enum import Enum

import numpy as np

from pydiag.core.errors import MeasurementError, UsageError
from pydiag.core.measurement import Measurement
from pydiag.gear.kinematics import GearKinematics
from pydiag.gear.machine import Machine
from pydiag.signal.angle import (EDGE_BANDWIDTHS, extend_linearly,
                                 tacho_revolutions, tone_phase)
from pydiag.signal.spectra import amplitude_spectrum

SPEED_METHODS = ("auto", "mesh", "tacho", "nominal")
#: The mesh search spans the nominal speed +- this fraction (induction-motor slip is a
#: few per cent; the nominal speed may be the synchronous one).
SPEED_SEARCH = 0.08
#: ... and within this many pinion orders at the mesh (module docstring).
SIDEBAND_FRACTION = 0.45
#: The search window of a machine of two or more stages, either side of nominal (module
#: docstring): a real drive slips a few per cent below its nominal speed.
MACHINE_SEARCH = 0.08
#: Sideband orders either side of each mesh harmonic that the search of a machine scores
#: (:class:`MeshComb`).
COMB_SIDEBANDS = 3
#: Mesh harmonics used by the search (fewer when the sample rate cannot hold them).
SEARCH_HARMONICS = 4
BLOCK_REVS = 10
#: "auto" follows the mesh phase only in a record longer than the two ends the
#: demodulation loses (EDGE_BANDWIDTHS / bandwidth each, :func:`tone_phase`) plus this
#: many fundamental periods; a shorter one is taken at the nominal speed, and says so.
MIN_TRACKED_PERIODS = 4
FALSE_ALARM = 1e-3
#: Times the demodulation band is moved onto the centroid of the line followed
#: (:func:`_centroid_hz`).
CENTROID_PASSES = 3
#: A tacho's speed and the mesh lines' may differ by this much (%) before a warning: ten
#: times what the mesh search measures on real records, far below a wrong pulse count.
TACHO_TOLERANCE_PCT = 0.1
#: The tacho's speed over the nominal beyond which (or below its inverse) the tacho is
#: checked against a mesh found near the nominal: a wrong count of pulses a turn.
PULSE_CHECK_RATIO = 1.5
#: A speed that swings by more than this share of the mesh demodulation's half-band
#: (half the speed's range over the record, against the half-band) may have left it: the
#: phase followed is then partly another line's, and the speed from it may be off, so it
#: is said (what was measured of it: docs/gearbox.md, "The speed from every mesh").
SWING_SHARE = 0.6


@dataclass(frozen=True)
class SpeedSettings:
    """How to find the speed: ``method`` (see :data:`SPEED_METHODS`), the ``channel``
    searched for mesh lines (default: the first), the ``tacho`` channel and its
    ``pulses_per_rev``."""

    method: str = "auto"
    channel: str | None = None
    tacho: str | None = None
    pulses_per_rev: int = 1

    def __post_init__(self) -> None:
        if self.method not in SPEED_METHODS:
            raise UsageError(f"speed method must be one of {SPEED_METHODS}, got {self.method!r}")
        if self.pulses_per_rev < 1:
            raise UsageError(f"pulses per revolution must be >= 1, got {self.pulses_per_rev}")


class SpeedSource(str, Enum):
    """Where a speed estimate comes from."""

    TACHO = "tacho"
    MESH = "mesh"
    NOMINAL = "nominal"  # not measured: the record is taken at the nominal speed


@dataclass(frozen=True)
class SpeedEstimate:
    """Attributes:
        speed_hz: mean pinion speed over the record
        variation_pct: speed range over the record, % of the mean (see module docstring)
        method: how, in words: "tacho", "mesh harmonic <h>" or "nominal" (and why)
        nominal_hz: the nominal speed the estimate started from
        revolutions: pinion revolutions at every sample (not serialised)
        valid: (first, last) sample where the angle is measured, not extrapolated
        source: where it comes from (:class:`SpeedSource`)
        confidence_db: from the mesh: how far the best speed's lines stand over the next
            candidate's (:func:`comb_speed`); None otherwise
        mesh_speed_hz: with a tacho, the speed the mesh lines give, to check it; None
            when the mesh was not searched or not found
        band_pct: the half-width of the band the mesh line's phase was followed in, % of
            the line's frequency; None when no mesh line was followed
        tacho_speed_hz: from the mesh with a tacho in the record, the tacho's speed, to
            check the mesh's with; None otherwise
    """

    speed_hz: float
    variation_pct: float
    method: str
    nominal_hz: float
    revolutions: np.ndarray = dataclasses.field(repr=False, compare=False)
    valid: tuple[int, int] = (0, -1)
    source: SpeedSource = SpeedSource.MESH
    confidence_db: float | None = None
    mesh_speed_hz: float | None = None
    band_pct: float | None = None
    tacho_speed_hz: float | None = None

    @property
    def tacho_disagreement_pct(self) -> float | None:
        """The mesh's speed over the tacho's, minus 1, in %: None unless both were found."""
        if self.source is not SpeedSource.TACHO or self.mesh_speed_hz is None:
            return None
        return 100 * (self.mesh_speed_hz / self.speed_hz - 1)

    @property
    def beyond_band(self) -> bool:
        """Whether the speed swings too far for the mesh phase to be followed
        (:data:`SWING_SHARE` of the band)."""
        return (self.band_pct is not None
                and 0.5 * self.variation_pct > SWING_SHARE * self.band_pct)

    def warning(self) -> str | None:
        """Why the speed may be wrong, or None: from the mesh, a swing near the edge of
        the band its phase is followed in; from a tacho, mesh lines that disagree with it
        past :data:`TACHO_TOLERANCE_PCT` (unless the swing is what kept the mesh off)."""
        swing = (f"the speed swings by +-{0.5 * self.variation_pct:.3g} % over the record, "
                 f"near the +-{self.band_pct:.3g} % the mesh line's phase is followed in"
                 if self.beyond_band else "")
        if self.source is SpeedSource.MESH and swing:
            return f"{swing}: the speed may be off; a tacho channel (--tacho) measures it"
        if self.source is SpeedSource.MESH and self.tacho_speed_hz is not None:
            off = 100 * (self.speed_hz / self.tacho_speed_hz - 1)
            if abs(off) > TACHO_TOLERANCE_PCT:
                return (f"the mesh lines give {self.speed_hz:.5f} Hz, {off:+.3f} % from the "
                        f"tacho's {self.tacho_speed_hz:.5f} Hz: the mesh search may have taken "
                        "another candidate; --speed tacho follows the tacho")
        off = self.tacho_disagreement_pct
        if off is None or abs(off) <= TACHO_TOLERANCE_PCT or swing:
            return None
        return (f"the mesh lines give {self.mesh_speed_hz:.5f} Hz, {off:+.3f} % from the "
                f"tacho's {self.speed_hz:.5f} Hz: check the tacho channel and "
                "--pulses-per-rev")

    def to_dict(self) -> dict:
        out = {"speed_hz": self.speed_hz, "speed_variation_pct": self.variation_pct,
               "speed_method": self.method, "nominal_speed_hz": self.nominal_hz}
        if self.confidence_db is not None:
            out["speed_confidence_db"] = (self.confidence_db
                                          if math.isfinite(self.confidence_db) else None)
        if self.mesh_speed_hz is not None:
            out["mesh_speed_hz"] = self.mesh_speed_hz
        return out


def _variation_pct(revs: np.ndarray, sample_rate_hz: float, mean_hz: float) -> float:
    total = revs[-1] - revs[0]
    n_blocks = max(int(total // BLOCK_REVS), 4) if total >= 4 else 1
    if n_blocks < 2:
        return 0.0
    edges = np.searchsorted(revs, revs[0] + total * np.arange(n_blocks + 1) / n_blocks)
    edges = np.clip(edges, 0, revs.size - 1)
    speeds = [(revs[b] - revs[a]) / ((b - a) / sample_rate_hz)
              for a, b in zip(edges[:-1], edges[1:]) if b > a]
    return float(100 * (max(speeds) - min(speeds)) / mean_hz)


def _mean_speed(revs: np.ndarray, sample_rate_hz: float) -> float:
    n = np.arange(revs.size)
    return float(np.polyfit(n, revs, 1)[0] * sample_rate_hz)


@dataclass(frozen=True)
class MeshComb:
    """The mesh lines a speed search looks for, in orders of the shaft whose speed is
    sought (the input shaft; a pair's pinion).

    Attributes:
        orders: each stage's mesh frequency in shaft orders
        bands: each mesh's demodulation half-width in shaft orders: half the slower of the
            stage's two shafts, so that no shaft-order sideband enters it
        search: the search window, a fraction of the nominal speed either side
        sidebands: per mesh, the shaft speeds (in shaft orders) whose sidebands 1 to
            :data:`COMB_SIDEBANDS` around each mesh harmonic are scored too: the spacing of
            a mesh's sideband family tells its speed apart from a sideband's (empty: the
            mesh lines alone)
    """

    orders: tuple[float, ...]
    bands: tuple[float, ...]
    search: float
    sidebands: tuple[tuple[float, ...], ...] = ()

    @classmethod
    def of_pair(cls, kinematics: GearKinematics, search: float = SPEED_SEARCH) -> "MeshComb":
        """One mesh: the window is also held within 0.45/Np (module docstring)."""
        n_p, n_g = kinematics.n_pinion, kinematics.n_gear
        return cls((float(n_p),), (0.5 * min(1.0, n_p / n_g),),
                   min(search, SIDEBAND_FRACTION / n_p))

    @classmethod
    def of_machine(cls, machine: Machine, search: float = MACHINE_SEARCH) -> "MeshComb":
        """Every stage's mesh and the sideband families at both of its shafts; one stage is
        a pair. With two or more stages the window is ``search`` whole: a speed that puts
        every stage's mesh on a sideband (module docstring) spaces every family wrong."""
        if len(machine.stages) == 1:
            s = machine.stages[0]
            return cls.of_pair(GearKinematics(s.pinion_teeth, s.gear_teeth, 1.0), search)
        orders = tuple(float(machine.mesh_order(k)) for k in range(len(machine.stages)))
        bands = tuple(0.5 * float(min(machine.shaft_ratio(k), machine.shaft_ratio(k + 1)))
                      for k in range(len(machine.stages)))
        sidebands = tuple((float(machine.shaft_ratio(k)), float(machine.shaft_ratio(k + 1)))
                          for k in range(len(machine.stages)))
        return cls(orders, bands, search, sidebands)


def comb_speed(signals: list[np.ndarray], sample_rate_hz: float, comb: MeshComb,
               nominal_hz: float) -> SpeedEstimate:
    """The shaft speed at which every mesh line of ``comb`` (and its harmonics) stands
    highest over its band's median in the summed log spectra of ``signals``, refined by the
    phase of the harmonic that stands highest (module docstring).

    The estimate's ``confidence_db`` is how far (geometric mean over the lines, dB) the
    lines stand higher at the best speed than at the best speed elsewhere in the window
    (more than a bin's width away at the lowest mesh: a distinct set of lines)."""
    low, high = nominal_hz * (1 - comb.search), nominal_hz * (1 + comb.search)
    spectra = [amplitude_spectrum(np.asarray(x, dtype=float), sample_rate_hz, "hann")
               for x in signals]
    freqs = spectra[0][0]
    bin_hz = freqs[1]
    lines = [(m, h) for m in range(len(comb.orders))
             for h in range(1, SEARCH_HARMONICS + 1)
             if h * comb.orders[m] * high <= 0.45 * sample_rate_hz]
    if not lines:
        top_hz = min(comb.orders) * high
        raise MeasurementError(
            f"the mesh frequency near {min(comb.orders) * nominal_hz:.1f} Hz, searched up to "
            f"{top_hz:.1f} Hz, needs a sample rate above {top_hz / 0.45:.0f} Hz; the record's "
            f"is {sample_rate_hz:g} Hz: check the speed, the teeth and the sample rate")
    n_side = COMB_SIDEBANDS if comb.sidebands else 0
    finest = max(h * comb.orders[m] for m, h in lines) + max(
        (n_side * max(sb) for sb in comb.sidebands), default=0.0)
    grid = np.arange(low, high, bin_hz / (4 * finest))
    score = np.zeros(grid.size)
    heights = []  # (the band's median, bins in the band, line, channel)
    n_terms = 0
    for c, (_, amp) in enumerate(spectra):
        for m, h in lines:
            f_line = h * comb.orders[m]
            band = (freqs >= f_line * low) & (freqs <= f_line * high)
            floor = max(float(np.median(amp[band])), 1e-300)
            score += np.log(np.interp(f_line * grid, freqs, amp) / floor + 1e-12)
            n_terms += 1
            for shaft in (comb.sidebands[m] if comb.sidebands else ()):
                for k in range(1, n_side + 1):
                    for side in (f_line - k * shaft, f_line + k * shaft):
                        score += np.log(np.interp(side * grid, freqs, amp) / floor + 1e-12)
                        n_terms += 1
            heights.append((floor, int(np.count_nonzero(band)), (m, h), c))
    best = int(np.argmax(score))
    coarse = float(grid[best])
    apart = np.abs(grid - coarse) > bin_hz / min(comb.orders)
    confidence_db = (20 / math.log(10) * float(score[best] - np.max(score[apart]))
                     / n_terms if np.any(apart) else math.inf)
    ratios = np.array([np.interp(h * comb.orders[m] * coarse, freqs, spectra[c][1]) / floor
                       for floor, _, (m, h), c in heights])
    needs = np.array([math.sqrt(math.log(max(n, 2) / FALSE_ALARM) / math.log(2))
                      for _, n, _, _ in heights])
    pick = int(np.argmax(ratios))
    ratio, needed = float(ratios[pick]), float(needs[pick])
    if comb.sidebands and ratio >= needed:
        # a machine's band may hold another stage's lines: follow the line that stands
        # highest over the rest of its own demodulation band, among those over chance
        purity = [_purity(spectra[c], h * comb.orders[m] * coarse,
                          comb.bands[m] * coarse) if r >= n else 0.0
                  for (_, _, (m, h), c), r, n in zip(heights, ratios, needs)]
        pick = int(np.argmax(purity))
    _, _, (m, h), c = heights[pick]
    if ratio < needed:
        raise MeasurementError(
            f"no mesh line stands out near {comb.orders[0] * nominal_hz:.1f} Hz "
            f"(+-{100 * comb.search:g} %): the best is {ratio:.1f}x its band's median, chance "
            f"reaches {needed:.1f}x; check the nominal speed (--rpm) and the teeth (--teeth or "
            "the machine file), or give a tacho channel (--tacho)")
    x = np.asarray(signals[c], dtype=float)
    order = h * comb.orders[m]
    band_hz = comb.bands[m] * coarse
    centre_hz = _centroid_hz(spectra[c], order * coarse, band_hz)
    index, cycles = tone_phase(x, sample_rate_hz, centre_hz, band_hz)
    revs = extend_linearly(index, cycles / order, x.size)
    inner = (np.arange(x.size) >= index[0]) & (np.arange(x.size) <= index[-1])
    mean = _mean_speed(revs[inner], sample_rate_hz)
    where = f" of stage {m + 1}" if len(comb.orders) > 1 else ""
    return SpeedEstimate(mean, _variation_pct(revs[inner], sample_rate_hz, mean),
                         f"mesh harmonic {h}{where}", nominal_hz, revs,
                         (int(np.ceil(index[0])), int(np.floor(index[-1]))),
                         confidence_db=confidence_db, band_pct=100 * comb.bands[m] / order)


def _centroid_hz(spectrum: tuple[np.ndarray, np.ndarray], freq_hz: float, band_hz: float,
                 passes: int = CENTROID_PASSES) -> float:
    """The mean frequency of the line near ``freq_hz``: the centroid of its power above the
    band's median within ``freq_hz +- band_hz``, the band moved onto it until it settles.

    A line whose frequency drifts within the record peaks where it dwells longest, at the
    ends of its swing (a speed swinging +-0.4 % once over a record peaks 0.4 % off its
    mean), and a demodulation band centred there loses the far end; the centroid of a
    constant-amplitude line's power is its mean frequency."""
    freqs, amp = spectrum
    centre = freq_hz
    for _ in range(passes):
        near = np.abs(freqs - centre) <= band_hz
        power = amp[near] ** 2
        power = np.maximum(power - np.median(power), 0.0)
        if not np.any(power > 0):
            break
        centre = float(np.sum(freqs[near] * power) / np.sum(power))
    return centre


def _purity(spectrum: tuple[np.ndarray, np.ndarray], freq_hz: float, band_hz: float) -> float:
    """A line's amplitude over the largest elsewhere in ``freq_hz +- band_hz`` (two bins
    either side of the line are its own, a Hann window's main lobe)."""
    freqs, amp = spectrum
    bin_hz = freqs[1]
    near = np.abs(freqs - freq_hz)
    rest = (near <= band_hz) & (near > 2 * bin_hz)
    if not np.any(rest):
        return math.inf
    return float(np.interp(freq_hz, freqs, amp) / max(float(np.max(amp[rest])), 1e-300))


def estimate_speed(measurement: Measurement, kinematics: GearKinematics,
                   settings: SpeedSettings = SpeedSettings(),
                   tracked_s: float | None = None,
                   machine: Machine | None = None) -> SpeedEstimate:
    """The pinion speed of ``measurement`` around ``kinematics.f_pinion_hz`` (nominal).

    ``settings.method``: "auto" (the tacho when one is named, else the mesh), "mesh",
    "tacho" or "nominal"; see :class:`SpeedSettings`. ``tracked_s``: under "auto", the
    shortest stretch worth following beyond the demodulation's edges (default
    :data:`MIN_TRACKED_PERIODS` fundamental periods: what a fit needs). ``machine``: the
    whole machine whose first stage ``kinematics`` is: the mesh search then looks for
    every stage's mesh at once, in every channel but the tacho unless
    ``settings.channel`` names one. A tacho's estimate carries the mesh's beside it
    (``mesh_speed_hz``) when the record is long enough to find it.
    """
    method, channel, tacho = settings.method, settings.channel, settings.tacho
    pulses_per_rev = settings.pulses_per_rev
    comb = (MeshComb.of_machine(machine) if machine is not None
            else MeshComb.of_pair(kinematics))
    if tracked_s is None:
        tracked_s = MIN_TRACKED_PERIODS * kinematics.period_s
    fs, nominal = measurement.sample_rate_hz, kinematics.f_pinion_hz
    short = measurement.duration_s < (2 * EDGE_BANDWIDTHS / (min(comb.bands) * nominal)
                                      + tracked_s)
    if method == "auto":
        method = "tacho" if tacho else "nominal" if short else "mesh"
    names = [c for c in measurement.channels if c != tacho]
    if channel is not None and channel not in measurement.channels:
        raise MeasurementError(f"channel '{channel}' not in the measurement")
    searched = [channel] if channel else names if machine is not None else names[:1]

    def from_mesh() -> SpeedEstimate:
        return comb_speed([measurement.channels[c] for c in searched], fs, comb, nominal)

    if method == "tacho":
        if not tacho:
            raise UsageError("the tacho method needs a tacho channel (--tacho NAME)")
        if tacho not in measurement.channels:
            raise MeasurementError(f"tacho channel '{tacho}' not in the measurement; it has: "
                                   f"{', '.join(measurement.channels)}")
        revs = tacho_revolutions(measurement.channels[tacho], pulses_per_rev)
        mean = _mean_speed(revs, fs)
        mesh = None
        if not short and searched:  # the mesh at the nominal, else at the tacho's speed
            for around in (nominal, mean):
                try:
                    mesh = comb_speed([measurement.channels[c] for c in searched], fs, comb,
                                      around)
                    break
                except MeasurementError:
                    mesh = None  # no mesh line stands out: nothing to check the tacho with
            _check_pulses(mean, mesh, nominal, pulses_per_rev)
        return SpeedEstimate(mean, _variation_pct(revs, fs, mean), "tacho", nominal, revs,
                             source=SpeedSource.TACHO,
                             mesh_speed_hz=None if mesh is None else mesh.speed_hz,
                             band_pct=None if mesh is None else mesh.band_pct)
    if method == "nominal":
        revs = np.arange(measurement.n_samples) * (nominal / fs)
        why = (f" (auto: a record of {measurement.duration_s:.3g} s is too short to follow the "
               "mesh phase)" if settings.method == "auto" else "")
        return SpeedEstimate(nominal, 0.0, "nominal" + why, nominal, revs,
                             source=SpeedSource.NOMINAL)
    if not searched:
        raise MeasurementError("the record has no channel but the tacho to find the mesh in")
    if not (tacho and tacho in measurement.channels):
        return from_mesh()
    # a tacho that is there checks the mesh's speed, and stands in when no mesh stands out
    revs = tacho_revolutions(measurement.channels[tacho], pulses_per_rev)
    mean = _mean_speed(revs, fs)
    try:
        return dataclasses.replace(from_mesh(), tacho_speed_hz=mean)
    except MeasurementError:
        return SpeedEstimate(mean, _variation_pct(revs, fs, mean),
                             "tacho (no mesh line stood out from chance)", nominal, revs,
                             source=SpeedSource.TACHO)


def _check_pulses(tacho_hz: float, mesh: SpeedEstimate | None, nominal_hz: float,
                  pulses_per_rev: int) -> None:
    """MeasurementError when the tacho's speed is far from the nominal and the mesh lines
    put the speed near the nominal instead: the tacho gives more (or fewer) pulses a turn
    than ``pulses_per_rev`` says, and every line would be read at the wrong speed."""
    ratio = tacho_hz / nominal_hz
    if mesh is None or 1 / PULSE_CHECK_RATIO <= ratio <= PULSE_CHECK_RATIO:
        return
    if abs(mesh.speed_hz / nominal_hz - 1) > abs(mesh.speed_hz / tacho_hz - 1):
        return  # the mesh is the tacho's: the nominal is what is off
    pulses = pulses_per_rev * tacho_hz / mesh.speed_hz
    raise MeasurementError(
        f"the tacho's pulses give {tacho_hz:.5g} Hz at {pulses_per_rev} a turn, but the mesh "
        f"lines put the input at {mesh.speed_hz:.5g} Hz, near its nominal {nominal_hz:.5g} Hz: "
        f"the tacho gives about {pulses:.3g} pulses a turn (pulses_per_rev in the machine "
        "file, or --pulses-per-rev)")
