"""Two regimes at one bowing: Helmholtz motion, multiple slipping, and what switches them.

On this model multiple slipping is not only a transient: at forces inside the Helmholtz
window it is a second steady regime beside Helmholtz motion, and which one a string plays
depends on how it got there. :func:`regime_switch` measures it on the block API of
:class:`synth.instrument.Instrument` (no body), as :mod:`synth.note_changes` does:

1. the bow is set on the string at the bowing's force and speeds up at
   :data:`ACCELERATION` to ``bow_velocity`` (beta held); the regime is read over the
   :data:`WINDOW` s before :data:`PULSE_AT`;
2. at :data:`PULSE_AT` the force is pushed to ``pulse`` x for :data:`PULSE_TIME` s (a bump
   of the arm); the regime is read again before :data:`RELIEF_AT`;
3. at :data:`RELIEF_AT` the force is eased to ``relief`` x for ``relief_time`` s (a player
   lightening the bow; ``relief=1`` leaves it alone, above 1 the bow is pressed harder
   instead); the regime is read from :data:`SETTLE` s after the relief's end, over
   :data:`WINDOW` s.

The regime is the slip count per nominal period of the open string (the instrument's slip
record): 1 in Helmholtz motion, about 2 or 3 in double or triple slipping. The attack after
the relief is timed as :func:`synth.note_changes.measure_change` times one: to the first
of five regular periods.

Examples
--------
>>> r = regime_switch("cello", 2, bow_force=0.57, bow_velocity=0.12, beta=0.165, relief=1.0)
>>> round(r.before_pulse), round(r.after_pulse), round(r.after_relief)
(1, 2, 2)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from data_schemas.errors import ParameterError
from synth.controls import BowControl
from synth.instrument import Instrument
from synth.note_changes import check_bowing, measure_change, slip_onsets

#: Bow acceleration of the start, m/s^2.
ACCELERATION = 5.0
#: Start (s from the bow's start) and length (s) of the pulse.
PULSE_AT, PULSE_TIME = 0.7, 0.03
#: Start of the relief, s from the bow's start.
RELIEF_AT = 1.0
#: Length of each window the regime is read over, s.
WINDOW = 0.2
#: Time after the relief's end before the last window, s.
SETTLE = 0.3
#: Largest relief factor (above 1 the bow is pressed harder instead of eased).
MAX_RELIEF = 4.0
#: Slips per period within this of 1 read as Helmholtz motion.
HELMHOLTZ_TOLERANCE = 0.15


@dataclass(frozen=True)
class RegimeSwitch:
    """One measured set-up.

    Attributes
    ----------
    before_pulse, after_pulse, after_relief : float
        Slips per nominal period over the window before the pulse, before the relief and
        from :data:`SETTLE` s after the relief's end.
    attack : float or None, s
        From the relief's end to the first of five regular periods (None: not within
        0.4 s).
    """

    before_pulse: float
    after_pulse: float
    after_relief: float
    attack: float | None

    @staticmethod
    def helmholtz(slips_per_period: float) -> bool:
        """Whether a slip rate (per period) reads as Helmholtz motion.

        Examples
        --------
        >>> RegimeSwitch.helmholtz(1.1), RegimeSwitch.helmholtz(2.0)
        (True, False)
        """
        return abs(slips_per_period - 1.0) <= HELMHOLTZ_TOLERANCE


def _rate(onsets: np.ndarray, f0: float, start: float, end: float) -> float:
    inside = (onsets >= start) & (onsets < end)
    return float(np.count_nonzero(inside) / ((end - start) * f0))


def _check(bow_force: float, bow_velocity: float, beta: float, pulse: float, relief: float,
           relief_time: float) -> None:
    check_bowing(bow_force, bow_velocity, beta)
    if not (pulse > 0.0 and 0.0 <= relief <= MAX_RELIEF and 0.0 < relief_time <= 0.5):
        raise ParameterError(f"need pulse > 0, 0 <= relief <= {MAX_RELIEF:g} and 0 < "
                             f"relief_time <= 0.5 s; got {pulse}, {relief}, {relief_time}")
    if bow_force * max(pulse, relief, 1.0) > 50.0:
        raise ParameterError(f"bow_force={bow_force} N x pulse={pulse} or relief={relief} "
                             f"exceeds 50 N")


def regime_switch(instrument: str, string: int, *, bow_force: float, bow_velocity: float,
                  beta: float, pulse: float = 2.0, relief: float = 0.3,
                  relief_time: float = 0.1, seed: int = 0) -> RegimeSwitch:
    """Bow an open string steadily, bump the force, then ease it; the regime after each.

    Parameters
    ----------
    instrument : str
    string : int
        String index, 0 = lowest (played open).
    bow_force : float, N
    bow_velocity : float, m/s
    beta : float
        Bow-bridge distance / string length.
    pulse : float
        Force factor of the bump (1: none).
    relief : float
        Force factor while the bow is eased, 0..:data:`MAX_RELIEF` (1: no relief; above
        1 the bow is pressed harder).
    relief_time : float, s
    seed : int
        Seed of the instrument.

    Returns
    -------
    RegimeSwitch

    Examples
    --------
    >>> r = regime_switch("cello", 2, bow_force=0.57, bow_velocity=0.12, beta=0.165)
    >>> round(r.after_pulse), round(r.after_relief), r.attack < 0.05
    (2, 1, True)
    """
    _check(bow_force, bow_velocity, beta, pulse, relief, relief_time)
    relief_end = RELIEF_AT + relief_time

    def control(inst: Instrument, t: float) -> BowControl:
        force = bow_force
        if PULSE_AT <= t < PULSE_AT + PULSE_TIME:
            force *= pulse
        elif RELIEF_AT <= t < relief_end:
            force *= relief
        return BowControl(min(ACCELERATION * t, bow_velocity), force, beta)

    end = relief_end + SETTLE + WINDOW
    onsets, f0 = slip_onsets(instrument, string, seed, end, control)
    return RegimeSwitch(_rate(onsets, f0, PULSE_AT - WINDOW, PULSE_AT),
                        _rate(onsets, f0, RELIEF_AT - WINDOW, RELIEF_AT),
                        _rate(onsets, f0, end - WINDOW, end),
                        measure_change(onsets, f0, f0, relief_end).attack)


__all__ = ["ACCELERATION", "HELMHOLTZ_TOLERANCE", "MAX_RELIEF", "PULSE_AT", "PULSE_TIME",
           "RELIEF_AT", "RegimeSwitch", "SETTLE", "WINDOW", "regime_switch"]
