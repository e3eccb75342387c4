"""Fixtures shared by several test modules (session-scoped: built once per worker)."""

from __future__ import annotations

import pytest
from _listening import MF_PAIRS, PAIR, TINY


def pytest_configure(config):
    """Compile (and cache) librosa's numba pitch kernels once, before xdist starts workers.

    In a fresh virtual environment several workers otherwise compile and write librosa's
    cached gufuncs (``librosa.yin``'s parabolic interpolation, ``localmax``, ``peak_pick``,
    ...) at the same moment, and a worker that loads a cache pair written by two processes
    dies of a segmentation fault (numba issue 10128).
    """
    if hasattr(config, "workerinput"):  # an xdist worker: the controller warmed the cache
        return
    import librosa
    import numpy as np

    for dtype in (np.float32, np.float64):  # each dtype is its own cached signature
        tone = np.sin(2 * np.pi * 220.0 * np.arange(8192) / 22050.0).astype(dtype)
        librosa.yin(tone, fmin=110.0, fmax=880.0, sr=22050, frame_length=2048)
        librosa.pyin(tone, fmin=110.0, fmax=880.0, sr=22050, frame_length=2048)
        librosa.zero_crossings(tone)
        for x in (tone[:64], np.stack([tone[:64], tone[64:128]])):
            librosa.util.localmax(x, axis=-1)
            librosa.util.localmin(x, axis=-1)
        librosa.util.peak_pick(tone[:256], pre_max=3, post_max=3, pre_avg=3, post_avg=5,
                               delta=0.1, wait=10)


@pytest.fixture(scope="session")
def models_dir(tmp_path_factory):
    """Violin D-string mf pair trained with TINY grids (reused: training resumes)."""
    from pipelines.listening.train import train_instrument

    out = tmp_path_factory.getbasetemp() / "listening-models"
    train_instrument("violin", out, pairs=[PAIR], settings=TINY, workers=1, progress=False)
    return out


@pytest.fixture(scope="session")
def mf_models_dir(models_dir):
    """All four violin mf pairs (TINY grids, two workers), beside the D-string pair."""
    from pipelines.listening.train import train_instrument

    train_instrument("violin", models_dir, pairs=MF_PAIRS, settings=TINY, workers=2,
                     progress=False)
    return models_dir


@pytest.fixture(scope="session")
def tiny_db(tmp_path_factory):
    """A database of one simulated 300-note take, with predictors saved beside it."""
    from gesture_db.build import build_database
    from gesture_db.predict import fit_predictors, save_predictors
    from gesture_db.simulate import simulate_recordings
    from gesture_db.store import GestureDB

    base = tmp_path_factory.mktemp("sampling")
    rec = base / "rec"
    simulate_recordings(300, 2, rec, seed=11, notes_per_take=150)
    build_database([rec], base / "db", workers=1, progress=False)
    db = GestureDB(base / "db")
    save_predictors(fit_predictors(db, max_folds=2), db.path)
    return base
