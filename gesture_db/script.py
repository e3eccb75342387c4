"""Recording scripts of the simulated violinist: scales and short exercises.

Like the recording scripts of Maestre et al. 2010, the exercises cover the techniques x five
dynamics x contexts (slur position, run position, tempo) x four strings. The constants are
``[script]`` of ``gesture_db/config/simulate.toml``; open strings are the facts of the
instrument played (:mod:`data_schemas.instruments`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from data_schemas.annotation import TECHNIQUES
from data_schemas.instruments import finger_ratio, instrument_facts
from gesture_db.simulate_config import simulator_config

#: The simulated performer's default instrument.
INSTRUMENT = "violin"


def script_finger_ratio(midi_pitch: np.ndarray | int, string: np.ndarray | int,
                        instrument: str = INSTRUMENT) -> np.ndarray:
    """Finger ratio of a pitch on a string (0 = lowest); pitches below it count as open.

    Examples
    --------
    >>> float(script_finger_ratio(69, 2))  # the violin's open A
    0.0
    >>> round(float(script_finger_ratio(48, 0, "cello")), 4)  # an octave up the C string
    0.5
    """
    opens = np.asarray(instrument_facts(instrument).open_strings, float)
    semis = np.asarray(midi_pitch, float) - opens[np.asarray(string)]
    return finger_ratio(np.maximum(semis, 0.0))


def recording_script(n_notes: int, rng: np.random.Generator,
                     instrument: str = INSTRUMENT) -> pd.DataFrame:
    """Generate a recording script of scales and short exercises.

    Exercises cycle through every technique x five dynamics x four strings (shuffled) and
    split their notes into runs separated by rests and, for legato, into slurs of 2-4 notes,
    so every slur and run position occurs.

    Parameters
    ----------
    n_notes : int
        Number of notes (the last exercise is cut to fit).
    rng : numpy.random.Generator
        Random source.
    instrument : {"violin", "viola", "cello"}
        Instrument whose open strings the exercises are written for.

    Returns
    -------
    pandas.DataFrame
        One row per note: ``instrument``, ``exercise``, ``run``,
        ``onset`` (nominal, s), ``duration`` (s),
        ``rest_after`` (s), ``midi_pitch``, ``string``, ``finger_ratio``, ``dynamic``,
        ``technique``, ``slur_position``, ``run_position``, ``tempo_bpm``.
    """
    cfg = simulator_config()["script"]
    n_strings = instrument_facts(instrument).n_strings
    combos = [(t, d, s) for t in TECHNIQUES for d in cfg["dynamics"]
              for s in range(n_strings)]
    rows: list[dict] = []
    state = {"time": cfg["start"], "exercise": 0, "run": 0, "instrument": instrument}
    while len(rows) < n_notes:
        for k in rng.permutation(len(combos)):
            if len(rows) >= n_notes:
                break
            _exercise(rows, combos[k], n_notes - len(rows), state, cfg, rng)
            state["exercise"] += 1
    frame = pd.DataFrame(rows)
    frame.insert(0, "instrument", instrument)
    frame["finger_ratio"] = script_finger_ratio(frame["midi_pitch"].to_numpy(),
                                                frame["string"].to_numpy(), instrument)
    return frame


def _exercise(rows: list[dict], combo: tuple[str, float, int], room: int, state: dict,
              cfg: dict, rng: np.random.Generator) -> None:
    """Append the notes of one exercise (at most ``room``) to ``rows``."""
    technique, dynamic, string = combo
    lo, hi = cfg["durations"][technique]
    dur = float(np.exp(rng.uniform(np.log(lo), np.log(hi))))
    pitches, strings = _exercise_pitches(technique, string, rng, state["instrument"])
    pitches = pitches[:room]
    strings = strings[: len(pitches)]
    runs = _split_runs(len(pitches), technique, rng)
    beat = dur if dur >= cfg["min_beat"] else cfg["short_notes_per_beat"] * dur
    idx = 0
    for r, length in enumerate(runs):
        positions = _positions(length)
        slurs = _slur_positions(length, rng) if technique == "legato" else ["iso"] * length
        for j in range(length):
            rest = 0.0
            if j == length - 1:
                rest = cfg["exercise_rest"] if r == len(runs) - 1 else max(beat,
                                                                           cfg["min_run_rest"])
            rows.append(dict(
                exercise=state["exercise"], run=state["run"], onset=state["time"],
                duration=dur, rest_after=rest, midi_pitch=int(pitches[idx]),
                string=int(strings[idx]), dynamic=dynamic, technique=technique,
                slur_position=slurs[j], run_position=positions[j], tempo_bpm=60.0 / beat))
            state["time"] += dur + rest
            idx += 1
        state["run"] += 1


def _exercise_pitches(technique: str, string: int, rng: np.random.Generator,
                      instrument: str = INSTRUMENT):
    """Pitches and strings of one exercise: a scale on one string or a two-string pattern."""
    cfg = simulator_config()["script"]
    facts = instrument_facts(instrument)
    opens = facts.open_strings
    n = int(rng.integers(*cfg["notes_per_exercise"]))
    if rng.random() < cfg["scale_share"] or string == facts.n_strings - 1:
        major = cfg["scale_steps"]
        start = int(rng.integers(0, cfg["scale_starts"]))
        steps = list(major[start:]) + list(major[::-1][1:])
        root = int(rng.choice(cfg["roots"]))
        semis = [root + s for s in steps]
        semis = (semis * 3)[:n]
        strings = [string] * len(semis)
        pitches = [opens[string] + s for s in semis]
    else:  # string crossings with the string above
        pattern = [(string + offset, semis) for offset, semis in cfg["crossing_pattern"]]
        pat = (pattern * 3)[:n]
        strings = [s for s, _ in pat]
        pitches = [opens[s] + k for s, k in pat]
    if technique == "legato":  # no repeated pitch inside a slur
        pitches = [p + (1 if i and p == pitches[i - 1] else 0) for i, p in enumerate(pitches)]
    return np.array(pitches), np.array(strings)


def _split_runs(n: int, technique: str, rng: np.random.Generator) -> list[int]:
    """Split ``n`` notes into runs without rests (lengths 1-8; legato runs >= 2)."""
    cfg = simulator_config()["script"]
    choices = cfg["legato_run_lengths"] if technique == "legato" else cfg["run_lengths"]
    runs: list[int] = []
    left = n
    while left > 0:
        length = min(int(rng.choice(choices)), left)
        if technique == "legato" and length == 1 and runs:
            runs[-1] += 1
        else:
            runs.append(length)
        left -= length
    return runs


def _positions(length: int) -> list[str]:
    if length == 1:
        return ["iso"]
    return ["init"] + ["mid"] * (length - 2) + ["end"]


def _slur_positions(length: int, rng: np.random.Generator) -> list[str]:
    out: list[str] = []
    left = length
    while left > 0:
        size = min(int(rng.integers(*simulator_config()["script"]["slur_sizes"])), left)
        if left - size == 1:
            size += 1
        out += _positions(size) if size > 1 else ["iso"]
        left -= size
    return out


__all__ = ["INSTRUMENT", "recording_script", "script_finger_ratio"]
