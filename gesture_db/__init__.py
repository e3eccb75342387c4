"""Gesture database: simulated and imported recordings, segmentation, contours, features.

Build a database from recordings (:func:`build_database`), open it (:class:`GestureDB`),
summarise it (:func:`summarize`) and search it for the gestures of a sequence of target notes
(:class:`SearchIndex` and :func:`gesture_db.search.search`: the function is not re-exported,
its name is its module's). Names load on first use (PEP 562, :mod:`data_schemas.lazy`).

Examples
--------
Simulate a short session, build its database and look inside:

>>> import tempfile
>>> from gesture_db import GestureDB, SearchIndex, build_database, simulate_recordings
>>> tmp = tempfile.mkdtemp()
>>> takes = simulate_recordings(40, 1, f"{tmp}/rec", seed=1)
>>> manifest = build_database([f"{tmp}/rec"], f"{tmp}/db", workers=1, progress=False)
>>> db = GestureDB(f"{tmp}/db")
>>> manifest["n_notes"], len(db.notes()), "legato-down-init-mid" in db.groups
(40, 40, True)
>>> SearchIndex.from_db(db).n_notes
40
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from data_schemas.lazy import lazy_exports

if TYPE_CHECKING:  # pragma: no cover - where each name lives (read by lazy_exports)
    from gesture_db.assemble import ContourSource, assemble_actions
    from gesture_db.build import BuildParams, build_database
    from gesture_db.info import format_summary, summarize
    from gesture_db.predict import fit_predictors, load_or_fit_predictors
    from gesture_db.search import (
        EmptyGroupsError,
        SearchIndex,
        SearchResult,
        load_search_config,
    )
    from gesture_db.simulate import simulate_recordings
    from gesture_db.store import GestureDB

__all__ = ["BuildParams", "ContourSource", "EmptyGroupsError", "GestureDB", "SearchIndex",
           "SearchResult", "build_database", "fit_predictors", "format_summary",
           "load_or_fit_predictors", "load_search_config", "assemble_actions",
           "simulate_recordings", "summarize"]

__getattr__, __dir__ = lazy_exports(__name__, __file__)
