"""Gesture sampling of parts with a single bowed note (a held-out excerpt crashed on one).

The full held-out protocol stopped after 23 minutes: one part of one excerpt had a single
bowed note among plucked ones, and building the sampling targets of a one-note part failed
on an empty neighbour array. These parts are common in real quartets (a cello's one bowed
note after a pizzicato passage, a part that enters on the last beat of an excerpt).
"""

import numpy as np
import pytest


@pytest.fixture(scope="module")
def scale():
    from pipelines.methods.feedback import scale_notes

    return scale_notes(tonic=62, octaves=1, tempo=120.0)


def _render(notes, tiny_db):
    from pipelines.methods.sampling import open_database, render_sampling

    return render_sampling(notes.reset_index(drop=True), db=open_database(tiny_db / "db"),
                           feedback=False, progress=False)


def test_a_part_of_one_bowed_note_is_sampled(tiny_db, scale):
    part = _render(scale.iloc[:1], tiny_db).parts[0]
    assert len(part.targets) == 1
    bowed = part.performance.actions["bow_force"].to_numpy() > 0
    assert bowed.any() and np.abs(part.audio).max() > 0


def test_one_bowed_note_among_plucked_ones_is_sampled(tiny_db, scale):
    notes = scale.iloc[:4].copy()
    notes["technique"] = ["pizz", "pizz", "pizz", None]
    part = _render(notes, tiny_db).parts[0]
    assert len(part.targets) == 1
    assert part.targets["midi_pitch"].tolist() == [int(notes["midi_pitch"].iloc[3])]


def test_a_render_that_fails_on_a_bug_is_reported_not_fatal(scale):
    """One render's bug leaves a one-line error naming it, and the run goes on."""
    from pipelines import Method, register_method
    from pipelines.methods.registry import unregister_method
    from pipelines.reports.compare import run_job

    def broken(notes, parts, *, seed, engine, **settings):
        return np.r_[False] & np.array([])  # the very TypeError of the one-note part

    register_method(Method("broken", "raises a TypeError (a test method)", broken))
    try:
        job = {"excerpt": "scale", "notes": scale, "parts": [0], "method": "broken",
               "seed": 0, "db": None, "models": None, "search_config": None,
               "needs_db": False, "sample_rate": 44100, "media_dir": None}
        done = run_job(job)
    finally:
        unregister_method("broken")
    error = done["figures"]["error"]
    assert error.startswith("internal error (a bug, please report it): TypeError")
    assert "test_sampling_short_parts.py:" in error and "\n" not in error
    assert (done["excerpt"], done["method"], done["seed"]) == ("scale", "broken", 0)
