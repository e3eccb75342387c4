"""The cws engine plays actions through cluster-weighted sampling of a (synthetic) database:
right pitch, no clicks, bit-identical for a seed, clear errors."""

import numpy as np
import pandas as pd
import pytest
from _audio_db import fake_audio_database

from data_schemas import ParameterError
from synth.clicks import find_clicks
from synth.engines import engine_names, get_engine

RATE = 22050


@pytest.fixture(scope="module")
def db():
    return fake_audio_database(seed=3)


def phrase(pitches_semitones, note_s=0.5, string=2, slur_pairs=False):
    """Detached (or pairwise slurred) notes on one string, 5 ms rows, alternating bows."""
    rows = []
    for i, semis in enumerate(pitches_semitones):
        bow = i // 2 if slur_pairs else i
        sign = 1.0 if bow % 2 == 0 else -1.0
        steps = int(round(note_s / 0.005))
        for t in np.round(i * note_s + 0.005 * np.arange(steps), 6):
            rows.append((t, string, 1 - 2 ** (-semis / 12), 0.6, 0.3 * sign, 0.1, 0.5, False))
    return pd.DataFrame(rows, columns=["time", "string", "finger_ratio", "bow_force",
                                       "bow_velocity", "beta", "bow_position", "pluck"])


def f0_of(x, rate):
    """f0 by the peak of a long zero-padded spectrum refined on the first partial."""
    spec = np.abs(np.fft.rfft(x * np.hanning(x.size), 1 << 18))
    freqs = np.fft.rfftfreq(1 << 18, 1 / rate)
    band = (freqs > 150) & (freqs < 2000)
    return freqs[band][np.argmax(spec[band])]


def test_registered():
    assert "cws" in engine_names()


def test_plays_the_target_pitches_without_clicks(db):
    engine = get_engine("cws", "violin", sample_rate=RATE, seed=0, audio_db=db, n_clusters=4)
    semis = [0, 2, 5, 7, 3]                          # on the A string: A4 B4 D5 E5 C5
    audio, diag = engine.render(phrase(semis), tail=0.3)
    assert diag is None and audio.dtype == np.float32
    assert find_clicks(audio, RATE).size == 0
    for i, s in enumerate(semis):                    # sustain: the middle of each note
        seg = audio[int((i * 0.5 + 0.2) * RATE):int((i * 0.5 + 0.45) * RATE)].astype(float)
        want = 440.0 * 2 ** (s / 12)
        assert abs(1200 * np.log2(f0_of(seg, RATE) / want)) < 10
    assert np.sqrt(np.mean(audio ** 2)) > 0.01


def test_slurs_join_without_clicks_and_same_seed_same_audio(db):
    engine = get_engine("cws", "violin", sample_rate=RATE, seed=2, audio_db=db, n_clusters=4)
    actions = phrase([0, 3, 5, 2, 7, 8], note_s=0.3, slur_pairs=True)
    a, _ = engine.render(actions)
    b, _ = get_engine("cws", "violin", sample_rate=RATE, seed=2, audio_db=db,
                      n_clusters=4).render(actions)
    assert np.array_equal(a, b)
    assert find_clicks(a, RATE).size == 0
    c, _ = get_engine("cws", "violin", sample_rate=RATE, seed=3, audio_db=db,
                      n_clusters=4).render(actions)
    assert not np.array_equal(a, c)


def test_attack_replays_the_sample_after_a_bow_change(db):
    """The first 30 ms after a bow change carry the sample's noisy attack: the sound is less
    periodic there than in the sustain (the sinusoidal model has no noise)."""
    engine = get_engine("cws", "violin", sample_rate=RATE, seed=0, audio_db=db, n_clusters=4)
    audio, _ = engine.render(phrase([0, 0]))
    x = audio.astype(float)

    def roughness(seg):
        return np.sum(np.diff(seg, 2) ** 2) / np.sum(seg ** 2)
    assert roughness(x[int(0.505 * RATE):int(0.535 * RATE)]) > 2 * roughness(
        x[int(0.8 * RATE):int(0.83 * RATE)])


def test_render_actions_plays_it_with_an_engine_object(db):
    from synth.render import render_actions

    engine = get_engine("cws", "violin", sample_rate=RATE, seed=0, audio_db=db, n_clusters=3,
                        oversample=2, body="synthesized", body_seed=0)
    audio = render_actions(phrase([0, 4]), instrument=engine, sample_rate=RATE)
    assert audio.size == int(round((0.995 + 1.0) * RATE)) and np.abs(audio).max() > 0.01


def test_clear_errors(db):
    with pytest.raises(ParameterError, match="audio_db"):
        get_engine("cws", "violin")
    engine = get_engine("cws", "violin", sample_rate=RATE, audio_db=db, n_clusters=2)
    with pytest.raises(ParameterError, match="blocks"):
        engine.process(256)
    with pytest.raises(ParameterError, match="diagnostics"):
        engine.render(phrase([0]), diagnostics=True)
    with pytest.raises(ParameterError, match="cws"):
        get_engine("cws", "violin", audio_db=db, attack_seconds=1.0)



def test_a_double_stop_plays_its_top_note_as_one_note():
    """One row per string at each time (how the rules write a double stop): one note, the
    upper string's pitch, not notes of one control period alternating between strings."""
    from synth.cws.notes import action_notes

    low, high = phrase([0], note_s=1.0, string=1), phrase([4], note_s=1.0, string=2)
    both = pd.concat([low, high]).sort_values("time", kind="stable")
    notes = action_notes(both)
    assert len(notes) == 1
    assert notes["string"].iloc[0] == 2
    assert notes["midi_pitch"].iloc[0] == pytest.approx(69 + 4, abs=0.01)


def test_the_lower_string_of_a_double_stop_is_a_second_voice():
    from synth.cws.notes import action_notes, voices

    low, high = phrase([0], note_s=1.0, string=1), phrase([4], note_s=1.0, string=2)
    both = pd.concat([low, high]).sort_values("time", kind="stable")
    assert voices(both) == 2 and voices(high) == 1
    lower = action_notes(both, voice=1)
    assert len(lower) == 1 and lower["string"].iloc[0] == 1
    assert lower["midi_pitch"].iloc[0] == pytest.approx(62, abs=0.01)
    assert action_notes(high, voice=1).empty


def _peak_db(x, rate, f0):
    """Level (dB) of the spectral peak within 3 % of ``f0`` and its frequency."""
    spec = np.abs(np.fft.rfft(x * np.hanning(x.size), 1 << 18))
    freqs = np.fft.rfftfreq(1 << 18, 1 / rate)
    band = np.abs(freqs - f0) < 0.03 * f0
    i = np.argmax(spec[band])
    return 20 * np.log10(spec[band][i]), freqs[band][i]


def test_a_two_voice_double_stop_sounds_both_pitches_at_their_solo_levels(db):
    """Truth: each string played alone. In the double stop both fundamentals are there, at
    their pitch (10 cents) and within 1.5 dB of their solo level."""
    engine = get_engine("cws", "violin", sample_rate=RATE, seed=0, audio_db=db, n_clusters=4)
    low, high = phrase([0], note_s=1.0, string=1), phrase([4], note_s=1.0, string=2)
    both = pd.concat([low, high]).sort_values("time", kind="stable")
    mid = slice(int(0.3 * RATE), int(0.9 * RATE))
    chord = engine.render(both, tail=0.2)[0][mid].astype(float)
    for alone, f0 in ((low, 440.0 * 2 ** (-7 / 12)), (high, 440.0 * 2 ** (4 / 12))):
        solo = engine.render(alone, tail=0.2)[0][mid].astype(float)
        level, freq = _peak_db(chord, RATE, f0)
        assert abs(1200 * np.log2(freq / f0)) < 10
        assert abs(level - _peak_db(solo, RATE, f0)[0]) < 1.5


def test_the_sustain_follows_the_vibrato_in_the_finger(db):
    """Truth: a finger moving +-30 cents at 5.5 Hz (pitch std 21 cents); the sustain (after
    the replayed attack) carries it, a steady finger gives a steady pitch."""
    import librosa

    from data_schemas.instruments import finger_ratio

    flat = phrase([2], note_s=1.5)
    vib = flat.assign(finger_ratio=finger_ratio(
        2 + 0.3 * np.sin(2 * np.pi * 5.5 * flat["time"].to_numpy())))
    engine = get_engine("cws", "violin", sample_rate=RATE, seed=0, audio_db=db, n_clusters=4)

    def cents(actions):
        y = engine.render(actions, tail=0.2)[0][int(0.65 * RATE):int(1.4 * RATE)]
        f0 = librosa.yin(y.astype(float), fmin=300, fmax=1200, sr=RATE, frame_length=1024,
                         hop_length=128)
        return 1200 * np.log2(f0 / (440 * 2 ** (2 / 12)))

    assert np.std(cents(flat)) < 3
    assert 15 < np.std(cents(vib)) < 27
    assert abs(np.median(cents(vib))) < 10
