"""The frames engine on a synthetic database of harmonic tones: finite, deterministic, in
tune (also where the database lacks the pitch), silent with the bow off, cached index."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from data_schemas.errors import ParameterError
from data_schemas.instruments import finger_ratio
from gesture_db.audio_build import build_audio_database
from synth.engines import EngineChoice, engine_names, get_engine
from synth.frames.index import INDEX_NAME
from tests._audio_dataset import write_dataset

SR = 44100


@pytest.fixture(scope="module")
def db(tmp_path_factory):
    root = write_dataset(tmp_path_factory.mktemp("data"))
    build_audio_database([root], root.parent / "db", workers=1, progress=False)
    return root.parent / "db"


def note_actions(midi_pitches, seconds=0.6, rest=0.2, string=2, vibrato_cents=0.0):
    """Bowed notes on the A string (open A4 = 69) with rests between them, 5 ms rows."""
    rows, now = [], 0.0
    for midi in midi_pitches:
        t = now + np.arange(0, seconds, 0.005)
        cents = vibrato_cents * np.sin(2 * np.pi * 5.5 * (t - now))
        ratio = finger_ratio(midi - 69 + cents / 100)
        rows.append(pd.DataFrame({"time": t, "string": string, "finger_ratio": ratio,
                                  "bow_force": 0.8, "bow_velocity": 0.3, "beta": 0.12,
                                  "bow_position": 0.5, "pluck": False}))
        now += seconds + rest
    return pd.concat(rows, ignore_index=True)


def median_pitch_cents(y, midi, start, stop):
    import librosa

    seg = y[int(start * SR):int(stop * SR)].astype(np.float64)
    f0 = librosa.yin(seg, fmin=150, fmax=2000, sr=SR, frame_length=2048)
    return float(np.median(1200 * np.log2(f0 / (440 * 2 ** ((midi - 69) / 12)))))


def test_frames_is_a_registered_engine_without_diagnostics(db):
    assert "frames" in engine_names()
    engine = get_engine(EngineChoice("frames", {"audio_db": str(db)}), "violin")
    assert engine.has_diagnostics is False
    with pytest.raises(ParameterError, match="whole actions tables"):
        engine.process(256, {})


def test_frames_needs_a_database():
    with pytest.raises(ParameterError, match="--audio-db"):
        get_engine("frames", "violin")


@pytest.mark.parametrize("midi", [71, 70, 73])  # in the database; between its tones
def test_render_is_finite_deterministic_and_in_tune(db, midi):
    actions = note_actions([midi], seconds=0.8)
    a, diag = get_engine("frames", "violin", audio_db=db).render(actions, tail=0.1)
    b, _ = get_engine("frames", "violin", audio_db=db).render(actions, tail=0.1)
    assert diag is None and a.dtype == np.float32 and np.isfinite(a).all()
    assert a.tobytes() == b.tobytes()
    assert a.size == int(round((actions.time.max() + 0.1) * SR))
    assert abs(median_pitch_cents(a, midi, 0.15, 0.65)) < 10


def test_vibrato_in_the_finger_reaches_the_sound(db):
    import librosa

    flat, _ = get_engine("frames", "violin", audio_db=db).render(note_actions([71], 1.0))
    vib, _ = get_engine("frames", "violin", audio_db=db).render(
        note_actions([71], 1.0, vibrato_cents=30.0))

    def spread(y):
        f0 = librosa.yin(y[int(0.1 * SR):int(0.9 * SR)].astype(float), fmin=150, fmax=2000,
                         sr=SR, frame_length=2048, hop_length=256)
        return float(np.std(1200 * np.log2(f0)))
    assert spread(vib) > 12 > spread(flat)


def test_silence_where_the_bow_is_off_the_string(db):
    actions = note_actions([71, 74], seconds=0.5, rest=0.4)
    y, _ = get_engine("frames", "violin", audio_db=db).render(actions, tail=0.3)
    rest = y[int(0.55 * SR):int(0.85 * SR)]
    note = y[int(0.1 * SR):int(0.4 * SR)]
    assert np.abs(rest).max() == 0.0 and np.sqrt(np.mean(note ** 2)) > 0.01
    assert np.abs(y[-int(0.2 * SR):]).max() == 0.0


def test_the_index_is_built_once_and_rebuilt_when_the_database_changes(db, tmp_path):
    import shutil

    get_engine("frames", "violin", audio_db=db)
    cache = db / INDEX_NAME
    first = cache.stat().st_mtime_ns
    get_engine("frames", "violin", audio_db=db)
    assert cache.stat().st_mtime_ns == first
    copy = tmp_path / "db"
    shutil.copytree(db, copy)
    manifest = (copy / "manifest.json").read_text()
    (copy / "manifest.json").write_text(manifest.replace('"digest": "', '"digest": "x'))
    get_engine("frames", "violin", audio_db=copy)
    assert (copy / INDEX_NAME).read_bytes() != cache.read_bytes()


def test_cli_builds_the_database_and_renders_a_score_with_frames(tmp_path, capsys):
    import soundfile as sf
    from _notation_score import write_score

    import pipelines.cli.main as cli

    root = write_dataset(tmp_path / "data")
    code = cli.main(["build-db", "--audio", str(root), "-o", str(tmp_path / "db"),
                     "--workers", "1"])
    out, err = capsys.readouterr()
    assert code == 0 and "audio-frame database generation 1" in out, err
    code = cli.main(["engines"])
    assert "frames" in capsys.readouterr().out
    (tmp_path / "score").mkdir()
    score = write_score(tmp_path / "score")
    wav = tmp_path / "x.wav"
    code = cli.main(["render", str(score), "--method", "rules", "--engine", "frames",
                     "--audio-db", str(tmp_path / "db"), "--end-measure", "2", "-o", str(wav),
                     "--quiet", "--transpose-octaves"])
    _, err = capsys.readouterr()
    assert code == 0, err
    y, sr = sf.read(wav)
    assert sr == SR and np.isfinite(y).all() and np.abs(y).max() > 0.01
    # a missing database is one line naming the option, exit 2
    code = cli.main(["render", str(score), "--engine", "frames", "--audio-db",
                     str(tmp_path / "nowhere"), "-o", str(wav), "--quiet"])
    assert code == 2 and "--audio-db" in capsys.readouterr().err


def _peak_db(x, f0):
    """Level (dB) and frequency of the spectral peak within 3 % of ``f0``."""
    spec = np.abs(np.fft.rfft(x * np.hanning(x.size), 1 << 18))
    freqs = np.fft.rfftfreq(1 << 18, 1 / SR)
    band = np.abs(freqs - f0) < 0.03 * f0
    i = np.argmax(spec[band])
    return 20 * np.log10(spec[band][i]), freqs[band][i]


def test_a_double_stop_sounds_both_strings_at_their_solo_levels(db):
    """Truth: each string alone. In the double stop (open A4 and open E5, one row per
    string) both fundamentals sound at their pitch and within 2 dB of their solo level."""
    low = note_actions([69], seconds=1.0, string=2)
    high = note_actions([69], seconds=1.0, string=3)    # note_actions' ratio: open E5
    both = pd.concat([low, high]).sort_values("time", kind="stable", ignore_index=True)
    engine = get_engine("frames", "violin", audio_db=db)
    mid = slice(int(0.25 * SR), int(0.85 * SR))
    chord = engine.render(both, tail=0.1)[0][mid].astype(float)
    for alone, midi in ((low, 69), (high, 76)):
        solo = engine.render(alone, tail=0.1)[0][mid].astype(float)
        f0 = 440.0 * 2 ** ((midi - 69) / 12)
        level, freq = _peak_db(chord, f0)
        assert abs(1200 * np.log2(freq / f0)) < 10
        assert abs(level - _peak_db(solo, f0)[0]) < 2.0
