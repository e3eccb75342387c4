"""Database build, Parquet round trips, atomic commits, resume, append, dask paths."""

import json
import shutil

import numpy as np
import pandas as pd
import pytest

from data_schemas.annotation import read_annotation, write_annotation
from data_schemas.errors import SchemaError
from data_schemas.gesture_db import MANIFEST_NAME
from data_schemas.recording import read_recording, write_recording
from gesture_db.build import build_database
from gesture_db.importers import load_mapped, recording_from_actions
from gesture_db.simulate import simulate_recordings
from gesture_db.store import GestureDB


@pytest.fixture(scope="module")
def recordings(tmp_path_factory):
    out = tmp_path_factory.mktemp("rec")
    simulate_recordings(160, 2, out, seed=7, notes_per_take=40)
    return out


def _tables(path):
    db = GestureDB(path)
    contours = pd.concat([db.contours(g) for g in db.groups], ignore_index=True)
    return db.notes(), db.models(), contours


def _assert_same(a, b):
    for x, y in zip(_tables(a), _tables(b), strict=True):
        pd.testing.assert_frame_equal(x.reset_index(drop=True), y.reset_index(drop=True))


def test_recording_and_annotation_round_trip(recordings, tmp_path):
    rec = read_recording(next(recordings.glob("*_take000.parquet")))
    ann = read_annotation(next(recordings.glob("*_take000.annotation.parquet")))
    for suffix in (".parquet", ".csv"):
        write_recording(rec, tmp_path / f"r{suffix}")
        write_annotation(ann, tmp_path / f"a{suffix}")
        pd.testing.assert_frame_equal(read_recording(tmp_path / f"r{suffix}"), rec,
                                      check_exact=False)
        back = read_annotation(tmp_path / f"a{suffix}")
        assert back["true_onset"].to_numpy() == pytest.approx(ann["true_onset"].to_numpy())
    bad = rec.copy()
    bad.loc[5, "beta"] = 0.7
    with pytest.raises(SchemaError, match=r"column 'beta', row 5"):
        write_recording(bad, tmp_path / "bad.parquet")
    bad = ann.copy()
    bad.loc[3, "technique"] = "col legno"
    with pytest.raises(SchemaError, match="technique"):
        write_annotation(bad, tmp_path / "bad_a.parquet")


def test_build_info_and_dask_paths_agree(recordings, tmp_path):
    from distributed import Client, LocalCluster

    local = tmp_path / "local"
    m = build_database([recordings], local, workers=1, progress=False)
    assert m["n_notes"] == 160
    seg = m["segmentation"]
    assert seg["median_boundary_error_ms"] <= 10 and seg["notes_found_share"] >= 0.98
    db = GestureDB(local)
    model, grammar = db.group_model(db.groups[0])
    notes = db.notes(db.groups[0])
    assert len(notes.iloc[0]["params"]) == grammar.dim == model.param_dim
    procs = tmp_path / "procs"
    build_database([recordings], procs, workers=2, progress=False)
    _assert_same(local, procs)
    with LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        dist = tmp_path / "dist"
        build_database([recordings], dist, scheduler=client, progress=False)
    _assert_same(local, dist)


def test_killed_build_keeps_previous_db_and_resumes(recordings, tmp_path):
    files = sorted(recordings.glob("*_take00[0-9].parquet"))
    first, rest = files[:1], files[1:]
    db = tmp_path / "db"
    build_database(first, db, workers=1, progress=False)
    before = GestureDB(db).notes()

    calls = []

    def crash(digest):
        calls.append(digest)
        if len(calls) == 2:
            raise KeyboardInterrupt("killed")

    with pytest.raises(KeyboardInterrupt):
        build_database(rest, db, workers=1, append=True, progress=False, on_source_done=crash)
    pd.testing.assert_frame_equal(GestureDB(db).notes(), before)  # previous db intact
    m = build_database(rest, db, workers=1, append=True, progress=False)
    assert m["resumed_sources"] == 2
    assert m["n_notes"] == 160 and m["generation"] == 2
    fresh = tmp_path / "fresh"
    build_database(files, fresh, workers=1, progress=False)
    _assert_same(db, fresh)


def test_corrupted_source_and_version_mismatch_leave_db_intact(recordings, tmp_path):
    files = sorted(recordings.glob("*_take00[0-9].parquet"))
    db = tmp_path / "db"
    build_database(files[:1], db, workers=1, progress=False)
    before = GestureDB(db).notes()
    broken = tmp_path / "broken.parquet"
    broken.write_bytes(files[1].read_bytes()[:500])
    with pytest.raises(SchemaError, match="broken.parquet"):
        build_database([broken], db, workers=1, append=True, progress=False)
    pd.testing.assert_frame_equal(GestureDB(db).notes(), before)
    # a corrupted database file is named when read
    part = db / GestureDB(db).manifest["files"]["notes"][GestureDB(db).groups[0]]
    saved = part.read_bytes()
    part.write_bytes(b"garbage")
    with pytest.raises(SchemaError, match="part.parquet"):
        GestureDB(db).verify()
    part.write_bytes(saved)
    manifest = json.loads((db / MANIFEST_NAME).read_text())
    manifest["schema_version"] = "9.0"
    shutil.copy(db / MANIFEST_NAME, tmp_path / "good.json")
    (db / MANIFEST_NAME).write_text(json.dumps(manifest))
    with pytest.raises(SchemaError, match="schema version 9.0"):
        GestureDB(db)
    with pytest.raises(SchemaError, match="schema version 9.0"):
        build_database(files[1:2], db, workers=1, append=True, progress=False)
    assert (db / MANIFEST_NAME).read_text() == json.dumps(manifest)  # untouched


def test_importers_mapping_and_actions(recordings, tmp_path):
    rec = read_recording(next(recordings.glob("*_take000.parquet")))
    export = pd.DataFrame({"T": rec["time"], "vel_cm_s": rec["bow_velocity"] * 100,
                           "F": rec["bow_force"], "b": rec["beta"],
                           "pos": rec["bow_position"], "str": rec["string"],
                           "fr": rec["finger_ratio"]})
    export.to_csv(tmp_path / "mocap.csv", index=False)
    (tmp_path / "mocap.toml").write_text(
        '[source]\npath = "mocap.csv"\nrecording_id = "m1"\n'
        '[columns]\ntime = "T"\nbow_velocity = "vel_cm_s"\nbow_force = "F"\nbeta = "b"\n'
        'bow_position = "pos"\nstring = "str"\nfinger_ratio = "fr"\n'
        '[scale]\nbow_velocity = 0.01\n')
    got, ann = load_mapped(tmp_path / "mocap.toml")
    assert ann is None and got["recording_id"].iloc[0] == "m1"
    np.testing.assert_allclose(got["bow_velocity"], rec["bow_velocity"], atol=1e-9)
    (tmp_path / "bad.toml").write_text('[source]\npath = "mocap.csv"\n[columns]\ntime = "X"\n')
    with pytest.raises(SchemaError, match="'X'"):
        load_mapped(tmp_path / "bad.toml")
    actions = rec.drop(columns="recording_id").iloc[::2].assign(pluck=False)
    back = recording_from_actions(actions, recording_id="a")
    assert 239 < 1 / np.median(np.diff(back["time"])) < 241
    m = build_database([tmp_path / "mocap.toml"], tmp_path / "db", workers=1, progress=False)
    assert m["n_notes"] > 20  # blind segmentation, unlabelled groups
    assert all(g.startswith("unlabelled-") for g in m["files"]["notes"])


def test_zero_notes_per_take_is_refused_instead_of_looping(tmp_path):
    from data_schemas.errors import ParameterError

    with pytest.raises(ParameterError, match="notes_per_take=0"):
        simulate_recordings(10, 1, tmp_path, notes_per_take=0, progress=False)
