"""Closed-form steady state of the harvester without its stop (phasors, docs/model.md)."""

from __future__ import annotations

import numpy as np


def linear_response(mass, natural_frequency, damping_ratio, coupling, capacitance, resistance,
                    amplitude, frequency, **_):
    """Complex amplitudes of x = Im(X e^{j w t}) and V = Im(V e^{j w t}) with no stop.

    X = m A / (k - m w^2 + j w c + j w theta^2 R / (1 + j w R C_p)),
    V = -j w theta R X / (1 + j w R C_p), with k = m wn^2, c = 2 zeta m wn.

    Parameters
    ----------
    mass : float
        Tip mass m [kg].
    natural_frequency : float
        f_n [Hz].
    damping_ratio : float
        zeta [-].
    coupling : float
        theta [N/V].
    capacitance : float
        C_p [F].
    resistance : float
        R [Ohm].
    amplitude : float
        Base acceleration amplitude A [m/s^2].
    frequency : float or numpy.ndarray
        Excitation frequency f [Hz]; any of the parameters may be an array (broadcast).
    **_
        Other parameters, ignored, so that a whole parameter dict can be passed.

    Returns
    -------
    X : complex numpy.ndarray
        Displacement amplitude [m].
    V : complex numpy.ndarray
        Voltage amplitude [V]; the mean power is |V|^2 / (2 R) [W].
    """
    wn = 2 * np.pi * np.asarray(natural_frequency)
    w = 2 * np.pi * np.asarray(frequency)
    k, c = mass * wn**2, 2 * damping_ratio * mass * wn
    load = 1 + 1j * w * resistance * capacitance
    X = mass * amplitude / (k - mass * w**2 + 1j * w * c + 1j * w * coupling**2 * resistance / load)
    return X, -1j * w * coupling * resistance * X / load
