"""Turn what a reader collected (raw notes, marks, words, tempi) into the notes table.

Readers only collect; everything that is computed from the collected marks lives here and
is shared by all formats: seconds from the tempo map, slur and run positions, dynamics with
hairpins, techniques, bow regions and string indications in effect.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from data_schemas.instruments import instrument_facts
from data_schemas.notes import (
    ARTICULATIONS,
    NOTES,
    UNPERFORMED,
    validate_notes,
    validate_unperformed,
)
from pipelines.perform.instruments import guess_instrument, string_index
from pipelines.score.errors import ScoreError
from pipelines.score.tempo import TempoMap
from pipelines.score.text import classify

#: Dynamic assumed before the first mark (mf).
DEFAULT_DYNAMIC = 5.0
_EPS = 1e-6


@dataclass
class RawPart:
    """What a reader collected for one part.

    Attributes
    ----------
    index : int
        Part number in score order, from 0.
    part_id, name : str
        Identifier and printed name.
    names : list of str
        Every name that may tell the instrument (part, instrument, abbreviation).
    notes : list of dict
        One dict per note with the notes-table columns that a reader knows (onset_beats,
        duration_beats, midi_pitch, cents, measure, voice, ties, articulations, grace,
        chord_size, chord_index, harmonic, string_indication).
    dynamics : list of (float, float)
        ``(beat, level)`` of dynamic marks (level on the 0..9 scale).
    hairpins : list of (float, float, int)
        ``(start_beat, end_beat, direction)``; direction +1 cresc., -1 dim.
    words : list of (float, str)
        ``(beat, text)`` of printed words (techniques, regions, strings, cresc. ...).
    slurs : list of (int, float, float)
        ``(voice, first_onset_beat, last_onset_beat)``.
    unperformed : list of dict
        Marks the reader found and Arco does not perform: ``measure``, ``movement``,
        ``kind``, ``detail`` (see :data:`data_schemas.notes.UNPERFORMED`).
    movement_titles : dict of int to str
        Heading of each movement (its first words).
    """

    index: int
    part_id: str
    name: str
    names: list[str] = field(default_factory=list)
    notes: list[dict] = field(default_factory=list)
    dynamics: list[tuple[float, float]] = field(default_factory=list)
    hairpins: list[tuple[float, float, int]] = field(default_factory=list)
    words: list[tuple[float, str]] = field(default_factory=list)
    slurs: list[tuple[int, float, float]] = field(default_factory=list)
    unperformed: list[dict] = field(default_factory=list)
    movement_titles: dict[int, str] = field(default_factory=dict)


def assemble(parts: list[RawPart], tempo: TempoMap, source: str) -> pd.DataFrame:
    """Build and validate the notes table.

    Parameters
    ----------
    parts : list of RawPart
        Collected parts, in score order.
    tempo : TempoMap
        The score's tempo map.
    source : str
        File name, copied to every row.

    Returns
    -------
    pandas.DataFrame
        The notes table (see :data:`data_schemas.notes.NOTES`), sorted by part, onset,
        voice and pitch.

    Raises
    ------
    ScoreError
        The score holds no notes.
    """
    return assemble_report(parts, tempo, source)[0]


def assemble_report(parts: list[RawPart], tempo: TempoMap,
                    source: str) -> tuple[pd.DataFrame, pd.DataFrame]:
    """:func:`assemble`, plus the table of marks not performed.

    Returns
    -------
    notes : pandas.DataFrame
        The notes table.
    unperformed : pandas.DataFrame
        :data:`data_schemas.notes.UNPERFORMED`, in part and score order.
    """
    titles: dict[int, str] = {}
    for p in parts:
        for k, v in p.movement_titles.items():
            titles.setdefault(k, v)
    frames = [_assemble_part(p, tempo, source, titles) for p in parts if p.notes]
    if not frames:
        raise ScoreError(f"{source}: the score holds no notes")
    table = pd.concat(frames, ignore_index=True)
    rows = [{"part_index": p.index, "part_name": p.name, "detail": "", **mark}
            for p in parts for mark in p.unperformed]
    columns = [c.name for c in UNPERFORMED.columns]
    unperformed = validate_unperformed(pd.DataFrame(rows, columns=columns), source=source)
    return validate_notes(table[NOTES.column_names], source=source), unperformed


def _assemble_part(part: RawPart, tempo: TempoMap, source: str,
                   titles: dict[int, str]) -> pd.DataFrame:
    df = pd.DataFrame(part.notes)
    defaults = {name: False for name in (*ARTICULATIONS, "tie_start", "tie_stop", "grace",
                                         "harmonic")}
    defaults.update({"cents": 0.0, "voice": 1, "chord_size": 1, "chord_index": 0,
                     "string_indication": None, "movement": 1, "ornament": None,
                     "ornament_upper": None, "ornament_lower": None, "grace_type": None,
                     "harmonic_type": None, "harmonic_node": None})
    for name, value in defaults.items():
        if name not in df:
            df[name] = value
        elif isinstance(value, bool):
            df[name] = df[name].fillna(value).astype(bool)
    for name in ("ornament_upper", "ornament_lower", "harmonic_node"):
        df[name] = pd.array([None if pd.isna(v) else int(v) for v in df[name]], dtype="Int8")
    for name in ("ornament", "grace_type", "harmonic_type"):
        df[name] = [v if isinstance(v, str) else None for v in df[name]]
    df = df.sort_values(["onset_beats", "voice", "grace", "midi_pitch"],
                        ascending=[True, True, False, True], kind="stable")
    df = df.reset_index(drop=True)
    instrument = guess_instrument(part.names, df["midi_pitch"].to_numpy())
    df["movement"] = df["movement"].fillna(1).astype(int)
    df["movement_title"] = [titles.get(int(m)) for m in df["movement"]]
    df["source_file"] = source
    df["part_index"] = part.index
    df["part_id"] = part.part_id
    df["part_name"] = part.name
    df["instrument"] = instrument
    onset = df["onset_beats"].to_numpy(dtype=np.float64)
    end = onset + df["duration_beats"].to_numpy(dtype=np.float64)
    start_s = tempo.seconds(onset)
    df["onset"] = start_s
    df["duration"] = np.maximum(tempo.seconds(end) - start_s, 0.0)
    df["tempo"] = tempo.tempo_at(onset)
    df["slur_id"], df["slur_position"] = _slurs(df, part.slurs)
    df["run_position"] = _runs(df)
    directions = _directions(part.words)
    hairpins = part.hairpins + _text_hairpins(directions["text_hairpins"], part.dynamics)
    df["dynamic"] = _dynamics(onset, part.dynamics, hairpins)
    technique = _state(onset, directions["technique"])
    if "technique_note" in df:
        technique = [t if isinstance(t, str) else s
                     for t, s in zip(df["technique_note"], technique, strict=True)]
    df["technique"] = technique
    # dots under a slur are played portato (louré)
    df["portato"] = df["portato"].astype(bool) | (df["staccato"].astype(bool)
                                                  & df["slur_id"].notna())
    df["bow_region"] = _state(onset, directions["region"])
    df["string_indication"] = _strings(df, directions, instrument)
    return df


def _events(df: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """Group chord members: return (event id per row, first row of each event)."""
    key = df["onset_beats"].round(6).astype(str) + "|" + df["voice"].astype(str) + "|" + \
        df["grace"].astype(str)
    codes, uniques = pd.factorize(key, sort=False)
    first = np.zeros(len(uniques), np.int64)
    first[codes[::-1]] = np.arange(len(codes))[::-1]
    return codes, first


def _position_labels(n: int) -> list[str]:
    if n == 1:
        return ["iso"]
    return ["init"] + ["mid"] * (n - 2) + ["end"]


def _slurs(df: pd.DataFrame, slurs: list[tuple[int, float, float]]) -> tuple[list, list]:
    """Slur id and position per row; nested or crossing slurs: the longest wins."""
    n = len(df)
    slur_id: list = [None] * n
    length = np.full(n, -1.0)
    onset = df["onset_beats"].to_numpy()
    voice = df["voice"].to_numpy()
    for k, (v, first, last) in enumerate(sorted(slurs, key=lambda s: (s[1], s[2]))):
        span = last - first
        mask = (voice == v) & (onset >= first - _EPS) & (onset <= last + _EPS) & \
            (span > length)
        for i in np.flatnonzero(mask):
            slur_id[i] = k
            length[i] = span
    position = ["iso"] * n
    by_slur: dict[int, list[int]] = {}
    for i, s in enumerate(slur_id):
        if s is not None:
            by_slur.setdefault(s, []).append(i)
    for rows in by_slur.values():
        onsets = sorted({round(float(onset[i]), 6) for i in rows})
        if len(onsets) < 2:
            for i in rows:
                slur_id[i] = None
            continue
        labels = dict(zip(onsets, _position_labels(len(onsets)), strict=True))
        for i in rows:
            position[i] = labels[round(float(onset[i]), 6)]
    # renumber densely in order of appearance
    remap: dict[int, int] = {}
    for i, s in enumerate(slur_id):
        if s is not None:
            slur_id[i] = remap.setdefault(s, len(remap))
    return slur_id, position


def _runs(df: pd.DataFrame) -> list[str]:
    """Position of each note in a run of notes without rests (per voice)."""
    codes, first = _events(df)
    onset = df["onset_beats"].to_numpy()[first]
    dur = df["duration_beats"].to_numpy()[first]
    voice = df["voice"].to_numpy()[first]
    ev_label = np.empty(first.size, dtype=object)
    for v in np.unique(voice):
        idx = np.flatnonzero(voice == v)
        idx = idx[np.argsort(onset[idx], kind="stable")]
        start = 0
        for j in range(1, idx.size + 1):
            joined = j < idx.size and onset[idx[j]] <= onset[idx[j - 1]] + \
                dur[idx[j - 1]] + 1e-4
            if not joined:
                for e, lab in zip(idx[start:j], _position_labels(j - start), strict=True):
                    ev_label[e] = lab
                start = j
    return list(ev_label[codes])


def _directions(words: list[tuple[float, str]]) -> dict[str, list]:
    out: dict[str, list] = {"technique": [], "region": [], "string": [], "string_once": [],
                            "hairpins": [], "text_hairpins": []}
    for beat, text in sorted(words, key=lambda w: w[0]):
        for d in classify(text):
            if d.kind == "technique":
                out["technique"].append((beat, d.value))
            elif d.kind == "ordinario":
                out["technique"].append((beat, None))
                out["region"].append((beat, None))
                out["string"].append((beat, None))
            elif d.kind == "region":
                out["region"].append((beat, d.value))
            elif d.kind == "string":
                out["string"].append((beat, d.value))
            elif d.kind == "string_once":
                out["string_once"].append((beat, d.value))
            elif d.kind == "hairpin":
                out["text_hairpins"].append((beat, d.value))
    return out


def _state(onset: np.ndarray, changes: list[tuple[float, object]]) -> list:
    """Value in effect at each onset from a list of ``(beat, value)`` changes."""
    if not changes:
        return [None] * onset.size
    beats = np.array([c[0] for c in changes]) - _EPS
    values = [c[1] for c in changes]
    k = np.searchsorted(beats, onset, side="right") - 1
    return [values[j] if j >= 0 else None for j in k]


def _strings(df: pd.DataFrame, directions: dict[str, list], instrument: str) -> list:
    inst = instrument_facts(instrument)
    onset = df["onset_beats"].to_numpy()
    changes = [(b, None if v is None else string_index(inst, str(v)))
               for b, v in directions["string"]]
    state = _state(onset, changes)
    explicit = df["string_indication"].tolist()
    runs = df["run_position"].tolist()
    for beat, s in directions["string_once"]:
        # a bare I..IV mark holds for the rest of the run it starts in
        for i in np.flatnonzero(onset >= beat - _EPS):
            state[i] = s
            if runs[i] in ("end", "iso"):
                break
    out = []
    for e, s in zip(explicit, state, strict=True):
        value = e if e is not None and not (isinstance(e, float) and np.isnan(e)) else s
        out.append(None if value is None else int(value))
    return out


def _text_hairpins(texts: list[tuple[float, int]],
                   marks: list[tuple[float, float]]) -> list[tuple[float, float, int]]:
    """A printed cresc./dim. lasts until the next dynamic mark (at most 32 beats), else 8."""
    beats = np.sort(np.array([m[0] for m in marks], dtype=np.float64))
    out = []
    for beat, direction in texts:
        k = np.searchsorted(beats, beat + _EPS, side="right")
        end = beats[k] if k < beats.size and beats[k] - beat <= 32.0 else beat + 8.0
        out.append((beat, float(end), direction))
    return out


def _dynamics(onset: np.ndarray, marks: list[tuple[float, float]],
              hairpins: list[tuple[float, float, int]]) -> np.ndarray:
    """Dynamic level at each onset: marks held, hairpins interpolated linearly in beats."""
    marks = sorted(marks)
    mb = np.array([m[0] for m in marks], dtype=np.float64)
    mv = np.array([m[1] for m in marks], dtype=np.float64)

    def level_at(beat: float) -> float:
        k = np.searchsorted(mb, beat + _EPS, side="right") - 1
        return float(mv[k]) if k >= 0 else DEFAULT_DYNAMIC

    def next_mark(beat: float, within: float) -> float | None:
        k = np.searchsorted(mb, beat - _EPS, side="left")
        if k < mb.size and mb[k] <= beat + within:
            return float(mv[k])
        return None

    out = np.array([level_at(b) for b in onset])
    for start, end, direction in hairpins:
        if end <= start:
            continue
        base = level_at(start)
        target = next_mark(end, 4.0)
        if target is None or np.sign(target - base) not in (0, np.sign(direction)):
            target = base + direction
        mask = (onset >= start - _EPS) & (onset < end - _EPS)
        out[mask] = base + (target - base) * (onset[mask] - start) / (end - start)
    return np.clip(out, 0.0, 9.0)
