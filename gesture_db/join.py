"""Join stretched samples into continuous bowing signals.

Inside a run (notes without rests) consecutive samples meet at a junction ``T``. Over a
window ``[T - x, T + x]`` (``x`` at most a quarter of either note) each sample is extended
by holding its edge value and the two are blended with complementary raised-cosine weights,
so force and beta (and velocity inside a slur) are continuous. At a bow change the velocity
of each side is faded to zero at ``T`` instead (``v_prev (t) sin(pi/2 |t - T| / x)`` before,
the same with ``v_next`` after), so it passes through zero exactly at the change, keeps each
stroke's sign and stays continuous.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from data_schemas.errors import ParameterError

#: Default half-width (s) of the junction window.
CROSSFADE = 0.03


@dataclass(frozen=True)
class Piece:
    """One stretched sample placed in time.

    Attributes
    ----------
    t0, t1 : float, s
        Span of the note.
    signal : callable
        ``signal(t) -> np.ndarray [shape=(len(t), 3)]`` velocity (m/s), force (N), beta at
        absolute times ``t`` (values held beyond the span).
    direction : int
        +1 down-bow, -1 up-bow.
    """

    t0: float
    t1: float
    signal: object
    direction: int


def join_run(pieces: list[Piece], t: np.ndarray, *, crossfade: float = CROSSFADE) -> np.ndarray:
    """Signals of one run of consecutive pieces on the frame times ``t``.

    Parameters
    ----------
    pieces : list of Piece
        In time order, each starting where the previous ends (``t0[m] == t1[m-1]``).
    t : np.ndarray [shape=(n,)], s
        Frame times (inside ``[pieces[0].t0, pieces[-1].t1]``).
    crossfade : float, s
        Half-width of the junction window.

    Returns
    -------
    np.ndarray [shape=(n, 3)]
        Velocity (m/s), force (N) and beta.
    """
    if not pieces:
        raise ParameterError("a run needs at least one piece")
    t = np.asarray(t, np.float64)
    out = np.zeros((t.size, 3))
    weight = np.zeros(t.size)
    x = [0.0] + [min(crossfade, 0.25 * (a.t1 - a.t0), 0.25 * (b.t1 - b.t0))
                 for a, b in zip(pieces[:-1], pieces[1:], strict=True)] + [0.0]
    change = [False] + [a.direction != b.direction
                        for a, b in zip(pieces[:-1], pieces[1:], strict=True)] + [False]
    for m, p in enumerate(pieces):
        xs, xe = x[m], x[m + 1]
        sel = np.flatnonzero((t >= p.t0 - xs) & (t <= p.t1 + xe))
        if sel.size == 0:
            continue
        tt = t[sel]
        w = np.ones(sel.size)   # weight of force and beta
        wv = np.ones(sel.size)  # factor of velocity
        if xs > 0:
            w *= _rise(tt, p.t0, xs)
            wv *= _fade_in(tt, p.t0, xs) if change[m] else _rise(tt, p.t0, xs)
        if xe > 0:
            w *= 1.0 - _rise(tt, p.t1, xe)
            wv *= _fade_in(-tt, -p.t1, xe, open_end=True) if change[m + 1] else \
                1.0 - _rise(tt, p.t1, xe)
        sig = np.asarray(p.signal(tt), np.float64)
        out[sel, 0] += wv * sig[:, 0]
        out[sel, 1:] += w[:, None] * sig[:, 1:]
        weight[sel] += w
    out[:, 1:] /= np.maximum(weight, 1e-12)[:, None]
    return out


def _fade_in(t: np.ndarray, T: float, x: float, open_end: bool = False) -> np.ndarray:
    """0 before ``T``, ``sin(pi/2 (t - T) / x)`` up to ``T + x``, then 1.

    With ``open_end`` the value at ``t == T`` itself is 0 on the other side too (the
    mirrored use for the end of a stroke, where ``T`` belongs to the next stroke).
    """
    u = np.clip((t - T) / x, 0.0, 1.0)
    out = np.sin(0.5 * np.pi * u)
    out[(t < T) | ((t <= T) & open_end)] = 0.0
    return out


def _rise(t: np.ndarray, T: float, x: float) -> np.ndarray:
    """Raised-cosine weight rising from 0 at ``T - x`` to 1 at ``T + x``."""
    u = np.clip((t - T + x) / (2 * x), 0.0, 1.0)
    return 0.5 - 0.5 * np.cos(np.pi * u)


__all__ = ["CROSSFADE", "Piece", "join_run"]
