"""The actions table: schema metadata, Parquet/CSV round trips, atomic writes."""

import json

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from data_schemas import ACTIONS, SchemaError, read_actions, write_actions


def table(n=5):
    return pd.DataFrame({
        "time": np.linspace(0, 1, n), "string": np.arange(n) % 4,
        "finger_ratio": np.full(n, 0.1), "bow_force": np.full(n, 0.5),
        "bow_velocity": np.linspace(-0.3, 0.3, n), "beta": np.full(n, 0.1),
        "bow_position": np.linspace(0, 1, n), "pluck": [False] * n})


def test_schema_carries_units_descriptions_and_version(tmp_path):
    path = write_actions(table(), tmp_path / "a.parquet")
    schema = pq.read_schema(path)
    assert schema.metadata[b"arco_schema_version"] == ACTIONS.version.encode()
    assert schema.field("bow_force").metadata[b"unit"] == b"N"
    assert schema.field("bow_velocity").metadata[b"unit"] == b"m/s"
    assert str(schema.field("string").type) == "int8"
    assert str(schema.field("finger_ratio").type) == "float"
    columns = json.loads(schema.metadata[b"columns"])
    assert set(columns) == set(ACTIONS.column_names)


@settings(max_examples=25, deadline=None)
@given(st.integers(1, 40), st.sampled_from([".parquet", ".csv"]))
def test_round_trip(tmp_path_factory, n, suffix):
    path = tmp_path_factory.mktemp("rt") / f"a{suffix}"
    original = table(n).assign(finger_touch=np.arange(n) % 3 == 1,
                               touch_ratio=np.where(np.arange(n) % 2 == 1, 0.3, np.nan))
    write_actions(original, path)
    back = read_actions(path)
    pd.testing.assert_frame_equal(back, original.astype(back.dtypes.to_dict()), check_exact=False,
                                  rtol=1e-6)


def test_failed_write_leaves_the_previous_file(tmp_path):
    path = tmp_path / "a.parquet"
    write_actions(table(), path)
    before = path.read_bytes()
    bad = table()
    bad.loc[3, "bow_force"] = -1.0
    with pytest.raises(SchemaError, match="row 3"):
        write_actions(bad, path)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["a.parquet"]


def test_wrong_table_version_and_corrupt_files_are_named(tmp_path):
    corrupt = tmp_path / "c.parquet"
    corrupt.write_bytes(b"not parquet at all")
    with pytest.raises(SchemaError, match=str(corrupt)):
        read_actions(corrupt)
    missing = table().drop(columns="beta")
    path = tmp_path / "m.csv"
    missing.to_csv(path, index=False)
    with pytest.raises(SchemaError, match="'beta'"):
        read_actions(path)
    import pyarrow as pa
    old = pa.Table.from_pandas(table(), preserve_index=False).replace_schema_metadata(
        {"arco_table": "actions", "arco_schema_version": "0.1"})
    pq.write_table(old, tmp_path / "old.parquet")
    with pytest.raises(SchemaError, match="incompatible"):
        read_actions(tmp_path / "old.parquet")


def test_the_documented_maximum_finger_ratio_is_accepted_as_float32_stores_it():
    """0.8 becomes 0.800000011920929 in float32: the limit the schema documents still holds."""
    import numpy as np
    import pandas as pd

    from data_schemas.actions import validate_actions

    table = pd.DataFrame({"time": [0.0, 0.5], "string": [1, 1], "finger_ratio": [0.8, 0.8],
                          "bow_force": [1.0, 1.0], "bow_velocity": [0.3, 0.3],
                          "beta": [0.1, 0.1], "bow_position": [0.2, 0.5],
                          "pluck": [False, False]})
    checked = validate_actions(table)
    assert np.float32(checked["finger_ratio"].iloc[0]) == np.float32(0.8)
    with pytest.raises(SchemaError, match="finger_ratio"):
        validate_actions(table.assign(finger_ratio=[0.8, 0.8001]))
