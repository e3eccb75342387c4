import numpy as np
import pandas as pd
import pytest

from data_schemas import SchemaError
from data_schemas.labels import LABELS_VERSION, merge_labels, read_labels, write_labels
from synth.listening.clips import ClipSpec, auto_label, render_clip
from synth.listening.teacher import RegimeStatistics, judge


def test_auto_label_rises_from_1_to_5_with_force():
    forces = (0.01, 0.1, 0.7, 4.0, 12.0)
    labels = [auto_label(render_clip(ClipSpec("violin", 1, 0.0, f, 0.33, 0.10), settle=0.6))
              for f in forces]
    assert labels == [1, 2, 3, 4, 5]


def test_judge_mapping_of_regimes():
    helm = RegimeStatistics(1.0, 1.0, 0.99, 0.98, 2.0, -20.0)
    assert judge(helm) == 3
    assert judge(RegimeStatistics(0.0, 0.0, 1.0, 1.0, 0.0, -60.0)) == 1
    assert judge(RegimeStatistics(3.0, 0.0, 0.99, 0.99, 0.0, -20.0)) == 2
    assert judge(RegimeStatistics(1.0, 1.0, 0.99, 0.98, -30.0, -20.0)) == 4  # flattening
    assert judge(RegimeStatistics(2.5, 0.0, 0.6, 0.5, 0.0, -10.0)) == 4  # raucous
    assert judge(RegimeStatistics(1.0, 0.0, 0.5, 0.95, 0.0, -10.0)) == 5  # ALF
    assert judge(RegimeStatistics(np.nan, 0.0, 0.0, 0.0, np.nan, 0.0, False)) == 5


def _labels(**over):
    row = dict(clip_id="c1", audio_path=None, instrument="violin", string=1, dynamic="mf",
               finger_semitones=0.0, bow_force=0.5, bow_velocity=0.33, beta=0.1, label=3,
               labeller="auto",
               time=pd.Timestamp("2024-01-01", tz="UTC"))
    row.update(over)
    return pd.DataFrame([row])


def test_labels_round_trip_and_human_override(tmp_path):
    auto = pd.concat([_labels(), _labels(clip_id="c2", label=2)], ignore_index=True)
    human = _labels(label=4, labeller="ann", audio_path="clips/c1.wav",
                    time=pd.Timestamp("2024-02-01", tz="UTC"))
    path = write_labels(auto, tmp_path / "labels.parquet")
    back = read_labels(path)
    assert back["label"].tolist() == [3, 2]
    merged = merge_labels(back, human).set_index("clip_id")
    assert merged.loc["c1", "label"] == 4 and merged.loc["c1", "labeller"] == "ann"
    assert merged.loc["c2", "label"] == 2


def test_labels_reject_bad_rows(tmp_path):
    with pytest.raises(SchemaError, match="label"):
        write_labels(_labels(label=6), tmp_path / "bad.parquet")
    with pytest.raises(SchemaError, match="dynamic"):
        write_labels(_labels(dynamic="fff"), tmp_path / "bad.parquet")


def _v1_table(**metadata):
    """Two rows of a labels table as Arco wrote version 1.0 (finger, force, velocity)."""
    import pyarrow as pa

    fields = [("clip_id", pa.string()), ("audio_path", pa.string()), ("instrument", pa.string()),
              ("string", pa.int8()), ("dynamic", pa.string()), ("finger", pa.float64()),
              ("force", pa.float64()), ("velocity", pa.float64()), ("beta", pa.float64()),
              ("label", pa.int8()), ("labeller", pa.string()),
              ("time", pa.timestamp("s", tz="UTC"))]
    columns = [["a", "b"], [None, "clips/b.wav"], ["violin", "viola"], [1, 3], ["mf", "p"],
               [0.0, 7.0], [0.25, 1.5], [0.33, -0.2], [0.1, 0.12], [3, 4], ["auto", "ann"],
               [pd.Timestamp("2024-01-01", tz="UTC")] * 2]
    schema = pa.schema(fields, metadata=metadata or None)
    return pa.table([pa.array(c, t) for c, (_, t) in zip(columns, fields, strict=True)],
                    schema=schema)


@pytest.mark.parametrize("metadata", [
    {"arco_table": "labels", "arco_schema_version": "1.0"},  # as version 1.0 wrote it
    {},  # a file without Arco's metadata, the old column names
])
def test_version_1_labels_are_read_with_the_new_column_names(tmp_path, metadata):
    import pyarrow.parquet as pq

    assert LABELS_VERSION == "2.0"
    path = tmp_path / "v1.parquet"
    pq.write_table(_v1_table(**metadata), path)
    back = read_labels(path)
    assert list(back.columns[5:8]) == ["finger_semitones", "bow_force", "bow_velocity"]
    assert back["finger_semitones"].tolist() == [0.0, 7.0]
    assert back["bow_force"].tolist() == [0.25, 1.5]
    assert back["bow_velocity"].tolist() == [0.33, -0.2]
    assert back["label"].tolist() == [3, 4] and back["clip_id"].tolist() == ["a", "b"]
    # Written back, it is a version 2.0 file.
    again = write_labels(back, tmp_path / "v2.parquet")
    assert pq.read_schema(again).metadata[b"arco_schema_version"] == b"2.0"
    pd.testing.assert_frame_equal(read_labels(again), back)


def test_version_1_labels_csv_is_migrated_and_other_versions_are_refused(tmp_path):
    import pyarrow.csv as pacsv
    import pyarrow.parquet as pq

    pacsv.write_csv(_v1_table(), tmp_path / "v1.csv")
    assert read_labels(tmp_path / "v1.csv")["bow_force"].tolist() == [0.25, 1.5]
    pq.write_table(_v1_table(arco_table="labels", arco_schema_version="3.0"),
                   tmp_path / "v3.parquet")
    with pytest.raises(SchemaError, match="v3.parquet.*version 3.0"):
        read_labels(tmp_path / "v3.parquet")
