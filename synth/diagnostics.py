"""Contact diagnostics of a block: what the string did under the bow.

The teacher and the evaluation read these; the feedback controller never does. The
per-sample counting is :func:`synth.diagnostics_kernel.summarise_slips` (numba).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from synth.diagnostics_kernel import summarise_slips


@dataclass(frozen=True)
class ContactDiagnostics:
    """What one string did during one block.

    Attributes
    ----------
    slip_onsets : int
        Number of slips: slipping phases in which the string slides past the bow at
        :data:`synth.diagnostics_kernel.SLIP_ONSET_SPEED_RATIO` of the bow's speed or more
        (micro-slips excluded).
    slipping_share : float
        Fraction of the block's samples spent slipping (0..1).
    contact_share : float
        Fraction of the block's samples with the bow (or a plucking finger) on the string.
    mean_slip_speed : float, m/s
        Mean |slip velocity| over slipping samples (0 when none).
    sounding_period : float, s
        Median interval between consecutive slip onsets, the last onset of earlier blocks
        included; NaN when fewer than two onsets are known.
    onset_times : np.ndarray [shape=(slip_onsets,)], s
        Times of the slip onsets from the start of the performance: the first sample of
        each counted slip at which it reaches that speed (within a sample or two of its
        start for a Helmholtz flyback).
    """

    slip_onsets: int
    slipping_share: float
    contact_share: float
    mean_slip_speed: float
    sounding_period: float
    onset_times: np.ndarray = field(repr=False)


_NO_ONSETS = np.zeros(0)


def _median_interval(first: float, later: np.ndarray) -> float:
    """Median interval (s) of the onsets ``first, *later``; NaN with fewer than two."""
    times = [first, *later.tolist()]
    intervals = sorted(b - a for a, b in zip(times[:-1], times[1:], strict=True))
    if not intervals:
        return float("nan")
    mid = len(intervals) // 2
    return float(intervals[mid] if len(intervals) % 2 else 0.5 * (intervals[mid - 1]
                                                                  + intervals[mid]))


class OnsetTracker:
    """Turns per-sample stick-slip states into :class:`ContactDiagnostics`, block by block."""

    def __init__(self, internal_rate: float) -> None:
        self.internal_rate = float(internal_rate)
        self._counted = False
        self._last_onset = np.nan

    def reset(self) -> None:
        """Forget earlier blocks."""
        self._counted = False
        self._last_onset = np.nan

    def update(self, stick_slip: np.ndarray, slip_velocity: np.ndarray, bow_velocity: np.ndarray,
               start_sample: int) -> ContactDiagnostics:
        """Summarise a block that starts at internal sample ``start_sample``.

        Parameters
        ----------
        stick_slip : np.ndarray [shape=(n,)], int8
            Stick-slip state per internal sample (:data:`synth.modal_kernel.OFF_STRING`,
            ``STICKING``, ``SLIPPING``).
        slip_velocity : np.ndarray [shape=(n,)], m/s
        bow_velocity : np.ndarray [shape=(n,)], m/s
        start_sample : int
        """
        if not stick_slip.any():  # bow off the string: nothing to count
            self._counted = False
            return ContactDiagnostics(0, 0.0, 0.0, 0.0, float("nan"), _NO_ONSETS)
        onsets, n_slip, n_contact, slip_sum, self._counted = summarise_slips(
            stick_slip, slip_velocity, bow_velocity, self._counted)
        n_onsets = onsets.size
        times = (start_sample + onsets) / self.internal_rate
        if np.isfinite(self._last_onset):
            period = _median_interval(self._last_onset, times)
        else:
            period = _median_interval(times[0], times[1:]) if n_onsets else float("nan")
        if n_onsets:
            self._last_onset = float(times[-1])
        n = max(stick_slip.size, 1)
        return ContactDiagnostics(
            slip_onsets=int(n_onsets),
            slipping_share=n_slip / n,
            contact_share=n_contact / n,
            mean_slip_speed=slip_sum / n_slip if n_slip else 0.0,
            sounding_period=period,
            onset_times=times,
        )


def merge_diagnostics(parts: list[ContactDiagnostics]) -> ContactDiagnostics:
    """Combine the diagnostics of consecutive equal-length hops into one."""
    times = np.concatenate([p.onset_times for p in parts]) if parts else np.zeros(0)
    n_slip_share = float(np.mean([p.slipping_share for p in parts])) if parts else 0.0
    weights = np.array([p.slipping_share for p in parts])
    speeds = np.array([p.mean_slip_speed for p in parts])
    periods = np.diff(times)
    return ContactDiagnostics(
        slip_onsets=int(times.size),
        slipping_share=n_slip_share,
        contact_share=float(np.mean([p.contact_share for p in parts])) if parts else 0.0,
        mean_slip_speed=float(np.sum(weights * speeds) / weights.sum()) if weights.sum() else 0.0,
        sounding_period=float(np.median(periods)) if periods.size else (
            parts[-1].sounding_period if parts else float("nan")),
        onset_times=times,
    )
