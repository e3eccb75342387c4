"""The left hand as a gesture: simulated, described, stored, sampled and played back.

The truths are independent of the code under test: the simulator's per-note draws (written
to the annotation) against its contour measured by an FFT and by zero crossings; contours
synthesised here from known parameters against their extracted descriptions; the database
against a direct extraction of the same take; the sampled render's finger contour against
the chosen notes' descriptions.
"""

import json

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from data_schemas.errors import SchemaError
from gesture_db.left_hand import (
    LEFT_HAND_DIM,
    PARTS,
    describe_left_hand,
    left_hand_cents,
    mean_extent,
    mean_rate,
)
from pipelines.reports.vibrato import contour_figures

FS = 240.0


def zero_crossing_figures(cents: np.ndarray, fs: float) -> tuple[float, float]:
    """Rate (Hz) from the zero crossings of the detrended, lightly smoothed contour, and
    peak extent (cents) as sqrt(2) times its standard deviation."""
    x = np.convolve(cents, np.ones(7) / 7, mode="valid")
    k = np.arange(x.size)
    x = x - np.polyval(np.polyfit(k, x, 1), k)
    s = np.signbit(x)
    z = np.flatnonzero(s[1:] != s[:-1])
    z = z + x[z] / (x[z] - x[z + 1])
    return (z.size - 1) / (2 * (z[-1] - z[0]) / fs), float(np.std(x) * np.sqrt(2))


# --------------------------------------------------------------------------- simulator


@pytest.fixture(scope="module")
def long_takes():
    """Each shipped performer plays a script whose detache notes last 1.5 s."""
    from gesture_db.playing import play_script
    from gesture_db.script import recording_script
    from gesture_db.simulate_config import PERFORMERS

    out = {}
    for perf in PERFORMERS:
        rng = np.random.default_rng(11)
        script = recording_script(240, rng, "violin")
        script.loc[script["technique"] == "detache", "duration"] = 1.5
        out[perf.name] = play_script(script, perf, rng)
    return out


def test_simulated_vibrato_is_measured_back(long_takes):
    for name, (rec, ann) in long_takes.items():
        t = rec["time"].to_numpy()
        cents = rec["pitch_deviation_cents"].to_numpy()
        notes = ann[(ann["true_vibrato_extent_cents"] > 0)
                    & (ann["true_offset"] - ann["true_onset"] > 1.0)]
        assert len(notes) >= 20, name
        for _, n in notes.iterrows():
            m = (t >= n["true_onset"] + 0.45) & (t <= n["true_offset"] - 0.1)
            extent, rate, _offset = contour_figures(cents[m], FS)
            zc_rate, zc_extent = zero_crossing_figures(cents[m], FS)
            true_rate, true_extent = n["true_vibrato_rate_hz"], n["true_vibrato_extent_cents"]
            assert abs(rate - true_rate) < 0.3 and abs(zc_rate - true_rate) < 0.3, name
            assert abs(extent * np.sqrt(2) / true_extent - 1) < 0.2, name
            assert abs(zc_extent / true_extent - 1) < 0.2, name
            assert 4.0 <= true_rate <= 8.0 and 3.0 <= true_extent <= 35.0


def test_simulated_intonation_open_strings_and_styles(long_takes):
    rates = {}
    for name, (rec, ann) in long_takes.items():
        t = rec["time"].to_numpy()
        cents = rec["pitch_deviation_cents"].to_numpy()
        string = rec["string"].to_numpy()
        opens = ann["finger_ratio"].to_numpy() == 0
        assert (ann.loc[opens, "true_intonation_cents"] == 0).all()
        assert (ann.loc[opens, "true_vibrato_extent_cents"] == 0).all()
        for _, n in ann[opens].iterrows():  # an open string neither vibrates nor is re-tuned
            m = (t >= n["true_onset"] + 0.05) & (t <= n["true_offset"] - 0.05) \
                & (string == n["string"])
            assert np.abs(cents[m]).max(initial=0.0) < 2.0
        spread = ann.loc[~opens, "true_intonation_cents"].std()
        assert 4.0 < spread < 16.0, name
        # the measured median pitch of long stopped notes follows the drawn offset
        for _, n in ann[~opens & (ann["true_offset"] - ann["true_onset"] > 1.0)].iterrows():
            m = (t >= n["true_onset"] + 0.45) & (t <= n["true_offset"] - 0.1)
            assert abs(np.median(cents[m]) - n["true_intonation_cents"]) < 4.0
        rates[name] = ann["true_vibrato_rate_hz"].mean()
    assert rates["gentle"] < rates["steady"] < rates["energetic"]


def test_simulated_shifts_slide_before_the_new_note():
    from gesture_db.playing import play_script
    from gesture_db.simulate_config import PERFORMERS

    # a slurred one-string scale: positions 0-4 and 5-9 semitones, a shift from 4 to 5
    script = pd.DataFrame(dict(
        run=0, exercise=0, duration=0.5, rest_after=[0.0, 0.0, 0.0, 1.0],
        midi_pitch=[69 + 2, 69 + 4, 69 + 5, 69 + 7], string=2, dynamic=5.0,
        technique="legato", slur_position=["init", "mid", "mid", "end"],
        run_position=["init", "mid", "mid", "end"], tempo_bpm=120.0, instrument="violin"))
    script["finger_ratio"] = 1 - 2.0 ** (-(script["midi_pitch"] - 69) / 12)
    rec, ann = play_script(script, PERFORMERS[0], np.random.default_rng(3))
    t = rec["time"].to_numpy()
    cents = rec["pitch_deviation_cents"].to_numpy()
    shift_at = float(ann["true_onset"].iloc[2])
    before = (t > shift_at - 0.012) & (t < shift_at)  # the slide's last frames
    assert cents[before].mean() > 40.0  # 70 % of the semitone up, minus vibrato
    plain = float(ann["true_onset"].iloc[1])
    assert np.abs(cents[(t > plain - 0.012) & (t < plain)] - ann[
        "true_intonation_cents"].iloc[0]).max() < 30.0


def test_same_seed_same_recording():
    from gesture_db.playing import play_script
    from gesture_db.script import recording_script
    from gesture_db.simulate_config import PERFORMERS

    def take(seed):
        rng = np.random.default_rng(seed)
        return play_script(recording_script(40, rng, "violin"), PERFORMERS[1], rng)[0]

    pd.testing.assert_frame_equal(take(5), take(5))
    assert not take(5)["pitch_deviation_cents"].equals(take(6)["pitch_deviation_cents"])


# --------------------------------------------------------------------------- extraction


def synthesise(intonation, delay, extent0, extent1, rate0, rate1, duration, *, noise=0.3,
               seed=0):
    """A contour from known parameters: linear envelopes from the onset to the end."""
    t = np.arange(0.0, duration, 1.0 / FS)
    x = np.clip((t - delay) / (duration - delay), 0.0, 1.0)
    rate = rate0 + (rate1 - rate0) * x
    phase = 2 * np.pi * np.cumsum(np.where(t >= delay, rate, 0.0)) / FS
    extent = np.where(t >= delay, extent0 + (extent1 - extent0) * x, 0.0)
    rng = np.random.default_rng(seed)
    return intonation + extent * np.sin(phase) + rng.normal(0.0, noise, t.size)


@settings(max_examples=25, deadline=None)
@given(intonation=st.floats(-15, 15), delay=st.floats(0.1, 0.3), extent0=st.floats(5, 25),
       extent1=st.floats(5, 25), rate0=st.floats(4.5, 7.0), rate1=st.floats(4.5, 7.0),
       duration=st.floats(0.9, 2.0))
def test_extraction_round_trip(intonation, delay, extent0, extent1, rate0, rate1, duration):
    cents = synthesise(intonation, delay, extent0, extent1, rate0, rate1, duration)
    d = describe_left_hand(cents, FS)
    assert d.shape == (LEFT_HAND_DIM,)
    assert d[PARTS["intonation"]][0] == pytest.approx(intonation, abs=1.5)
    assert d[PARTS["onset_delay"]][0] == pytest.approx(delay, abs=0.1)
    assert d[PARTS["glide_time"]][0] == 0.0
    assert mean_rate(d) == pytest.approx(0.5 * (rate0 + rate1), abs=0.2)
    assert mean_extent(d) == pytest.approx(0.5 * (extent0 + extent1), rel=0.15)


def test_extraction_of_a_plain_note_and_of_a_glide():
    plain = describe_left_hand(6.0 + np.random.default_rng(1).normal(0, 0.3, 200), FS)
    assert mean_extent(plain) == 0.0
    assert plain[PARTS["onset_delay"]][0] == pytest.approx(199 / FS)
    assert plain[0] == pytest.approx(6.0, abs=0.3)
    body = synthesise(-4.0, 0.15, 12, 12, 5.5, 5.5, 0.8)
    glide = np.linspace(0.0, 70.0, 13)[1:] ** 1.0  # 50 ms sliding up 70 cents
    d = describe_left_hand(np.r_[body, body[-1] + glide], FS)
    assert d[PARTS["glide_time"]][0] == pytest.approx(0.03, abs=0.025)
    assert d[0] == pytest.approx(-4.0, abs=1.5)
    assert mean_rate(d) == pytest.approx(5.5, abs=0.2)


def test_play_back_keeps_rate_and_extent_when_stretched():
    d = describe_left_hand(synthesise(3.0, 0.2, 10, 16, 5.0, 6.0, 1.2), FS)
    for target in (0.9, 1.2, 2.4):
        t = np.arange(0.0, target, 1.0 / FS)
        cents, end = left_hand_cents(d, 1.2 - 1 / FS, target, t, phase=0.3)
        m = t >= 0.45
        extent, rate, _offset = contour_figures(cents[m], FS)
        assert rate == pytest.approx(mean_rate(d), abs=0.3)
        assert extent * np.sqrt(2) == pytest.approx(mean_extent(d), rel=0.2)
        # phase continuous: the next note starts where this one ends
        nxt, _ = left_hand_cents(d, 1.2, 1.0, np.array([0.0, 1 / FS]), phase=end)
        assert np.isfinite(nxt).all() and np.isfinite(end)
    off, _ = left_hand_cents(d, 1.2, 1.0, t, vibrato=False)
    assert np.allclose(off, d[0])


def test_bad_descriptions_are_refused():
    from data_schemas.errors import ParameterError

    with pytest.raises(ParameterError):
        left_hand_cents(np.zeros(3), 1.0, 1.0, np.zeros(2))
    with pytest.raises(ParameterError):
        describe_left_hand(np.array([0.0, np.nan, 1.0, 2.0, 3.0]), FS)


# --------------------------------------------------------------------------- recordings


def _csv_take(tmp_path, cents):
    from gesture_db.playing import play_script
    from gesture_db.script import recording_script
    from gesture_db.simulate_config import PERFORMERS

    rng = np.random.default_rng(2)
    rec, _ann = play_script(recording_script(12, rng, "violin"), PERFORMERS[0], rng)
    if cents is None:
        rec = rec.drop(columns="pitch_deviation_cents")
    else:
        rec["pitch_deviation_cents"] = rec["pitch_deviation_cents"].astype(object)
        rec.loc[7, "pitch_deviation_cents"] = cents
    path = tmp_path / "take.csv"
    rec.to_csv(path, index=False)
    return path


def test_recording_without_the_left_hand_still_loads(tmp_path):
    from gesture_db.importers import load_recording_file

    rec = load_recording_file(_csv_take(tmp_path, None))
    assert rec["pitch_deviation_cents"].isna().all()


@pytest.mark.parametrize("bad", ["wobbly", 5000.0])
def test_bad_left_hand_value_names_file_column_row(tmp_path, bad):
    from gesture_db.importers import load_recording_file

    path = _csv_take(tmp_path, bad)
    with pytest.raises(SchemaError) as err:
        load_recording_file(path)
    text = str(err.value)
    assert "take.csv" in text and "pitch_deviation_cents" in text and "row 7" in text


# --------------------------------------------------------------------------- database


def test_database_round_trip_of_the_left_hand(tiny_db):
    from data_schemas.annotation import read_annotation
    from data_schemas.recording import read_recording
    from gesture_db.extract import extract_take
    from gesture_db.store import GestureDB

    db = GestureDB(tiny_db / "db")
    assert db.manifest["schema_version"] == "1.2"
    notes = db.notes()
    path = sorted((tiny_db / "rec").glob("*take000.parquet"))[0]
    rec = read_recording(path)
    ann = read_annotation(str(path).replace(".parquet", ".annotation.parquet"))
    direct, contours, _ = extract_take(rec, ann, source_hash="x", source_path=str(path))
    stored = notes[notes["recording_id"] == rec["recording_id"].iloc[0]].sort_values(
        "note_index")
    assert stored["note_index"].tolist() == direct["note_index"].tolist()
    for want, got in zip(direct["left_hand"], stored["left_hand"], strict=True):
        np.testing.assert_allclose(np.asarray(got), want, rtol=0, atol=1e-12)
    assert contours["pitch_deviation_cents"].notna().all()
    from gesture_db.left_hand import LeftHandSource, stopped_notes

    stopped = stopped_notes(notes)
    assert stopped.mean() > 0.5 and (notes["left_hand_features"].notna() == stopped).all()
    described = 0
    source = LeftHandSource(db)
    for group in db.groups:
        model = db.left_hand_model(group)
        g = notes[(notes["group"] == group) & stopped]
        if model is None:
            assert g.empty
            continue
        described += len(g)
        feats = model.transform(np.vstack(g["left_hand"].to_numpy()))
        np.testing.assert_allclose(np.vstack(g["left_hand_features"].to_numpy()), feats,
                                   atol=1e-9)
        assert np.all(np.linalg.eigvalsh(model.feature_cov) > 0)
        mean = np.vstack(g["left_hand"].to_numpy()).mean(axis=0)
        for nid in notes.loc[(notes["group"] == group) & ~stopped, "note_id"]:
            np.testing.assert_allclose(source.get(nid), mean)  # open: the stopped notes' mean
    assert described == stopped.sum()
    # vibrato is found where the simulator played it
    vib = ann["true_vibrato_extent_cents"].to_numpy() > 0
    ext = np.array([mean_extent(np.asarray(v)) for v in direct["left_hand"]])
    long = (ann["true_offset"] - ann["true_onset"]).to_numpy() > 0.5
    assert (ext[vib & long] > 2.0).mean() > 0.8 and (ext[~vib] < 2.0).mean() > 0.9


def test_sampled_render_carries_the_sampled_vibrato(tiny_db):
    from pipelines.methods.feedback import scale_notes
    from pipelines.methods.sampling import open_database, render_sampling

    sdb = open_database(tiny_db / "db")
    scale = scale_notes(tonic=62, octaves=1, tempo=60.0)
    result = render_sampling(scale, db=sdb, feedback=False, progress=False, audio=False)
    part = result.parts[0]
    actions = part.performance.actions
    assert not part.performance.warnings
    checked = 0
    for m in range(len(part.targets)):
        target, choice = part.targets.iloc[m], part.choices.iloc[m]
        rows = actions[(actions["string"] == target["string"])
                       & (actions["time"] >= target["onset"] + 0.35)
                       & (actions["time"] < target["onset"] + target["duration"] - 0.05)]
        fr = rows["finger_ratio"].to_numpy(np.float64)
        cents = 1200 * np.log2((1 - target["finger_ratio"]) / (1 - fr))
        desc = sdb.left_hand.get(choice["note_id"])
        if target["finger_ratio"] == 0:
            assert np.ptp(cents) == 0  # open string: no vibrato
            continue
        if mean_extent(desc) < 5.0:
            continue
        extent, rate, _ = contour_figures(cents, 240.0)
        assert rate == pytest.approx(mean_rate(desc), abs=0.3)
        assert extent * np.sqrt(2) == pytest.approx(mean_extent(desc), rel=0.2)
        checked += 1
    assert checked >= 3
    again = render_sampling(scale, db=sdb, feedback=False, progress=False, audio=False)
    pd.testing.assert_frame_equal(again.parts[0].performance.actions, actions)


def test_old_database_plays_the_rules_left_hand_with_a_warning(tiny_db, tmp_path):
    import shutil

    import pyarrow.parquet as pq

    from pipelines.methods.feedback import scale_notes
    from pipelines.methods.sampling import open_database, render_sampling

    old = tmp_path / "old"
    shutil.copytree(tiny_db / "db", old)
    manifest = json.loads((old / "manifest.json").read_text())
    manifest["schema_version"] = "1.1"
    (old / "manifest.json").write_text(json.dumps(manifest))
    for f in manifest["files"]["notes"].values():  # a 1.1 database has no left hand
        table = pq.read_table(old / f)
        pq.write_table(table.drop_columns(["left_hand", "left_hand_features"]), old / f)
    sdb = open_database(old)
    assert sdb.left_hand.n_described == 0
    scale = scale_notes(tonic=62, octaves=1, tempo=60.0)
    part = render_sampling(scale, db=sdb, feedback=False, progress=False,
                           audio=False).parts[0]
    assert any("no left-hand gesture" in w for w in part.performance.warnings)
    stopped = part.targets[part.targets["finger_ratio"] > 0].iloc[1]
    rows = part.performance.actions
    rows = rows[(rows["string"] == stopped["string"])
                & (rows["time"] > stopped["onset"] + 0.4)
                & (rows["time"] < stopped["onset"] + stopped["duration"] - 0.05)]
    assert np.ptp(rows["finger_ratio"].to_numpy()) > 0  # the rules' vibrato
