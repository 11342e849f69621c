"""Steady state of the harvester without its stop: the phasor of the model's linear system.

The model declares itself, clear of its stops, as ``y' = M y + b a(t)`` (its
``linear_system``); under the base acceleration ``a(t) = A sin(w t) = Im(A e^{j w t})`` the
steady state is ``y = Im(Y e^{j w t})`` with ``(j w I - M) Y = b A``. For the tip-mass
model this is the textbook closed form (docs/model.md), its forcing corrected by the
base-forcing factor mu_1 (1 in the paper's model; ``A`` stands for mu_1 A above)::

    X = m mu_1 A / (k - m w^2 + j w c + j w theta^2 R / (1 + j w R C_p)),
    V = -j w theta R X / (1 + j w R C_p)
"""

from __future__ import annotations

import numpy as np

from .models import tip_mass


def linear_response(amplitude, frequency, base_forcing_factor=1.0, **parameters):
    """Complex amplitudes of x = Im(X e^{j w t}) and V = Im(V e^{j w t}) with no stop.

    Parameters
    ----------
    amplitude : float
        Base acceleration amplitude A [m/s^2].
    frequency : float or numpy.ndarray
        Excitation frequency f [Hz].
    base_forcing_factor : float or numpy.ndarray
        The base-forcing correction mu_1 [-]: the tip is forced by mu_1 A (1: the paper's
        model).
    **parameters
        The model's parameters its linear system reads (the tip-mass model: mass [kg],
        natural_frequency [Hz], damping_ratio [-], coupling [N/V], capacitance [F],
        resistance [Ohm]); any of them, and ``amplitude`` and ``frequency``, may be arrays
        (broadcast). Other parameters are ignored, so that a whole parameter dict can be
        passed.

    Returns
    -------
    X : complex numpy.ndarray
        Displacement amplitude [m].
    V : complex numpy.ndarray
        Voltage amplitude [V]; the mean power is |V|^2 / (2 R) [W].
    """
    forcing = np.multiply(base_forcing_factor, amplitude)  # mu_1 A [m/s^2]
    return phasor(*tip_mass.linear_system(**parameters), forcing, frequency)


def phasor(m, b, amplitude, frequency):
    """The complex amplitudes (X [m], V [V]) of the steady state of the model's linear
    system ``y' = M y + b a(t)`` (``m`` (..., n, n), ``b`` (n,)) under the base
    acceleration ``amplitude`` sin(2 pi ``frequency`` t) [m/s^2, Hz]; arrays broadcast."""
    system = 2j * np.pi * np.asarray(frequency, dtype=float)[..., None, None] * _EYE - m
    forcing = np.asarray(amplitude, dtype=float)[..., None, None] * b[:, None]
    try:
        y = np.linalg.solve(system, forcing)[..., 0]  # (stacks broadcast against each other)
    except np.linalg.LinAlgError:  # undamped and at resonance: unbounded, inf
        shape = np.broadcast_shapes(system.shape[:-2], forcing.shape[:-2])
        system = np.broadcast_to(system, shape + system.shape[-2:])
        forcing = np.broadcast_to(forcing, shape + forcing.shape[-2:])
        y = np.full(shape + (len(b),), complex(np.inf, np.inf))
        for i in np.ndindex(shape):
            if np.linalg.matrix_rank(system[i]) == len(b):
                y[i] = np.linalg.solve(system[i], forcing[i])[:, 0]
    return y[..., _COMPONENT["x"]], y[..., _COMPONENT["voltage"]]


_COMPONENT = {c.name: i for i, c in enumerate(tip_mass.STATE)}
_EYE = np.eye(len(tip_mass.STATE))
