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


__all__ = ["natural_node", "node_semitones", "place_natural_harmonics"]
