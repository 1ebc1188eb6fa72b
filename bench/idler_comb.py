"""The comb the PHM09 machine loop leaves on ``spur 2_30hz_High_1`` (bench/RESULTS.md
section 13): ch1 (or ch2) resampled at the tacho's angle, averaged over the idler's turn,
its lines in idler orders round the output stage's mesh (48 idler orders), the two halves
of the turns side by side; the mesh band's envelope over the turn; and the best single
strike once an idler turn ringing one structural mode (the bearing effects' ring-down,
written here), by least squares on the idler orders 30-66 but the mesh line.

    .venv/bin/python bench/idler_comb.py [--record PATH] [--channel ch2]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from scipy.signal import hilbert

from pydiag.io.readers import read_measurement
from pydiag.signal.angle import angular_resample, tacho_revolutions

ROOT = Path(__file__).resolve().parents[1]
RATE_HZ = 66_666.67  # the challenge's documentation (../shared/data/phm09/README.md)
PULSES_PER_REV = 10  # the tacho on the input shaft
IDLER_REVS = 3  # input turns an idler turn (32/96)
MESH = 48  # the output stage's mesh, in idler orders
SAMPLES_PER_REV = 2048


def idler_turns(path: Path, channel: str = "ch1") -> tuple[np.ndarray, float]:
    """``channel`` at SAMPLES_PER_REV a turn of the input (pydiag's order tracking on the
    tacho's angle), cut into whole idler turns (rows), and the input's mean speed, Hz."""
    m = read_measurement(path, sample_rate_hz=RATE_HZ)
    revs = tacho_revolutions(m.channels["ch3"], PULSES_PER_REV)
    first = float(np.ceil(revs[0]))
    n = int((revs[-1] - first) // IDLER_REVS)
    tracked = angular_resample([m.channels[channel]], revs, SAMPLES_PER_REV, first,
                               n * IDLER_REVS)[0]
    speed_hz = (revs[-1] - revs[0]) / (revs.size - 1) * m.sample_rate_hz
    return tracked.reshape(n, IDLER_REVS * SAMPLES_PER_REV), speed_hz


def lines(average: np.ndarray) -> np.ndarray:
    """Complex amplitudes of the idler orders of one turn's average, V."""
    return np.fft.rfft(average) / average.size * 2


def ring_down(turn: np.ndarray, turn_s: float, f_n: float, zeta: float, at: float) -> np.ndarray:
    """A mode struck at ``at`` of the turn, its acceleration ringing down (peak about 1)."""
    tau = ((turn - at) % 1.0) * turn_s
    alpha, beta = zeta * 2 * np.pi * f_n, 2 * np.pi * f_n * np.sqrt(1 - zeta ** 2)
    return (np.exp(-alpha * tau) * ((beta ** 2 - alpha ** 2) * np.sin(beta * tau)
                                    + 2 * alpha * beta * np.cos(beta * tau)) / (alpha ** 2 + beta ** 2))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--record", type=Path,
                    default=ROOT.parent / "shared/data/phm09/spur 2_30hz_High_1.zip")
    ap.add_argument("--channel", default="ch1", choices=("ch1", "ch2"))
    args = ap.parse_args()
    record = args.record
    turns, input_hz = idler_turns(record, args.channel)
    average = turns.mean(axis=0)
    spectrum = lines(average)
    halves = [lines(h.mean(axis=0)) for h in np.array_split(turns, 2)]
    sidebands = range(-8, 9)
    print(f"{record.name}: {args.channel} over {turns.shape[0]} idler turns; lines at the output mesh "
          f"({MESH} idler orders) + k, 1e-4 V")
    print("| k | " + " | ".join(f"{k:+d}" for k in sidebands) + " |")
    print("|---|" + "---|" * len(sidebands))
    for name, s in (("all", spectrum), ("first half", halves[0]), ("second half", halves[1])):
        print(f"| {name} | " + " | ".join(f"{1e4 * abs(s[MESH + k]):.0f}" for k in sidebands) + " |")

    band = np.zeros_like(spectrum)
    band[MESH - 12:MESH + 13] = spectrum[MESH - 12:MESH + 13]
    turn = np.arange(average.size) / average.size
    envelope = hilbert(np.fft.irfft(band * average.size / 2, n=average.size))
    envelope *= np.exp(-2j * np.pi * MESH * turn)
    phase = np.unwrap(np.angle(envelope))
    print("\nthe output mesh's band (orders 36-60) over the idler's turn:")
    print("| turn | " + " | ".join(f"{u:.2f}" for u in turn[::average.size // 24]) + " |")
    print("| V x1e-4 | " + " | ".join(f"{1e4 * abs(e):.0f}" for e in envelope[::average.size // 24]) + " |")
    print("| phase, rad | " + " | ".join(f"{p - phase.mean():+.1f}" for p in phase[::average.size // 24]) + " |")

    orders = np.array([k for k in range(30, 67) if k != MESH])
    measured = spectrum[orders]
    turn_s = IDLER_REVS / input_hz
    best = None
    for f_n in np.arange(300.0, 700.0, 2.0):
        for zeta in (0.01, 0.02, 0.03, 0.05, 0.07, 0.1, 0.14, 0.2):
            for at in np.arange(0.0, 1.0, 1 / 96):
                model = lines(ring_down(turn, turn_s, f_n, zeta, at))[orders]
                size = (np.vdot(model, measured) / np.vdot(model, model)).real
                left = float(np.sum(np.abs(measured - size * model) ** 2))
                if best is None or left < best[0]:
                    best = (left, f_n, zeta, at)
    left, f_n, zeta, at = best
    print(f"\none strike an idler turn ringing one mode: {f_n:.0f} Hz, damping {zeta:.2f}, at "
          f"{at:.2f} of the turn; explains {1 - left / np.sum(np.abs(measured) ** 2):.2f} of "
          "the energy of idler orders 30-66 (the mesh line aside)")


if __name__ == "__main__":
    main()
