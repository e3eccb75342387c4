"""Sampled gestures brought into the instrument model's playable space (Maestre et al. 2010).

A sample keeps its recorded contours when it is stretched and joined, but the note it plays
may ask for a slower bow (a longer note: the bow-length budget scales the velocity down) or
come from a performer who pressed harder at soft dynamics than this model's strings allow.
Pressed far above the middle of its Helmholtz window the modal string sounds flat and
raucous; far below, it slips several times a period. Maestre et al. name the remedy as a
post-processing step: transform the samples so that the resulting signals stay within the
limits of the playable space. Here each sampled note's bow force is scaled, as a whole
(its contour's shape kept), so that its sustained force lies within ``band`` times the
middle of the string's window at the note's own bow velocity and beta:

    F_mid = F_ref (|v| / 0.3 m/s) (0.1 / beta)^1.5

with ``F_ref`` the string's reference force (the window's middle at 0.3 m/s and beta 0.1,
``synth/config/strings.toml``). The window's edges scale as F_min ~ v / beta^2 and F_max ~
v / beta, so F_mid is their geometric middle at any bowing; the rules' bow lanes sit on it
at every dynamic (``data_schemas/config/instruments.toml``). The factor applied to each note
is recorded (the ``force_factor`` column of the sample choices). Where the instrument's
pressing limit (:mod:`pipelines.methods.pressing`) lies below the band's top, the note's
sustained force stays under it and its first :data:`ATTACK_HOLD` s keep the band's force.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from data_schemas.actions import ACTIONS
from data_schemas.errors import ParameterError

if TYPE_CHECKING:
    from pipelines.methods.pressing import PressingLimit

#: Frames whose bow speed is at least this share of the note's fastest are its sustained
#: part, on which the note's force ratio is measured.
SUSTAIN_SHARE = 0.5
#: A note whose bow never moves faster than this (m/s) is left as sampled (a bow resting
#: on the string has no window to be in).
MOVING = 0.01
#: A note's force is scaled by no more than this factor either way.
MAX_FACTOR = 4.0
#: Neighbouring notes' factors are blended over this time (s), so a slur's force stays
#: continuous across a finger change.
BLEND = 0.03
#: Under a pressing limit a note keeps the band's force for this long (s) after its start,
#: then moves to the limited force over :data:`ATTACK_RELEASE` s: the attack needs the
#: force (a lighter start is slower on this model), the sustain must not sound flat.
ATTACK_HOLD = 0.1
ATTACK_RELEASE = 0.05


def window_middle(reference_force: np.ndarray | float, bow_velocity: np.ndarray | float,
                  beta: np.ndarray | float) -> np.ndarray:
    """Middle of a string's Helmholtz window at a bowing, N.

    Parameters
    ----------
    reference_force : float or np.ndarray, N
        The string's reference force (window middle at 0.3 m/s and beta 0.1).
    bow_velocity : float or np.ndarray, m/s
        Signed or not; its magnitude counts (floored at 1 mm/s).
    beta : float or np.ndarray
        Bow-bridge distance / effective string length (floored at 0.001).

    Returns
    -------
    np.ndarray, N
        ``F_ref (|v| / 0.3) (0.1 / beta)^1.5``, broadcast over the inputs.

    Examples
    --------
    >>> float(window_middle(1.5, 0.3, 0.1))
    1.5
    >>> round(float(window_middle(1.0, -0.62, 0.08)), 3)   # the ffff lane's 2.89 x F_ref
    2.888
    """
    v = np.maximum(np.abs(np.asarray(bow_velocity, np.float64)), 1e-3)
    b = np.maximum(np.asarray(beta, np.float64), 1e-3)
    return np.asarray(reference_force, np.float64) * (v / 0.3) * (0.1 / b) ** 1.5


def _check_band(band: float) -> None:
    if not band >= 1.0:
        raise ParameterError(f"playable band={band!r} must be a ratio >= 1")


def playable_band(search_config: dict) -> float:
    """The search settings' ``[render] playable_band`` (0: the transform is off)."""
    return float(search_config.get("render", {}).get("playable_band", 0.0))


def note_of_rows(actions: pd.DataFrame, targets: pd.DataFrame) -> np.ndarray:
    """Target index of each bowed row (-1: before the first target, a lift or a pluck).

    Parameters
    ----------
    actions : pandas.DataFrame
        Actions of one part (``time`` s, ``pluck``, ``bow_force`` N).
    targets : pandas.DataFrame
        Sampling targets sorted by ``onset`` (s), with ``duration`` (s).

    Returns
    -------
    np.ndarray [shape=(len(actions),)], int

    Examples
    --------
    >>> acts = pd.DataFrame({"time": [0.0, 0.3, 0.6], "pluck": False, "bow_force": 1.0})
    >>> note_of_rows(acts, pd.DataFrame({"onset": [0.2], "duration": [0.2]})).tolist()
    [-1, 0, -1]
    """
    onset = targets["onset"].to_numpy(np.float64)
    end = onset + targets["duration"].to_numpy(np.float64)
    t = actions["time"].to_numpy(np.float64)
    if onset.size == 0:
        return np.full(t.shape, -1)
    note = np.searchsorted(onset, t, side="right") - 1
    inside = (note >= 0) & (t < end[np.maximum(note, 0)] + 1e-9)
    bowed = ~actions["pluck"].to_numpy(bool) & (actions["bow_force"].to_numpy() > 0)
    return np.where(inside & bowed, note, -1)


def note_force_factors(actions: pd.DataFrame, targets: pd.DataFrame,
                       reference_forces: np.ndarray, band: float,
                       limit: PressingLimit | None = None) -> np.ndarray:
    """The force factor that brings each target note into the playable band.

    Parameters
    ----------
    actions : pandas.DataFrame
        Assembled actions (:data:`data_schemas.actions.ACTIONS`) of one part.
    targets : pandas.DataFrame
        The sampling targets (:data:`data_schemas.sampling.SAMPLING_TARGETS`).
    reference_forces : np.ndarray [shape=(4,)], N
        Reference force of each string of the instrument model.
    band : float
        Allowed ratio (>= 1) of a note's sustained force to :func:`window_middle`, either
        way.
    limit : PressingLimit, optional
        The instrument's pressing limit (:mod:`pipelines.methods.pressing`): the band's top
        is at most the limit at the note's string and median sustained speed and beta.

    Returns
    -------
    np.ndarray [shape=(len(targets),)]
        ``clip(q, 1 / band, top) / q`` with ``q`` the median ratio over the note's
        sustained frames and ``top`` the band (or the limit, if lower), limited to
        ``[1 / MAX_FACTOR, MAX_FACTOR]``; 1 for notes without frames or whose bow stays
        below :data:`MOVING`.

    Raises
    ------
    ParameterError
        ``band`` below 1 or not a number.
    """
    _check_band(band)
    return _factors(actions, note_of_rows(actions, targets), len(targets), reference_forces,
                    band, limit)


def _factors(actions: pd.DataFrame, note: np.ndarray, n_notes: int,
             reference_forces: np.ndarray, band: float,
             limit: PressingLimit | None = None) -> np.ndarray:
    """:func:`note_force_factors` from each row's note (``note_of_rows``)."""
    v = np.abs(actions["bow_velocity"].to_numpy(np.float64))
    string = actions["string"].to_numpy(int)
    beta = actions["beta"].to_numpy(np.float64)
    ratio = actions["bow_force"].to_numpy(np.float64) / window_middle(
        np.asarray(reference_forces)[string], v, beta)
    factors = np.ones(n_notes)
    for m in np.unique(note[note >= 0]):
        rows = note == m
        if v[rows].max() < MOVING:
            continue
        sustained = v[rows] >= SUSTAIN_SHARE * v[rows].max()
        q = float(np.median(ratio[rows][sustained]))
        top = band
        if limit is not None:
            where = [np.bincount(string[rows][sustained]).argmax()]
            top = min(band, float(limit(np.array(where), np.median(v[rows][sustained])[None],
                                        np.median(beta[rows][sustained])[None])[0]))
        if q > 0:
            factors[m] = np.clip(np.clip(q, 1.0 / band, top) / q, 1.0 / MAX_FACTOR, MAX_FACTOR)
    return factors


def _blended(times: np.ndarray, values: np.ndarray, counted: np.ndarray,
             width: float) -> np.ndarray:
    """Mean of the counted ``values`` within ``width / 2`` of each row's time (sorted times).

    Rows with no counted row near them keep their own value.
    """
    csum = np.r_[0.0, np.cumsum(np.where(counted, values, 0.0))]
    count = np.r_[0, np.cumsum(counted)]
    lo = np.searchsorted(times, times - width / 2, side="left")
    hi = np.searchsorted(times, times + width / 2, side="right")
    n = count[hi] - count[lo]
    return np.where(n > 0, (csum[hi] - csum[lo]) / np.maximum(n, 1), values)


def into_playable(actions: pd.DataFrame, targets: pd.DataFrame, reference_forces: np.ndarray,
                  band: float, limit: PressingLimit | None = None
                  ) -> tuple[pd.DataFrame, np.ndarray]:
    """Scale each sampled note's bow force into the playable band.

    Parameters
    ----------
    actions, targets, reference_forces, band, limit
        As for :func:`note_force_factors`; ``actions`` sorted by time.

    Returns
    -------
    actions : pandas.DataFrame
        A copy whose bowed rows carry the scaled force (blended over :data:`BLEND` s
        between notes; clipped to the actions table's maximum); plucks and lifts untouched.
        Under a ``limit``, each note's first :data:`ATTACK_HOLD` s keep the band's factor
        and move to the limited one over :data:`ATTACK_RELEASE` s.
    factors : np.ndarray [shape=(len(targets),)]
        The factor of each target note's sustained part (1 = untouched).

    Examples
    --------
    >>> t = np.arange(0.0, 1.0, 1 / 240)
    >>> acts = pd.DataFrame({"time": t, "string": 1, "bow_velocity": 0.3, "beta": 0.1,
    ...                      "bow_force": 4.5, "pluck": False})
    >>> tgt = pd.DataFrame({"onset": [0.0], "duration": [1.0]})
    >>> out, f = into_playable(acts, tgt, np.array([1.5, 1.5, 0.5, 0.5]), 1.5)
    >>> round(float(f[0]), 3), round(float(out["bow_force"].iloc[120]), 3)
    (0.5, 2.25)
    """
    _check_band(band)
    note = note_of_rows(actions, targets)
    factors = _factors(actions, note, len(targets), reference_forces, band, limit)
    out = actions.copy()
    if np.all(factors == 1.0):  # then the band alone moves no note either
        return out, factors
    per_row = _row_factors(actions, note, factors)
    if limit is not None:
        banded = _row_factors(actions, note, _factors(actions, note, len(targets),
                                                      reference_forces, band))
        onset = targets["onset"].to_numpy(np.float64)
        since = actions["time"].to_numpy(np.float64) - onset[np.maximum(note, 0)]
        w = np.clip((since - ATTACK_HOLD) / ATTACK_RELEASE, 0.0, 1.0)
        per_row = (1.0 - w) * banded + w * per_row
    force = actions["bow_force"].to_numpy(np.float64)
    out["bow_force"] = np.where(note >= 0, np.clip(force * per_row, 0.0,
                                                   ACTIONS.column("bow_force").maximum), force)
    return out, factors


def _row_factors(actions: pd.DataFrame, note: np.ndarray, factors: np.ndarray) -> np.ndarray:
    """Each row's factor: its note's, blended over :data:`BLEND` s (1 outside notes)."""
    rows = note >= 0
    per_row = np.where(rows, factors[np.maximum(note, 0)], 1.0)
    times = actions["time"].to_numpy(np.float64)
    order = np.argsort(times, kind="stable")
    blended = np.empty_like(per_row)
    blended[order] = _blended(times[order], per_row[order], rows[order], BLEND)
    return np.where(rows, blended, 1.0)


def to_playable(actions: pd.DataFrame, targets: pd.DataFrame, choices: pd.DataFrame,
                instrument: str, search_config: dict) -> tuple[pd.DataFrame, pd.DataFrame]:
    """:func:`into_playable` with the search settings' ``[render] playable_band``.

    Under the instrument's pressing limit when ``[render] pressing_limit`` names it
    (:func:`pipelines.methods.pressing.pressing_limit`). Returns the transformed actions and
    a copy of ``choices`` with the ``force_factor`` of each note (all 1 when the band is 0:
    the transform is off).
    """
    from pipelines.methods.pressing import pressing_limit
    from synth.strings import reference_forces

    band = playable_band(search_config)
    choices = choices.copy()
    if band == 0.0:
        choices["force_factor"] = 1.0
        return actions, choices
    actions, factors = into_playable(actions, targets, reference_forces(instrument), band,
                                     pressing_limit(instrument, search_config))
    choices["force_factor"] = factors[choices["target_index"].to_numpy(int)]
    return actions, choices


def loop_range(planned: np.ndarray, bow_velocity: np.ndarray, beta: np.ndarray,
               reference_forces: np.ndarray, band: float,
               limit: PressingLimit | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Per-hop force range of a listening loop that corrects sampled forces.

    The loop may move a hop's force anywhere inside the playable band, but not further out
    of it than the sample already is (at a bow change the window's middle falls to zero
    with the bow speed, and the sampled force stays playable there).

    Parameters
    ----------
    planned : np.ndarray [shape=(n, n_strings)], N
        The sampled force per hop and string.
    bow_velocity, beta : np.ndarray [shape=(n, n_strings)]
        The hops' bowing (m/s; ratio).
    reference_forces : np.ndarray [shape=(n_strings,)], N
    band : float
        As for :func:`note_force_factors` (>= 1).
    limit : PressingLimit, optional
        The instrument's pressing limit: the band's top at each hop is at most the limit at
        its bowing (the loop heard wispy hops better than flat ones and pressed sampled
        cello notes flat at the band's top).

    Returns
    -------
    lowest, highest : np.ndarray [shape=(n, n_strings)], N
        ``min(planned, F_mid / band)`` and ``max(planned, F_mid top)``, ``top`` the band or
        the limit where it is lower.

    Examples
    --------
    >>> lo, hi = loop_range(np.array([[1.5, 4.0]]), np.full((1, 2), 0.3), np.full((1, 2), 0.1),
    ...                     np.array([1.5, 1.5]), 1.5)
    >>> lo.tolist(), hi.tolist()
    ([[1.0, 1.0]], [[2.25, 4.0]])
    """
    _check_band(band)
    middle = window_middle(np.asarray(reference_forces)[None, :], bow_velocity, beta)
    planned = np.asarray(planned, np.float64)
    top = np.full(middle.shape, float(band))
    if limit is not None:
        strings = np.broadcast_to(np.arange(middle.shape[1])[None, :], middle.shape)
        top = np.minimum(band, limit(strings.ravel(), np.ravel(bow_velocity),
                                     np.ravel(beta)).reshape(middle.shape))
    return np.minimum(planned, middle / band), np.maximum(planned, middle * top)


__all__ = ["ATTACK_HOLD", "ATTACK_RELEASE", "BLEND", "MAX_FACTOR", "MOVING", "SUSTAIN_SHARE",
           "into_playable", "loop_range", "note_force_factors", "note_of_rows", "playable_band",
           "to_playable", "window_middle"]
