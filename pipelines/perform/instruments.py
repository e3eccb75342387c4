"""Violin, viola and cello: tunings, ranges, and the choice of string and finger.

Strings are counted from 0 = the lowest string. A stopped note's finger position is given in
semitones above the open string; the actions table wants ``finger_ratio = 1 - 2**(-s/12)``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
import pandas as pd

from data_schemas.errors import ParameterError
from pipelines.score.errors import ScoreError


@dataclass(frozen=True)
class Instrument:
    """Constants of one member of the violin family.

    Attributes
    ----------
    name : str
        ``violin``, ``viola`` or ``cello``.
    open_strings : tuple of int
        MIDI pitches of the open strings, lowest first.
    string_names : tuple of str
        Letter names of the strings, lowest first.
    highest : int
        Highest playable (stopped) MIDI pitch.
    bow_length : float, m
        Usable length of the bow hair.
    """

    name: str
    open_strings: tuple[int, ...]
    string_names: tuple[str, ...]
    highest: int
    bow_length: float

    @property
    def lowest(self) -> int:
        """Lowest playable MIDI pitch (the open lowest string)."""
        return self.open_strings[0]

    def string_index(self, name: str) -> int | None:
        """Return the index of string ``name`` (a letter, solfège syllable or I..IV)."""
        key = name.strip().lower().rstrip(".")
        key = {"do": "c", "re": "d", "mi": "e", "sol": "g", "la": "a"}.get(key, key)
        roman = {"i": 3, "ii": 2, "iii": 1, "iv": 0}
        if key in roman:
            return roman[key]
        for i, letter in enumerate(self.string_names):
            if letter.lower() == key:
                return i
        return None


INSTRUMENTS: dict[str, Instrument] = {
    "violin": Instrument("violin", (55, 62, 69, 76), ("G", "D", "A", "E"), 100, 0.65),
    "viola": Instrument("viola", (48, 55, 62, 69), ("C", "G", "D", "A"), 93, 0.67),
    "cello": Instrument("cello", (36, 43, 50, 57), ("C", "G", "D", "A"), 84, 0.62),
}

_NAME_PATTERNS = (
    (r"viol(on)?cell|\bvc\b|\bvlc\b|cello|\bvcl\b", "cello"),
    (r"viola|\bvla\b|\bva\b|bratsche|alto", "viola"),
    (r"violin|\bvln?\b|\bvn\b|violon|geige|\bvl\b", "violin"),
)


def get_instrument(name: str) -> Instrument:
    """Return the :class:`Instrument` called ``name`` (violin, viola or cello)."""
    try:
        return INSTRUMENTS[name]
    except KeyError:
        raise ParameterError(
            f"instrument={name!r} is not one of {sorted(INSTRUMENTS)}") from None


def guess_instrument(names: list[str], pitches: np.ndarray | None = None) -> str:
    """Guess the instrument of a part from its names, else from its lowest pitch.

    Parameters
    ----------
    names : list of str
        Part name, instrument name, abbreviations (any may be empty).
    pitches : np.ndarray [shape=(n,)], MIDI, optional
        The part's pitches, used when no name matches.

    Returns
    -------
    str
        ``violin``, ``viola`` or ``cello``.
    """
    text = " ".join(n for n in names if n).lower()
    for pattern, name in _NAME_PATTERNS:
        if re.search(pattern, text):
            return name
    if pitches is not None and len(pitches):
        low = float(np.min(pitches))
        if low >= INSTRUMENTS["violin"].lowest:
            return "violin"
        if low >= INSTRUMENTS["viola"].lowest:
            return "viola"
        return "cello"
    return "violin"


def finger_ratio(semitones: np.ndarray) -> np.ndarray:
    """Fraction of the string length removed by the finger.

    Parameters
    ----------
    semitones : np.ndarray [shape=(n,)], semitones
        Finger position above the open string (0 = open).

    Returns
    -------
    np.ndarray [shape=(n,)], 1
        ``1 - 2**(-semitones/12)``.
    """
    return 1.0 - 2.0 ** (-np.asarray(semitones, dtype=np.float64) / 12.0)


def _where(notes: pd.DataFrame, i: int) -> str:
    row = notes.iloc[i]
    name = row["part_name"] or row["part_id"]
    return f"{row['source_file']}: part {name!r}, measure {row['measure']}"


def fit_range(notes: pd.DataFrame, instrument: Instrument, *,
              transpose_octaves: bool = False) -> pd.DataFrame:
    """Check (or fold by octaves) the pitches of a part into the instrument's range.

    Parameters
    ----------
    notes : pandas.DataFrame
        Notes of one part (notes table columns).
    instrument : Instrument
        The instrument playing the part.
    transpose_octaves : bool
        Move out-of-range notes by whole octaves instead of failing.

    Returns
    -------
    pandas.DataFrame
        ``notes`` (a copy, with ``midi_pitch`` folded when ``transpose_octaves``).

    Raises
    ------
    ScoreError
        A pitch is out of range (names file, part and measure).
    """
    pitch = notes["midi_pitch"].to_numpy(dtype=np.int64).copy()
    low, high = instrument.lowest, instrument.highest
    bad = np.flatnonzero((pitch < low) | (pitch > high))
    if bad.size and not transpose_octaves:
        i = int(bad[0])
        raise ScoreError(
            f"{_where(notes, i)}: MIDI pitch {pitch[i]} is outside the {instrument.name}'s "
            f"range {low}..{high} ({bad.size} such notes; use --transpose-octaves to fold "
            f"them by octaves)")
    while np.any(pitch < low):
        pitch = np.where(pitch < low, pitch + 12, pitch)
    while np.any(pitch > high):
        pitch = np.where(pitch > high, pitch - 12, pitch)
    out = notes.copy()
    out["midi_pitch"] = pitch.astype(np.int16)
    return out


def lowest_position_string(pitch: float, instrument: Instrument) -> int:
    """Return the highest string whose open pitch is at or below ``pitch`` (lowest position)."""
    opens = np.asarray(instrument.open_strings)
    return int(max(np.searchsorted(opens, pitch + 1e-6, side="right") - 1, 0))


def choose_strings(notes: pd.DataFrame, instrument: Instrument, *,
                   slur_span: float = 7.0) -> pd.DataFrame:
    """Choose string and finger for every note of one part.

    Rules, in order: a string indication is honoured where the pitch is playable on it
    (no higher above the open string than the top string's range allows); a
    double stop goes to two adjacent strings (lowest position) or, where that is impossible
    (three or more notes, or no adjacent pair fits), is marked ``rolled``; a slurred group
    stays on one string where all its pitches fit within ``slur_span`` semitones above the
    open string; otherwise each note takes the lowest position.

    Parameters
    ----------
    notes : pandas.DataFrame
        Notes of one part, pitches already in range (see :func:`fit_range`).
    instrument : Instrument
        The instrument.
    slur_span : float, semitones
        Largest finger position for keeping a slurred group on one string.

    Returns
    -------
    pandas.DataFrame [shape=(len(notes), 3)]
        Columns ``string`` (int8), ``semitones`` (float64, semitones above the open
        string) and ``rolled`` (bool), indexed like ``notes``.
    """
    n = len(notes)
    opens = np.asarray(instrument.open_strings, dtype=np.float64)
    pitch = notes["midi_pitch"].to_numpy(dtype=np.float64) + notes["cents"].to_numpy() / 100.0
    string = np.array([lowest_position_string(p, instrument) for p in pitch], dtype=np.int64)
    fixed = np.zeros(n, bool)
    rolled = np.zeros(n, bool)
    max_stop = instrument.highest - instrument.open_strings[-1]

    indication = notes["string_indication"].to_numpy(dtype=np.float64, na_value=np.nan)
    for i in np.flatnonzero(np.isfinite(indication)):
        s = int(indication[i])
        if 0 <= s < len(opens) and 0 <= pitch[i] - opens[s] + 1e-6 <= max_stop + 2e-6:
            string[i] = s
            fixed[i] = True

    chord_size = notes["chord_size"].to_numpy()
    onset = notes["onset_beats"].to_numpy()
    voice = notes["voice"].to_numpy()
    grace = notes["grace"].to_numpy()
    if np.any(chord_size > 1):
        key = pd.Series(list(zip(onset, voice, grace, strict=True)))
        for _, idx in key.groupby(key).groups.items():
            idx = np.asarray(idx)
            if idx.size < 2:
                continue
            order = idx[np.argsort(pitch[idx])]
            pair = _adjacent_pair(pitch[order], opens) if order.size == 2 else None
            if pair is not None:
                string[order] = pair
                fixed[order] = True
                continue
            rolled[order] = True
            used = _distinct_strings(pitch[order], opens)
            string[order] = used
            fixed[order] = True

    slur = notes["slur_id"].to_numpy(dtype=np.float64, na_value=np.nan)
    for sid in np.unique(slur[np.isfinite(slur)]):
        idx = np.flatnonzero((slur == sid) & ~fixed & (chord_size == 1))
        if idx.size < 2 or np.unique(string[idx]).size == 1:
            continue
        lo, hi = pitch[idx].min(), pitch[idx].max()
        fits = [s for s in range(len(opens))
                if lo >= opens[s] - 1e-6 and hi - opens[s] <= slur_span]
        if fits:
            string[idx] = max(fits)

    semitones = pitch - opens[string]
    bad = (semitones > max_stop + 1e-6) | (semitones < -1e-6)
    if bad.any():  # a chord or slur placement that the hand cannot reach: play it plainly
        string[bad] = [lowest_position_string(p, instrument) for p in pitch[bad]]
        semitones = pitch - opens[string]
    semitones = np.maximum(semitones, 0.0)
    return pd.DataFrame({"string": string.astype(np.int8), "semitones": semitones,
                         "rolled": rolled}, index=notes.index)


def _adjacent_pair(pitches: np.ndarray, opens: np.ndarray) -> np.ndarray | None:
    """Strings (s, s+1) for a two-note chord, lowest position first, or None."""
    lo, hi = pitches
    for s in range(len(opens) - 2, -1, -1):
        if lo >= opens[s] - 1e-6 and hi >= opens[s + 1] - 1e-6 and hi - opens[s + 1] <= 12:
            return np.array([s, s + 1])
    return None


def _distinct_strings(pitches: np.ndarray, opens: np.ndarray) -> np.ndarray:
    """Assign increasing strings to an ascending chord, as far as the strings allow."""
    k = pitches.size
    out = np.zeros(k, np.int64)
    nxt = len(opens) - 1
    for j in range(k - 1, -1, -1):
        s = min(nxt, int(max(np.searchsorted(opens, pitches[j] + 1e-6, side="right") - 1, 0)))
        out[j] = max(s, 0)
        nxt = max(s - 1, 0)
    return out
