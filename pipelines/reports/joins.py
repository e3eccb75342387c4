"""Figures of concatenated audio: clicks at joins and pitch against a target trajectory.

- :func:`click_ratio`: the largest sample-to-sample jump over the local RMS slope (RMS of
  the first difference within +-``window`` samples); a click stands out as a large ratio
  (the ``frames`` engine's target: no jump above 6x);
- :func:`pitch_error_cents`: YIN pitch of the render against the pitch it was asked for,
  per sustained stretch (the middle 60 % of each stretch of at least 0.31 s).
"""

from __future__ import annotations

import numpy as np

from pipelines.reports.vibrato import EDGE, LONG_NOTE, pitch_track

#: Local slopes below this RMS (per sample, full scale 1) are silence, not measured.
SLOPE_FLOOR = 1e-4


def click_ratio(audio: np.ndarray, sample_rate: int = 44100, *,
                window_s: float = 0.01) -> tuple[float, float]:
    """(max, 99.9th percentile) of ``|x[n+1] - x[n]|`` over the local RMS slope.

    The local slope is :func:`synth.clicks.local_rms_slope` (the same measure the engines'
    click check, :func:`synth.clicks.find_clicks`, uses); slopes below :data:`SLOPE_FLOOR`
    are silence and not measured.

    Examples
    --------
    >>> t = np.arange(44100) / 44100
    >>> tone = 0.3 * np.sin(2 * np.pi * 440 * t)
    >>> round(click_ratio(tone)[0], 1)   # a sine's slope peaks at sqrt(2) x its RMS
    1.4
    >>> tone[22075:] *= -1               # a phase jump at a crest: a click
    >>> click_ratio(tone)[0] > 6
    True
    """
    from synth.clicks import local_rms_slope

    x = np.asarray(audio, np.float64)
    if x.size < 2:
        return 0.0, 0.0
    d = np.abs(np.diff(x))
    rms = local_rms_slope(x, sample_rate, window_s=window_s)
    ok = rms > SLOPE_FLOOR
    if not ok.any():
        return 0.0, 0.0
    ratio = d[ok] / rms[ok]
    return float(ratio.max()), float(np.percentile(ratio, 99.9))


def pitch_error_cents(audio: np.ndarray, sample_rate: int, times: np.ndarray,
                      target_f0: np.ndarray) -> dict[str, float | int | None]:
    """The render's pitch against ``target_f0`` (Hz, NaN silent) on a grid ``times`` (s).

    Returns
    -------
    dict
        ``median_abs_cents`` (median over the sustained stretches of each stretch's median
        error), ``p90_abs_cents``, ``share_within_10_cents`` and ``stretches``.
    """
    f0, ft = pitch_track(audio, sample_rate)
    on = np.isfinite(target_f0)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], on.astype(int), [0]])))
    errors = []
    for a, b in zip(edges[::2], edges[1::2], strict=True):
        start, end = times[a], times[b - 1]
        if end - start < LONG_NOTE:
            continue
        lo, hi = start + EDGE * (end - start), end - EDGE * (end - start)
        m = (ft >= lo) & (ft <= hi)
        want = np.interp(ft[m], times[a:b], target_f0[a:b])
        with np.errstate(divide="ignore", invalid="ignore"):
            cents = 1200 * np.log2(f0[m] / want)
        cents = cents[np.isfinite(cents) & (np.abs(cents) < 300)]  # octave errors out
        if cents.size:
            errors.append(float(np.median(cents)))
    if not errors:
        return {"median_abs_cents": None, "p90_abs_cents": None,
                "share_within_10_cents": None, "stretches": 0}
    e = np.abs(np.asarray(errors))
    return {"median_abs_cents": float(np.median(e)), "p90_abs_cents": float(np.percentile(e, 90)),
            "share_within_10_cents": float(np.mean(e < 10)), "stretches": int(e.size)}


__all__ = ["click_ratio", "pitch_error_cents"]
