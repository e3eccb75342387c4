"""The control law's force factor of one hop, from the classifier's class probabilities.

:func:`correction` is the law the feedback controller (:mod:`synth.listening.controller`)
applies each hop once it has listened long enough: ``step ** E[3 - c]`` under the averaged
probabilities of classes 1..5, unless the sound is good enough or neither side is sure.
"""

from __future__ import annotations

import numpy as np

#: 3 - c of the classes 1..5: the direction the force should move (class 2: up).
DIRECTION = np.array([2.0, 1.0, 0.0, -1.0, -2.0])


def correction(probabilities: np.ndarray, step: float, good_share: float,
               sure: float = 0.0) -> float:
    """Force factor of one hop from averaged class probabilities.

    ``step ** E[3 - c]`` under ``probabilities`` (of classes 1..5); 1 while class 3 holds at
    least ``good_share``, or while neither side (classes 1-2, "too little"; classes 4-5,
    "too much") holds at least ``sure``.

    Parameters
    ----------
    probabilities : np.ndarray [shape=(5,)]
        Probabilities of classes 1..5 (averaged over the last hops).
    step : float
        Force factor per hop at full confidence (> 1).
    good_share : float
        Class-3 probability from which the force is left alone.
    sure : float
        Probability one side must hold before the law acts (0: always).

    Returns
    -------
    float
        Factor to multiply the bow force by.

    Examples
    --------
    >>> correction(np.array([0.0, 1.0, 0.0, 0.0, 0.0]), 1.2, 0.5)  # surely too little
    1.2
    >>> correction(np.array([0.0, 0.3, 0.6, 0.1, 0.0]), 1.2, 0.5)  # good enough
    1.0
    """
    if probabilities[2] >= good_share:
        return 1.0
    if max(probabilities[0] + probabilities[1], probabilities[3] + probabilities[4]) < sure:
        return 1.0
    return float(step ** float(probabilities @ DIRECTION))


__all__ = ["DIRECTION", "correction"]
