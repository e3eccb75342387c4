"""Sampling with the listening controller correcting the sampled force."""

import numpy as np
import pytest
from _listening import d_string_notes


@pytest.fixture(scope="module")
def played(tiny_db, models_dir):
    from pipelines.methods.sampling import open_database, render_sampling

    sdb = open_database(tiny_db / "db")
    notes = d_string_notes()
    closed = render_sampling(notes, db=sdb, models=models_dir, progress=False)
    open_ = render_sampling(notes, db=sdb, models=models_dir, feedback=False, progress=False)
    return closed.parts[0], open_.parts[0]


def test_feedback_corrects_the_sampled_force(played):
    closed, open_ = played
    assert closed.feedback and not open_.feedback
    sampled = closed.extras["sampled_actions"]
    pd_open = open_.performance.actions
    assert sampled.equals(pd_open)  # same gestures before correction
    acts = closed.performance.actions
    bowed = acts[acts["bow_force"] > 0]
    assert len(bowed) > 100 and closed.diagnostics is not None and len(closed.diagnostics)
    # the force played is the sampled one times a per-stroke correction: not identical
    f_sampled = np.interp(bowed["time"], sampled["time"], sampled["bow_force"])
    ratio = bowed["bow_force"].to_numpy() / np.maximum(f_sampled, 1e-9)
    assert np.nanstd(ratio) > 1e-3 and np.all(np.isfinite(closed.audio))
