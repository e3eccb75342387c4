"""Tunings, ranges, string and finger choice."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from data_schemas.errors import ParameterError
from data_schemas.instruments import finger_ratio, instrument_facts
from pipelines.perform.instruments import (
    choose_strings,
    fit_range,
    guess_instrument,
    string_index,
)
from pipelines.score import ScoreError


def part(pitches, **columns) -> pd.DataFrame:
    n = len(pitches)
    base = {
        "source_file": "x.musicxml", "part_name": "Violin", "part_id": "P1", "measure": 1,
        "voice": 1, "midi_pitch": pitches, "cents": 0.0, "onset_beats": np.arange(n, dtype=float),
        "grace": False, "chord_size": 1, "chord_index": 0,
        "slur_id": pd.array([None] * n, dtype="Int32"),
        "string_indication": pd.array([None] * n, dtype="Int8"),
    }
    base.update(columns)
    return pd.DataFrame(base)


def test_tunings():
    assert instrument_facts("violin").open_strings == (55, 62, 69, 76)
    assert instrument_facts("viola").open_strings == (48, 55, 62, 69)
    assert instrument_facts("cello").open_strings == (36, 43, 50, 57)
    with pytest.raises(ParameterError, match="not one of"):
        instrument_facts("guitar")


def test_string_index_by_letter_syllable_and_roman_numeral():
    cello = instrument_facts("cello")
    assert [string_index(cello, n) for n in ("C", "sol", "re.", "I", "IV", "E")] == \
        [0, 1, 2, 3, 0, None]


def test_lowest_position_and_open_strings():
    got = choose_strings(part([55, 57, 62, 68, 69, 76, 88]), instrument_facts("violin"))
    assert got["string"].tolist() == [0, 0, 1, 1, 2, 3, 3]
    assert got["semitones"].tolist() == [0, 2, 0, 6, 0, 0, 12]


def test_string_indication_is_honoured_where_playable():
    ind = pd.array([0, 0, None], dtype="Int8")
    got = choose_strings(part([69, 50, 69], string_indication=ind), instrument_facts("viola"))
    assert got["string"].tolist() == [0, 0, 3]
    assert got["semitones"].iloc[0] == 21


def test_slurred_group_stays_on_one_string_where_it_fits():
    slur = pd.array([0, 0, 0], dtype="Int32")
    got = choose_strings(part([66, 67, 69], slur_id=slur), instrument_facts("violin"))
    assert got["string"].nunique() == 1 and got["string"].iloc[0] == 1
    free = choose_strings(part([66, 67, 69]), instrument_facts("violin"))
    assert free["string"].nunique() == 2


def test_double_stop_on_adjacent_strings_else_rolled():
    notes = part([62, 69, 55, 62, 71], onset_beats=[0.0, 0.0, 1.0, 1.0, 1.0],
                 chord_size=[2, 2, 3, 3, 3], chord_index=[0, 1, 0, 1, 2])
    got = choose_strings(notes, instrument_facts("violin"))
    assert got["string"].tolist()[:2] == [1, 2] and not got["rolled"].iloc[:2].any()
    assert got["rolled"].iloc[2:].all()
    assert got["string"].iloc[2:].is_monotonic_increasing


def test_out_of_range_names_part_and_measure_unless_transposed():
    notes = part([40, 60], measure=[7, 8])
    with pytest.raises(ScoreError, match=r"part 'Violin', measure 7"):
        fit_range(notes, instrument_facts("violin"))
    folded = fit_range(notes, instrument_facts("violin"), transpose_octaves=True)
    assert folded["midi_pitch"].tolist() == [64, 60]


def test_guess_instrument_from_names_and_range():
    assert guess_instrument(["Violoncello"]) == "cello"
    assert guess_instrument(["Vla."]) == "viola"
    assert guess_instrument(["Violin 2"]) == "violin"
    assert guess_instrument(["Flute"], np.array([40, 60])) == "cello"


def test_finger_ratio():
    assert finger_ratio(np.array([0.0, 12.0])) == pytest.approx([0.0, 0.5])
