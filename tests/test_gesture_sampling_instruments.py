"""Gesture sampling per instrument, the simulator's context effects, the quality cost.

Truths: the instrument of a sample is read back from the notes table (which take it came
from); the simulated crescendo is the performer's own parameter; the quality cost's effect is
checked against the same search with the weight at zero.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from data_schemas.annotation import read_annotation
from data_schemas.instruments import dynamics_table
from data_schemas.recording import read_recording
from gesture_db.build import build_database
from gesture_db.simulate import simulate_recordings
from gesture_db.simulate_config import PERFORMERS
from gesture_db.store import GestureDB
from pipelines.cli.commands.simulate_recordings import string_forces


@pytest.fixture(scope="module")
def two_db(tmp_path_factory):
    """A database of simulated violin and cello takes (one seed: the same scripts)."""
    base = tmp_path_factory.mktemp("two")
    dirs = []
    for name in ("violin", "cello"):
        rec = base / name
        simulate_recordings(240, 2, rec, seed=20, notes_per_take=120, instrument=name,
                            force_factors=string_forces(name))
        dirs.append(rec)
    build_database(dirs, base / "db", workers=1, progress=False)
    return base / "db"


def test_database_records_each_notes_instrument(two_db):
    db = GestureDB(two_db)
    notes = db.notes()
    assert db.instruments == ["cello", "violin"]
    cello = notes["instrument"] == "cello"
    # a cello take's notes carry the cello's scale length and its recording ids
    assert notes.loc[cello, "recording_id"].str.startswith("cello-").all()
    assert not notes.loc[~cello, "recording_id"].str.startswith("cello-").any()
    assert notes.loc[cello, "effective_string_length"].max() > 0.5
    assert notes.loc[~cello, "effective_string_length"].max() < 0.33
    # the same scripts and draws: the cellist bows each string harder than the violinist by
    # the ratio of the instrument model's reference forces (string_forces)
    ratio = string_forces("cello")
    for s in range(4):
        got = [np.median(r.loc[(r["string"] == s) & (r["bow_force"] > 0.05), "bow_force"])
               for r in (_takes(two_db.parent / name) for name in ("cello", "violin"))]
        assert 0.9 * ratio[s] < got[0] / got[1] < 1.1 * ratio[s]


def _takes(folder):
    return pd.concat([read_recording(p) for p in sorted(folder.glob("*_take???.parquet"))])


def test_quality_table_round_trip(two_db):
    db = GestureDB(two_db)
    assert db.quality() is None
    ids = db.notes()["note_id"].iloc[:3].tolist()
    table = pd.DataFrame({"note_id": ids, "instrument": "violin",
                          "class_counts": [[0, 1, 8, 1, 0], [0, 0, 0, 0, 5], [0, 0, 3, 0, 0]],
                          "helmholtz_share": [0.8, 0.0, 1.0], "attack_ms": [40.0, np.nan, 12.0],
                          "seed": 0})
    db.write_quality(table)
    back = db.quality()
    assert back["note_id"].tolist() == ids
    assert [list(c) for c in back["class_counts"]] == table["class_counts"].tolist()
    assert np.isnan(back["attack_ms"].iloc[1])
    (db.path / "quality" / "gen-1.parquet").unlink()


def test_each_part_samples_its_own_instrument(two_db):
    from pipelines.methods.feedback import scale_notes
    from pipelines.methods.sampling import open_database, sample_part
    from pipelines.perform.config import load_config

    sdb = open_database(two_db, predictors=False)
    notes = sdb.db.notes().set_index("note_id")
    for name, tonic in (("cello", 36), ("violin", 55)):
        part = scale_notes(tonic=tonic, octaves=1, tempo=120.0, instrument=name)
        perf, _targets, choices = sample_part(part, sdb, load_config(), instrument=name)
        assert set(notes.loc[choices["note_id"], "instrument"]) == {name}
        assert not any("holds no" in w for w in perf.warnings)


def test_missing_instrument_warns_and_transfers(two_db):
    from pipelines.methods.feedback import scale_notes
    from pipelines.methods.sampling import open_database, sample_part
    from pipelines.perform.config import load_config

    sdb = open_database(two_db, predictors=False)
    part = scale_notes(tonic=48, octaves=1, tempo=120.0, instrument="viola")
    perf, targets, choices = sample_part(part, sdb, load_config(), instrument="viola")
    assert any("holds no viola notes" in w for w in perf.warnings)
    notes = sdb.db.notes().set_index("note_id")
    assert set(notes.loc[choices["note_id"], "instrument"]) == {"violin"}
    assert targets["effective_string_length"].max() < 0.33  # violin-equivalent lengths


def test_simulated_crescendo_is_recovered_by_regression(tmp_path):
    """Each note's held force over the dynamics table's force rises with its phrase place."""
    from dataclasses import replace

    perf = replace(PERFORMERS[0], name="swell", crescendo=0.4, accent=0.0, variability=0.02)
    path = simulate_recordings(400, 1, tmp_path, seed=5, notes_per_take=400,
                               performers=[perf])[0]
    rec = read_recording(path)
    ann = read_annotation(path.with_name(f"{path.stem}.annotation.parquet"))
    ann = ann[ann["technique"] == "detache"].copy()
    t = rec["time"].to_numpy()
    force = rec["bow_force"].to_numpy()
    held = []
    for on, off in zip(ann["true_onset"], ann["true_offset"], strict=True):
        mid = (t > on + 0.4 * (off - on)) & (t < on + 0.6 * (off - on))
        held.append(np.median(force[mid]))
    _, table_force, _ = dynamics_table("violinist").at(ann["dynamic"].to_numpy())
    rel = np.log(np.asarray(held) / table_force)
    # place in the run from the annotation (the truth the simulator wrote)
    place = np.zeros(len(ann))
    runs = (ann["run_position"].isin(["init", "iso"])).cumsum().to_numpy()
    for r in np.unique(runs):
        rows = np.flatnonzero(runs == r)
        if rows.size > 1:
            place[rows] = np.arange(rows.size) / (rows.size - 1)
    inside = ann["run_position"].to_numpy() != "iso"
    inside &= ann["slur_position"].to_numpy() == "iso"
    X = np.column_stack([np.ones(inside.sum()), place[inside]])
    coef = np.linalg.lstsq(X, rel[inside], rcond=None)[0]
    # swell 1 + 0.4 (place - 0.5): log slope about log(1.2 / 0.8) = 0.405
    assert 0.25 < coef[1] < 0.55


def test_quality_cost_changes_the_choice(two_db):
    from gesture_db.search import SearchIndex, search
    from gesture_db.search_config import load_search_config

    db = GestureDB(two_db)
    notes = db.notes()
    notes = notes[notes["instrument"] == "violin"]
    group = notes["group"].value_counts().index[0]
    rows = notes[notes["group"] == group]
    target = rows.iloc[[0]]
    targets = pd.DataFrame({
        "onset": [0.5], "duration": target["duration"].to_numpy(),
        "midi_pitch": target["midi_pitch"].to_numpy(), "string": target["string"].to_numpy(),
        "finger_ratio": [0.0],
        "effective_string_length": target["effective_string_length"].to_numpy(),
        "dynamic": target["dynamic"].to_numpy(np.float64),
        "technique": target["technique"].to_numpy(),
        "bow_direction": target["bow_direction"].to_numpy(),
        "slur_position": target["slur_position"].to_numpy(),
        "run_position": target["run_position"].to_numpy(), "group": [group]})
    config = load_search_config()
    plain = SearchIndex.from_db(db, instrument="violin")
    first = search(targets, plain, config=config).choices["note_id"].iloc[0]
    # the sample chosen without judgement sounds bad (all class 5), every other one good
    ids = rows["note_id"].tolist()
    quality = pd.DataFrame({"note_id": ids, "instrument": "violin",
                            "class_counts": [[0, 0, 0, 0, 20] if i == first
                                             else [0, 0, 20, 0, 0] for i in ids],
                            "helmholtz_share": 1.0, "attack_ms": 20.0, "seed": 0})
    judged = SearchIndex.from_db(db, instrument="violin", quality=quality)
    second = search(targets, judged, config=config).choices["note_id"].iloc[0]
    assert second != first
    off = load_search_config(overrides={"weights": {"quality": 0.0}})
    assert search(targets, judged, config=off).choices["note_id"].iloc[0] == first
