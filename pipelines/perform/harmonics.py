"""Natural harmonics as the left hand plays them: a light finger at a node of the open string.

A natural harmonic (the notes table's ``harmonic_type`` ``"natural"``, ``midi_pitch`` its
sounding pitch) is the n-th harmonic of an open string: the finger only touches the string
at 1/n of its length from the nut (the actions table's ``finger_touch`` with
``finger_ratio = 1/n``), the whole string vibrates and only its partials with a node there
(multiples of n) sound. :func:`place_natural_harmonics` chooses string and n: the lowest n
whose harmonic sounds the written pitch (within half a semitone), on the indicated string
when the score gives one (the MusicXML reader turns a notated touching pitch into a string
indication, :func:`pipelines.score.marks.touched_string`). A natural harmonic no open string
gives is played stopped at its sounding pitch, with a warning.

Settings are ``[harmonics]`` in ``rules.toml``: ``highest_node`` (the highest n played) and
``min_beta``. The bow keeps its relative place on the sounding segment (L / n): beta on the
whole string is the dynamic's beta / n, at least ``min_beta`` (measured: the violin A
string's 4th harmonic at beta 0.025 slips four times a period; from 0.04 on it speaks).
Natural harmonics get no vibrato, intonation offset, ornament or portamento.

An artificial harmonic (``harmonic_type`` ``"artificial"``) is the n-th harmonic of a
stopped length: the first finger stops the string at the stopped note (``midi_pitch`` minus
12 log2 n semitones), a second, light finger touches it 1/n of the stopped length further
(the actions table's ``touch_ratio``): a fourth above for n = 4 (the default, two octaves
above the stopped note), a fifth for n = 3, a major third for n = 5, as the notes table's
``harmonic_node`` says (:func:`place_artificial_harmonics`). Its bow and force are those of
a natural harmonic of the same n (beta refers to the stopped length); no vibrato, intonation
offset, ornament or portamento; the stopping finger is corrected by ear like a stopped
note's.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

#: Largest distance (semitones) between a written pitch and the harmonic that plays it.
PITCH_TOLERANCE = 0.5


def node_semitones(n: int) -> float:
    """The touching point of the n-th harmonic (1/n from the nut), semitones above the open.

    :func:`data_schemas.instruments.finger_ratio` of it is 1/n.

    Examples
    --------
    >>> round(node_semitones(2), 6), round(node_semitones(4), 3)
    (12.0, 4.98)
    """
    return float(-12.0 * np.log2(1.0 - 1.0 / n))


def natural_node(pitch: float, open_strings: tuple[float, ...] | np.ndarray, *,
                 highest_node: int = 6, string: int | None = None) -> tuple[int, int] | None:
    """String and node n of the natural harmonic sounding ``pitch``, or None.

    Parameters
    ----------
    pitch : float, MIDI
        Sounding pitch.
    open_strings : sequence of float, MIDI
        The open strings, lowest first.
    highest_node : int
        Highest harmonic number considered.
    string : int, optional
        The indicated string: taken when one of its harmonics sounds ``pitch``.

    Returns
    -------
    (string, n) or None
        The lowest n (then the highest string) whose harmonic is within
        :data:`PITCH_TOLERANCE` of ``pitch``.

    Examples
    --------
    >>> violin = (55.0, 62.0, 69.0, 76.0)
    >>> natural_node(74.0, violin), natural_node(74.0, violin, string=0)
    ((1, 2), (0, 3))
    >>> natural_node(93.0, violin), natural_node(70.0, violin)
    ((2, 4), None)
    """
    found = []
    for s, open_pitch in enumerate(open_strings):
        for n in range(2, int(highest_node) + 1):
            if abs(pitch - open_pitch - 12.0 * np.log2(n)) <= PITCH_TOLERANCE:
                found.append((s, n))
    if not found:
        return None
    indicated = [f for f in found if f[0] == string]
    return min(indicated or found, key=lambda f: (f[1], -f[0]))


def place_natural_harmonics(notes: pd.DataFrame, strings: pd.DataFrame,
                            open_strings: tuple[float, ...], config: dict[str, Any],
                            warnings: list[str] | None = None) -> pd.DataFrame:
    """Put the part's natural harmonics on their string with a touching finger.

    Parameters
    ----------
    notes : pandas.DataFrame
        Notes of one part (notes table), indexed like ``strings``.
    strings : pandas.DataFrame
        :func:`pipelines.perform.instruments.choose_strings` output.
    open_strings : tuple of float, MIDI
        The instrument's open strings.
    config : dict
        Rules configuration (``[harmonics]``).
    warnings : list of str, optional
        Receives one line for natural harmonics played stopped: no open string gives them,
        or they sound in a chord (one finger touches only in single notes).

    Returns
    -------
    pandas.DataFrame
        ``strings`` with ``semitones`` at the node (:func:`node_semitones`) and two more
        columns: ``touch`` (bool, the finger only touches) and ``node`` (n, 0 = stopped).
    """
    out = strings.copy()
    out["touch"] = False
    out["node"] = 0
    if "harmonic_type" not in notes.columns:
        return out
    natural = (notes["harmonic_type"] == "natural").to_numpy()
    chord = notes["chord_size"].to_numpy() > 1
    highest = int(config["harmonics"]["highest_node"])
    indication = notes["string_indication"].to_numpy(dtype=np.float64, na_value=np.nan)
    missed = []
    for i in np.flatnonzero(natural):
        pitch = float(notes["midi_pitch"].iloc[i]) + float(notes["cents"].iloc[i]) / 100.0
        hint = int(indication[i]) if np.isfinite(indication[i]) else None
        found = None if chord[i] else natural_node(pitch, open_strings, highest_node=highest,
                                                   string=hint)
        if found is None:
            missed.append(int(notes["measure"].iloc[i]))
            continue
        s, n = found
        row = out.index[i]
        out.loc[row, ["string", "semitones", "touch", "node"]] = [s, node_semitones(n), True, n]
    out["string"] = out["string"].astype(np.int8)
    out["touch"] = out["touch"].astype(bool)
    out["node"] = out["node"].astype(np.int64)
    if missed and warnings is not None:
        warnings.append(f"part {notes['part_name'].iloc[0]!r}: {len(missed)} natural "
                        f"harmonic(s) in chords or given by no open string are played "
                        f"stopped (m. "
                        f"{', '.join(str(m) for m in sorted(set(missed)))})")
    return out


#: The artificial harmonic played when the score gives no touching pitch: a fourth above.
DEFAULT_ARTIFICIAL_NODE = 4


def artificial_stop(pitch: float, n: int, open_strings: tuple[float, ...] | np.ndarray, *,
                    max_semitones: float, string: int | None = None,
                    ) -> tuple[int, float] | None:
    """String and stopping finger (semitones above the open string) of an artificial harmonic.

    Parameters
    ----------
    pitch : float, MIDI
        Sounding pitch, the n-th harmonic of the stopped note.
    n : int
        Harmonic number (the touching finger at 1/n of the stopped length).
    open_strings : sequence of float, MIDI
        The open strings, lowest first.
    max_semitones : float
        Highest stopping position (semitones above the open string).
    string : int, optional
        The indicated string, taken when the stopped note lies on it.

    Returns
    -------
    (string, semitones) or None
        The indicated string or else the highest string on which the stopped note is at
        least a semitone above the open string (the lowest position); None when none fits.

    Examples
    --------
    >>> violin = (55.0, 62.0, 69.0, 76.0)
    >>> artificial_stop(93.0, 4, violin, max_semitones=27.0)  # A6: A4 stopped on D
    (1, 7.0)
    >>> artificial_stop(93.0, 4, violin, max_semitones=27.0, string=0)
    (0, 14.0)
    >>> artificial_stop(70.0, 4, violin, max_semitones=27.0) is None
    True
    """
    stopped = pitch - 12.0 * np.log2(n)
    fits = [s for s, o in enumerate(open_strings) if 1.0 - PITCH_TOLERANCE
            <= stopped - o <= max_semitones]
    if not fits:
        return None
    chosen = string if string in fits else max(fits)
    return chosen, float(stopped - open_strings[chosen])


def place_artificial_harmonics(notes: pd.DataFrame, strings: pd.DataFrame,
                               open_strings: tuple[float, ...], config: dict[str, Any],
                               warnings: list[str] | None = None) -> pd.DataFrame:
    """Put the part's artificial harmonics on a string: a stopping and a touching finger.

    Parameters and returns as :func:`place_natural_harmonics`, whose output ``strings`` is
    (with its ``touch`` and ``node`` columns): an artificial harmonic gets ``semitones`` at
    the stopped note, ``touch`` False and ``node`` n (the touching finger at 1/n of the
    stopped length, from ``harmonic_node``, default :data:`DEFAULT_ARTIFICIAL_NODE`). Those in
    chords or whose stopped note lies on no string are played stopped at their sounding
    pitch, with a line in ``warnings``.
    """
    out = strings.copy()
    if "harmonic_type" not in notes.columns:
        return out
    from data_schemas.instruments import limits

    top = float(-12.0 * np.log2(1.0 - limits().max_finger_ratio))
    artificial = (notes["harmonic_type"] == "artificial").to_numpy()
    chord = notes["chord_size"].to_numpy() > 1
    nodes = (notes["harmonic_node"].to_numpy(dtype=np.float64, na_value=np.nan)
             if "harmonic_node" in notes.columns else np.full(len(notes), np.nan))
    indication = notes["string_indication"].to_numpy(dtype=np.float64, na_value=np.nan)
    missed = []
    for i in np.flatnonzero(artificial):
        n = int(nodes[i]) if np.isfinite(nodes[i]) else DEFAULT_ARTIFICIAL_NODE
        pitch = float(notes["midi_pitch"].iloc[i]) + float(notes["cents"].iloc[i]) / 100.0
        hint = int(indication[i]) if np.isfinite(indication[i]) else None
        found = None if chord[i] else artificial_stop(pitch, n, open_strings,
                                                      max_semitones=top, string=hint)
        if found is None:
            missed.append(int(notes["measure"].iloc[i]))
            continue
        row = out.index[i]
        out.loc[row, ["string", "semitones", "touch", "node"]] = [found[0], found[1], False, n]
    out["string"] = out["string"].astype(np.int8)
    out["touch"] = out["touch"].astype(bool)
    out["node"] = out["node"].astype(np.int64)
    if missed and warnings is not None:
        warnings.append(f"part {notes['part_name'].iloc[0]!r}: {len(missed)} artificial "
                        f"harmonic(s) in chords or with their stopped note on no string are "
                        f"played stopped (m. "
                        f"{', '.join(str(m) for m in sorted(set(missed)))})")
    return out


__all__ = ["DEFAULT_ARTIFICIAL_NODE", "artificial_stop", "natural_node", "node_semitones",
           "place_artificial_harmonics", "place_natural_harmonics"]
