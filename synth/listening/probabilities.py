"""Class probabilities of the one-vs-one SVC from its decision values.

The controller weighs its correction by how sure it is: :func:`vote_probabilities` turns the
decision values of :func:`synth.listening.svm_kernel.svc_decisions` into probabilities.
"""

from __future__ import annotations

import numpy as np

#: The teacher's classes.
CLASSES = (1, 2, 3, 4, 5)
#: Sharpness of the soft one-vs-one vote (per unit decision value) and of the softmax over
#: the soft votes (per vote): a class winning every pair by a unit margin gets ~0.85 of 5.
VOTE_SHARPNESS = 2.0


def vote_probabilities(decisions: np.ndarray, n_class: int) -> np.ndarray:
    """Class probabilities from one-vs-one decision values (softmax over soft votes).

    Each pair ``(i, j)`` (libsvm's order) gives class ``i`` the soft vote
    ``sigmoid(a d)`` and ``j`` the rest, ``a`` = :data:`VOTE_SHARPNESS`; the probabilities
    are the softmax of ``a`` x the soft vote counts, so they sum to 1 and rise with every
    decision value in a class's favour.

    Parameters
    ----------
    decisions : np.ndarray [shape=(n_class * (n_class - 1) / 2,)]
    n_class : int

    Returns
    -------
    np.ndarray [shape=(n_class,)]

    Examples
    --------
    >>> p = vote_probabilities(np.array([3.0]), 2)
    >>> bool(p[0] > p[1]), round(float(p.sum()), 12)
    (True, 1.0)
    """
    d = np.asarray(decisions, np.float64)
    soft = 1.0 / (1.0 + np.exp(-VOTE_SHARPNESS * d))
    votes = np.zeros(n_class)
    k = 0
    for i in range(n_class):
        for j in range(i + 1, n_class):
            votes[i] += soft[k]
            votes[j] += 1.0 - soft[k]
            k += 1
    e = np.exp(VOTE_SHARPNESS * (votes - votes.max()))
    return e / e.sum()
