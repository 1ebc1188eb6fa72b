"""Gear condition indicators on the time-synchronous average (arrays in, numbers out).

The definitions follow Lebold, McClintic, Campbell, Byington and Maynard, "Review of
vibration analysis methods for gearbox diagnostics and prognostics" (Proc. 54th MFPT,
2000), which collects Stewart's FM0 and FM4 (1977), M6A and M8A, NA4 (Zakrajsek, Townsend
and Decker, NASA TM-105950, 1993) and NB4 (Zakrajsek et al. 1994), and the energy ratio;
docs/indicators.md states each one with its normal value.

The time-synchronous average (TSA) is one revolution of the shaft of interest sampled at
``n`` equal angle steps, so its DFT bin k is shaft order k. With ``mesh_order`` teeth on
that shaft:

- regular signal: shaft orders 1..``shaft_orders``, the mesh harmonics (orders m x
  mesh_order) and their first-order sidebands (m x mesh_order +- 1);
- difference signal: the TSA minus the regular signal;
- residual signal: the TSA minus shaft orders 1..``shaft_orders`` and the mesh harmonics
  (the sidebands stay);
- with ``faster_shafts`` (a gearbox's shafts that turn a whole number n of times per turn
  of this one: their lines are every n-th order of its TSA, which does not average them
  out), those orders are the other shafts', left out of the difference and residual
  signals: a chipped input pinion is not the idler's fault;
- envelope signal (NB4): the magnitude of the analytic signal of the TSA band-passed to
  orders (mesh_order/2, 3 mesh_order/2) around the first mesh harmonic.

Every signal is taken without its mean (order 0).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Sidebands counted on each side of the mesh line by the sideband energy ratio.
SER_SIDEBANDS = 6
#: Shaft orders 1..this are the shaft's own (imbalance, misalignment), removed from the
#: residual and difference signals.
SHAFT_ORDERS = 2


def synchronous_average(signal: np.ndarray, samples_per_rev: int) -> np.ndarray:
    """The mean revolution of ``signal`` sampled at ``samples_per_rev`` per revolution
    (its whole revolutions; a trailing part is dropped)."""
    signal = np.asarray(signal, dtype=float)
    n_revs = signal.size // samples_per_rev
    if n_revs < 1:
        raise ValueError(f"{signal.size} samples hold no revolution of {samples_per_rev}")
    return signal[:n_revs * samples_per_rev].reshape(n_revs, samples_per_rev).mean(axis=0)


@dataclass(frozen=True)
class TsaSignals:
    """The TSA and the signals derived from it (see the module docstring), one revolution each."""

    tsa: np.ndarray
    regular: np.ndarray
    difference: np.ndarray
    residual: np.ndarray
    envelope: np.ndarray
    spectrum: np.ndarray  # one-sided amplitude per shaft order (index = order)
    mesh_order: int
    residual_orders: int = 0  # how many orders the residual keeps


def order_masks(n_orders: int, mesh_order: int, shaft_orders: int = SHAFT_ORDERS,
                other_meshes: tuple[int, ...] = (), faster_shafts: tuple[int, ...] = ()
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Which of the orders 0..``n_orders`` - 1 of a shaft's TSA (:func:`tsa_signals`'
    arguments) are its meshes' harmonics, their first sidebands, its first
    ``shaft_orders`` orders and the faster shafts' lines (boolean masks, in that order);
    the residual is every order > 0 that is none of the first, third and fourth."""
    orders = np.arange(n_orders)
    mesh = np.zeros(orders.size, dtype=bool)
    sidebands = np.zeros(orders.size, dtype=bool)
    for teeth in (mesh_order, *other_meshes):
        mesh |= (orders % teeth == 0) & (orders > 0)
        sidebands |= ((orders + 1) % teeth == 0) | ((orders - 1) % teeth == 0)
    sidebands &= (orders > 1) & ~mesh
    shaft = (orders >= 1) & (orders <= shaft_orders)
    foreign = np.zeros(orders.size, dtype=bool)
    for turns in faster_shafts:
        if turns < 2:
            raise ValueError(f"a faster shaft turns a whole number >= 2 of times, got {turns}")
        foreign |= orders % turns == 0
    return mesh, sidebands, shaft, foreign


def tsa_signals(tsa: np.ndarray, mesh_order: int, shaft_orders: int = SHAFT_ORDERS,
                other_meshes: tuple[int, ...] = (),
                faster_shafts: tuple[int, ...] = ()) -> TsaSignals:
    """Regular, difference, residual and envelope signals of one revolution ``tsa`` of a
    shaft carrying ``mesh_order`` teeth; ``other_meshes``: the teeth of the shaft's other
    gears (an intermediate shaft of a gearbox carries two), whose mesh harmonics and first
    sidebands are regular too; ``faster_shafts``: the turns per turn of this one of the
    shafts whose lines are not its own (module docstring)."""
    tsa = np.asarray(tsa, dtype=float)
    n = tsa.size
    if mesh_order < 2 or mesh_order >= n // 2:
        raise ValueError(f"mesh order {mesh_order} needs 2 <= order < {n // 2} (samples/2)")
    coeffs = np.fft.rfft(tsa - tsa.mean())
    mesh, sidebands, shaft, foreign = order_masks(coeffs.size, mesh_order, shaft_orders,
                                                  other_meshes, faster_shafts)
    orders = np.arange(coeffs.size)

    def part(keep: np.ndarray) -> np.ndarray:
        return np.fft.irfft(np.where(keep, coeffs, 0), n)

    regular = part(mesh | sidebands | shaft)
    band = (orders > mesh_order / 2) & (orders < 1.5 * mesh_order)
    analytic = np.fft.ifft(np.concatenate([np.where(band, 2 * coeffs, 0),
                                           np.zeros(n - coeffs.size)]))
    residual = ~(mesh | shaft | foreign) & (orders > 0)
    return TsaSignals(tsa=tsa - tsa.mean(), regular=regular,
                      difference=part(~(mesh | sidebands | shaft | foreign) & (orders > 0)),
                      residual=part(residual), envelope=np.abs(analytic),
                      spectrum=2 * np.abs(coeffs) / n, mesh_order=mesh_order,
                      residual_orders=int(np.count_nonzero(residual)))


def normalized_moment(x: np.ndarray, k: int, variance: float | None = None) -> float:
    """mean((x - mean x)^k) / variance^(k/2); ``variance`` defaults to x's own.

    k = 4 is the kurtosis (3 for Gaussian noise, 1.5 for a sine)."""
    x = np.asarray(x, dtype=float)
    dev = x - x.mean()
    var = float(np.mean(dev ** 2)) if variance is None else variance
    if not var > 0:
        return float("nan")
    return float(np.mean(dev ** k) / var ** (k / 2))


def variance(x: np.ndarray) -> float:
    return float(np.var(np.asarray(x, dtype=float)))


@dataclass(frozen=True)
class TrendReference:
    """The variances NA4 and NB4 divide by: of the residual and of the envelope of a
    reference (healthy, or first) record; None: the record's own."""

    residual_variance: float | None = None
    envelope_variance: float | None = None

    @classmethod
    def of(cls, signals: TsaSignals) -> "TrendReference":
        return cls(variance(signals.residual), variance(signals.envelope))


def raw_indicators(signal: np.ndarray) -> dict[str, float]:
    """rms, peak, crest factor and kurtosis of a record (its mean removed)."""
    x = np.asarray(signal, dtype=float)
    x = x - x.mean()
    rms = float(np.sqrt(np.mean(x ** 2)))
    peak = float(np.max(np.abs(x)))
    return {"rms": rms, "peak": peak, "crest_factor": peak / rms if rms > 0 else float("nan"),
            "kurtosis": normalized_moment(x, 4)}


def tsa_indicators(signals: TsaSignals,
                   reference: TrendReference = TrendReference()) -> dict[str, float]:
    """fm0, fm4, na4, nb4, m6a, m8a, er and ser of one TSA (see docs/indicators.md)."""
    spectrum, mesh = signals.spectrum, signals.mesh_order
    harmonics = spectrum[mesh::mesh]
    sides = [spectrum[mesh + k] + spectrum[mesh - k] for k in range(1, SER_SIDEBANDS + 1)
             if mesh - k > 0 and mesh + k < spectrum.size]
    d, regular = signals.difference, signals.regular
    rms_regular = float(np.sqrt(np.mean(regular ** 2)))
    floor = 1e-9 * float(np.sqrt(np.mean(signals.tsa ** 2)))

    def moment(x: np.ndarray, k: int, reference_variance: float | None = None) -> float:
        """A signal at rounding level (a pure tone's difference signal) has no moments."""
        if not np.sqrt(np.mean(x ** 2)) > floor:
            return float("nan")
        return normalized_moment(x, k, reference_variance)

    mesh_sum = float(harmonics.sum())
    return {
        "fm0": float(np.ptp(signals.tsa)) / mesh_sum if mesh_sum > 0 else float("nan"),
        "fm4": moment(d, 4),
        "na4": moment(signals.residual, 4, reference.residual_variance),
        "nb4": moment(signals.envelope - signals.envelope.mean(), 4, reference.envelope_variance),
        "m6a": moment(d, 6),
        "m8a": moment(d, 8),
        "er": float(np.sqrt(np.mean(d ** 2)) / rms_regular) if rms_regular > 0 else float("nan"),
        "ser": float(sum(sides) / spectrum[mesh]) if spectrum[mesh] > 0 else float("nan"),
    }
