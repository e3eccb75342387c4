"""Training picks each cluster's sample among solo, in-tune notes, with the right f0."""

import numpy as np
import pytest
from _audio_db import fake_audio_database

from data_schemas import ParameterError
from synth.cws.training import clean_notes, frame_table, train


@pytest.fixture(scope="module")
def db():
    return fake_audio_database(seed=5)


def test_samples_are_clean_notes_at_their_pitch(db):
    model = train(db, n_clusters=5, seed=0)
    assert model.pointers.shape == (5, model.pitches.size)
    assert len(model.samples) == len(np.unique(model.pointers))
    assert "velocity" not in model.inputs           # all 64: no information, dropped
    for s in model.samples:
        note = db.notes[(db.notes.recording == s.recording) & (db.notes.note == s.note)].iloc[0]
        want = 440.0 * 2 ** ((note.midi_pitch - 69) / 12)
        assert abs(1200 * np.log2(s.f0_hz / want)) < 1.0
        assert s.audio.size == s.envelope.size > 0.25 * db.sample_rate
        assert s.partials[0] > s.partials[4]        # the fixture's partials fall as 1/h


def test_each_cluster_points_at_a_note_of_every_covered_semitone(db):
    """A note is played from a database note at its own semitone when there is one (the
    fixture's pitches), else at the nearest covered semitone: never an octave away."""
    model = train(db, n_clusters=5, seed=0)
    table = frame_table(db)
    covered = np.unique(db.notes.merge(table[clean_notes(db, table)][["recording", "note"]]
                                       .drop_duplicates()).midi_pitch)
    assert model.pitches.tolist() == covered.tolist()
    for k in range(5):
        for j, m in enumerate(model.pitches):
            s = model.samples[model.pointers[k, j]]
            assert abs(12 * np.log2(s.f0_hz / 440.0) + 69 - m) < 0.1
        for want in (55.0, 63.2, 70.4, 90.0):
            got = 12 * np.log2(model.sample_for(k, want).f0_hz / 440.0) + 69
            assert abs(got - want) == pytest.approx(np.min(np.abs(covered - want)), abs=0.1)


def test_overlapping_notes_are_not_candidates(db):
    notes = db.notes.copy()
    first = notes.index[(notes.recording == "rec0") & (notes.note == 1)][0]
    notes.loc[first, "offset_s"] += 0.3              # note 1 now overlaps note 2: a chord
    chord = type(db)(db.root, db.sample_rate, db.hop_s, db.frames, notes, db.audio_paths,
                     db.audio)
    table = frame_table(chord)
    ok = clean_notes(chord, table)
    rec0 = table.recording == "rec0"
    assert not ok[rec0 & table.note.isin([1, 2])].any()
    assert ok[rec0 & (table.note == 3)].all()


def test_too_few_frames_is_a_clear_error(db):
    tiny = type(db)(db.root, db.sample_rate, db.hop_s, db.frames.iloc[:20], db.notes,
                    db.audio_paths, db.audio)
    with pytest.raises(ParameterError, match="frames"):
        train(tiny, n_clusters=12)
