"""A built-in exercise: a detache pentachord on every string, as an actions table."""

from __future__ import annotations

import pandas as pd

from data_schemas.instruments import finger_ratio
from synth.strings import load_instrument

#: Semitones above the open string of the built-in exercise.
SCALE_STEPS = (0, 2, 4, 5, 7)
NOTE_NAMES = ("C", "C#", "D", "Eb", "E", "F", "F#", "G", "Ab", "A", "Bb", "B")
#: Shortest note of the exercise, s.
MIN_NOTE_DURATION = 0.45
#: Periods of the instrument's lowest open string a note lasts at least: the attack of a low
#: string takes more periods' time (the cello's open C2 settles after about 0.4 s).
NOTE_PERIODS = 60.0
#: The pitch is measured from this share of the note (and at least 0.15 s) ...
MEASURE_FROM = 0.45
#: ... to this long before its end (the bow stops), s.
MEASURE_STOP = 0.1


def note_name(midi_pitch: int) -> str:
    """Scientific pitch name of a MIDI pitch (60 -> C4)."""
    return f"{NOTE_NAMES[midi_pitch % 12]}{midi_pitch // 12 - 1}"


def default_note_duration(instrument: str) -> float:
    """Note length of the exercise on ``instrument``, s.

    At least :data:`MIN_NOTE_DURATION`, and :data:`NOTE_PERIODS` periods of the lowest open
    string (violin 0.45 s, viola 0.46 s, cello 0.92 s).

    Examples
    --------
    >>> round(default_note_duration("cello"), 2)
    0.92
    """
    lowest = load_instrument(instrument).strings[0]
    return max(MIN_NOTE_DURATION, NOTE_PERIODS / lowest.nominal_frequency())


def scale_actions(instrument: str, *, note_duration: float | None = None,
                  bow_velocity: float = 0.3, beta: float = 0.1,
                  start: float = 0.0) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Build the actions of a detache pentachord up every string of ``instrument``.

    Each note sets the bow on the string, accelerates to ``bow_velocity`` (m/s) in 50 ms,
    holds, and stops before the bow change; the force is the string's reference force (its
    Helmholtz mid force at beta 0.1, 0.3 m/s) scaled with velocity.

    Parameters
    ----------
    instrument : str
    note_duration : float, s, optional
        Length of each note (default :func:`default_note_duration`).
    bow_velocity : float, m/s
    beta : float
    start : float, s
        Time of the first note.

    Returns
    -------
    actions : pandas.DataFrame
        Actions table.
    events : pandas.DataFrame
        ``t0`` (s), ``label`` (note name), ``direction`` (+1 down, -1 up) per note, and
        ``measure_start``, ``measure_end`` (s): the settled part over which to measure its
        pitch (from :data:`MEASURE_FROM` of the note, at least 0.15 s in, to
        :data:`MEASURE_STOP` s before its end).
    """
    constants = load_instrument(instrument)
    if note_duration is None:
        note_duration = default_note_duration(instrument)
    settled = max(0.15, MEASURE_FROM * note_duration)
    rows, events = [], []
    t = start
    direction = 1.0
    for s, string in enumerate(constants.strings):
        force = string.reference_force * bow_velocity / 0.3
        for step in SCALE_STEPS:
            finger = float(finger_ratio(step))
            # the bow is set on the string with its force (5 ms), then accelerates in 50 ms
            for dt, v, f in ((0.0, 0.0, 0.0), (0.005, 0.0, force), (0.055, bow_velocity, force),
                             (note_duration - 0.08, bow_velocity, force),
                             (note_duration - 0.02, 0.0, 0.0)):
                rows.append((t + dt, s, finger, f, direction * v, beta, 0.5, False))
            events.append((t, note_name(string.midi_pitch + step), int(direction),
                           t + settled, t + note_duration - MEASURE_STOP))
            t += note_duration
            direction = -direction
        t += 0.2
    actions = pd.DataFrame(rows, columns=["time", "string", "finger_ratio", "bow_force",
                                          "bow_velocity", "beta", "bow_position", "pluck"])
    return actions, pd.DataFrame(events, columns=["t0", "label", "direction",
                                                  "measure_start", "measure_end"])
