"""Recorded bowing contours without their sensor noise.

A recording's contours carry the noise of its sensors (motion capture and strain gauges:
independent from frame to frame; the simulated recordings draw it from ``[noise]`` in
``gesture_db/config/simulate.toml``), and a sample played as recorded plays that noise as
bow motion: a bow that trembles by a few per cent every frame. A player's arm moves far
more slowly than the frame rate, so a low-pass filter with its cut-off well above the
arm's own movements (bow changes take some 50-100 ms) and well below the frame rate
removes most of the noise and keeps the gesture. The filter is a Gaussian (zero phase and
without overshoot: a bow that stops is not sent backwards, a force that rises to a level
does not pass it).
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import gaussian_filter1d

from data_schemas.errors import ParameterError

#: Gain of the Gaussian at its cut-off frequency (-3 dB).
_HALF_POWER = np.sqrt(0.5)


def gaussian_sigma(cutoff: float) -> float:
    """The Gaussian's standard deviation (s) whose gain is -3 dB at ``cutoff`` (Hz).

    The gain at ``f`` is ``exp(-(2 pi f sigma)^2 / 2)``.

    Examples
    --------
    >>> round(gaussian_sigma(20.0) * 1000.0, 2)
    6.63
    """
    if not cutoff > 0:
        raise ParameterError(f"cutoff={cutoff!r} Hz must be > 0")
    return float(np.sqrt(-2.0 * np.log(_HALF_POWER)) / (2.0 * np.pi * cutoff))


def smooth_contours(values: np.ndarray, frame_rate: float, cutoff: float) -> np.ndarray:
    """Low-pass filtered contours on a regular frame grid.

    Parameters
    ----------
    values : np.ndarray [shape=(n, k)]
        Contours in frames (e.g. bow velocity m/s, bow force N, beta), one column each.
    frame_rate : float, Hz
        Frames per second of ``values``.
    cutoff : float, Hz
        Frequency where the filter's gain is -3 dB; 0 returns ``values`` unchanged.

    Returns
    -------
    np.ndarray [shape=(n, k)]
        Each column convolved with a Gaussian (the edge frames held beyond the ends).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> noisy = 0.3 + 0.004 * rng.standard_normal((2400, 1))
    >>> smooth = smooth_contours(noisy, 240.0, 20.0)
    >>> bool(smooth.std() < 0.5 * noisy.std()), round(float(smooth.mean()), 3)
    (True, 0.3)
    """
    values = np.asarray(values, np.float64)
    if values.ndim != 2:
        raise ParameterError(f"values of shape {values.shape}: need (frames, contours)")
    if not frame_rate > 0 or not cutoff >= 0:
        raise ParameterError(f"frame_rate={frame_rate!r} Hz must be > 0 and "
                             f"cutoff={cutoff!r} Hz >= 0")
    if cutoff == 0 or len(values) < 2:
        return values.copy()
    sigma = gaussian_sigma(cutoff) * frame_rate
    return gaussian_filter1d(values, sigma, axis=0, mode="nearest")
