"""How a stroke starts decides its regime: force ramps and a player's attack.

The Schelleng windows of :mod:`synth.playability_maps` bow each force from rest, so each
limit they find is where an abrupt start (5 m/s^2 with the full force) lands, which is
Guettler's question as much as Schelleng's. Two other measurements, both on the public
block API of :class:`synth.instrument.Instrument` (no body):

- :func:`ramped_limit`: Helmholtz motion is set up at a force inside the window, then the
  force glides (exponentially) down or up at constant bow velocity and beta; the limit is
  the force at which Helmholtz motion ends: the edge of the regime's existence, as force
  ramps on a bowing machine find it;
- :func:`bitten_stroke`: a player's attack on a light note: the bow starts at a force
  whose attack speaks (the string's reference force), then lightens to the note's force
  over ``settle_time``; the regime is judged on the settled part, like
  :func:`synth.playability.steady_stroke`.

Examples
--------
>>> f = ramped_limit("violin", 1, bow_velocity=0.3, beta=0.1, start_force=1.0,
...                  end_force=0.005)
>>> 0.005 < f < 0.1
True
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from synth.controls import BowControl
from synth.instrument import Instrument
from synth.playability import PERIOD_TOLERANCE
from synth.strings import InstrumentConstants

HOP = 256
#: Blocks of Helmholtz motion required before a ramp starts (else no limit is found).
SETTLED_BLOCKS = 10
#: Periods each side of a block whose slip intervals judge it.
JUDGED_PERIODS = 3


def _onsets(instrument: str | InstrumentConstants, string: int, beta: float, duration: float,
            control: Callable[[float], tuple[float, float]], seed: int
            ) -> tuple[np.ndarray, np.ndarray, float]:
    """Slip-onset times, block start times and the string's nominal frequency."""
    inst = Instrument(instrument, seed=seed, body=None)
    rate = inst.sample_rate
    n_blocks = int(round(duration * rate / HOP))
    onsets, starts = [], np.arange(n_blocks) * HOP / rate
    for t in starts:
        speed, force = control(float(t))
        onsets.append(inst.process(HOP, {string: BowControl(speed, force, beta)})
                      .diagnostics[string].onset_times)
    f0 = inst.voices[string].string.nominal_frequency(inst.constants.tuning_a4)
    return np.concatenate(onsets), starts, float(f0)


def _helmholtz_blocks(onsets: np.ndarray, starts: np.ndarray, f0: float) -> np.ndarray:
    """Per block: every slip interval within +-3 periods of its centre is one period."""
    period = 1.0 / f0
    centres = starts + 0.5 * (starts[1] - starts[0]) if starts.size > 1 else starts
    out = np.zeros(starts.size, bool)
    for i, c in enumerate(centres):
        near = onsets[(onsets > c - JUDGED_PERIODS * period) & (onsets < c + JUDGED_PERIODS
                                                                 * period)]
        iv = np.diff(near) * f0
        out[i] = iv.size >= 3 and bool(np.all(np.abs(iv - 1.0) < PERIOD_TOLERANCE))
    return out


def ramped_limit(instrument: str | InstrumentConstants, string: int, *, bow_velocity: float,
                 beta: float, start_force: float, end_force: float, acceleration: float = 0.5,
                 hold: float = 0.4, ramp: float = 2.0, seed: int = 0) -> float | None:
    """Force (N) at which Helmholtz motion ends while the force glides to ``end_force``.

    Parameters
    ----------
    instrument : str or InstrumentConstants
        Instrument name, or constants to try (:func:`synth.strings.load_instrument`).
    string : int
        0 = lowest.
    bow_velocity : float, m/s
    beta : float
    start_force : float, N
        Force of the start and the hold, inside the window.
    end_force : float, N
        Force the glide ends at (below ``start_force``: the lower limit; above: the upper).
    acceleration : float, m/s^2
        Bow acceleration of the start.
    hold, ramp : float, s
        Time at ``start_force``, then time of the exponential glide.
    seed : int

    Returns
    -------
    float or None
        None when the stroke is not in Helmholtz motion when the glide starts;
        ``end_force`` when it never leaves it.
    """
    def control(t: float) -> tuple[float, float]:
        x = min(max(t - hold, 0.0) / ramp, 1.0)
        return min(bow_velocity, acceleration * t), start_force * (end_force
                                                                   / start_force) ** x

    onsets, starts, f0 = _onsets(instrument, string, beta, hold + ramp, control, seed)
    helm = _helmholtz_blocks(onsets, starts, f0)
    first = int(np.searchsorted(starts, hold))
    if not helm[first:first + SETTLED_BLOCKS].all():
        return None
    lost = np.flatnonzero(~helm[first:])
    return float(control(starts[first + lost[0]])[1]) if lost.size else float(end_force)


def bitten_stroke(instrument: str | InstrumentConstants, string: int, *, bow_force: float,
                  bite_force: float, bow_velocity: float = 0.3, beta: float = 0.1,
                  bite_time: float = 0.1, settle_time: float = 0.6, acceleration: float = 5.0,
                  duration: float = 1.5, analysed: float = 0.5, seed: int = 0) -> bool:
    """Whether a light note started at ``bite_force`` settles in Helmholtz motion.

    The bow is set on the string at ``max(bite_force, bow_force)`` and accelerates at
    ``acceleration`` to ``bow_velocity``; after ``bite_time`` the force glides
    (exponentially) to ``bow_force`` over ``settle_time`` and stays. The last ``analysed``
    s are judged: Helmholtz motion when at least 90 % of the slip intervals are one period
    (within 3 %) and there is about one slip per period, as
    :attr:`synth.playability.StrokeReport.is_helmholtz`.
    """
    start = max(bite_force, bow_force)

    def control(t: float) -> tuple[float, float]:
        x = min(max(t - bite_time, 0.0) / settle_time, 1.0)
        return min(bow_velocity, acceleration * t), start * (bow_force / start) ** x

    onsets, _, f0 = _onsets(instrument, string, beta, duration, control, seed)
    tail = onsets[onsets >= duration - analysed]
    iv = np.diff(tail) * f0
    share = float(np.mean(np.abs(iv - 1.0) < PERIOD_TOLERANCE)) if iv.size else 0.0
    return share >= 0.9 and abs(tail.size / (analysed * f0) - 1.0) < 0.1


__all__ = ["bitten_stroke", "ramped_limit"]
