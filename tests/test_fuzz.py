"""Fuzz every reader: mutated inputs end in exit 0 or one clean error naming the file.

Hypothesis mutates a good input of each reader (byte flips, truncation, inserted bytes,
dropped, duplicated or renamed columns, cells swapped to NaN, inf, huge, negative or text
values, JSON and TOML values swapped or removed) and runs the reader through ``arco``
in-process. Each run must return 0 or 2; on 2 stderr is one line ``arco CMD: error: ...``
naming the mutated file (or its folder), never a traceback; no run may take over 30 s or
leave a partial output or a temp file.

``ARCO_FUZZ_EXAMPLES`` sets the examples per reader (default 3, fixed seed, as in
``make test``); ``make fuzz`` runs many more with fresh random mutations.
The model folders, labels and the rules and search configs are fuzzed through their readers
(the commands that read them train or render, far too slow per example).
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import os
import re
import shutil
import signal
import tempfile
from collections.abc import Callable
from pathlib import Path

import mido
import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from data_schemas.errors import ArcoError
from pipelines.cli.main import main
from tests.test_bad_inputs import _MUSICXML, _recording

EXAMPLES = int(os.environ.get("ARCO_FUZZ_EXAMPLES", "3"))
FUZZ = settings(max_examples=EXAMPLES, deadline=None, database=None,
                derandomize=os.environ.get("ARCO_FUZZ_RANDOM") is None,
                suppress_health_check=list(HealthCheck))
TIME_LIMIT = 30  # s per run

_BAR = re.compile(r"^[\w -]+: +\d+%\|")
_BAD_VALUES = [math.nan, math.inf, -math.inf, 1e300, -1.0, -1e9, 0.0, "abc", "", None]


# --- mutations ---------------------------------------------------------------------------


@st.composite
def byte_mutation(draw, data: bytes) -> bytes:
    """Flip bytes, truncate, insert or repeat a slice of ``data``."""
    kind = draw(st.sampled_from(["flip", "truncate", "insert", "repeat"]))
    n = len(data)
    if kind == "truncate":
        return data[:draw(st.integers(0, max(n - 1, 0)))]
    if kind == "insert":
        at = draw(st.integers(0, n))
        return data[:at] + draw(st.binary(min_size=1, max_size=16)) + data[at:]
    if kind == "repeat":
        a = draw(st.integers(0, max(n - 1, 0)))
        b = draw(st.integers(a, min(n, a + 64)))
        return data[:b] + data[a:b] + data[b:]
    out = bytearray(data)
    for _ in range(draw(st.integers(1, 8))):
        i = draw(st.integers(0, max(n - 1, 0)))
        if out:
            out[i] ^= draw(st.integers(1, 255))
    return bytes(out)


@st.composite
def table_mutation(draw, frame: pd.DataFrame) -> pd.DataFrame:
    """Drop, duplicate or rename a column, or set some cells to a bad value."""
    frame = frame.copy()
    cols = list(frame.columns)
    kind = draw(st.sampled_from(["drop", "dupe", "rename", "cell", "cell", "column"]))
    col = draw(st.sampled_from(cols))
    if kind == "drop":
        return frame.drop(columns=[col])
    if kind == "dupe":
        other = frame[[col]]
        return pd.concat([frame, other], axis=1)
    if kind == "rename":
        return frame.rename(columns={col: draw(st.sampled_from(["x", "", "time", col + " "]))})
    value = draw(st.sampled_from(_BAD_VALUES))
    frame[col] = frame[col].astype(object)
    if kind == "column":
        frame[col] = value
    else:
        rows = draw(st.lists(st.integers(0, len(frame) - 1), min_size=1, max_size=3))
        for r in rows:
            frame.iat[r, cols.index(col)] = value
    return frame


def _json_paths(obj, prefix=()):
    yield prefix
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _json_paths(v, (*prefix, k))
    elif isinstance(obj, list):
        for i, v in enumerate(obj[:5]):
            yield from _json_paths(v, (*prefix, i))


_JSON_VALUES = [None, "abc", -1, 0, 1e300, [], {}, "../../outside", "/etc/passwd", True, [1, "x"]]


@st.composite
def json_mutation(draw, obj) -> str:
    """Replace or remove one value anywhere in a JSON document."""
    obj = json.loads(json.dumps(obj))
    paths = [p for p in _json_paths(obj) if p]
    if not paths:
        return json.dumps(draw(st.sampled_from(_JSON_VALUES)))
    path = draw(st.sampled_from(paths))
    parent = obj
    for k in path[:-1]:
        parent = parent[k]
    if draw(st.booleans()) and isinstance(parent, dict):
        del parent[path[-1]]
    else:
        parent[path[-1]] = draw(st.sampled_from(_JSON_VALUES))
    return json.dumps(obj)


_TOML_VALUE = re.compile(r"(=\s*)([^\n]+)")
_TOML_BAD = ['"abc"', "nan", "inf", "-1", "1e300", "0", "true", "[]", '"../../x"', "5",
             '["x", 1]', "{}"]


@st.composite
def toml_mutation(draw, text: str) -> bytes:
    """Swap one value of a TOML file for a bad one, or mutate its bytes."""
    spots = list(_TOML_VALUE.finditer(text))
    if spots and draw(st.booleans()):
        m = draw(st.sampled_from(spots))
        text = text[:m.start(2)] + draw(st.sampled_from(_TOML_BAD)) + text[m.end(2):]
        return text.encode()
    return draw(byte_mutation(text.encode()))


def _to_parquet(frame: pd.DataFrame, path: Path) -> None:
    """Write a mutated frame as Parquet as it is (duplicated names, mixed types as text)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    arrays = []
    for i in range(frame.shape[1]):
        col = frame.iloc[:, i]
        try:
            arrays.append(pa.array(col, from_pandas=True))
        except (pa.ArrowInvalid, pa.ArrowTypeError):
            arrays.append(pa.array(col.astype(str)))
    pq.write_table(pa.Table.from_arrays(arrays, names=[str(c) for c in frame.columns]), path)


# --- running -----------------------------------------------------------------------------


def _timeout(*_):
    raise TimeoutError(f"a run took over {TIME_LIMIT} s")


def _arco(argv: list[str]) -> tuple[int, str]:
    err, out = io.StringIO(), io.StringIO()
    old = signal.signal(signal.SIGALRM, _timeout)
    signal.alarm(TIME_LIMIT)
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
            try:
                code = main([str(a) for a in argv])
            except SystemExit as stop:  # argparse's usage errors
                code = stop.code
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
    return int(code or 0), err.getvalue()


def _error_lines(raw: str) -> list[str]:
    return [line for line in re.split(r"[\r\n]+", raw) if line.strip() and not _BAR.match(line)]


def check_run(argv: list[str], named: Path, outputs: list[Path], work: Path) -> None:
    """Exit 0 or 2; on 2 one line naming ``named``; no outputs then; never temp files."""
    code, raw = _arco(argv)
    assert code in (0, 2), raw
    assert "Traceback" not in raw, raw
    if code == 2:
        lines = _error_lines(raw)
        assert len(lines) == 1, raw
        assert lines[0].startswith(f"arco {argv[0]}: error: "), raw
        assert named.name in lines[0] or named.parent.name in lines[0], raw
        for out in outputs:
            assert not out.exists(), f"{out} left after a failed run: {raw}"
    assert not list(work.rglob("*.tmp")), "temp files left"


def check_reader(read: Callable[[], object], named: Path) -> None:
    """A reader returns or raises an ArcoError naming ``named`` (one line), within 30 s."""
    old = signal.signal(signal.SIGALRM, _timeout)
    signal.alarm(TIME_LIMIT)
    try:
        read()
    except ArcoError as exc:
        text = str(exc)
        assert "\n" not in text.strip(), text
        assert named.name in text or named.parent.name in text, text
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


@contextlib.contextmanager
def _work():
    with tempfile.TemporaryDirectory(prefix="arco-fuzz-") as tmp:
        yield Path(tmp)


# --- the good inputs ---------------------------------------------------------------------

_SCORE = _MUSICXML.format(per_minute="120").encode()


def _midi_bytes() -> bytes:
    mid = mido.MidiFile(ticks_per_beat=480)
    track = mido.MidiTrack()
    track.append(mido.MetaMessage("set_tempo", tempo=500000, time=0))
    track.append(mido.MetaMessage("time_signature", numerator=4, denominator=4, time=0))
    for pitch in (62, 64, 66):
        track.append(mido.Message("note_on", note=pitch, velocity=64, time=0))
        track.append(mido.Message("note_off", note=pitch, velocity=0, time=480))
    mid.tracks.append(track)
    buf = io.BytesIO()
    mid.save(file=buf)
    return buf.getvalue()


_MIDI = _midi_bytes()

_ACTIONS = pd.DataFrame({
    "time": [0.0, 0.2, 0.4], "string": [1, 1, 2], "finger_ratio": [0.0, 0.1, 0.8],
    "bow_force": [0.5, 0.6, 0.5], "bow_velocity": [0.3, 0.3, -0.3], "beta": [0.1, 0.1, 0.12],
    "bow_position": [0.2, 0.3, 0.5], "pluck": [False, False, False]})


# --- scores ------------------------------------------------------------------------------


@FUZZ
@given(data=st.data())
def test_fuzz_musicxml(data):
    blob = data.draw(byte_mutation(_SCORE))
    with _work() as work:
        path = work / "score.musicxml"
        path.write_bytes(blob)
        check_run(["notes", path], path, [], work)


@FUZZ
@given(data=st.data())
def test_fuzz_midi(data):
    blob = data.draw(byte_mutation(_MIDI))
    with _work() as work:
        path = work / "score.mid"
        path.write_bytes(blob)
        check_run(["notes", path], path, [], work)


# --- actions tables ----------------------------------------------------------------------


def _synth(path: Path, work: Path) -> None:
    out = work / "out.wav"
    check_run(["synth", path, "-o", out, "--quiet", "--max-duration", "5",
               "--body", "none"], path, [out], work)


@FUZZ
@given(data=st.data())
def test_fuzz_actions_csv(data):
    with _work() as work:
        path = work / "actions.csv"
        if data.draw(st.booleans()):
            data.draw(table_mutation(_ACTIONS)).to_csv(path, index=False)
        else:
            path.write_bytes(data.draw(byte_mutation(_ACTIONS.to_csv(index=False).encode())))
        _synth(path, work)


@FUZZ
@given(data=st.data())
def test_fuzz_actions_parquet(data):
    from data_schemas.actions import write_actions

    with _work() as work:
        path = work / "actions.parquet"
        if data.draw(st.booleans()):
            _to_parquet(data.draw(table_mutation(_ACTIONS)), path)
        else:
            write_actions(_ACTIONS, path)
            path.write_bytes(data.draw(byte_mutation(path.read_bytes())))
        _synth(path, work)


# --- recordings, annotations and mappings through build-db --------------------------------


def _build_db(target: Path, named: Path, work: Path) -> None:
    db = work / "db"
    check_run(["build-db", target, "-o", db, "--workers", "1"], named, [db], work)


@FUZZ
@given(data=st.data())
def test_fuzz_recording(data):
    take = _recording()
    with _work() as work:
        path = work / "take.csv"
        if data.draw(st.booleans()):
            data.draw(table_mutation(take)).to_csv(path, index=False)
        else:
            _to_parquet(take, path := work / "take.parquet")
            path.write_bytes(data.draw(byte_mutation(path.read_bytes())))
        _build_db(path, path, work)


@pytest.fixture(scope="module")
def simulated_take(tmp_path_factory):
    from gesture_db.simulate import simulate_recordings

    rec = tmp_path_factory.mktemp("fuzz_take") / "rec"
    simulate_recordings(20, 1, rec, seed=1, notes_per_take=20)
    take = sorted(p for p in rec.glob("*.parquet") if ".annotation" not in p.name)[0]
    return take, take.with_name(take.stem + ".annotation.parquet")


@FUZZ
@given(data=st.data())
def test_fuzz_annotation(simulated_take, data):
    from data_schemas.annotation import read_annotation

    take, annotation = simulated_take
    notes = read_annotation(annotation)
    with _work() as work:
        shutil.copy(take, work / take.name)
        path = work / (take.stem + ".annotation.csv")
        data.draw(table_mutation(notes)).to_csv(path, index=False)
        _build_db(work / take.name, path, work)


@FUZZ
@given(data=st.data())
def test_fuzz_toml_mapping(data):
    mapping = ('[source]\npath = "export.csv"\n[columns]\ntime = "t"\nbow_velocity = "v"\n'
               'bow_force = "f"\nbeta = "b"\n[scale]\nbow_force = 1.0\n[constants]\n'
               "string = 2\nbow_position = 0.5\nfinger_ratio = 0.0\n")
    take = _recording()
    export = pd.DataFrame({"t": take["time"], "v": take["bow_velocity"],
                           "f": take["bow_force"], "b": take["beta"]})
    with _work() as work:
        path = work / "take.toml"
        if data.draw(st.booleans()):
            path.write_bytes(data.draw(toml_mutation(mapping)))
            export.to_csv(work / "export.csv", index=False)
            named = path
        else:
            path.write_text(mapping)
            data.draw(table_mutation(export)).to_csv(work / "export.csv", index=False)
            named = work / "export.csv"
        code, raw = _arco(["build-db", path, "-o", work / "db", "--workers", "1"])
        assert code in (0, 2) and "Traceback" not in raw, raw
        if code == 2:
            lines = _error_lines(raw)
            assert len(lines) == 1, raw
            assert path.name in lines[0] or named.name in lines[0], raw
            assert not (work / "db").exists(), raw


# --- a gesture database's manifest and predictors ----------------------------------------


@pytest.fixture(scope="module")
def database(tmp_path_factory):
    from data_schemas.recording import write_recording
    from gesture_db.build import build_database

    base = tmp_path_factory.mktemp("fuzz_db")
    rec = write_recording(_recording(), base / "take.parquet")
    build_database([rec], base / "db", workers=1, progress=False)
    return base / "db"


@FUZZ
@given(data=st.data())
def test_fuzz_manifest(database, data):
    manifest = json.loads((database / "manifest.json").read_text())
    with _work() as work:
        db = work / "db"
        shutil.copytree(database, db)
        path = db / "manifest.json"
        if data.draw(st.booleans()):
            path.write_text(data.draw(json_mutation(manifest)))
        else:
            path.write_bytes(data.draw(byte_mutation(path.read_bytes())))
        plots = work / "plots"
        check_run(["db", "info", db, "--json", "--plots", plots], path, [plots], work)


@FUZZ
@given(data=st.data())
def test_fuzz_database_tables(database, data):
    files = sorted(p.relative_to(database) for p in database.rglob("*.parquet"))
    with _work() as work:
        db = work / "db"
        shutil.copytree(database, db)
        path = db / data.draw(st.sampled_from(files))
        path.write_bytes(data.draw(byte_mutation(path.read_bytes())))
        code, raw = _arco(["db", "info", db, "--json", "--no-plots"])
        assert code in (0, 2) and "Traceback" not in raw, raw
        if code == 2:
            lines = _error_lines(raw)
            assert len(lines) == 1 and (path.name in lines[0] or "db" in lines[0]), raw


# --- model folders, labels and configs, through their readers ----------------------------


@pytest.fixture(scope="module")
def model_folder(tmp_path_factory):
    from synth.listening.classifier import FEATURE_NAMES, fit_pair, save_pair

    rng = np.random.default_rng(0)
    X = rng.normal(size=(120, len(FEATURE_NAMES)))
    y = 1 + np.digitize(X[:, 0], [-1, 0, 1])
    folder = tmp_path_factory.mktemp("fuzz_models")
    save_pair(fit_pair(X, y, instrument="violin", string=2, dynamic="p", folds=2), folder)
    return folder


@FUZZ
@given(data=st.data())
def test_fuzz_model_folder(model_folder, data):
    from synth.listening.classifier import load_models

    with _work() as work:
        folder = work / "models"
        shutil.copytree(model_folder, folder)
        name = data.draw(st.sampled_from(["violin-2-p.json", "violin-2-p.npz"]))
        path = folder / name
        if name.endswith(".json") and data.draw(st.booleans()):
            path.write_text(data.draw(json_mutation(json.loads(path.read_text()))))
        else:
            path.write_bytes(data.draw(byte_mutation(path.read_bytes())))
        check_reader(lambda: load_models(folder, "violin"), path)


@FUZZ
@given(data=st.data())
def test_fuzz_labels(data):
    from data_schemas.labels import read_labels

    labels = pd.DataFrame({
        "clip_id": ["a", "b"], "audio_path": [None, None], "instrument": "violin",
        "string": [2, 2], "dynamic": "mf", "finger_semitones": [0.0, 2.0],
        "bow_force": [0.5, 1.0], "bow_velocity": [0.2, 0.2], "beta": [0.1, 0.1],
        "label": [3, 5], "labeller": "ann",
        "time": pd.Timestamp("2026-01-01", tz="UTC")})
    with _work() as work:
        path = work / "labels.csv"
        data.draw(table_mutation(labels)).to_csv(path, index=False)
        check_reader(lambda: read_labels(path), path)


def _rules_text() -> str:
    from importlib import resources

    return resources.files("pipelines.perform").joinpath("rules.toml").read_text("utf-8")


@FUZZ
@given(data=st.data())
def test_fuzz_rules_config(data):
    from pipelines.perform.config import load_config

    with _work() as work:
        path = work / "rules.toml"
        path.write_bytes(data.draw(toml_mutation(_rules_text())))
        check_reader(lambda: load_config(path), path)


@FUZZ
@given(data=st.data())
def test_fuzz_search_config(data):
    from gesture_db.search_config import load_search_config

    text = ("n_best = 8\n[weights]\ngesture = 1.0\nbasic = 0.5\n"
            "[fallback]\nmax_distance = 3.0\n")
    with _work() as work:
        path = work / "search.toml"
        path.write_bytes(data.draw(toml_mutation(text)))
        check_reader(lambda: load_search_config(path), path)
