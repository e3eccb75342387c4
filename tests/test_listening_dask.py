import pytest
from _listening import TINY

from pipelines.listening.train import train_instrument
from synth.listening.classifier import load_pair


@pytest.mark.slow
def test_training_runs_on_a_dask_cluster(tmp_path):
    from distributed import LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                      dashboard_address=None) as cluster:
        results = train_instrument("violin", tmp_path, pairs=[(3, "f")], settings=TINY,
                                   scheduler=cluster.scheduler_address, progress=False)
    assert [r["key"] for r in results] == ["violin-3-f"]
    assert load_pair(tmp_path, "violin", 3, "f").metadata["complete"]
