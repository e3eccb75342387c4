"""From one take to database rows: segment, group, cut contours and fit Bezier vectors.

:func:`extract_take` is the unit of work of a database build: it is a pure function of the
take (recording + optional annotation + the instrument played), so parallel builds give
identical tables. The instrument's facts (:mod:`data_schemas.instruments`) give the open
strings (pitches of notes found without a score) and the scale length (each note's
effective string length).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from data_schemas.instruments import (
    InstrumentFacts,
    dynamics_table,
    instrument_facts,
    limits,
)
from gesture_db.bezier import fit_note
from gesture_db.groups import CONTOUR_PARAMS, chain_positions, grammar_for, group_names
from gesture_db.left_hand import describe_notes
from gesture_db.segment import detect_notes, refine_boundaries
from gesture_db.segment_events import detect_events
from gesture_db.segment_score import score_segmentation

_CONTOUR_COLS = ("bow_velocity", "bow_force", "beta", "bow_position", "finger_ratio")


def extract_take(recording: pd.DataFrame, annotation: pd.DataFrame | None, *,
                 source_hash: str, source_path: str, instrument: str = "violin",
                 max_candidates: int = 24) -> tuple[pd.DataFrame, pd.DataFrame, dict]:
    """Segment one take and fit every note.

    Parameters
    ----------
    recording : pandas.DataFrame
        Frames of one take (recording table, a single ``recording_id``).
    annotation : pandas.DataFrame or None
        Its aligned score notes; None to detect notes from the signals alone (the notes are
        then labelled technique ``"unlabelled"``, with direction, slur and run positions,
        pitch and dynamic estimated from the signals).
    source_hash, source_path : str
        Pointer to the source written into every note.
    instrument : {"violin", "viola", "cello"}
        Instrument of the take (:func:`gesture_db.importers.source_instrument`).
    max_candidates : int
        Candidate boundary frames of the Bezier dynamic programme.

    Returns
    -------
    notes : pandas.DataFrame
        Rows of the database notes table (without ``features``); ``effective_string_length``
        is the instrument's scale length times ``1 - finger_ratio`` (m); ``left_hand`` is
        each note's left-hand description, None when the take has no
        ``pitch_deviation_cents``.
    contours : pandas.DataFrame
        Rows of the contours table plus a ``group`` column.
    stats : dict
        ``recording_id``, ``n_notes`` and, with ground truth, the raw boundary errors
        (``onset_errors`` and ``offset_errors`` in s) and ``found`` / ``n_true`` counts.
    """
    facts = instrument_facts(instrument)
    rec = recording.sort_values("time", kind="stable").reset_index(drop=True)
    rid = str(rec["recording_id"].iloc[0]) if len(rec) else "empty"
    t = rec["time"].to_numpy()
    events = detect_events(t, rec["bow_velocity"].to_numpy(), rec["bow_force"].to_numpy(),
                           rec["finger_ratio"].to_numpy(), rec["string"].to_numpy())
    stats: dict = {"recording_id": rid}
    if annotation is not None and len(annotation):
        notes = _annotated_notes(rec, annotation, events, stats)
    else:
        notes = _blind_notes(rec, events, facts)
    notes = notes[np.isfinite(notes["offset"]) & (notes["offset"] > notes["onset"] + 1e-3)]
    notes = notes.reset_index(drop=True)
    notes["group"] = group_names(notes).to_numpy()
    note_ids = np.array([f"{source_hash}:{rid}:{int(k)}" for k in notes["note_index"]],
                        dtype=object)
    params, rms_rows, contours, hands = _fit_contours(rec, notes, note_ids, max_candidates)
    out = pd.DataFrame(dict(
        note_id=list(note_ids), recording_id=rid,
        note_index=notes["note_index"].to_numpy(np.int32), source_hash=source_hash,
        source_path=source_path, group=notes["group"].to_numpy(),
        technique=notes["technique"].to_numpy(), bow_direction=notes["bow_direction"].to_numpy(),
        slur_position=notes["slur_position"].to_numpy(),
        run_position=notes["run_position"].to_numpy(),
        onset=notes["onset"].to_numpy(float), offset=notes["offset"].to_numpy(float),
        duration=(notes["offset"] - notes["onset"]).to_numpy(float),
        midi_pitch=notes["midi_pitch"].to_numpy(np.int16),
        string=notes["string"].to_numpy(np.int8),
        effective_string_length=facts.effective_length(notes["finger_ratio"].to_numpy(float)),
        dynamic=notes["dynamic"].to_numpy(np.float32),
        params=[p.tolist() for p in params],
        fit_rms_velocity=[r["bow_velocity"] for r in rms_rows],
        fit_rms_force=[r["bow_force"] for r in rms_rows],
        fit_rms_beta=[r["beta"] for r in rms_rows],
        instrument=instrument, left_hand=hands,
        true_onset=_column_or_nan(notes, "true_onset"),
        true_offset=_column_or_nan(notes, "true_offset"),
    ))
    stats["n_notes"] = len(out)
    return out, contours, stats


def _column_or_nan(notes: pd.DataFrame, name: str) -> np.ndarray:
    if name in notes:
        return notes[name].to_numpy(float)
    return np.full(len(notes), np.nan)


def _annotated_notes(rec: pd.DataFrame, annotation: pd.DataFrame, events,
                     stats: dict) -> pd.DataFrame:
    """The annotation's notes with refined boundaries; ground-truth errors into ``stats``."""
    ann = refine_boundaries(rec, annotation, events=events)
    notes = ann.assign(onset=ann["seg_onset"], offset=ann["seg_offset"])
    if "true_onset" in ann and ann["true_onset"].notna().all():
        end = ann["run_position"].isin(["end", "iso"]).to_numpy()
        to = np.where(end, ann["true_offset"].to_numpy(float), np.nan)
        so = np.where(end, notes["offset"].to_numpy(float), np.nan)
        sc = score_segmentation(ann["true_onset"].to_numpy(float),
                                notes["onset"].to_numpy(float), true_offset=to,
                                seg_offset=so)
        err_on = np.abs(notes["onset"].to_numpy() - ann["true_onset"].to_numpy())
        ok = np.isfinite(to) & np.isfinite(so)
        stats.update(onset_errors=err_on.tolist(),
                     offset_errors=np.abs(so[ok] - to[ok]).tolist(),
                     found=int(round(sc["notes_found_share"] * len(ann))),
                     n_true=len(ann))
    return notes


def _fit_contours(rec: pd.DataFrame, notes: pd.DataFrame, note_ids: np.ndarray,
                  max_candidates: int) -> tuple[list, list, pd.DataFrame, list]:
    """Fit each note's Bezier vector and left-hand description and cut its contour frames.

    Returns
    -------
    params : list of np.ndarray
    rms : list of dict
        Fit RMS errors per parameter.
    contours : pandas.DataFrame
        Contour frames (time from the note's onset) with ``note_id`` and ``group``.
    hands : list of (list of float or None)
        Left-hand descriptions (:func:`gesture_db.left_hand.describe_left_hand`); None for
        a note whose frames carry no ``pitch_deviation_cents``.
    """
    t = rec["time"].to_numpy()
    fs = 1.0 / float(np.median(np.diff(t))) if t.size > 1 else 240.0
    i0 = np.clip(np.round((notes["onset"].to_numpy() - t[0]) * fs).astype(int), 0, len(t) - 1)
    i1 = np.clip(np.round((notes["offset"].to_numpy() - t[0]) * fs).astype(int), 0, len(t) - 1)
    cols = {c: rec[c].to_numpy(np.float64) for c in _CONTOUR_COLS}
    params, rms_rows = [], []
    i1 = np.maximum(i1, i0 + 1)
    groups = notes["group"].to_numpy()
    grammars = {g: grammar_for(g) for g in set(groups)}
    for k in range(len(notes)):
        a, b = int(i0[k]), int(i1[k])
        sig = {c: cols[c][a:b + 1] for c in CONTOUR_PARAMS}
        p, rms = fit_note(sig, grammars[groups[k]], max_candidates=max_candidates)
        params.append(p)
        rms_rows.append(rms)
    cents = (rec["pitch_deviation_cents"].to_numpy(np.float64)
             if "pitch_deviation_cents" in rec else np.full(len(rec), np.nan))
    hands = describe_notes(cents, np.column_stack([i0, i1]), fs)
    counts = i1 - i0 + 1
    which = np.repeat(np.arange(len(notes)), counts)
    frames = (np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
              + np.repeat(i0, counts)) if len(notes) else np.zeros(0, int)
    contours = pd.DataFrame({"note_id": note_ids[which],
                             "time": t[frames] - notes["onset"].to_numpy()[which],
                             **{c: cols[c][frames] for c in _CONTOUR_COLS},
                             "pitch_deviation_cents": cents[frames],
                             "group": groups[which]})
    return params, rms_rows, contours, hands


def _blind_notes(rec: pd.DataFrame, events, facts: InstrumentFacts) -> pd.DataFrame:
    """Notes detected without a score, labelled from the signals.

    Pitch is the open string of ``facts`` plus the finger's semitones (rounded); the dynamic
    is the level whose typical force (the facts' violinist table, calibrated on a violin) is
    the note's mean force.
    """
    det = detect_notes(rec, events=events)
    n = len(det)
    t = rec["time"].to_numpy()
    fs = 1.0 / float(np.median(np.diff(t))) if t.size > 1 else 240.0
    mid = np.clip(((0.5 * (det["onset"] + det["offset"]) - t[0]) * fs).astype(int), 0,
                  len(t) - 1).to_numpy()
    string = rec["string"].to_numpy()[mid].astype(int)
    fr = rec["finger_ratio"].to_numpy()[mid]
    # semitones_of(fr) in the recording's float32 precision (as the database was built)
    semis = -12.0 * np.log2(np.clip(1.0 - fr, 1.0 - limits().max_finger_ratio, 1.0))
    pitch = facts.open_pitch(string) + np.round(semis).astype(int)
    force = np.array([rec["bow_force"].to_numpy()[max(int((a - t[0]) * fs), 0):
                                                    max(int((b - t[0]) * fs), 1)].mean()
                      for a, b in zip(det["onset"], det["offset"], strict=True)]) if n else []
    dynamic = np.clip(dynamics_table("violinist").level_of_force(force), 0, 9) if n else []
    # slur: consecutive notes in one bow direction whose boundary is a finger change
    from gesture_db.segment_events import FINGER, START

    kind = det["kind"].to_numpy()
    offs = det["offset"].to_numpy()
    ons = det["onset"].to_numpy()
    linked_next = np.r_[np.abs(offs[:-1] - ons[1:]) < 1e-9, False] if n else np.zeros(0, bool)
    starts_run = (kind == START) | ~np.r_[False, linked_next[:-1]] if n else np.zeros(0, bool)
    slur_next = np.r_[kind[1:] == FINGER, False] if n else np.zeros(0, bool)
    slur_prev = kind == FINGER
    return pd.DataFrame(dict(
        note_index=np.arange(n), onset=ons, offset=offs, technique="unlabelled",
        bow_direction=det["bow_direction"].to_numpy(),
        slur_position=chain_positions(slur_prev, slur_next),
        run_position=chain_positions(~starts_run, linked_next & np.r_[~starts_run[1:], False]),
        midi_pitch=pitch, string=string, finger_ratio=fr, dynamic=dynamic))


__all__ = ["extract_take"]
