"""The notes table: MusicXML reading of every notation, and notes -> Parquet -> notes."""

from __future__ import annotations

import pandas as pd
import pytest
from _notation_score import write_score

from data_schemas.errors import SchemaError
from data_schemas.notes import NOTES, read_notes, validate_notes, write_notes
from pipelines.score import read_score


@pytest.fixture(scope="module")
def notes(tmp_path_factory):
    return read_score(write_score(tmp_path_factory.mktemp("score")))


def test_every_notation_is_read(notes):
    by_measure = notes.groupby("measure")
    flags = {c: set(notes.loc[notes[c], "measure"]) for c in (
        "staccato", "portato", "accent", "tie_start", "tie_stop", "breath_mark", "up_bow",
        "down_bow", "tremolo", "fermata", "staccatissimo", "tenuto", "strong_accent", "grace")}
    assert flags["staccato"] == {1} and flags["portato"] == {1} and flags["accent"] == {1}
    assert flags["tie_start"] == {3} and flags["tie_stop"] == {4}
    assert flags["breath_mark"] == {4} and flags["up_bow"] == {6} and flags["down_bow"] == {6}
    assert flags["tremolo"] == {8} and flags["fermata"] == {9} and flags["grace"] == {12}
    assert flags["staccatissimo"] == {11} and flags["strong_accent"] == {11}
    assert by_measure.get_group(2)["slur_position"].tolist() == ["init", "mid", "mid", "end"]
    assert by_measure.get_group(1)["dynamic"].tolist() == [5.0] * 4
    assert by_measure.get_group(6)["technique"].tolist()[:2] == ["pizz", "pizz"]
    assert by_measure.get_group(7)["bow_region"].tolist() == ["tip", "tip", "frog", "frog"]
    assert notes.loc[notes["measure"] == 11, "string_indication"].iloc[0] == 0
    assert by_measure.get_group(12)["technique"].iloc[-1] == "sul_ponticello"
    assert by_measure.get_group(10)["chord_size"].tolist() == [2, 2, 3, 3, 3]
    assert notes["onset"].iloc[-1] == pytest.approx(48.0)  # 60 qpm
    assert notes["run_position"].iloc[-1] == "iso"
    assert set(notes["instrument"]) == {"violin"} and set(notes["part_name"]) == {"Violin"}


@pytest.mark.parametrize("suffix", [".parquet", ".csv"])
def test_round_trip(notes, tmp_path, suffix):
    path = write_notes(notes, tmp_path / f"notes{suffix}")
    back = read_notes(path)
    pd.testing.assert_frame_equal(back, validate_notes(notes), check_dtype=suffix == ".parquet")


def test_parquet_carries_schema_metadata(notes, tmp_path):
    import pyarrow.parquet as pq

    path = write_notes(notes, tmp_path / "notes.parquet")
    meta = pq.read_schema(path).metadata
    assert meta[b"arco_table"] == b"notes"
    assert meta[b"arco_schema_version"] == NOTES.version.encode()


def test_invalid_positions_are_rejected(notes):
    bad = notes.copy()
    bad.loc[3, "slur_position"] = "middle"
    with pytest.raises(SchemaError, match="slur_position"):
        validate_notes(bad)
