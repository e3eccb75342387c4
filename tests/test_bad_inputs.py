"""Every bad input is one line on stderr naming the file, and exit code 2 (no traceback).

Grouped by the reader that must catch the problem. Each test crafts the bad file in
``tmp_path`` and drives the real ``arco`` command (or the reader function).
"""

from __future__ import annotations

import re

import mido
import pytest

from pipelines.cli.main import main


def _arco_fails(capsys, *argv: str) -> str:
    """Run ``arco argv``; assert exit 2 with a single stderr line; return that line.

    Progress-bar frames (tqdm's ``name:  0%|...``) are not error output and are dropped.
    """
    capsys.readouterr()
    code = main([str(a) for a in argv])
    raw = capsys.readouterr().err
    assert code == 2, raw
    assert "Traceback" not in raw
    lines = [line for line in re.split(r"[\r\n]+", _PROGRESS.sub("", raw)) if line.strip()]
    assert len(lines) == 1, raw
    assert lines[0].startswith(f"arco {argv[0]}: error: "), raw
    return lines[0]


_PROGRESS = re.compile(r"[\w -]+: +\d+%\|[^\r\n]*?(it|s|source|group)/s\]")


# --- pipelines/score/midi.py -------------------------------------------------------------


def _midi(path, *, ticks_per_beat: int = 480, tempo: int = 500000):
    mid = mido.MidiFile(ticks_per_beat=ticks_per_beat)
    track = mido.MidiTrack()
    track.append(mido.MetaMessage("set_tempo", tempo=tempo, time=0))
    track.append(mido.Message("note_on", note=60, velocity=64, time=0))
    track.append(mido.Message("note_off", note=60, velocity=0, time=480))
    mid.tracks.append(track)
    mid.save(path)
    return path


def test_midi_ticks_per_beat_zero(tmp_path, capsys):
    path = _midi(tmp_path / "tpb0.mid", ticks_per_beat=0)
    err = _arco_fails(capsys, "notes", path)
    assert str(path) in err and "ticks per beat" in err


def test_midi_tempo_zero_names_track_and_tick(tmp_path, capsys):
    path = _midi(tmp_path / "tempo0.mid", tempo=0)
    err = _arco_fails(capsys, "notes", path)
    assert str(path) in err and "track 0" in err and "tempo" in err


def test_midi_time_signature_of_zero_beats(tmp_path, capsys):
    mid = mido.MidiFile(ticks_per_beat=480)
    track = mido.MidiTrack()
    track.append(mido.MetaMessage("time_signature", numerator=0, denominator=4, time=0))
    track.append(mido.Message("note_on", note=60, velocity=64, time=0))
    track.append(mido.Message("note_off", note=60, velocity=0, time=480))
    mid.tracks.append(track)
    path = tmp_path / "meter0.mid"
    mid.save(path)
    err = _arco_fails(capsys, "notes", path)
    assert f"{path}: track 0 tick 0: time signature 0/4" in err


# --- pipelines/score/musicxml.py ---------------------------------------------------------

_MUSICXML = """<?xml version="1.0" encoding="UTF-8"?>
<score-partwise version="3.1">
  <part-list><score-part id="P1"><part-name>Violin</part-name></score-part></part-list>
  <part id="P1">
    <measure number="1">
      <attributes><divisions>1</divisions></attributes>
      <note><pitch><step>A</step><octave>4</octave></pitch><duration>4</duration></note>
    </measure>
    <measure number="2">
      <direction><direction-type><metronome><beat-unit>quarter</beat-unit>
        <per-minute>{per_minute}</per-minute></metronome></direction-type></direction>
      <note><pitch><step>A</step><octave>4</octave></pitch><duration>4</duration></note>
    </measure>
  </part>
</score-partwise>
"""


@pytest.mark.parametrize("per_minute", ["0", "-60"])
def test_musicxml_metronome_not_positive(tmp_path, capsys, per_minute):
    path = tmp_path / "tempo.musicxml"
    path.write_text(_MUSICXML.format(per_minute=per_minute))
    err = _arco_fails(capsys, "notes", path)
    assert str(path) in err and "measure 2" in err and "metronome" in err


def test_musicxml_good_metronome_still_reads(tmp_path, capsys):
    path = tmp_path / "tempo.musicxml"
    path.write_text(_MUSICXML.format(per_minute="30"))
    assert main(["notes", str(path)]) == 0
    # the first mark's tempo also applies before it: 8 beats at 30 qpm
    assert "16.0 s" in capsys.readouterr().out


# --- data_schemas/io.py: Parquet metadata, CSV headers ----------------------------------


def _recording(n: int = 480, rate: float = 240.0, rid: str = "take"):
    import numpy as np
    import pandas as pd

    return pd.DataFrame({
        "recording_id": rid, "time": np.arange(n) / rate,
        "bow_velocity": 0.2 * np.sin(np.arange(n) / 50.0), "bow_force": 0.5, "beta": 0.1,
        "bow_position": 0.5, "string": np.int8(2), "finger_ratio": np.float32(0.0)})


def _with_metadata(tmp_path, key: bytes, value: bytes):
    import pyarrow.parquet as pq

    from data_schemas.recording import write_recording

    good = write_recording(_recording(), tmp_path / "good.parquet")
    table = pq.read_table(good)
    path = tmp_path / "bad.parquet"
    pq.write_table(table.replace_schema_metadata({**table.schema.metadata, key: value}), path)
    return path


@pytest.mark.parametrize("key", [b"arco_table", b"instrument"])
def test_parquet_metadata_not_utf8(tmp_path, capsys, key):
    path = _with_metadata(tmp_path, key, b"\xff\xfe")
    err = _arco_fails(capsys, "build-db", path, "-o", tmp_path / "db", "--workers", "1")
    assert str(path) in err and f"metadata '{key.decode()}' is not UTF-8" in err


@pytest.mark.parametrize("key", [b"arco_table", b"arco_schema_version"])
def test_read_table_metadata_not_utf8(tmp_path, key):
    from data_schemas.errors import SchemaError
    from data_schemas.recording import read_recording

    path = _with_metadata(tmp_path, key, b"\xff\xfe")
    with pytest.raises(SchemaError, match=f"bad.parquet: metadata '{key.decode()}' is not UTF-8"):
        read_recording(path)


def test_csv_duplicated_header_names_the_column(tmp_path, capsys):
    from data_schemas.errors import SchemaError
    from data_schemas.recording import read_recording

    path = tmp_path / "dup.csv"
    text = _recording().to_csv(index=False).replace("beta", "bow_force", 1)
    path.write_text(text)
    with pytest.raises(SchemaError, match="column 'bow_force': the column name appears 2"):
        read_recording(path)
    err = _arco_fails(capsys, "build-db", path, "-o", tmp_path / "db", "--workers", "1")
    assert str(path) in err and "'bow_force'" in err and "2 times" in err


def test_mapped_export_duplicated_header(tmp_path, capsys):
    path = tmp_path / "export.csv"
    path.write_text("t,v,v\n0,0.1,0.2\n")
    mapping = tmp_path / "take.toml"
    mapping.write_text('[source]\npath = "export.csv"\n[columns]\ntime = "t"\n')
    err = _arco_fails(capsys, "build-db", mapping, "-o", tmp_path / "db", "--workers", "1")
    assert str(path) in err and "'v'" in err and "2 times" in err


# --- data_schemas/recording.py: the 200-240 Hz frame rate --------------------------------


@pytest.mark.parametrize("rate", [10.0, 100.0, 10000.0])
def test_recording_frame_rate_outside_200_240_hz(tmp_path, capsys, rate):
    import pyarrow as pa
    import pyarrow.parquet as pq

    from data_schemas.errors import SchemaError
    from data_schemas.recording import RECORDING, write_recording

    path = tmp_path / "take.parquet"
    good = write_recording(_recording(), tmp_path / "ok" / "good.parquet")
    bad = _recording(int(2 * rate), rate)
    with pytest.raises(SchemaError, match="outside 200-240 Hz"):
        write_recording(bad, tmp_path / "refused.parquet")
    pq.write_table(pa.Table.from_pandas(bad.reindex(columns=RECORDING.column_names),
                                        schema=RECORDING.schema, preserve_index=False), path)
    err = _arco_fails(capsys, "build-db", path, "-o", tmp_path / "db", "--workers", "1")
    assert str(path) in err and "'time'" in err and f"{rate:g} Hz" in err
    assert "200-240 Hz" in err
    assert main(["build-db", str(good), "-o", str(tmp_path / "db2"), "--workers", "1"]) == 0


def test_recording_times_all_equal(tmp_path, capsys):
    path = tmp_path / "take.csv"
    frame = _recording()
    frame["time"] = 0.0
    frame.to_csv(path, index=False)
    err = _arco_fails(capsys, "build-db", path, "-o", tmp_path / "db", "--workers", "1")
    assert str(path) in err and "'time'" in err and "do not advance" in err


def test_recording_frame_rate_checked_per_take():
    import pandas as pd

    from data_schemas.errors import SchemaError
    from data_schemas.recording import validate_recording

    two = pd.concat([_recording(rid="a"), _recording(100, 200.0, rid="b")], ignore_index=True)
    assert len(validate_recording(two)) == 580
    bad = pd.concat([_recording(rid="a"), _recording(100, 50.0, rid="b")], ignore_index=True)
    with pytest.raises(SchemaError, match=r"row 480: take 'b': frame rate 50 Hz"):
        validate_recording(bad)


# --- data_schemas/annotation.py ----------------------------------------------------------


def _annotation(onset: float = 0.2, offset: float = 1.5):
    import pandas as pd

    return pd.DataFrame({
        "recording_id": ["take"], "note_index": [0], "onset": [onset], "offset": [offset],
        "midi_pitch": [62], "string": [2], "finger_ratio": [0.0], "dynamic": [5.0],
        "technique": ["detache"], "bow_direction": ["down"], "slur_position": ["iso"],
        "run_position": ["iso"]})


@pytest.mark.parametrize("offset", [0.1, 0.2])
def test_annotation_offset_not_after_onset(tmp_path, capsys, offset):
    from data_schemas.recording import write_recording

    path = write_recording(_recording(), tmp_path / "take.parquet")
    ann = tmp_path / "take.annotation.csv"
    _annotation(0.2, offset).to_csv(ann, index=False)
    err = _arco_fails(capsys, "build-db", path, "-o", tmp_path / "db", "--workers", "1")
    assert str(ann) in err and "column 'offset', row 0" in err and "not after onset" in err


def test_annotation_offset_after_the_take(tmp_path, capsys):
    from data_schemas.recording import write_recording

    path = write_recording(_recording(), tmp_path / "take.parquet")  # 2 s long
    ann = tmp_path / "take.annotation.csv"
    _annotation(0.2, 1e9).to_csv(ann, index=False)
    err = _arco_fails(capsys, "build-db", path, "-o", tmp_path / "db", "--workers", "1")
    assert str(ann) in err and "column 'offset', row 0" in err and "after the end of take" in err


def test_annotation_checks_in_memory_and_on_write(tmp_path):
    from data_schemas.annotation import validate_annotation, write_annotation
    from data_schemas.errors import SchemaError

    assert len(validate_annotation(_annotation())) == 1
    with pytest.raises(SchemaError, match="row 0: offset 0.1 s is not after onset 0.2 s"):
        validate_annotation(_annotation(0.2, 0.1))
    with pytest.raises(SchemaError, match="not after onset"):
        write_annotation(_annotation(0.2, 0.1), tmp_path / "a.parquet")
    assert not (tmp_path / "a.parquet").exists()


# --- gesture_db/importers.py: TOML column mappings ---------------------------------------

_COLUMNS = """[columns]
time = "t"
bow_velocity = "v"
bow_force = "f"
beta = "b"
[defaults]
string = 2
finger_ratio = 0.0
bow_position = 0.5
"""


def _export(tmp_path):
    """A motion-capture style CSV export with a text column ``label``."""
    frame = _recording()
    out = frame.rename(columns={"time": "t", "bow_velocity": "v", "bow_force": "f",
                                "beta": "b"})[["t", "v", "f", "b"]]
    out["label"] = "x"
    out.to_csv(tmp_path / "export.csv", index=False)
    (tmp_path / "folder").mkdir()


@pytest.mark.parametrize(("text", "expected"), [
    ('[source]\npath = 5\n' + _COLUMNS, "[source] path must be a file name in quotes, not 5"),
    ('source = "x"\n' + _COLUMNS, "'source' must be a table ([source]), not 'x'"),
    ('[source]\npath = "missing.csv"\n' + _COLUMNS, "[source] path 'missing.csv': file not found"),
    ('[source]\npath = "folder"\n' + _COLUMNS, "[source] path 'folder' is a folder"),
    ('[source]\npath = "export.csv"\n' + _COLUMNS + '[scale]\nbow_velocity = "abc"\n',
     "column 'bow_velocity': [scale] bow_velocity must be a number, not 'abc'"),
    ('[source]\npath = "export.csv"\n' + _COLUMNS + '[scale]\nbow_velocity = nan\n',
     "[scale] bow_velocity must be a number, not nan"),
    ('[source]\npath = "export.csv"\n' + _COLUMNS.replace('beta = "b"', "beta = 3"),
     "column 'beta': [columns] beta must be a column name in quotes, not 3"),
    ('[source]\npath = "export.csv"\nannotation = 1\n' + _COLUMNS,
     "[source] annotation must be text in quotes, not 1"),
    ('[source]\npath = "export.csv"\n' + _COLUMNS.replace("string = 2", 'string = "G"'),
     "column 'string': [defaults] string must be a number, not 'G'"),
])
def test_mapping_bad_values(tmp_path, capsys, text, expected):
    _export(tmp_path)
    mapping = tmp_path / "take.toml"
    mapping.write_text(text)
    err = _arco_fails(capsys, "build-db", mapping, "-o", tmp_path / "db", "--workers", "1")
    assert f"file {mapping}" in err and expected in err


def test_mapping_not_utf8(tmp_path, capsys):
    _export(tmp_path)
    mapping = tmp_path / "take.toml"
    mapping.write_bytes(b'[source]\npath = "export\xff.csv"\n' + _COLUMNS.encode())
    err = _arco_fails(capsys, "build-db", mapping, "-o", tmp_path / "db", "--workers", "1")
    assert f"file {mapping}: cannot read mapping" in err


def test_mapping_column_mapped_to_text(tmp_path, capsys):
    _export(tmp_path)
    mapping = tmp_path / "take.toml"
    mapping.write_text('[source]\npath = "export.csv"\n'
                       + _COLUMNS.replace('beta = "b"', 'beta = "label"'))
    err = _arco_fails(capsys, "build-db", mapping, "-o", tmp_path / "db", "--workers", "1")
    assert f"file {tmp_path / 'export.csv'}, column 'label', row 0: value 'x' is not a number" \
        in err


def test_mapping_good_export_builds(tmp_path, capsys):
    _export(tmp_path)
    mapping = tmp_path / "take.toml"
    mapping.write_text('[source]\npath = "export.csv"\n' + _COLUMNS)
    assert main(["build-db", str(mapping), "-o", str(tmp_path / "db"), "--workers", "1"]) == 0


# --- data_schemas/gesture_db.py: the manifest -------------------------------------------


@pytest.fixture(scope="module")
def small_db(tmp_path_factory):
    """A database built from one 2 s take (its manifest is edited by the tests)."""
    from data_schemas.recording import write_recording
    from gesture_db.build import build_database

    base = tmp_path_factory.mktemp("small_db")
    rec = write_recording(_recording(), base / "take.parquet")
    build_database([rec], base / "db", workers=1, progress=False)
    return base / "db"


@pytest.mark.parametrize(("edit", "expected"), [
    (lambda m: m.pop("files"), "manifest key 'files' must be an object, not None"),
    (lambda m: m.pop("sources"), "manifest key 'sources' must be an object, not None"),
    (lambda m: m.pop("generation"), "manifest key 'generation' must be an integer >= 1"),
    (lambda m: m.update(generation="abc"), "'generation' must be an integer >= 1, not 'abc'"),
    (lambda m: m.update(generation=0), "'generation' must be an integer >= 1, not 0"),
    (lambda m: m["files"].update(notes=["a.parquet"]), "'files.notes' must be an object"),
    (lambda m: m["files"].update(models=3), "'files.models' must be a file name, not 3"),
    (lambda m: next(iter(m["sources"].values())).update(contour_files="x.parquet"),
     "contour_files' must be a list of file names, not 'x.parquet'"),
])
def test_manifest_bad_shape(small_db, tmp_path, capsys, edit, expected):
    import json
    import shutil

    db = tmp_path / "db"
    shutil.copytree(small_db, db)
    manifest = json.loads((db / "manifest.json").read_text())
    edit(manifest)
    (db / "manifest.json").write_text(json.dumps(manifest))
    err = _arco_fails(capsys, "db", "info", db, "--no-plots")
    assert f"file {db / 'manifest.json'}: " in err and expected in err


def test_manifest_good_reads(small_db, capsys):
    assert main(["db", "info", str(small_db), "--no-plots", "--json"]) == 0
    assert '"generation": 1' in capsys.readouterr().out


# --- gesture_db/search_config.py --------------------------------------------------------


@pytest.mark.parametrize(("text", "expected"), [
    ("[weights]\ngesture = nan\n", "weights.gesture=nan must be a finite number"),
    ("[weights]\nbasic = inf\n", "weights.basic=inf must be a finite number"),
    ("[weights]\nbasic = true\n", "weights.basic=True must be a finite number"),
    ('[continuity_scale]\nbeta = "x"\n', "continuity_scale.beta='x' must be a finite number"),
    ("[fallback]\nmax_distance = nan\n", "fallback.max_distance=nan must be a finite number"),
    ('[fallback.technique]\n"detache-legato" = -1.0\n',
     "fallback.technique.detache-legato=-1.0 must be >= 0"),
    ("[render]\nrecorded_reference_force = 1e300\n",
     "render.recorded_reference_force=1e+300 must be <= 1e+06"),
    ("[costs]\ndynamic_span = nan\n", "costs.dynamic_span=nan must be a finite number"),
    ("n_best = true\n", "n_best=True must be an integer in 1..1024"),
])
def test_search_config_values_finite_and_sane(tmp_path, text, expected):
    from data_schemas.errors import ParameterError
    from gesture_db.search_config import load_search_config

    path = tmp_path / "search.toml"
    path.write_text(text)
    with pytest.raises(ParameterError) as info:
        load_search_config(path)
    assert str(info.value) == f"search config {path}: {expected}"


# --- pipelines/perform/config.py: the rules config ---------------------------------------


def _settings(config: dict, prefix: str = ""):
    """Dotted names and values of every leaf setting."""
    for key, value in config.items():
        if isinstance(value, dict):
            yield from _settings(value, f"{prefix}{key}.")
        else:
            yield f"{prefix}{key}", value


def _toml_for(name: str, value: str) -> str:
    section, key = name.rsplit(".", 1)
    return f'[{section}]\n"{key}" = {value}\n'


def test_rules_config_text_in_a_list_via_cli(tmp_path, capsys):
    path = tmp_path / "rules.toml"
    path.write_text('[dynamics]\nbeta = ["x", 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1]\n')
    score = tmp_path / "tune.mid"
    _midi(score)
    err = _arco_fails(capsys, "render", score, "--method", "rules", "--actions",
                      tmp_path / "a.parquet", "--config", path, "--quiet")
    assert f"{path}: dynamics.beta must hold 10 numbers > 0" in err


def _leaf_names():
    from pipelines.perform.config import default_config

    return [name for name, _ in _settings(default_config())]


@pytest.mark.parametrize("name", _leaf_names())
@pytest.mark.parametrize("value", ["1e300", "nan", '"abc"', "true"])
def test_rules_config_every_value_finite_and_bounded(tmp_path, name, value):
    from data_schemas.errors import ParameterError
    from pipelines.perform.config import default_config, load_config

    shipped = dict(_settings(default_config()))[name]
    if isinstance(shipped, bool):  # a switch: true is a valid value, a number is not
        value = "1e300" if value == "true" else value
    text = "[" + ", ".join([value] * len(shipped)) + "]" if isinstance(shipped, list) else value
    path = tmp_path / "rules.toml"
    path.write_text(_toml_for(name, text))
    with pytest.raises(ParameterError) as info:
        load_config(path)
    message = str(info.value)
    assert message.startswith(f"{path}: ") and name.split(".")[-1] in message
    assert "\n" not in message


# --- gesture_db/build.py: sources and the scheduler --------------------------------------


def test_build_db_empty_folder(tmp_path, capsys):
    empty = tmp_path / "recordings"
    empty.mkdir()
    (empty / "notes.txt").write_text("not a recording")
    err = _arco_fails(capsys, "build-db", empty, "-o", tmp_path / "db", "--workers", "1")
    assert f"file {empty}: the folder holds no recordings" in err
    assert not (tmp_path / "db").exists()


def test_build_db_recording_without_notes(tmp_path, capsys):
    from data_schemas.recording import write_recording

    frame = _recording()
    frame["bow_velocity"] = 0.2  # one endless down-bow: no onset anywhere
    path = write_recording(frame, tmp_path / "take.parquet")
    err = _arco_fails(capsys, "build-db", path, "-o", tmp_path / "db", "--workers", "1")
    assert f"file {path}: no notes found in any take" in err


def test_build_db_unreachable_scheduler(tmp_path, capsys, monkeypatch):
    import time

    from data_schemas.recording import write_recording
    from gesture_db import build

    monkeypatch.setattr(build, "CONNECT_TIMEOUT", "1s")
    path = write_recording(_recording(), tmp_path / "take.parquet")
    start = time.monotonic()
    err = _arco_fails(capsys, "build-db", path, "-o", tmp_path / "db", "--scheduler",
                      "tcp://127.0.0.1:1")
    assert "--scheduler tcp://127.0.0.1:1: cannot connect" in err
    assert time.monotonic() - start < 10
    assert not (tmp_path / "db").exists()


# --- pipelines/cli/outputs.py: -o targets ------------------------------------------------


@pytest.fixture()
def taken(tmp_path):
    """An existing file where an output folder is asked for."""
    path = tmp_path / "taken"
    path.write_text("x")
    return path


@pytest.mark.parametrize("argv", [
    ("build-db", "{rec}", "-o", "{out}", "--workers", "1"),
    ("simulate-recordings", "--notes", "4", "-o", "{out}"),
    ("train", "--instrument", "violin", "-o", "{out}"),
    ("compare", "{rec}", "-o", "{out}"),
    ("demo", "-o", "{out}"),
])
@pytest.mark.parametrize("where", ["file", "below a file", "read-only"])
def test_folder_outputs(tmp_path, capsys, monkeypatch, taken, argv, where):
    import os

    out = {"file": taken, "below a file": taken / "sub", "read-only": tmp_path / "ro" / "db"}
    expected = {"file": "names an existing file, not a folder",
                "below a file": f"{taken} is a file, not a folder",
                "read-only": f"cannot write in the folder {tmp_path / 'ro'}"}
    (tmp_path / "ro").mkdir()
    if where == "read-only":  # tests may run as root, who may write anywhere
        real = os.access
        monkeypatch.setattr(os, "access", lambda p, mode: real(p, mode)
                            and os.fspath(p) != os.fspath(tmp_path / "ro"))
    rec = tmp_path / "take.parquet"
    err = _arco_fails(capsys, *[a.format(rec=rec, out=out[where]) for a in argv])
    assert f"-o {out[where]}: {expected[where]}" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ro", "taken"]


@pytest.mark.parametrize("argv", [
    ("notes", "{score}", "-o", "{out}"),
    ("synth", "{actions}", "-o", "{out}"),
    ("render", "{score}", "--method", "rules", "-o", "{out}"),
    ("render", "{score}", "--method", "rules", "--actions", "{out}"),
    ("render", "{score}", "--method", "rules", "--plot", "{out}"),
])
def test_file_outputs(tmp_path, capsys, taken, argv):
    score = _midi(tmp_path / "tune.mid")
    actions = tmp_path / "a.parquet"
    folder = tmp_path / "folder.wav"
    folder.mkdir()
    for out, expected in ((folder, "is a folder, expected a file name"),
                          (taken / "x.wav", f"{taken} is a file, not a folder")):
        err = _arco_fails(capsys, *[a.format(score=score, actions=actions, out=out)
                                    for a in argv])
        assert f"{argv[argv.index('{out}') - 1]} {out}: {expected}" in err
