import numpy as np
import pandas as pd
import pytest

from data_schemas import SchemaError
from data_schemas.labels import merge_labels, read_labels, write_labels
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
               finger=0.0, force=0.5, velocity=0.33, beta=0.1, label=3, labeller="auto",
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
