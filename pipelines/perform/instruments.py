"""Violin, viola and cello in a score: which instrument, range folding, string and finger.

The instruments' facts (tunings, ranges, bow) are :mod:`data_schemas.instruments`'s
:class:`~data_schemas.instruments.InstrumentFacts`. Strings are counted from 0 = the lowest
string. A stopped note's finger position is given in semitones above the open string; the
actions table wants :func:`data_schemas.instruments.finger_ratio` of it.
"""

from __future__ import annotations

import re

import numpy as np
import pandas as pd

from data_schemas.instruments import InstrumentFacts, instrument_facts
from pipelines.score.errors import ScoreError


def string_index(instrument: InstrumentFacts, name: str) -> int | None:
    """Return the index of string ``name`` (a letter, solfège syllable or I..IV), or None.

    Examples
    --------
    >>> violin = instrument_facts("violin")
    >>> string_index(violin, "III"), string_index(violin, "e"), string_index(violin, "x")
    (1, 3, None)
    """
    key = name.strip().lower().rstrip(".")
    key = {"do": "c", "re": "d", "mi": "e", "sol": "g", "la": "a"}.get(key, key)
    roman = {"i": 3, "ii": 2, "iii": 1, "iv": 0}
    if key in roman:
        return roman[key]
    for i, letter in enumerate(instrument.string_names):
        if letter.lower() == key:
            return i
    return None


_NAME_PATTERNS = (
    (r"viol(on)?cell|\bvc\b|\bvlc\b|cello|\bvcl\b", "cello"),
    (r"viola|\bvla\b|\bva\b|bratsche|alto", "viola"),
    (r"violin|\bvln?\b|\bvn\b|violon|geige|\bvl\b", "violin"),
)


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
        if low >= instrument_facts("violin").lowest:
            return "violin"
        if low >= instrument_facts("viola").lowest:
            return "viola"
        return "cello"
    return "violin"


def _where(notes: pd.DataFrame, i: int) -> str:
    row = notes.iloc[i]
    name = row["part_name"] or row["part_id"]
    return f"{row['source_file']}: part {name!r}, measure {row['measure']}"


def fit_range(notes: pd.DataFrame, instrument: InstrumentFacts, *,
              transpose_octaves: bool = False) -> pd.DataFrame:
    """Check (or fold by octaves) the pitches of a part into the instrument's range.

    Parameters
    ----------
    notes : pandas.DataFrame
        Notes of one part (notes table columns).
    instrument : InstrumentFacts
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


def lowest_position_string(pitch: float, instrument: InstrumentFacts) -> int:
    """Return the highest string whose open pitch is at or below ``pitch`` (lowest position)."""
    opens = np.asarray(instrument.open_strings)
    return int(max(np.searchsorted(opens, pitch + 1e-6, side="right") - 1, 0))


def choose_strings(notes: pd.DataFrame, instrument: InstrumentFacts, *,
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
    instrument : InstrumentFacts
        The instrument.
    slur_span : float, semitones
        Largest finger position for keeping a slurred group on one string.

    Returns
    -------
    pandas.DataFrame [shape=(len(notes), 3)]
        Columns ``string`` (int8), ``semitones`` (float64, semitones above the open
        string) and ``rolled`` (bool), indexed like ``notes``.
    """
    opens = np.asarray(instrument.open_strings, dtype=np.float64)
    pitch = notes["midi_pitch"].to_numpy(dtype=np.float64) + notes["cents"].to_numpy() / 100.0
    string = np.array([lowest_position_string(p, instrument) for p in pitch], dtype=np.int64)
    max_stop = instrument.highest - instrument.open_strings[-1]
    fixed = _honour_indications(notes, pitch, opens, max_stop, string)
    rolled = _place_chords(notes, pitch, opens, string, fixed)
    _keep_slurs_on_one_string(notes, pitch, opens, string, fixed, slur_span)
    semitones = pitch - opens[string]
    bad = (semitones > max_stop + 1e-6) | (semitones < -1e-6)
    if bad.any():  # a chord or slur placement that the hand cannot reach: play it plainly
        string[bad] = [lowest_position_string(p, instrument) for p in pitch[bad]]
        semitones = pitch - opens[string]
    semitones = np.maximum(semitones, 0.0)
    return pd.DataFrame({"string": string.astype(np.int8), "semitones": semitones,
                         "rolled": rolled}, index=notes.index)


def _honour_indications(notes: pd.DataFrame, pitch: np.ndarray, opens: np.ndarray,
                        max_stop: float, string: np.ndarray) -> np.ndarray:
    """Put notes on their indicated string where playable there; return which were placed."""
    fixed = np.zeros(len(notes), bool)
    indication = notes["string_indication"].to_numpy(dtype=np.float64, na_value=np.nan)
    for i in np.flatnonzero(np.isfinite(indication)):
        s = int(indication[i])
        if 0 <= s < len(opens) and 0 <= pitch[i] - opens[s] + 1e-6 <= max_stop + 2e-6:
            string[i] = s
            fixed[i] = True
    return fixed


def _place_chords(notes: pd.DataFrame, pitch: np.ndarray, opens: np.ndarray,
                  string: np.ndarray, fixed: np.ndarray) -> np.ndarray:
    """Double stops on adjacent strings, other chords rolled; return which notes are rolled."""
    rolled = np.zeros(len(notes), bool)
    chord_size = notes["chord_size"].to_numpy()
    if not np.any(chord_size > 1):
        return rolled
    key = pd.Series(list(zip(notes["onset_beats"].to_numpy(), notes["voice"].to_numpy(),
                             notes["grace"].to_numpy(), strict=True)))
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
        string[order] = _distinct_strings(pitch[order], opens)
        fixed[order] = True
    return rolled


def _keep_slurs_on_one_string(notes: pd.DataFrame, pitch: np.ndarray, opens: np.ndarray,
                              string: np.ndarray, fixed: np.ndarray, slur_span: float) -> None:
    """Move each slurred group not yet placed to the highest string that holds it all."""
    chord_size = notes["chord_size"].to_numpy()
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


__all__ = ["choose_strings", "fit_range", "guess_instrument", "lowest_position_string",
           "string_index"]
