"""An imported take keeps its instrument: open-string pitches and effective string lengths.

The truth is read straight from ``data_schemas/config/instruments.toml`` with tomllib (not
through :mod:`data_schemas.instruments`), and the scale length is its lowest string's
speaking length.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from data_schemas.annotation import read_annotation
from data_schemas.errors import SchemaError
from data_schemas.recording import read_recording, write_recording
from gesture_db.build import BuildParams, process_source
from gesture_db.importers import Source, resolve_sources, source_instrument
from gesture_db.simulate import simulate_recordings

ROOT = Path(__file__).resolve().parents[1]


def toml_facts(name: str) -> dict:
    data = tomllib.loads((ROOT / "data_schemas/config/instruments.toml").read_text())
    return next(e for e in data["instrument"] if e["name"] == name)


@pytest.fixture(scope="module")
def take(tmp_path_factory):
    out = tmp_path_factory.mktemp("rec")
    path = simulate_recordings(80, 1, out, seed=11, notes_per_take=80)[0]
    return read_recording(path), read_annotation(path.with_name(f"{path.stem}.annotation"
                                                                ".parquet"))


def _mapped(tmp_path: Path, rec: pd.DataFrame, ann: pd.DataFrame | None,
            instrument: str | None) -> Source:
    rec.drop(columns="recording_id").to_csv(tmp_path / "export.csv", index=False)
    lines = ['[source]', 'path = "export.csv"', 'recording_id = "m1"']
    if instrument is not None:
        lines.append(f'instrument = "{instrument}"')
    if ann is not None:
        ann.assign(recording_id="m1").to_csv(tmp_path / "m1.annotation.csv", index=False)
        lines.append('annotation = "m1.annotation.csv"')
    (tmp_path / "m1.toml").write_text("\n".join(lines) + "\n")
    return resolve_sources([tmp_path / "m1.toml"])[0]


def _extract(source: Source) -> pd.DataFrame:
    notes, _, _ = process_source(source, BuildParams(max_candidates=8), "hash")
    return notes.sort_values("note_index", ignore_index=True)


@pytest.mark.parametrize("instrument", ["cello", "viola"])
def test_mapped_take_gets_its_instruments_string_lengths(take, tmp_path, instrument):
    rec, ann = take
    source = _mapped(tmp_path, rec, ann, instrument)
    assert source_instrument(source) == instrument
    notes = _extract(source)
    fr = ann.set_index("note_index").loc[notes["note_index"], "finger_ratio"].to_numpy(float)
    scale = toml_facts(instrument)["string_lengths"][0]
    np.testing.assert_allclose(notes["effective_string_length"], scale * (1.0 - fr), rtol=1e-12)
    assert scale != pytest.approx(toml_facts("violin")["string_lengths"][0])


@pytest.mark.parametrize("instrument", ["cello", "viola"])
def test_blind_take_gets_its_instruments_open_strings(take, tmp_path, instrument):
    rec, ann = take
    write_recording(rec, tmp_path / "v.parquet")
    write_recording(rec, tmp_path / "x.parquet", instrument=instrument)
    violin, other = (_extract(Source(tmp_path / f"{n}.parquet")) for n in ("v", "x"))
    assert len(violin) == len(other) > 40 and (violin["string"] == other["string"]).all()
    string = violin["string"].to_numpy(int)
    shift = (np.array(toml_facts(instrument)["open_strings"])
             - np.array(toml_facts("violin")["open_strings"]))[string]
    np.testing.assert_array_equal(other["midi_pitch"] - violin["midi_pitch"], shift)
    ratio = toml_facts(instrument)["string_lengths"][0] / toml_facts("violin")["string_lengths"][0]
    np.testing.assert_allclose(other["effective_string_length"] / violin["effective_string_length"],
                               ratio, rtol=1e-12)
    # the violin reading is the simulated violinist's truth for nearly every note
    mid = 0.5 * (violin["onset"] + violin["offset"]).to_numpy()
    k = np.clip(np.searchsorted(ann["true_onset"].to_numpy(), mid) - 1, 0, len(ann) - 1)
    assert np.mean(violin["midi_pitch"].to_numpy() == ann["midi_pitch"].to_numpy()[k]) > 0.8


def test_instrument_defaults_to_violin_and_unknown_names_are_rejected(take, tmp_path):
    rec, _ = take
    assert source_instrument(_mapped(tmp_path, rec, None, None)) == "violin"
    write_recording(rec, tmp_path / "plain.parquet")
    assert source_instrument(Source(tmp_path / "plain.parquet")) == "violin"
    with pytest.raises(SchemaError, match="'guitar' is not one of"):
        source_instrument(_mapped(tmp_path, rec, None, "guitar"))
    with pytest.raises(SchemaError, match="'guitar' is not one of"):
        write_recording(rec, tmp_path / "g.parquet", instrument="guitar")
