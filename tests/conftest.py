"""Fixtures shared by several test modules (session-scoped: built once per worker)."""

from __future__ import annotations

import pytest
from _listening import MF_PAIRS, PAIR, TINY


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
