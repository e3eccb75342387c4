"""The left hand of sampled renders: the sampled notes' vibrato in the finger.

:func:`gesture_db.assemble.assemble_actions` writes each target's finger as the score and
the rules' front end placed it. :func:`play_left_hand` then bends it frame by frame (the
actions' 240 Hz control frames: 34 or more per cycle of a vibrato of up to 7 Hz) with the
left-hand description of the database note chosen for each target
(:class:`gesture_db.left_hand.LeftHandSource`): its vibrato is re-synthesised from its rate
and extent envelopes stretched to the target (:func:`gesture_db.left_hand.left_hand_cents`,
phase continuous from note to note), in cents of the target's pitch, so the sampled note's
vibrato sounds at any pitch, string or instrument. The intonation stays the rules' (a seeded
offset per note plus the expressive semitone steps, already in the target's finger): a
recorded note's offset is an error of that note, and the search reuses good samples, so
copying it made the same offset recur (measured: a note-to-note spread of 4.8 cents on the
Bach recordings against the rules' 8.1). Open strings get none (unless ``[vibrato]
open_strings``: a one-sided vibrato); trills and other ornaments of the rules keep their
finger figures, shifts their portamento (a trilled note has no vibrato). A target whose
sample has no description (a database built from recordings without
``pitch_deviation_cents``, or of schema 1.0 / 1.1) plays the rules' left hand, with one
warning per part.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from data_schemas.instruments import finger_ratio, limits
from gesture_db.left_hand import PARTS, left_hand_cents
from pipelines.perform.expression import string_cents
from pipelines.perform.ornaments import ornament_cents

_OPEN = 1e-6  # semitones: a finger this close to the nut is an open string


def _target_of_rows(actions: pd.DataFrame, targets: pd.DataFrame) -> np.ndarray:
    """Index of the target sounding at each actions row on its string, -1 for none."""
    onset = targets["onset"].to_numpy(np.float64)
    t = actions["time"].to_numpy(np.float64)
    k = np.clip(np.searchsorted(onset, t + 1e-9, side="right") - 1, 0, len(targets) - 1)
    same = targets["string"].to_numpy()[k] == actions["string"].to_numpy()
    bowed = ~actions["pluck"].to_numpy(bool)
    return np.where(same & bowed, k, -1)


def _note_cents(description: np.ndarray, choice: pd.Series, event, duration: float,
                t: np.ndarray, semitones: float, phase: float,
                config: dict[str, Any]) -> tuple[np.ndarray, float]:
    """Cents of one sampled note (from its description) at times ``t`` (s from its onset)."""
    ornament = getattr(event, "ornament", None)
    vibrato = ornament is None or ornament.kind == "portamento"
    shape = np.array(description, np.float64)
    shape[PARTS["intonation"]] = 0.0  # the target keeps the rules' intonation
    cents, end_phase = left_hand_cents(shape, float(choice["sample_duration"]),
                                       duration, t, phase=phase, vibrato=vibrato)
    if semitones <= _OPEN:
        if not config["vibrato"]["open_strings"]:
            return np.zeros(t.size), end_phase
        cents = np.abs(cents)  # a finger can only shorten it
    return cents, end_phase


def play_left_hand(actions: pd.DataFrame, targets: pd.DataFrame, choices: pd.DataFrame,
                   events: list, source, config: dict[str, Any]) -> tuple[pd.DataFrame,
                                                                           list[str]]:
    """Bend the sampled actions' finger with the sampled notes' left hand.

    Parameters
    ----------
    actions : pandas.DataFrame
        Assembled actions (:func:`gesture_db.assemble.assemble_actions`).
    targets, choices : pandas.DataFrame
        The sampling targets and the samples chosen for them (same order).
    events : list of pipelines.perform.events.Event
        The bowed events of the targets (:func:`pipelines.methods.sampling.
        targets_from_events`), with the rules' vibrato and ornaments.
    source : gesture_db.left_hand.LeftHandSource or None
        Descriptions of the database notes (None: the rules' left hand throughout).
    config : dict
        Rules configuration (``[vibrato] open_strings``).

    Returns
    -------
    actions : pandas.DataFrame
        A copy with ``finger_ratio`` bent row by row.
    warnings : list of str
        One line when some targets fell back to the rules' left hand.
    """
    out = actions.copy()
    which = _target_of_rows(out, targets)
    times = out["time"].to_numpy(np.float64)
    finger = out["finger_ratio"].to_numpy(np.float64).copy()
    onset = targets["onset"].to_numpy(np.float64)
    duration = targets["duration"].to_numpy(np.float64)
    phase, fallback = 0.0, 0
    for m, e in enumerate(events):
        rows = np.flatnonzero(which == m)
        played = float(e.semitones[-1])  # the rules' intonation included
        desc = source.get(str(choices["note_id"].iloc[m])) if source is not None else None
        t = times[rows]
        if desc is None:
            fallback += 1
            cents = string_cents(e, played, t, config)
        else:
            cents, phase = _note_cents(desc, choices.iloc[m], e, duration[m], t - onset[m],
                                       played, phase, config)
        semis = played
        cents = cents + ornament_cents(getattr(e, "ornament", None), t, floor=-100.0 * semis)
        finger[rows] = finger_ratio(np.maximum(semis + cents / 100.0, 0.0))
    out["finger_ratio"] = np.clip(finger, 0.0, limits().max_finger_ratio).astype(np.float32)
    warnings = []
    if fallback:
        warnings.append(f"{fallback} of {len(events)} sampled notes have no left-hand gesture "
                        "in the database (recordings without pitch_deviation_cents, or a "
                        "database older than schema 1.2): they play the rules' vibrato and "
                        "intonation")
    return out, warnings


__all__ = ["play_left_hand"]
