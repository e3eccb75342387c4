"""Torsional modes of a string, coupled at the bow through the string's radius.

The bow grips the string's surface, so the surface velocity under the bow is the transverse
velocity plus the radius times the angular velocity. Seen at the surface, torsion behaves
like a second string on the same length (bridge to finger) with its own wave speed
``c_t = ratio_f * c`` and impedance ``Z_t = ratio_z * Z0`` (c, Z0: the transverse wave speed
and impedance), so its "linear density" is ``Z_t / c_t`` and its "tension" ``Z_t c_t``. Its
modes are heavily damped (quality factor ``torsion_q``, frequency independent) and do not
drive the bridge: they take up part of the bow's friction force and so damp the ripples
that would otherwise set off extra slips, without damping the transverse partials that are
heard. The finger clamps the string's rotation, so the torsional modes live on the stopped
length.

Figures (shared/reference/modal-string.md and the literature it cites): torsional
fundamentals 2-7 times the transverse one, torsional impedance at the surface of the order
of the transverse impedance, Q of the order of 10-50.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from synth.strings import StringConstants


@dataclass(frozen=True)
class TorsionModes:
    """Torsional modes of one stopped length, as the kernel's exact step needs them.

    Attributes
    ----------
    omega : np.ndarray [shape=(n_modes,)], rad/s
    free : np.ndarray [shape=(4, n_modes)]
        ``(c_aa, c_av, c_va, c_vv)`` of the exact damped step.
    force_to_displacement, force_to_velocity : np.ndarray [shape=(n_modes,)]
        End-of-step surface displacement (m/N) and velocity (m/(s N)) per unit modal force.
    shape_bow : np.ndarray [shape=(n_modes,)], 1/sqrt(m)
        Mode shapes at the bow. Modes at or above the frequency limit have zero
        coefficients (they stay at rest).
    """

    omega: np.ndarray
    free: np.ndarray
    force_to_displacement: np.ndarray
    force_to_velocity: np.ndarray
    shape_bow: np.ndarray

    @property
    def n_modes(self) -> int:
        """Number of torsional modes (including frozen ones)."""
        return self.omega.size


def torsion_mode_count(string: StringConstants, limit: float) -> int:
    """Torsional modes of the open string below ``limit`` Hz (0 without torsion)."""
    if string.torsion_frequency_ratio <= 0.0:
        return 0
    first = string.torsion_frequency_ratio * string.mode_frequency(1)
    return max(int(math.ceil(limit / first)) - 1, 0)


def torsion_modes(string: StringConstants, effective_length: float, bow_distance: float,
                  sample_rate: float, limit: float, n_modes: int) -> TorsionModes:
    """Torsional modes on ``effective_length`` (m), read at the bow ``bow_distance`` (m).

    Parameters
    ----------
    string : StringConstants
    effective_length : float, m
        Bridge to finger (or nut).
    bow_distance : float, m
        Bow-bridge distance.
    sample_rate : float, Hz
        Internal rate of the simulation.
    limit : float, Hz
        Modes at or above this frequency are frozen (zero coefficients).
    n_modes : int
        Number of modes returned (:func:`torsion_mode_count` of the open string).

    Returns
    -------
    TorsionModes
    """
    if n_modes <= 0:
        return no_torsion()
    c = math.sqrt(string.tension / string.linear_density)
    speed = string.torsion_frequency_ratio * c
    impedance = string.torsion_impedance_ratio * string.impedance
    density = impedance / speed
    n = np.arange(1, n_modes + 1)
    k = n * math.pi / effective_length
    omega = speed * k
    keep = omega / (2.0 * math.pi) < limit
    decay = omega / (2.0 * string.torsion_q)
    wd = np.sqrt(omega**2 - decay**2)
    h = 1.0 / sample_rate
    e = np.exp(-decay * h)
    cos, sin = np.cos(wd * h), np.sin(wd * h)
    free = np.stack([e * (cos + decay * sin / wd), e * sin / wd,
                     -e * (wd + decay**2 / wd) * sin, e * (cos - decay * sin / wd)])
    static = 1.0 / (density * omega**2)
    to_disp = (1.0 - free[0]) * static
    to_vel = -free[2] * static
    shape = math.sqrt(2.0 / effective_length) * np.sin(k * bow_distance)
    for row in (free, to_disp, to_vel, shape):
        row[..., ~keep] = 0.0
    return TorsionModes(omega, free, to_disp, to_vel, shape)


def no_torsion() -> TorsionModes:
    """An empty set of torsional modes (strings without torsion)."""
    empty = np.zeros(0)
    return TorsionModes(empty, np.zeros((4, 0)), empty, empty, empty)
