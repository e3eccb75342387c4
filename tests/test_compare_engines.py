"""``arco compare --engines``: engines against (synthetic) recordings, leaving one out.

The recordings are tests/_audio_dataset.py's harmonic tones laid out like bach-violin; the
audio-frame database is built from them by gesture_db's build (what ``arco build-db
--audio`` runs).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import pipelines.cli.main as cli
from data_schemas.audio_frames import read_audio_database
from data_schemas.errors import ParameterError
from gesture_db.audio_build import build_audio_database
from pipelines.reports.engine_compare import FIGURES, compare_engines
from pipelines.reports.leave_out import without
from synth.frames.index import database_key
from tests._audio_dataset import RECORDINGS, write_dataset
from tests._audio_db import fake_audio_database


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    root = write_dataset(tmp_path_factory.mktemp("data"))
    build_audio_database([root], root.parent / "db", workers=1, progress=False)
    return root, root.parent / "db"


def test_cli_compares_three_engines_leaving_each_recording_out(data, tmp_path, capsys):
    root, db = data
    out = tmp_path / "report"
    code = cli.main(["compare", "--engines", "modal,frames,cws", "--audio-db", str(db),
                     "--recordings", str(root), "--seconds", "2", "-o", str(out), "--quiet"])
    stdout, err = capsys.readouterr()
    assert code == 0, err
    res = json.loads((out / "results.json").read_text())
    assert set(res["recordings"]) == set(RECORDINGS)
    for name, rec in res["recordings"].items():
        figs = rec["figures"]
        assert {"real", "modal", "frames", "cws", "fluidr3"} <= set(figs)
        for engine in ("modal", "frames", "cws"):
            assert np.isfinite(figs[engine]["mfcc_frechet"]) and figs[engine]["mfcc_frechet"] > 0
            assert figs[engine]["real_time_factor"] > 0
        # the database engines played the other recording only
        for engine in ("frames", "cws"):
            assert rec["engines"][engine]["database_recordings"] == sorted(
                set(RECORDINGS) - {name})
            assert rec["engines"][engine]["bit_identical_rerender"] is True
        assert figs["fluidr3"]["mfcc_frechet"] is not None or figs["fluidr3"]["reason"]
    # the verdict ranks the sources by the mean MFCC Frechet distance written beside it
    means = {s: m["mfcc_frechet"] for s, m in res["mean"].items()
             if s != "real" and m["mfcc_frechet"] is not None}
    order = sorted(means, key=means.get)
    assert stdout.strip() == res["verdict"]
    positions = [res["verdict"].index(f" {s} (") for s in order]
    assert positions == sorted(positions)
    for f in FIGURES:
        assert (out / f"bars-{f}.png").stat().st_size > 1000
    assert res["verdict"] in (out / "index.html").read_text()
    assert (out / "tones-a-frames.wav").is_file()


def test_modal_alone_needs_no_database(data, tmp_path, capsys):
    root, _ = data
    code = cli.main(["compare", "--engines", "modal", "--recordings", str(root),
                     "--seconds", "1", "-o", str(tmp_path / "r"), "--quiet"])
    assert code == 0, capsys.readouterr().err
    res = json.loads((tmp_path / "r" / "results.json").read_text())
    assert res["sources"] == ["real", "modal", "fluidr3"]
    assert res["recordings"]["tones-b"]["engines"]["modal"].get("database_recordings") is None


@pytest.mark.parametrize(("argv", "message"), [
    (["--engines", "modal,frames"], "--engines frames needs --audio-db"),
    (["--engines", "modal,cws"], "--engines cws needs --audio-db"),
    (["--engines", "modal,harp"], "unknown engine harp"),
    (["score.mxl", "--engines", "modal"], "give no SCORE"),
    (["score.mxl", "--audio-db", "adb"], "apply to --engines"),
])
def test_bad_engine_options_are_one_line_exit_2(data, tmp_path, capsys, argv, message):
    root, _ = data
    out = tmp_path / "r"
    code = cli.main(["compare", *argv, "--recordings", str(root), "-o", str(out), "--quiet"])
    err = capsys.readouterr().err
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1, err
    assert not (out / "results.json").exists()


def test_a_recording_missing_from_the_database_is_refused(data, tmp_path, capsys):
    _, db = data
    more = write_dataset(tmp_path / "more", {**RECORDINGS, "tones-c": [(79, 0.8)]})
    out = tmp_path / "r"
    code = cli.main(["compare", "--engines", "frames", "--audio-db", str(db), "--recordings",
                     str(more), "--seconds", "1", "-o", str(out), "--quiet"])
    err = capsys.readouterr().err
    assert code == 2 and "tones-c" in err and "not in the audio-frame database" in err, err
    assert not out.exists() or not any(out.iterdir())


def test_no_engine_ever_gets_the_left_out_recording(data, tmp_path, monkeypatch):
    import synth.engines

    root, db = data
    real_get = synth.engines.get_engine
    seen = []

    def spy(name, instrument="violin", **options):
        if "audio_db" in options:
            d = options["audio_db"]
            seen.append((name, set(d.audio_paths), set(d.frames["recording"]),
                         set(d.notes["recording"]), set(d.manifest["recordings"])))
        return real_get(name, instrument, **options)

    monkeypatch.setattr(synth.engines, "get_engine", spy)
    res = compare_engines(["frames", "cws"], root, tmp_path / "r", audio_db=db, seconds=1.0,
                          keep_audio=False, progress=False)
    assert len(seen) == 2 * len(RECORDINGS)
    # in order: each recording is measured with both engines, on a database without it
    for (engine, *holds), left_out in zip(seen, np.repeat(sorted(RECORDINGS), 2), strict=True):
        assert all(h == set(RECORDINGS) - {left_out} for h in holds), (engine, left_out, holds)
    assert set(res["recordings"]) == set(RECORDINGS)
    # the whole database's frames index was not written over by a subset's
    assert not (db / "frames_index.npz").exists() or database_key(
        read_audio_database(db).manifest) == str(np.load(db / "frames_index.npz")["key"])


def test_without_keeps_every_other_row_and_changes_the_cache_key(data, tmp_path):
    full = fake_audio_database(n_recordings=3, notes_each=4)
    sub = without(full, "rec1")
    for table in ("frames", "notes"):
        t = getattr(full, table)
        assert len(getattr(sub, table)) == int((t["recording"] != "rec1").sum()) > 0
        assert "rec1" not in set(getattr(sub, table)["recording"])
    assert set(sub.audio_paths) == {"rec0", "rec2"}
    with pytest.raises(ParameterError, match="no recording 'rec1'"):
        without(sub, "rec1")
    # a real database: the subset's manifest (the frames index's cache key) loses the
    # recording too, and its caches go to the given folder
    real = read_audio_database(data[1])
    part = without(real, "tones-a", tmp_path / "sub")
    assert set(part.manifest["recordings"]) == {"tones-b"}
    assert database_key(part.manifest) != database_key(real.manifest)
    assert part.root == tmp_path / "sub"
    with pytest.raises(ParameterError, match="nothing is left"):
        without(part, "tones-b")


def test_leave_one_performer_out_withholds_every_recording_of_the_performer(
        tmp_path, monkeypatch):
    import synth.engines

    recs = {"ann_a": RECORDINGS["tones-a"], "ann_b": RECORDINGS["tones-b"],
            "bob_a": [(64, 0.8), (66, 0.8), (68, 0.8)]}
    root = write_dataset(tmp_path / "data", recs)
    db = tmp_path / "db"
    build_audio_database([root], db, workers=1, progress=False)
    real_get = synth.engines.get_engine
    seen = []

    def spy(name, instrument="violin", **options):
        seen.append(set(options["audio_db"].audio_paths))
        return real_get(name, instrument, **options)

    monkeypatch.setattr(synth.engines, "get_engine", spy)
    res = compare_engines(["cws"], root, tmp_path / "r", audio_db=db, seconds=1.0,
                          keep_audio=False, progress=False, leave_out="performer")
    assert seen == [{"bob_a"}, {"bob_a"}, {"ann_a", "ann_b"}]     # ann_a, ann_b, bob_a
    assert res["settings"]["leave_out"] == "performer"
    seen.clear()
    compare_engines(["cws"], root, tmp_path / "r2", audio_db=db, seconds=1.0,
                    keep_audio=False, progress=False)
    assert seen == [{"ann_b", "bob_a"}, {"ann_a", "bob_a"}, {"ann_a", "ann_b"}]
    with pytest.raises(ParameterError, match="leave-out"):
        compare_engines(["cws"], root, tmp_path / "r3", audio_db=db, leave_out="violin")


def test_leave_one_performer_out_of_a_one_performer_database_is_refused(tmp_path, capsys):
    root = write_dataset(tmp_path / "data", {"ann_a": RECORDINGS["tones-a"],
                                             "ann_b": RECORDINGS["tones-b"]})
    db = tmp_path / "db"
    build_audio_database([root], db, workers=1, progress=False)
    code = cli.main(["compare", "--engines", "cws", "--audio-db", str(db), "--recordings",
                     str(root), "--seconds", "1", "--leave-out", "performer", "-o",
                     str(tmp_path / "r"), "--quiet"])
    err = capsys.readouterr().err
    assert code == 2 and "nothing is left" in err, err
