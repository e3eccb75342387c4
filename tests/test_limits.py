"""Bounded work: the reproducers of issue 16 item 3 fail fast, before any allocation.

Each runs the real ``arco`` command under a 30 s alarm: a hang or a MemoryError fails it.
"""

from __future__ import annotations

import signal
import subprocess

import mido
import numpy as np
import pandas as pd
import pytest

from data_schemas.limits import LIMITS, load_limits
from pipelines.cli.main import main
from tests.test_bad_inputs import _MUSICXML, _arco_fails


@pytest.fixture(autouse=True)
def _alarm():
    def fail(*_):
        raise TimeoutError("the run did not fail fast")

    old = signal.signal(signal.SIGALRM, fail)
    signal.alarm(30)
    yield
    signal.alarm(0)
    signal.signal(signal.SIGALRM, old)


def test_limits_are_read_from_the_config():
    import tomllib
    from importlib import resources

    raw = tomllib.loads(resources.files("data_schemas").joinpath("config/limits.toml")
                        .read_text("utf-8"))
    assert load_limits() is LIMITS
    assert LIMITS.max_duration == raw["performance"]["max_duration"] == 1800.0
    assert (LIMITS.min_bpm, LIMITS.max_bpm) == (10.0, 1000.0)


def _actions(path, last: float):
    pd.DataFrame({"time": [0.0, last], "string": [1, 1], "finger_ratio": [0.0, 0.0],
                  "bow_force": [0.5, 0.5], "bow_velocity": [0.3, 0.3], "beta": [0.1, 0.1],
                  "bow_position": [0.5, 0.5], "pluck": [False, False]}).to_csv(path, index=False)
    return path


def test_synth_actions_last_time_1e9(tmp_path, capsys):
    path = _actions(tmp_path / "long.csv", 1e9)
    err = _arco_fails(capsys, "synth", path, "-o", tmp_path / "o.wav")
    assert str(path) in err and "1e+09 s" in err and "--max-duration" in err
    assert not (tmp_path / "o.wav").exists()


def test_synth_max_duration_is_the_bound(tmp_path, capsys):
    path = _actions(tmp_path / "short.csv", 1.0)  # 1 s + the ring-out tail
    err = _arco_fails(capsys, "synth", path, "-o", tmp_path / "o.wav", "--max-duration", "1.0")
    assert "limit of 1 s" in err
    assert main(["synth", str(path), "-o", str(tmp_path / "o.wav"), "--max-duration", "5",
                 "--quiet"]) == 0


def _score(tmp_path, *, duration: str = "4", per_minute: str = "60"):
    text = _MUSICXML.format(per_minute=per_minute).replace(
        "<duration>4</duration>", f"<duration>{duration}</duration>", 1)
    path = tmp_path / "score.musicxml"
    path.write_text(text)
    return path


def test_musicxml_huge_duration(tmp_path, capsys):
    path = _score(tmp_path, duration="99999999999999")
    err = _arco_fails(capsys, "render", path, "-o", tmp_path / "o.wav")
    assert str(path) in err and "over the limit of 1800 s" in err


@pytest.mark.parametrize("per_minute,ok", [("0.0001", False), ("9.9", False), ("1001", False),
                                           ("10", True), ("1000", True)])
def test_musicxml_tempo_range(tmp_path, capsys, per_minute, ok):
    path = _score(tmp_path, per_minute=per_minute)
    if ok:
        assert main(["notes", str(path)]) == 0
    else:
        err = _arco_fails(capsys, "render", path, "-o", tmp_path / "o.wav")
        assert str(path) in err and "measure 2" in err and "outside 10-1000" in err


def _midi(path, *, delta: int = 480, tempo: int = 500000):
    mid = mido.MidiFile(ticks_per_beat=480)
    track = mido.MidiTrack()
    track.append(mido.MetaMessage("set_tempo", tempo=tempo, time=0))
    track.append(mido.Message("note_on", note=69, velocity=64, time=0))
    track.append(mido.Message("note_off", note=69, velocity=0, time=delta))
    mid.tracks.append(track)
    mid.save(path)
    return path


def test_midi_huge_delta(tmp_path, capsys):
    path = _midi(tmp_path / "delta.mid", delta=0x0FFFFFFF)
    err = _arco_fails(capsys, "render", path, "-o", tmp_path / "o.wav")
    # 0x0FFFFFFF ticks / 480 per beat at 120 bpm = 279620 s
    assert str(path) in err and "279620 s" in err


@pytest.mark.parametrize("tempo", [0xFFFFFF, 50000])  # 3.6 bpm and 1200 bpm
def test_midi_tempo_range(tmp_path, capsys, tempo):
    path = _midi(tmp_path / "tempo.mid", tempo=tempo)
    err = _arco_fails(capsys, "notes", path)
    assert str(path) in err and "track 0 tick 0" in err and "outside 10-1000" in err


def test_render_note_count_limit(tmp_path, capsys):
    path = _score(tmp_path)  # two notes
    err = _arco_fails(capsys, "render", path, "-o", tmp_path / "o.wav", "--max-notes", "1")
    assert str(path) in err and "2 notes, over the limit of 1" in err
    err = _arco_fails(capsys, "render", path, "-o", tmp_path / "o.wav", "--max-duration", "2")
    assert "lasts 8 s" in err


def test_simulate_recordings_zero_notes_per_take(tmp_path, capsys):
    capsys.readouterr()
    with pytest.raises(SystemExit) as stop:
        main(["simulate-recordings", "-o", str(tmp_path / "sim"), "--notes-per-take", "0"])
    assert stop.value.code == 2
    assert "--notes-per-take: 0 is not an integer >= 1" in capsys.readouterr().err


def _take(n: int = 480, rate: float = 240.0) -> pd.DataFrame:
    return pd.DataFrame({
        "recording_id": "take", "time": np.arange(n) / rate,
        "bow_velocity": 0.2 * np.sin(np.arange(n) / 50.0), "bow_force": 0.5, "beta": 0.1,
        "bow_position": 0.5, "string": 2, "finger_ratio": 0.0})


@pytest.mark.parametrize("last,expected", [(1e9, "over the limit of 1800 s"),
                                           (100.0, "a gap of 98")])
def test_build_db_recording_time_bounds(tmp_path, capsys, last, expected):
    take = _take()
    take.loc[take.index[-1], "time"] = last
    path = tmp_path / "take.csv"
    take.to_csv(path, index=False)
    err = _arco_fails(capsys, "build-db", path, "-o", tmp_path / "db", "--workers", "1")
    assert str(path) in err and "'time'" in err and expected in err
    assert "row 479" in err


def test_build_db_actions_spanning_1e9(tmp_path, capsys):
    path = _actions(tmp_path / "played.csv", 1e9)
    err = _arco_fails(capsys, "build-db", path, "-o", tmp_path / "db", "--workers", "1")
    assert str(path) in err and "1e+09 s" in err


def test_build_db_empty_actions_table_names_the_file(tmp_path, capsys):
    path = tmp_path / "played.csv"
    path.write_text("time,string,finger_ratio,bow_force,bow_velocity,beta,bow_position,pluck\n")
    err = _arco_fails(capsys, "build-db", path, "-o", tmp_path / "db", "--workers", "1")
    assert f"{path}: the actions table is empty" in err
    assert not (tmp_path / "db").exists()


def _limits_in_fresh_process(env_file) -> subprocess.CompletedProcess:
    import os
    import sys

    env = {**os.environ, "ARCO_LIMITS": str(env_file)}
    code = ("from data_schemas.limits import LIMITS; "
            "print(LIMITS.max_take_duration, LIMITS.min_bpm, LIMITS.max_duration)")
    return subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                          text=True, timeout=60)


def test_arco_limits_raises_a_limit_for_every_command(tmp_path):
    """A TOML named by ARCO_LIMITS is merged over the shipped limits (others unchanged)."""
    f = tmp_path / "limits.toml"
    f.write_text("[recordings]\nmax_take_duration = 7200\n[tempo]\nmin_bpm = 2\n")
    run = _limits_in_fresh_process(f)
    assert run.returncode == 0, run.stderr
    assert run.stdout.split() == ["7200.0", "2.0", str(LIMITS.max_duration)]


@pytest.mark.parametrize("text, words", [
    ("[recordings]\nmax_take_length = 5\n", "max_take_length"),
    ("[tempo]\nmin_bpm = -1\n", "min_bpm = -1"),
    ("[nowhere]\nx = 1\n", "[nowhere]"),
    ("[tempo\n", "cannot read"),
])
def test_a_bad_arco_limits_file_is_named(tmp_path, text, words):
    f = tmp_path / "limits.toml"
    f.write_text(text)
    run = _limits_in_fresh_process(f)
    assert run.returncode != 0 and str(f) in run.stderr and words in run.stderr
