"""Natural harmonics: a light finger at 1/n of the string, from the score to the sound.

Independent truths: the n-th harmonic of an open string sounds n times its nominal
(equal-tempered) frequency, measured by librosa's YIN; a touch at a node of mode n leaves
only the partials that have a node there (multiples of n), the others fall by 20 dB or more;
the node of the n-th harmonic is 1/n of the string from the nut (physics, not the code);
a MusicXML diamond notehead at a touching pitch names the string and the node (music
theory: a diamond an octave above an open string is its 2nd harmonic, a fourth above its
4th).
"""

from __future__ import annotations

import librosa
import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.csv as pacsv
import pyarrow.parquet as pq
import pytest

from data_schemas.actions import ACTIONS, read_actions
from pipelines.perform.config import load_config
from pipelines.perform.harmonics import natural_node
from synth.instrument import Instrument
from synth.strings import load_instrument

SR = 44100
STROKE = 1.5  # s


def _stroke(string: int, finger_ratio: float, touch, *, beta: float, force: float,
            velocity: float = 0.3) -> pd.DataFrame:
    t = np.array([0.0, 0.05, STROKE - 0.05, STROKE])
    table = {"time": t, "string": string, "finger_ratio": finger_ratio,
             "bow_force": force * np.array([0.0, 1.0, 1.0, 0.0]),
             "bow_velocity": velocity * np.array([0.0, 1.0, 1.0, 0.0]), "beta": beta,
             "bow_position": 0.5, "pluck": False}
    if touch is not None:
        table["finger_touch"] = touch
    return pd.DataFrame(table)


def _harmonic(string: int, n: int) -> tuple[np.ndarray, float]:
    """Bow the n-th natural harmonic as the rules do at beta 0.1 (``[harmonics]``)."""
    const = load_instrument("violin").strings[string]
    harm = load_config()["harmonics"]
    beta = max(0.1 * harm["segment_beta"] / n, harm["min_beta"])
    audio, _ = Instrument("violin", seed=0).render(
        _stroke(string, 1.0 / n, True, beta=beta, force=harm["force"] * const.reference_force))
    f_open = 440.0 * 2.0 ** ((const.midi_pitch - 69) / 12.0)
    return audio[int(0.5 * SR):int((STROKE - 0.1) * SR)].astype(np.float64), f_open


CASES = [(s, n) for s in (1, 2) for n in (2, 3, 4)]  # violin D and A strings


@pytest.fixture(scope="module")
def harmonics():
    return {case: _harmonic(*case) for case in CASES}


@pytest.mark.parametrize(("string", "n"), CASES)
def test_natural_harmonic_sounds_n_times_the_open_string(harmonics, string, n,
                                                         record_property):
    steady, f_open = harmonics[(string, n)]
    target = n * f_open
    f0 = librosa.yin(steady, fmin=target / 1.5, fmax=target * 1.5, sr=SR, frame_length=4096)
    cents = 1200.0 * np.log2(np.median(f0) / target)
    record_property("cents", round(float(cents), 2))
    print(f"violin string {string} harmonic {n}: {cents:+.2f} cents")
    assert abs(cents) <= 10.0


def _partials_db(steady: np.ndarray, f_open: float, count: int) -> np.ndarray:
    spectrum = np.abs(np.fft.rfft(steady * np.hanning(steady.size)))
    freqs = np.fft.rfftfreq(steady.size, 1.0 / SR)
    return np.array([20.0 * np.log10(spectrum[(freqs > 0.97 * k * f_open)
                                              & (freqs < 1.03 * k * f_open)].max() + 1e-30)
                     for k in range(1, count + 1)])


@pytest.mark.parametrize(("string", "n"), CASES)
def test_partials_without_a_node_at_the_finger_are_20_db_down(harmonics, string, n,
                                                              record_property):
    steady, f_open = harmonics[(string, n)]
    db = _partials_db(steady, f_open, 3 * n)
    k = np.arange(1, db.size + 1)
    margin = db[k % n == 0].max() - db[k % n != 0].max()
    record_property("margin_db", round(float(margin), 1))
    assert margin >= 20.0  # e.g. for n = 2 every odd partial of the open string


def test_a_touching_finger_is_not_a_stopping_one():
    """The same finger_ratio 1/3 stopped sounds a fifth above the open string, not a 12th."""
    const = load_instrument("violin").strings[1]
    audio, _ = Instrument("violin", seed=0).render(
        _stroke(1, 1.0 / 3.0, False, beta=0.1, force=const.reference_force))
    steady = audio[int(0.5 * SR):int((STROKE - 0.1) * SR)].astype(np.float64)
    f_open = 440.0 * 2.0 ** ((const.midi_pitch - 69) / 12.0)
    f0 = np.median(librosa.yin(steady, fmin=100.0, fmax=2000.0, sr=SR, frame_length=4096))
    assert abs(1200.0 * np.log2(f0 / (1.5 * f_open))) <= 10.0


def _old_table(path, frame: pd.DataFrame) -> None:
    """Write ``frame`` as an actions file of schema 1.0 (no finger_touch nor touch_ratio)."""
    fields = [c.to_field() for c in ACTIONS.columns
              if c.name not in ("finger_touch", "touch_ratio")]
    meta = dict(ACTIONS.schema.metadata)
    meta[b"arco_schema_version"] = b"1.0"
    table = pa.Table.from_pandas(frame, preserve_index=False).cast(pa.schema(fields))
    if str(path).endswith(".csv"):
        pacsv.write_csv(table, str(path))
    else:
        pq.write_table(table.replace_schema_metadata(meta), str(path))


@pytest.mark.parametrize("suffix", [".parquet", ".csv"])
def test_old_actions_file_loads_as_stopped_and_renders_identically(tmp_path, suffix):
    frame = _stroke(1, 1 - 2 ** (-7 / 12), None, beta=0.1, force=1.0)
    frame["time"] = frame["time"] * 0.4
    path = tmp_path / f"old{suffix}"
    _old_table(path, frame)
    loaded = read_actions(path)
    assert loaded["finger_touch"].isna().all()
    old = Instrument("violin", seed=1).render(loaded)[0]
    stopped = Instrument("violin", seed=1).render(frame.assign(finger_touch=False))[0]
    touched = Instrument("violin", seed=1).render(frame.assign(finger_touch=True))[0]
    np.testing.assert_array_equal(old, stopped)
    assert not np.array_equal(old, touched)


def test_finger_touch_steps_at_its_row_within_one_render():
    """Stopped, then touched at the same 1/3 on one string: a fifth, then a twelfth up."""
    const = load_instrument("violin").strings[2]
    a = _stroke(2, 1.0 / 3.0, False, beta=0.1, force=const.reference_force)
    b = _stroke(2, 1.0 / 3.0, True, beta=0.04, force=const.reference_force)
    b["time"] = b["time"] + STROKE  # its first row shares a's last row's time: b wins
    audio, _ = Instrument("violin", seed=0).render(pd.concat([a, b], ignore_index=True))
    for start, expect in ((0.5, 1.5 * 440.0), (STROKE + 0.5, 3.0 * 440.0)):
        seg = audio[int(start * SR):int((start + 0.8) * SR)].astype(np.float64)
        f0 = np.median(librosa.yin(seg, fmin=400.0, fmax=2500.0, sr=SR, frame_length=4096))
        assert abs(1200.0 * np.log2(f0 / expect)) <= 10.0


def _diamond_score(path):
    """Violin: diamonds at D5, C4, E5 (touching pitches), an o-marked A5, a stopped B4."""
    from music21 import articulations, note, stream
    from music21 import instrument as m21instrument

    part = stream.Part(id="P1")
    part.partName = "Violin"
    part.insert(0, m21instrument.Violin())
    measure = stream.Measure(number=1)
    for name in ("D5", "C4", "E5"):
        n = note.Note(name, quarterLength=1.0)
        n.notehead = "diamond"
        measure.append(n)
    o = note.Note("A5", quarterLength=1.0)
    o.articulations.append(articulations.StringHarmonic())
    measure.append(o)
    part.append(measure)
    part.append(stream.Measure([note.Note("B4", quarterLength=4.0)], number=2))
    score = stream.Score()
    score.insert(0, part)
    score.write("musicxml", fp=str(path))
    return path


def test_musicxml_diamonds_become_touching_rows_at_the_node(tmp_path):
    from pipelines.perform.rules import perform_part
    from pipelines.score import read_score_report

    notes, _ = read_score_report(_diamond_score(tmp_path / "harmonics.musicxml"))
    assert notes["midi_pitch"].tolist() == [74, 79, 88, 81, 71]  # sounding pitches
    perf = perform_part(notes, load_config())
    a = perf.actions[perf.actions["bow_force"] > 0]
    # (string, n): D5 on the D string's octave; C4 a fourth above G3 -> G string's 4th;
    # E5 a fifth above A4 -> A string's 3rd; A5 (o) -> the A string's octave (lowest n)
    expected = [(1, 2), (0, 4), (2, 3), (2, 2)]
    for (t0, end), (string, n) in zip(perf.events[["t0", "end"]].to_numpy()[:4], expected,
                                      strict=True):
        rows = a[(a["time"] > t0 + 0.01) & (a["time"] < end - 0.02)]  # not the last note's
        assert rows["finger_touch"].eq(True).all() and (rows["string"] == string).all()
        np.testing.assert_allclose(rows["finger_ratio"], 1.0 / n, atol=1e-6)  # no vibrato
    t0 = perf.events["t0"].iloc[4]
    stopped = a[a["time"] >= t0 + 0.3]
    assert not stopped["finger_touch"].eq(True).any()
    assert stopped["finger_ratio"].std() > 0  # the stopped B4 has its vibrato


@pytest.mark.parametrize(("pitch", "string", "expect"), [
    (74.0, None, (1, 2)),   # D5: the D string's octave (the G string's 3rd is higher n)
    (74.0, 0, (0, 3)),      # ... sul G: the G string's 3rd harmonic (G3 + 19 = D5)
    (79.0, None, (0, 4)),   # G5: the G string's 4th (two octaves)
    (88.0, None, (3, 2)),   # E6: the E string's octave (lower n than the A string's 3rd)
    (88.0, 2, (2, 3)),      # ... sul A: the A string's 3rd (A4 + 19)
    (93.0, None, (2, 4)),   # A6
    (70.0, None, None),     # Bb4: no open string's harmonic
])
def test_natural_node_chooses_the_lowest_harmonic(pitch, string, expect):
    assert natural_node(pitch, (55.0, 62.0, 69.0, 76.0), string=string) == expect


def test_rendered_diamond_score_sounds_the_harmonics(tmp_path):
    """End to end (rules, modal engine): each harmonic at its sounding pitch (YIN, 10 cents)."""
    from pipelines.methods.render import render_score

    out = render_score(_diamond_score(tmp_path / "h.musicxml"), method="rules", seed=0)
    audio = out.audio.astype(np.float64)
    events = out.parts[0].events
    for (t0, end), midi in zip(events[["t0", "end"]].to_numpy()[:4], (74, 79, 88, 81),
                               strict=True):
        target = 440.0 * 2.0 ** ((midi - 69) / 12.0)
        seg = audio[int((t0 + 0.15) * SR):int((end - 0.05) * SR)]
        f0 = librosa.yin(seg, fmin=target / 1.5, fmax=target * 1.5, sr=SR, frame_length=2048)
        assert abs(1200.0 * np.log2(np.median(f0) / target)) <= 10.0


@pytest.mark.parametrize(("touch", "ratio"), [(False, 1.5), (True, 3.0)])
def test_block_api_takes_the_touching_finger(touch, ratio):
    """Instrument.process with BowControl(finger_touch=...): a fifth stopped, a twelfth touched."""
    from synth.controls import BowControl

    const = load_instrument("violin").strings[2]
    violin = Instrument("violin", seed=0)
    beta = 0.1 * 2.5 / 3 if touch else 0.1
    control = BowControl(0.3, 0.5 * const.reference_force if touch else const.reference_force,
                         beta, 1.0 / 3.0, finger_touch=touch)
    blocks = [violin.process(1024, {2: control}, diagnostics=False).audio for _ in range(60)]
    steady = np.concatenate(blocks)[int(0.5 * SR):].astype(np.float64)
    f0 = np.median(librosa.yin(steady, fmin=400.0, fmax=2500.0, sr=SR, frame_length=4096))
    assert abs(1200.0 * np.log2(f0 / (ratio * 440.0))) <= 10.0


def test_gesture_sampling_keeps_a_harmonics_light_finger():
    from pipelines.methods.sampling import _touches
    from pipelines.perform.events import Event

    actions = pd.DataFrame({"time": [0.0, 0.5, 1.0, 1.5, 0.5], "string": [1, 1, 1, 1, 2],
                            "finger_ratio": 0.5})
    harmonic = Event(rows=[0], t0=0.4, end=1.1, strings=[1], semitones=[12.0], dynamic=5.0,
                     label="h", touch=True, node=2)
    stopped = Event(rows=[1], t0=1.2, end=2.0, strings=[1], semitones=[12.0], dynamic=5.0,
                    label="s")
    out = _touches(actions, [harmonic, stopped])
    assert out["finger_touch"].tolist() == [False, True, True, False, False]
    assert "finger_touch" not in _touches(actions, [stopped])
