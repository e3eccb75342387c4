"""Easing the bow when the loop hears lasting extra slips (zero crossings per period).

On the modal string multiple slipping at forces inside the Helmholtz window is a steady
regime beside Helmholtz motion: lightening the bow for a moment ends it and leaves
Helmholtz motion alone, while more force does not (:mod:`synth.regime_switches`,
``bench/regime_switch.py``). The trained classifiers do not hear it in music; the
listener's zero-crossing rate read per period of the expected pitch rises with the extra
slips (a double-slipping cello note: 10 crossings a period against a median of 5.7 for the
cello's good hops; README, "Multiple slipping is a second steady regime"). :class:`Easing`
counts the hops whose crossings per period reach a threshold and, after enough of them in
a row, eases the bow once per stroke.

Examples
--------
>>> e = Easing(threshold=9.0, after=2, factor=0.3, hops=3)
>>> [e.hear(c) for c in (10.0, 10.0, None, None, None, 10.0, 10.0)]
[False, True, False, False, False, False, False]
"""

from __future__ import annotations


def crossings_per_period(zcr: float, sample_rate: int, f0: float) -> float:
    """Zero crossings per period of ``f0`` from a zero-crossing rate per sample.

    Parameters
    ----------
    zcr : float
        Share of sample pairs that cross zero (the listener's ``zcr`` feature).
    sample_rate : int, Hz
    f0 : float, Hz
        Expected pitch (floored at 1 Hz).

    Returns
    -------
    float

    Examples
    --------
    >>> crossings_per_period(0.02, 44100, 441.0)
    2.0
    """
    return float(zcr) * sample_rate / max(float(f0), 1.0)


class Easing:
    """When one string's bow is eased within a stroke.

    Parameters
    ----------
    threshold : float
        Crossings per period that count as heard extra slips.
    after : int
        Hops in a row at or above ``threshold`` that start an easing.
    factor : float
        Force factor while eased.
    hops : int
        Hops the bow stays eased (the one that starts it included).
    """

    def __init__(self, threshold: float, after: int, factor: float, hops: int) -> None:
        self.threshold, self.after, self.ease, self.hops = threshold, after, factor, hops
        self.reset()

    def reset(self) -> None:
        """A new stroke: nothing counted, no easing yet."""
        self.left = 0
        self.high = 0
        self.done = False

    def hear(self, crossings: float | None) -> bool:
        """One hop: its crossings per period (None: not listened to). True when it eases.

        While an easing runs the hop only counts it down; once a stroke has been eased it
        is not eased again.
        """
        if self.left > 0:
            self.left -= 1
            return False
        if crossings is None or self.done:
            self.high = 0
            return False
        self.high = self.high + 1 if crossings >= self.threshold else 0
        if self.high < self.after:
            return False
        self.left, self.high, self.done = self.hops, 0, True
        return True

    @property
    def factor(self) -> float:
        """Force factor of the current hop (1 unless eased)."""
        return self.ease if self.left > 0 else 1.0


__all__ = ["Easing", "crossings_per_period"]
