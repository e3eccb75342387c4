"""MIDI reading through mido."""

from __future__ import annotations

import mido
import numpy as np
import pytest

from pipelines.score import read_score
from pipelines.score.midi import velocity_to_dynamic


@pytest.fixture()
def midi_file(tmp_path):
    mid = mido.MidiFile(ticks_per_beat=480)
    meta = mido.MidiTrack()
    meta.append(mido.MetaMessage("set_tempo", tempo=mido.bpm2tempo(100), time=0))
    meta.append(mido.MetaMessage("time_signature", numerator=3, denominator=4, time=0))
    meta.append(mido.MetaMessage("set_tempo", tempo=mido.bpm2tempo(50), time=480 * 6))
    mid.tracks.append(meta)
    track = mido.MidiTrack()
    track.append(mido.MetaMessage("track_name", name="Solo", time=0))
    track.append(mido.Message("program_change", program=41, channel=0, time=0))
    events = [(0, 60, 49), (480, 62, 80), (960, 64, 96), (3 * 480, 50, 112), (3 * 480, 57, 112),
              (6 * 480, 60, 64)]
    msgs = []
    for start, pitch, vel in events:
        msgs.append((start, mido.Message("note_on", note=pitch, velocity=vel, channel=0)))
        msgs.append((start + 480, mido.Message("note_off", note=pitch, velocity=0, channel=0)))
    now = 0
    for tick, msg in sorted(msgs, key=lambda m: (m[0], m[1].type == "note_on")):
        track.append(msg.copy(time=tick - now))
        now = tick
    mid.tracks.append(track)
    path = tmp_path / "solo.mid"
    mid.save(path)
    return path


def test_midi_notes_timing_and_tempo(midi_file):
    notes = read_score(midi_file)
    assert len(notes) == 6
    assert notes["midi_pitch"].tolist() == [60, 62, 64, 50, 57, 60]
    assert notes["onset_beats"].tolist() == [0, 1, 2, 3, 3, 6]
    # 100 qpm for 6 beats (3.6 s), then 50 qpm
    assert notes["onset"].to_numpy() == pytest.approx([0, 0.6, 1.2, 1.8, 1.8, 3.6])
    assert notes["duration"].iloc[-1] == pytest.approx(1.2)
    assert notes["measure"].tolist() == [1, 1, 1, 2, 2, 3]


def test_midi_instrument_chords_and_dynamics(midi_file):
    notes = read_score(midi_file)
    assert set(notes["instrument"]) == {"viola"}
    assert notes["part_name"].iloc[0] == "Solo"
    assert notes["chord_size"].tolist() == [1, 1, 1, 2, 2, 1]
    assert notes["dynamic"].to_numpy() == pytest.approx(velocity_to_dynamic(
        np.array([49, 80, 96, 112, 112, 64])))
    assert notes["dynamic"].iloc[1] == pytest.approx(5.0)  # velocity 80 = mf
    assert not notes[["staccato", "accent", "tie_start"]].to_numpy().any()
    assert notes["run_position"].tolist()[:3] == ["init", "mid", "mid"]
