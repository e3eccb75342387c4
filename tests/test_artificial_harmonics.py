"""Artificial harmonics: a stopping finger and a light touching finger, score to sound.

Independent truths: the n-th harmonic of a stopped length sounds n times the stopped note's
equal-tempered frequency (here two octaves above for a touch a fourth above, n = 4),
measured by librosa's YIN; a touch at the node of the stopped length's n-th partial leaves
only its multiples of n (the others fall by 20 dB or more); the touching point of the n-th
harmonic is 1/n of the stopped length from the stopping finger (physics, not the code);
tables written before the touch_ratio column load with no second finger.
"""

from __future__ import annotations

import librosa
import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from data_schemas.actions import ACTIONS, read_actions
from pipelines.perform.config import load_config
from pipelines.perform.harmonics import artificial_stop
from synth.instrument import Instrument
from synth.strings import load_instrument

SR = 44100
STROKE = 1.5  # s
FIFTH = 1.0 - 2.0 ** (-7 / 12)  # finger_ratio of a stopped fifth


def _stroke(string: int, finger_ratio: float, touch_ratio, *, beta: float,
            force: float) -> pd.DataFrame:
    t = np.array([0.0, 0.05, STROKE - 0.05, STROKE])
    ramp = np.array([0.0, 1.0, 1.0, 0.0])
    table = {"time": t, "string": string, "finger_ratio": finger_ratio,
             "bow_force": force * ramp, "bow_velocity": 0.3 * ramp, "beta": beta,
             "bow_position": 0.5, "pluck": False}
    if touch_ratio is not None:
        table["touch_ratio"] = touch_ratio
    return pd.DataFrame(table)


def _artificial(string: int, n: int, seed: int = 0) -> tuple[np.ndarray, float]:
    """A stopped fifth with a touch at 1/n of the stopped length, bowed as the rules do."""
    const = load_instrument("violin").strings[string]
    harm = load_config()["harmonics"]
    touch = FIFTH + (1.0 - FIFTH) / n  # 1/n of the stopped length beyond the finger
    audio, _ = Instrument("violin", seed=seed).render(
        _stroke(string, FIFTH, touch, beta=max(0.1 * harm["segment_beta"] / n, harm["min_beta"]),
                force=harm["force"] * const.reference_force))
    f_stopped = 440.0 * 2.0 ** ((const.midi_pitch + 7 - 69) / 12.0)
    return audio[int(0.5 * SR):int((STROKE - 0.1) * SR)].astype(np.float64), f_stopped


CASES = [1, 2]  # violin D (A4 stopped -> A6) and A (E5 stopped -> E7)


@pytest.fixture(scope="module")
def fourths():
    return {s: _artificial(s, 4) for s in CASES}


@pytest.mark.parametrize("string", CASES)
def test_touch_a_fourth_above_sounds_two_octaves_above_the_stopped_note(fourths, string,
                                                                         record_property):
    steady, f_stopped = fourths[string]
    target = 4.0 * f_stopped
    f0 = librosa.yin(steady, fmin=target / 1.5, fmax=target * 1.5, sr=SR, frame_length=4096)
    cents = 1200.0 * np.log2(np.median(f0) / target)
    record_property("cents", round(float(cents), 2))
    assert abs(cents) <= 10.0


@pytest.mark.parametrize("string", CASES)
def test_partials_that_are_not_multiples_of_four_are_20_db_down(fourths, string):
    steady, f_stopped = fourths[string]
    spectrum = np.abs(np.fft.rfft(steady * np.hanning(steady.size)))
    freqs = np.fft.rfftfreq(steady.size, 1.0 / SR)
    k = np.arange(1, 9)
    db = np.array([20.0 * np.log10(spectrum[(freqs > 0.97 * j * f_stopped)
                                            & (freqs < 1.03 * j * f_stopped)].max() + 1e-30)
                   for j in k])
    assert db[k % 4 == 0].max() - db[k % 4 != 0].max() >= 20.0


def test_without_the_touch_the_stopped_note_sounds():
    """The same stopping finger with touch_ratio null: the stopped fifth (A4 on D)."""
    const = load_instrument("violin").strings[1]
    audio, _ = Instrument("violin", seed=0).render(
        _stroke(1, FIFTH, np.nan, beta=0.1, force=const.reference_force))
    steady = audio[int(0.5 * SR):int((STROKE - 0.1) * SR)].astype(np.float64)
    f0 = np.median(librosa.yin(steady, fmin=200.0, fmax=2000.0, sr=SR, frame_length=4096))
    assert abs(1200.0 * np.log2(f0 / 440.0)) <= 15.0


def test_null_touch_ratio_renders_bit_identical_to_no_column(tmp_path):
    """Old tables (schema 1.1, no touch_ratio) load with no second finger and sound the same."""
    frame = _stroke(1, FIFTH, None, beta=0.1, force=1.0)
    frame["time"] = frame["time"] * 0.4
    fields = [c.to_field() for c in ACTIONS.columns if c.name != "touch_ratio"]
    meta = dict(ACTIONS.schema.metadata)
    meta[b"arco_schema_version"] = b"1.1"
    table = pa.Table.from_pandas(frame.assign(finger_touch=False), preserve_index=False)
    pq.write_table(table.cast(pa.schema(fields)).replace_schema_metadata(meta),
                   str(tmp_path / "old.parquet"))
    loaded = read_actions(tmp_path / "old.parquet")
    assert loaded["touch_ratio"].isna().all()
    old = Instrument("violin", seed=1).render(loaded)[0]
    new = Instrument("violin", seed=1).render(frame.assign(touch_ratio=np.nan))[0]
    touched = Instrument("violin", seed=1).render(
        frame.assign(touch_ratio=FIFTH + (1 - FIFTH) / 4))[0]
    np.testing.assert_array_equal(old, new)
    assert not np.array_equal(old, touched)


def test_artificial_stop_takes_the_stopped_note_two_octaves_below():
    """Music theory: A6 = A4 stopped + a fourth; A4 lies on the D string a fifth up."""
    violin = (55.0, 62.0, 69.0, 76.0)
    assert artificial_stop(93.0, 4, violin, max_semitones=27.0) == (1, 7.0)
    # D5 + a fifth: the just twelfth (19.02 semitones) puts D5 two cents flat
    string, semitones = artificial_stop(93.0, 3, violin, max_semitones=27.0)
    assert string == 2 and semitones == pytest.approx(5.0 - 0.0196, abs=1e-3)
    assert artificial_stop(60.0, 4, violin, max_semitones=27.0) is None  # C2: below G3


@pytest.fixture(scope="module")
def score_render(tmp_path_factory):
    """A4 stopped with a D5 diamond (sounds A6), then D4 + G4 (D6), E4 + A4 (E6): rules."""
    from music21 import chord, dynamics, stream, tempo
    from music21 import instrument as m21instrument

    from pipelines.methods.render import render_score

    part = stream.Part(id="P1")
    part.partName = "Violin"
    part.insert(0, m21instrument.Violin())
    measure = stream.Measure(number=1)
    measure.insert(0, tempo.MetronomeMark(number=60))
    measure.insert(0, dynamics.Dynamic("mf"))
    for low, high in (("A4", "D5"), ("D4", "G4"), ("E4", "A4")):
        c = chord.Chord([low, high], quarterLength=1.5)
        c.notes[1].notehead = "diamond"
        measure.append(c)
    part.append(measure)
    score = stream.Score()
    score.insert(0, part)
    path = tmp_path_factory.mktemp("art") / "artificial.musicxml"
    score.write("musicxml", fp=str(path))
    return render_score(path, method="rules", seed=0)


def test_rules_stop_the_written_note_and_touch_a_fourth_above(score_render):
    actions = score_render.parts[0].actions
    sounding = actions[actions["bow_force"] > 0]
    assert sounding["touch_ratio"].notna().all()
    fr = sounding["finger_ratio"].to_numpy(np.float64)
    tr = sounding["touch_ratio"].to_numpy(np.float64)
    np.testing.assert_allclose(tr - fr, (1.0 - fr) / 4.0, atol=1e-6)  # 1/4 of the stopped
    assert not sounding["finger_touch"].eq(True).any()
    assert sounding["finger_ratio"].nunique() == 3  # one finger per note: no vibrato


def test_rules_artificial_harmonics_sound_two_octaves_up(score_render):
    audio = score_render.audio.astype(np.float64)
    events = score_render.parts[0].events
    for (t0, end), midi in zip(events[["t0", "end"]].to_numpy(), (93, 86, 88), strict=False):
        target = 440.0 * 2.0 ** ((midi - 69) / 12.0)
        seg = audio[int((t0 + 0.2) * SR):int((end - 0.05) * SR)]
        f0 = librosa.yin(seg, fmin=target / 1.5, fmax=target * 1.5, sr=SR, frame_length=2048)
        assert abs(1200.0 * np.log2(np.median(f0) / target)) <= 10.0


def test_gesture_sampling_adds_an_artificial_harmonics_touching_finger():
    """Rows of the harmonic's string over the note touch at 1/n of the stopped length."""
    from pipelines.methods.sampling import _touches
    from pipelines.perform.events import Event

    actions = pd.DataFrame({"time": [0.0, 0.5, 1.0, 1.5, 0.5], "string": [1, 1, 1, 1, 2],
                            "finger_ratio": np.float32(FIFTH)})
    harmonic = Event(rows=[0], t0=0.4, end=1.1, strings=[1], semitones=[7.0], dynamic=5.0,
                     label="a", node=4)
    out = _touches(actions, [harmonic])
    touch = out["touch_ratio"].to_numpy(np.float64)
    assert np.isnan(touch[[0, 3, 4]]).all()
    np.testing.assert_allclose(touch[[1, 2]], FIFTH + (1.0 - FIFTH) / 4.0, rtol=1e-6)
    assert not out["finger_touch"].any()
