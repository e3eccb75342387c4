"""Strokes slowed to fit the bow play nearer the bridge, but not past ``slowed_min_beta``."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from data_schemas.errors import ParameterError
from pipelines.methods.playable import window_middle
from pipelines.perform.config import dynamic_table, load_config, validate_config
from pipelines.perform.events import Event
from pipelines.perform.note_shape import note_beta, slowing_floor
from pipelines.perform.rules import perform_part
from synth.playability import steady_stroke
from synth.strings import reference_forces

CFG = load_config()
SCORE = Path(__file__).resolve().parents[1] / "pipelines" / "data" / "mozart-k421.mxl"


def _event(level: float) -> Event:
    return Event(t0=0.0, end=1.0, strings=[1], semitones=[0.0], rows=[0], label="G2",
                 dynamic=level)


@settings(max_examples=80, deadline=None)
@given(st.floats(0.0, 9.0), st.floats(0.1, 1.5), st.floats(0.03, 0.2))
def test_the_floor_keeps_slowed_strokes_off_the_bridge(level, scale, floor):
    config = copy.deepcopy(CFG)
    config["bow"]["slowed_min_beta"] = floor
    config["bow"]["node_guard"] = []  # the floor alone (the nodes: test_node_guard.py)
    t = np.array([0.5])
    lane = float(dynamic_table(config, "beta", np.array([level]))[0])
    beta = float(note_beta(_event(level), t, config, scale)[0])
    if scale >= 1.0:
        assert beta == pytest.approx(lane * scale, rel=1e-12)
    else:
        assert beta == pytest.approx(max(lane * scale, min(lane, floor)), rel=1e-12)
        assert beta <= lane + 1e-12
    assert float(slowing_floor(_event(level), t, config, scale)[0]) >= 1.0


def test_no_stroke_of_a_quartet_is_bowed_nearer_than_the_floor():
    """K. 421, m. 1-8: the first violin slows long notes under slurs (a fifth of its moving
    rows went below beta 0.08 without the floor); the lanes themselves never do. Each row
    keeps its force's place in the window (its ratio to the window's middle)."""
    from pipelines.score.dispatch import read_score
    from pipelines.score.select import select_measures

    notes = select_measures(read_score(str(SCORE)), 1, 8)
    free = copy.deepcopy(CFG)
    free["bow"]["slowed_min_beta"] = 0.02
    ratios = []
    for config, nearer in ((free, True), (CFG, False)):
        a = perform_part(notes[notes["part_index"] == 0], config,
                         rng=np.random.default_rng(0)).actions
        moving = a[(a["bow_force"] > 0) & (a["bow_velocity"].abs() > 0.01)]
        assert (moving["beta"].min() < 0.079) == nearer
        ratios.append(a["bow_force"] / window_middle(
            reference_forces("violin")[a["string"].to_numpy()], a["bow_velocity"], a["beta"]))
    # kept off the bridge, the force stays where it was in the string's window
    np.testing.assert_allclose(ratios[1], ratios[0], rtol=1e-9)


def test_a_slowed_cello_stroke_sounds_at_the_floor():
    """Physical truth: the rules' mezzo-forte slowed to 0.12 m/s on the cello's C and G
    strings at the window's middle. At beta 0.05 (the lane's 0.1 x sqrt(speed scale)) the
    C string is not in Helmholtz motion and the G string sounds flat; at the floor both are
    in Helmholtz motion and in tune."""
    v = 0.12
    for string, flat_by in ((0, None), (1, 7.0)):
        ref = reference_forces("cello")[string]
        near, floored = (steady_stroke("cello", string, bow_velocity=v, beta=b,
                                       bow_force=float(window_middle(ref, v, b)),
                                       duration=1.2, analysed=0.4)
                         for b in (0.05, CFG["bow"]["slowed_min_beta"]))
        assert floored.is_helmholtz and abs(floored.pitch_error_cents) <= 5.0
        if flat_by is None:
            assert not near.is_helmholtz
        else:
            assert near.pitch_error_cents < floored.pitch_error_cents - flat_by


def test_the_setting_is_checked():
    bad = copy.deepcopy(CFG)
    bad["bow"]["slowed_min_beta"] = 0.0
    with pytest.raises(ParameterError, match="bow.slowed_min_beta"):
        validate_config(bad, "my.toml")


def test_harmonics_keep_their_own_placement():
    harmonic = Event(t0=0.0, end=1.0, strings=[1], semitones=[12.0], rows=[0], label="G3",
                     dynamic=5.0, touch=True, node=2)
    assert float(slowing_floor(harmonic, np.array([0.5]), CFG, 0.25)[0]) == 1.0
    plain = float(slowing_floor(_event(5.0), np.array([0.5]), CFG, 0.25)[0])
    assert plain == pytest.approx(0.08 / (0.1 * 0.25))  # the mf lane: beta 0.1
