"""Initial forces that rise with the dynamic: p <= mp <= mf <= f on every string and finger.

Training searches each string x dynamic's initial force on its own, and a noisy search can
invert the order (the cello's C string trained p 5.1-7.0 N against f 1.4-1.8 N). A louder
lane plays faster and nearer the bridge and needs more force, so :func:`monotone_in_dynamic`
replaces each string's forces at a finger by their isotonic fit across the dynamics (pool
adjacent violators, equal weights): unchanged where already ordered.
"""

from __future__ import annotations

import numpy as np


def isotonic(values: list[float]) -> list[float]:
    """The non-decreasing sequence nearest ``values`` in least squares (pool adjacent violators).

    Examples
    --------
    >>> isotonic([1.0, 3.0, 2.0, 4.0])
    [1.0, 2.5, 2.5, 4.0]
    >>> isotonic([6.0, 1.5])
    [3.75, 3.75]
    """
    blocks: list[list[float]] = []  # [sum, count]
    for v in values:
        blocks.append([float(v), 1.0])
        while len(blocks) > 1 and blocks[-2][0] / blocks[-2][1] > blocks[-1][0] / blocks[-1][1]:
            total, count = blocks.pop()
            blocks[-1][0] += total
            blocks[-1][1] += count
    out: list[float] = []
    for total, count in blocks:
        out.extend([total / count] * int(count))
    return out


def monotone_in_dynamic(forces: dict[str, list[float]], order: tuple[str, ...]) -> dict:
    """Initial forces of one string made non-decreasing in the dynamic, finger by finger.

    Parameters
    ----------
    forces : dict of str to list of float
        Per dynamic, the initial forces (N) at each finger.
    order : tuple of str
        Dynamics from softest to loudest (those absent are skipped).

    Returns
    -------
    dict of str to list of float
        The same keys, forces in N.

    Examples
    --------
    >>> monotone_in_dynamic({"p": [6.0, 7.0], "f": [1.5, 1.8]}, ("p", "mp", "mf", "f"))
    {'p': [3.75, 4.4], 'f': [3.75, 4.4]}
    """
    present = [d for d in order if d in forces]
    table = np.array([forces[d] for d in present], np.float64)
    fitted = np.array([isotonic(list(column)) for column in table.T]).T
    return {d: [float(f) for f in fitted[i]] for i, d in enumerate(present)}
