"""The audio-frame database: build, Parquet round trip, resume, and errors naming the file."""

from __future__ import annotations

import shutil

import numpy as np
import pandas as pd
import pytest
import soundfile as sf

from data_schemas.audio_frames import AUDIO_FRAMES, read_audio_database
from data_schemas.errors import SchemaError
from data_schemas.io import read_frame, write_table
from gesture_db.audio_build import build_audio_database
from tests._audio_dataset import GAP_S, RECORDINGS, SAMPLE_RATE, write_dataset


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    root = write_dataset(tmp_path_factory.mktemp("data"))
    db = root.parent / "db"
    manifest = build_audio_database([root], db, workers=1, progress=False)
    return root, db, manifest


def test_frames_carry_the_tones_pitch_and_their_note(built):
    root, db, manifest = built
    adb = read_audio_database(db)
    assert sorted(adb.audio_paths) == sorted(RECORDINGS)
    assert adb.sample_rate == 44100 and 0.0058 <= adb.hop_s <= 0.0117
    f = adb.frames
    for name, notes in RECORDINGS.items():
        for i, (midi, _) in enumerate(notes):
            g = f[(f.recording == name) & (f.note == i) & f.voiced]
            cents = 1200 * np.log2(g.f0_hz.to_numpy() / (440 * 2 ** ((midi - 69) / 12)))
            assert len(g) > 40 and np.median(np.abs(cents)) < 5
    # frames in the gaps between notes belong to no note and are quiet or unvoiced
    gap = f[(f.recording == "tones-a") & (f.time_s < GAP_S - 0.03)]
    assert (gap.note == -1).all() and (gap.energy_db < -60).all()
    assert manifest["n_frames"] == len(f)


def test_refined_onsets_stay_near_the_tones_start(built):
    _, db, _ = built
    notes = read_audio_database(db).notes
    first = notes[(notes.recording == "tones-a") & (notes.note == 0)].iloc[0]
    assert abs(first.onset_s - GAP_S) < 0.03


def test_audio_is_referenced_and_loads_at_the_database_rate(built):
    root, db, _ = built
    adb = read_audio_database(db)
    assert adb.audio_paths["tones-a"] == (root / "audio" / "tones-a.wav").resolve()
    y = adb.load_audio("tones-a")
    n = sf.info(str(root / "audio" / "tones-a.wav")).frames
    assert y.dtype == np.float32 and abs(y.size - n * 44100 / SAMPLE_RATE) <= 2
    assert not list(db.rglob("*.wav"))


def test_tables_round_trip_through_parquet(built, tmp_path):
    _, db, manifest = built
    entry = manifest["recordings"]["tones-b"]
    frames = read_frame(db / entry["frames"], AUDIO_FRAMES)
    again = tmp_path / "f.parquet"
    write_table(frames, again, AUDIO_FRAMES)
    back = read_frame(again, AUDIO_FRAMES)
    pd.testing.assert_frame_equal(frames, back)
    assert frames["f0_hz"].isna().any() and frames["f0_hz"].notna().any()  # NaN survives


def test_a_second_build_resumes_without_analysing_again(built):
    root, db, manifest = built
    seen = []
    again = build_audio_database([root], db, workers=1, progress=False, on_done=seen.append)
    assert seen == [] and again["resumed_recordings"] == 2
    assert again["generation"] == manifest["generation"] + 1


def test_a_corrupted_table_is_named(built, tmp_path):
    _, db, manifest = built
    copy = tmp_path / "db"
    shutil.copytree(db, copy)
    target = copy / manifest["recordings"]["tones-a"]["frames"]
    target.write_bytes(b"not parquet")
    with pytest.raises(SchemaError, match="tones-a"):
        read_audio_database(copy)


def one_recording(tmp_path, notes="onset,offset,pitch,velocity\n0,12,69,64\n",
                  align="start,end\n0.1,0.5\n"):
    root = write_dataset(tmp_path / "one", {"x": [(69, 0.5)]})
    (root / "notes" / "x.csv").write_text(notes)
    (root / "alignments" / "x.csv").write_text(align)
    return root


@pytest.mark.parametrize("notes, align, file, what", [
    ("onset,offset,pitch,velocity\n0,12,69,64\n12,24,71,64\n", "start,end\n0.1,0.5\n",
     "alignments/x.csv", "1 alignment rows but x.csv has 2 notes"),
    ("onset,offset,pitch,velocity\n0,12,69,64\n", "start,end\n0.5,0.1\n",
     "alignments/x.csv", "end before start"),
    ("onset,offset,pitch,velocity\n0,12,69,64\n", "start,end\n0.1,9.0\n",
     "alignments/x.csv", "beyond the audio"),
    ("onset,offset,pitch,velocity\n0,12,40,64\n", "start,end\n0.1,0.5\n",
     "notes/x.csv", "outside the violin's range 55..100"),
    ("onset,offset,pitch\n0,12,69\n", "start,end\n0.1,0.5\n",
     "notes/x.csv", "column 'velocity'"),
])
def test_bad_annotations_are_named(tmp_path, notes, align, file, what):
    root = one_recording(tmp_path, notes, align)
    with pytest.raises(SchemaError) as err:
        build_audio_database([root], tmp_path / "db", workers=1, progress=False)
    assert str(root / file) in str(err.value) and what in str(err.value)
    assert not (tmp_path / "db" / "manifest.json").exists()


def test_a_bad_audio_file_is_named(tmp_path):
    root = one_recording(tmp_path)
    (root / "audio" / "x.wav").write_bytes(b"RIFF nonsense")
    with pytest.raises(SchemaError, match=r"x\.wav.*cannot read audio"):
        build_audio_database([root], tmp_path / "db", workers=1, progress=False)


def test_an_aligned_midi_file_annotates_audio(tmp_path):
    import mido

    root = tmp_path / "midi"
    root.mkdir()
    tone = np.concatenate([np.zeros(2205), 0.1 * np.sin(2 * np.pi * 440 * np.arange(11025)
                                                          / SAMPLE_RATE), np.zeros(2205)])
    sf.write(root / "take.wav", tone, SAMPLE_RATE)
    mid = mido.MidiFile(ticks_per_beat=1000)  # 120 bpm: 1 tick = 0.5 ms
    track = mido.MidiTrack([mido.Message("note_on", note=69, velocity=80, time=200),
                            mido.Message("note_off", note=69, velocity=0, time=1000)])
    mid.tracks.append(track)
    mid.save(str(root / "take.mid"))
    build_audio_database([root], tmp_path / "db", workers=1, progress=False)
    notes = read_audio_database(tmp_path / "db").notes
    assert notes[["midi_pitch", "velocity"]].values.tolist() == [[69.0, 80.0]]
    assert abs(notes.onset_s[0] - 0.1) < 0.03 and notes.offset_s[0] == pytest.approx(0.6)
