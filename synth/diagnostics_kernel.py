"""Slip counting over one block's stick-slip states (numba), behind a checking wrapper.

:func:`summarise_slips` is the entry point; the slow numpy twin that checks it is
``naive_summarise_slips`` in ``tests/naive_kernels.py``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from synth.array_checks import check_array, check_size
from synth.modal_kernel import OFF_STRING, SLIPPING

#: A slip counts (as an onset) once the string slides past the bow at this share of the
#: bow's speed. Near the lower force limit the string also releases for 3-4 internal samples
#: at 0.02-0.05 m/s against a 0.33 m/s bow (a Helmholtz flyback slides at about 3 m/s):
#: such micro-slips leave the sound unchanged (harmonics within 0.4 dB) but, counted, made
#: Helmholtz motion look like multiple slipping to the teacher (violin A string, mf lane).
SLIP_ONSET_SPEED_RATIO = 0.5


@njit(cache=True)
def _summarise(stick_slip, slip_velocity, bow_velocity, counted, onsets):  # pragma: no cover
    """Count slips (onset samples written to ``onsets``), slipping and contact samples, slip sum.

    ``counted`` says whether the slip under way when the block starts has been counted
    (False when none is); returns it for the block's end too.
    """
    n_onsets = 0
    n_slip = 0
    n_contact = 0
    slip_sum = 0.0
    for i in range(stick_slip.size):
        if stick_slip[i] == SLIPPING:
            n_slip += 1
            slip_sum += slip_velocity[i]
            if not counted and slip_velocity[i] >= SLIP_ONSET_SPEED_RATIO * abs(bow_velocity[i]):
                onsets[n_onsets] = i
                n_onsets += 1
                counted = True
        else:
            counted = False
        if stick_slip[i] != OFF_STRING:
            n_contact += 1
    return n_onsets, n_slip, n_contact, slip_sum, counted


def summarise_slips(stick_slip: np.ndarray, slip_velocity: np.ndarray,
                    bow_velocity: np.ndarray,
                    counted: bool) -> tuple[np.ndarray, int, int, float, bool]:
    """Count a block's slips, slipping samples and contact samples.

    A slip is a run of slipping samples; it counts once, at its first sample whose slip
    velocity reaches :data:`SLIP_ONSET_SPEED_RATIO` of the bow's speed.

    Parameters
    ----------
    stick_slip : np.ndarray [shape=(n,)], int8
        Stick-slip state per sample (:data:`synth.modal_kernel.OFF_STRING`, ``STICKING``,
        ``SLIPPING``).
    slip_velocity : np.ndarray [shape=(n,)], float64, m/s
        Slip velocity per sample.
    bow_velocity : np.ndarray [shape=(n,)], float64, m/s
        Bow velocity per sample.
    counted : bool
        Whether the slip under way when the block starts (if any) has been counted already.

    Returns
    -------
    onsets : np.ndarray [shape=(n_onsets,)], int64
        Block sample of each counted slip's onset.
    n_slip : int
        Slipping samples.
    n_contact : int
        Samples with the string in contact (not ``OFF_STRING``).
    slip_sum : float, m/s
        Sum of the slip velocity over the slipping samples.
    counted : bool
        Whether a slip under way at the block's end has been counted (for the next block).

    Raises
    ------
    ParameterError
        An argument of another dtype or shape, or arrays of unequal length.
    """
    check_array("stick_slip", stick_slip, np.int8, 1)
    check_array("slip_velocity", slip_velocity, np.float64, 1)
    check_array("bow_velocity", bow_velocity, np.float64, 1)
    check_size("slip_velocity", slip_velocity, stick_slip.size, "one per stick_slip sample")
    check_size("bow_velocity", bow_velocity, stick_slip.size, "one per stick_slip sample")
    onsets = np.empty(stick_slip.size, np.int64)
    n_onsets, n_slip, n_contact, slip_sum, counted = _summarise(
        stick_slip, slip_velocity, bow_velocity, bool(counted), onsets)
    return onsets[:n_onsets], n_slip, n_contact, slip_sum, counted


__all__ = ["SLIP_ONSET_SPEED_RATIO", "summarise_slips"]
