"""Bow speed curves: how fast a stroke may speed up and slow down.

- :func:`limit_acceleration`: lower a target speed curve until no segment changes faster
  than the bow's acceleration limit.
- :func:`stroke_acceleration`: the limit a stroke is played with (a short stroke may
  accelerate faster, so that it reaches its speed within :data:`SHORT_STROKE_RAMP`).
"""

from __future__ import annotations

from typing import Any

import numpy as np


def limit_acceleration(t: np.ndarray, speed: np.ndarray,
                       max_acceleration: float | np.ndarray) -> np.ndarray:
    """Lower a speed curve until no segment changes faster than ``max_acceleration``.

    Parameters
    ----------
    t : np.ndarray [shape=(n,)], s
        Increasing times.
    speed : np.ndarray [shape=(n,)], m/s
        Target speeds (>= 0); the result is pointwise <= the target.
    max_acceleration : float or np.ndarray [shape=(n - 1,)], m/s^2
        Largest allowed change of speed per second (one value, or one per segment).

    Returns
    -------
    np.ndarray [shape=(n,)], m/s
    """
    v = speed.astype(np.float64).tolist()
    dv = (np.diff(t) * max_acceleration).tolist()
    n = len(v)
    for k in range(1, n):
        cap = v[k - 1] + dv[k - 1]
        if v[k] > cap:
            v[k] = cap
    for k in range(n - 2, -1, -1):
        cap = v[k + 1] + dv[k]
        if v[k] > cap:
            v[k] = cap
    return np.asarray(v)


#: A short stroke reaches its speed within this share of its length (when
#: ``bow.short_stroke_acceleration`` allows).
SHORT_STROKE_RAMP = 0.25


def stroke_acceleration(t: np.ndarray, target: np.ndarray, bow: dict[str, Any]) -> float:
    """The bow acceleration a stroke is played with, m/s^2.

    ``bow.max_acceleration``, unless the stroke is too short to reach its largest target
    speed within :data:`SHORT_STROKE_RAMP` of its length at that rate: then the rate that
    does, up to ``bow.short_stroke_acceleration``.

    Parameters
    ----------
    t : np.ndarray [shape=(n,)], s
        The stroke's times.
    target : np.ndarray [shape=(n,)], m/s
        Its target speeds.
    bow : dict
        The ``[bow]`` settings.

    Examples
    --------
    >>> bow = {"max_acceleration": 5.0, "short_stroke_acceleration": 20.0}
    >>> stroke_acceleration(np.array([0.0, 1.0]), np.array([0.3, 0.3]), bow)
    5.0
    >>> round(stroke_acceleration(np.array([0.0, 0.12]), np.array([0.3, 0.3]), bow), 6)
    10.0
    >>> stroke_acceleration(np.array([0.0, 0.03]), np.array([0.3, 0.3]), bow)
    20.0
    """
    base = float(bow["max_acceleration"])
    length = float(t[-1] - t[0]) if t.size > 1 else 0.0
    if length <= 0.0 or not target.size:
        return base
    needed = float(np.max(target)) / (SHORT_STROKE_RAMP * length)
    return float(min(max(base, needed), max(base, bow["short_stroke_acceleration"])))
