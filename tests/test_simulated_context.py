"""Context effects of the simulated performer (issue 14), read back from the recordings."""

from dataclasses import replace

import numpy as np

from data_schemas.annotation import read_annotation
from data_schemas.instruments import dynamics_table
from data_schemas.recording import read_recording
from gesture_db.simulate import simulate_recordings
from gesture_db.simulate_config import PERFORMERS, simulator_config


def _held(path):
    """Per detache note: its annotation row, held force over the table's, median beta."""
    rec = read_recording(path)
    ann = read_annotation(path.with_name(f"{path.stem}.annotation.parquet"))
    t = rec["time"].to_numpy()
    rows = []
    for k, (on, off) in enumerate(zip(ann["true_onset"], ann["true_offset"], strict=True)):
        mid = (t > on + 0.4 * (off - on)) & (t < on + 0.6 * (off - on))
        rows.append((k, np.median(rec["bow_force"].to_numpy()[mid]),
                     np.median(rec["beta"].to_numpy()[mid])))
    k, force, beta = np.array(rows).T
    return ann, force, beta


#: The effects under test, switched on (the shipped simulate.toml keeps them off).
EFFECTS = {"crossing_lift": 0.15, "crossing_slow": 0.1, "beta_speed_exponent": 0.6}


def test_string_crossing_lightens_and_slow_notes_play_nearer_the_bridge(tmp_path,
                                                                        monkeypatch):
    import gesture_db.playing as playing

    shipped = simulator_config()
    config = {**shipped, "magnitudes": {**shipped["magnitudes"], **EFFECTS}}
    monkeypatch.setattr(playing, "simulator_config", lambda: config)
    perf = replace(PERFORMERS[0], name="plain", crescendo=0.0, accent=0.0, phrase_arch=0.0,
                   variability=0.02)
    path = simulate_recordings(900, 1, tmp_path, seed=3, notes_per_take=900,
                               performers=[perf])[0]
    ann, force, beta = _held(path)
    string = ann["string"].to_numpy()
    same_run = ann["run_position"].isin(["init", "mid"]).to_numpy()
    crossing = np.r_[string[1:] != string[:-1], False] & same_run
    plain = ann["technique"].isin(["detache"]).to_numpy() & \
        (ann["slur_position"].to_numpy() == "iso")
    _, table_force, table_beta = dynamics_table("violinist").at(ann["dynamic"].to_numpy())
    rel = np.log(force / table_force)
    lift = EFFECTS["crossing_lift"]
    before, other = rel[plain & crossing], rel[plain & ~crossing]
    assert before.size >= 4 and other.size >= 20
    # force of the note before a crossing: log(1 - lift) below the others (+- a few %)
    assert abs((np.median(before) - np.median(other)) - np.log(1 - lift)) < 0.06
    # contact point: beta over the table's (and the finger's shortening) falls with length
    dur = (ann["true_offset"] - ann["true_onset"]).to_numpy()
    fr = ann["finger_ratio"].to_numpy()
    rel_beta = np.log(beta * np.sqrt(1 - fr) / table_beta)
    slope = np.polyfit(np.log(dur[plain]), rel_beta[plain], 1)[0]
    assert slope < -0.1  # a longer (slower) note is bowed nearer the bridge
