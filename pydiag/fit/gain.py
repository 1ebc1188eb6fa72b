"""The model's level at a sensor: one gain a channel, or a gain curve over frequency.

Both enter linearly and are fitted in closed form at every evaluation, to the measured
amplitudes with the noise taken out (``R~ = sqrt(max(R^2 - P, 0))``):

- a gain: ``g = sum(S R~) / sum(S^2)`` (least squares, not below 0);
- a gain curve (``--gain curve``): a real accelerometer sits on a housing whose transfer
  from the mesh varies over the band by more than the model's own dynamics say. The curve
  is piecewise linear in frequency between nodes at every stage's mesh harmonics (flat
  below the first and above the last), its node values non-negative least squares. Each
  mesh harmonic's level is then the housing's, and the model is judged on the pattern of
  lines around each harmonic (sidebands against their carrier, the shafts' comb between
  them), not on the spectrum's shape: what the transfer path of a real record does not
  let a pair model match. Nodes closer than :data:`MIN_NODE_SPACING` of the finest mesh
  spacing are one node (another stage's harmonic a few hertz from this one's).
"""

from __future__ import annotations

import numpy as np

from pydiag.gear.kinematics import GearKinematics

#: Nodes of a gain curve closer than this share of the smallest mesh frequency are merged.
MIN_NODE_SPACING = 0.25


def fitted_gain(model: np.ndarray, clean: np.ndarray) -> float:
    """The least-squares gain of ``model`` onto ``clean`` (0 at least; 1 for a model
    without power)."""
    power = float(np.dot(model, model))
    return max(float(np.dot(model, clean)) / power, 0.0) if power > 0 else 1.0


def curve_nodes(kinematics: GearKinematics, top_hz: float) -> np.ndarray:
    """The frequencies, Hz, of a gain curve's nodes: every stage's mesh harmonics up to
    the first at or above ``top_hz``, those closer than MIN_NODE_SPACING of the smallest
    mesh frequency merged into their mean."""
    meshes = [s.f_mesh_hz for s in kinematics.stages()]
    harmonics = sorted(h * f for f in meshes
                       for h in range(1, int(np.ceil(top_hz / f)) + 1))
    merged: list[list[float]] = []
    for f in harmonics:
        if merged and f - merged[-1][-1] < MIN_NODE_SPACING * min(meshes):
            merged[-1].append(f)
        else:
            merged.append([f])
    return np.array([np.mean(group) for group in merged])


def curve_basis(freq_hz: np.ndarray, nodes_hz: np.ndarray) -> np.ndarray:
    """(n_freq, n_nodes): each node's hat function at ``freq_hz`` (linear interpolation
    between nodes, the end nodes' value beyond them)."""
    eye = np.eye(nodes_hz.size)
    return np.column_stack([np.interp(freq_hz, nodes_hz, eye[j]) for j in range(nodes_hz.size)])


def fitted_curve(model: np.ndarray, clean: np.ndarray, basis: np.ndarray) -> np.ndarray:
    """The curve's node values (non-negative least squares) that scale ``model`` onto
    ``clean``, at the bins ``basis`` (:func:`curve_basis`) is of."""
    from scipy.optimize import nnls  # here: importing it takes 0.3 s of every command's start

    return nnls(basis * model[:, None], clean)[0]


def apply_curve(signal: np.ndarray, sample_rate_hz: float, nodes_hz: np.ndarray,
                values: np.ndarray) -> np.ndarray:
    """``signal`` through the zero-phase filter whose gain is the curve (``nodes_hz``,
    ``values``): its spectrum at whole-period bins is the curve times the signal's."""
    spectrum = np.fft.rfft(signal)
    freqs = np.fft.rfftfreq(signal.size, 1.0 / sample_rate_hz)
    return np.fft.irfft(spectrum * np.interp(freqs, nodes_hz, values), n=signal.size)
