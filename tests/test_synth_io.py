"""The synth CLI: determinism, formats, and clear errors on bad input."""

import hashlib
import subprocess
import sys
import time

import numpy as np
import pandas as pd
import pytest
import soundfile as sf
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from data_schemas import SchemaError, validate_actions, write_actions
from pipelines.cli.main import main
from synth import BowControl, Instrument, render_actions


def stroke(string=1, force=0.6, duration=0.4, finger=0.0):
    times = [0.0, 0.05, duration - 0.05, duration]
    return pd.DataFrame({
        "time": times, "string": [string] * 4, "finger_ratio": [finger] * 4,
        "bow_force": [0.0, force, force, 0.0], "bow_velocity": [0.0, 0.3, 0.3, 0.0],
        "beta": [0.1] * 4, "bow_position": [0.2, 0.3, 0.6, 0.7], "pluck": [False] * 4})


def digest(path):
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_same_actions_and_seed_give_bit_identical_wav(tmp_path):
    actions = tmp_path / "a.parquet"
    write_actions(stroke(), actions)
    paths = [tmp_path / f"{k}.wav" for k in "abc"]
    for path, seed in zip(paths, (7, 7, 8), strict=True):
        # Separate processes, a second apart: no state and no time stamp may leak into files.
        run = subprocess.run([sys.executable, "-m", "pipelines.cli.main", "synth", str(actions),
                              "-o", str(path), "--seed", str(seed), "--quiet"],
                             capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
        time.sleep(1.1)
    assert digest(paths[0]) == digest(paths[1])
    assert digest(paths[0]) != digest(paths[2])
    audio, rate = sf.read(paths[0], dtype="float32")
    assert rate == 44100 and audio.dtype == np.float32 and np.abs(audio).max() > 0.01


@pytest.mark.parametrize(("rate", "oversample", "suffix"),
                         [(48000, 1, ".wav"), (44100, 4, ".flac")])
def test_cli_rates_oversampling_and_csv(tmp_path, rate, oversample, suffix):
    actions = tmp_path / "a.csv"
    write_actions(stroke(string=0), actions)
    out = tmp_path / f"out{suffix}"
    code = main(["synth", str(actions), "-o", str(out), "--instrument", "viola",
                 "--sample-rate", str(rate), "--oversample", str(oversample), "--quiet"])
    assert code == 0
    audio, got_rate = sf.read(out)
    assert got_rate == rate and np.all(np.isfinite(audio)) and np.abs(audio).max() > 0.001


def test_out_of_range_value_names_file_column_and_row(tmp_path, capsys):
    bad = stroke()
    bad.loc[2, "beta"] = 0.7
    path = tmp_path / "bad.csv"
    bad.to_csv(path, index=False)
    code = main(["synth", str(path), "-o", str(tmp_path / "x.wav")])
    err = capsys.readouterr().err
    assert code == 2
    assert str(path) in err and "'beta'" in err and "row 2" in err
    assert "Traceback" not in err
    assert not (tmp_path / "x.wav").exists()


@pytest.mark.parametrize(("column", "value"), [
    ("bow_force", -0.1), ("bow_velocity", 9.0), ("finger_ratio", 0.95), ("bow_position", 1.2),
    ("beta", 0.0), ("time", float("nan")), ("string", 4)])
def test_render_rejects_values_outside_documented_ranges(column, value):
    bad = stroke()
    bad[column] = bad[column].astype(float) if column != "string" else bad[column]
    bad.loc[1, column] = value
    with pytest.raises(SchemaError) as err:
        render_actions(bad)
    assert f"'{column}'" in str(err.value) and "row 1" in str(err.value)


def test_decreasing_time_is_rejected_with_its_row():
    bad = stroke()
    bad.loc[3, "time"] = 0.01
    with pytest.raises(SchemaError, match="row 3"):
        validate_actions(bad)


controls = st.builds(
    BowControl,
    bow_velocity=st.floats(-5.0, 5.0),
    bow_force=st.floats(0.0, 50.0),
    beta=st.floats(0.001, 0.499),
    finger_ratio=st.floats(0.0, 0.8))


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(st.integers(0, 3), controls), min_size=1, max_size=4),
       st.sampled_from(["violin", "viola", "cello"]))
def test_no_nan_or_inf_anywhere_in_the_documented_ranges(blocks, name):
    inst = Instrument(name, body=None)
    for string, control in blocks:
        block = inst.process(128, {string: control}, plucks=[string] if control.beta > 0.4
                             else [])
        assert np.all(np.isfinite(block.audio))
        assert np.all(np.isfinite(block.bridge_force))


def test_block_api_rejects_out_of_range_controls_by_name():
    inst = Instrument("violin", body=None)
    with pytest.raises(ValueError, match="beta"):
        inst.process(64, {0: BowControl(0.3, 0.5, 0.6)})
    with pytest.raises(ValueError, match="string=5"):
        inst.process(64, {5: BowControl(0.3, 0.5, 0.1)})
