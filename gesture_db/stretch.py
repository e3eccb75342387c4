"""Time-stretch a gesture sample to a score duration, keeping its attack and release shapes.

The warp maps target time ``t`` in [0, D_target] to sample time ``u`` in [0, D_sample] with
slope 1 over the first and last ``edge`` seconds (the attack and the release are copied
unchanged), a constant slope ``c`` in the middle, and raised-cosine transitions of the slope
over the next ``edge`` seconds, so the warp is C1 and monotone. ``c`` follows from
``u(D_target) = D_sample``. The edge shrinks to a quarter of the shorter duration, so the
middle slope stays positive.
"""

from __future__ import annotations

import numpy as np

from data_schemas.errors import ParameterError

#: Default span (s) of the attack and of the release kept unchanged.
EDGE = 0.06
_DENSE = 2048


def edge_length(target_duration: float, sample_duration: float, edge: float = EDGE) -> float:
    """Length (s) of the attack and release copied unchanged: ``edge``, at most D / 4."""
    return float(min(edge, 0.25 * min(target_duration, sample_duration)))


def warp(t: np.ndarray, target_duration: float, sample_duration: float, *,
         edge: float = EDGE) -> np.ndarray:
    """Sample times ``u(t)`` for target times ``t``.

    Parameters
    ----------
    t : np.ndarray [shape=(n,)], s
        Times in the stretched note (clipped to [0, target_duration]).
    target_duration, sample_duration : float, s
        Durations of the stretched note and of the sample, > 0.
    edge : float, s
        Attack / release length kept unchanged (see :func:`edge_length`).

    Returns
    -------
    np.ndarray [shape=(n,)], s
        Monotone non-decreasing, ``u(0) = 0``, ``u(target_duration) = sample_duration``.
    """
    Dt, Ds = float(target_duration), float(sample_duration)
    if not (Dt > 0 and Ds > 0):
        raise ParameterError(f"durations must be > 0 (target {Dt} s, sample {Ds} s)")
    t = np.clip(np.asarray(t, np.float64), 0.0, Dt)
    e = edge_length(Dt, Ds, edge)
    if e <= 0 or abs(Dt - Ds) < 1e-12:
        return t * (Ds / Dt)
    grid = np.linspace(0.0, Dt, _DENSE)
    h = _middle_weight(grid, Dt, e)
    step = np.diff(grid)
    one = np.r_[0.0, np.cumsum(0.5 * ((1 - h[1:]) + (1 - h[:-1])) * step)]
    mid = np.r_[0.0, np.cumsum(0.5 * (h[1:] + h[:-1]) * step)]
    c = (Ds - one[-1]) / mid[-1]
    u = one + c * mid
    u[-1] = Ds
    out = np.interp(t, grid, u)
    # exact copies of the edges (the dense grid only approximates them)
    head = t <= e
    tail = t >= Dt - e
    out[head] = t[head]
    out[tail] = Ds - (Dt - t[tail])
    return out


def _middle_weight(t: np.ndarray, Dt: float, e: float) -> np.ndarray:
    """0 on the edges, raised-cosine rise over [e, 2e], 1 in the middle, fall before Dt-e."""
    rise = np.clip((t - e) / e, 0.0, 1.0)
    fall = np.clip((Dt - e - t) / e, 0.0, 1.0)
    return 0.5 - 0.5 * np.cos(np.pi * np.minimum(rise, fall))


def stretch(times: np.ndarray, values: np.ndarray, target_duration: float,
            t_out: np.ndarray, *, edge: float = EDGE) -> np.ndarray:
    """Resample a sample's signals at target times through the edge-keeping warp.

    Parameters
    ----------
    times : np.ndarray [shape=(n,)], s
        Frame times of the sample from its onset (increasing; the last is its duration).
    values : np.ndarray [shape=(n,) or (n, p)]
        The sample's signals.
    target_duration : float, s
        Duration to fill.
    t_out : np.ndarray [shape=(m,)], s
        Times in the stretched note; outside [0, target_duration] the edge values are held.
    edge : float, s
        Attack / release kept unchanged.

    Returns
    -------
    np.ndarray [shape=(m,) or (m, p)]
    """
    times = np.asarray(times, np.float64)
    values = np.asarray(values, np.float64)
    if times.ndim != 1 or times.size < 2 or values.shape[0] != times.size:
        raise ParameterError(f"a sample needs >= 2 frames with matching values "
                             f"(times {times.shape}, values {values.shape})")
    u = warp(t_out, target_duration, times[-1] - times[0], edge=edge) + times[0]
    if values.ndim == 1:
        return np.interp(u, times, values)
    return np.column_stack([np.interp(u, times, values[:, j]) for j in range(values.shape[1])])


__all__ = ["EDGE", "edge_length", "stretch", "warp"]
