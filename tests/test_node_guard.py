"""The rules keep the bow off the strings' low nodes (``[bow] node_guard``, ``node_width``).

Truths: a brute-force search for the nearest contact point outside every zone; the rules'
own lanes interpolated between ppp and pp (which pass through beta = 1/6); the force's
place in the string's Helmholtz window, which the move must keep.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from data_schemas.errors import ParameterError
from pipelines.methods.feedback import scale_notes
from pipelines.methods.playable import window_middle
from pipelines.perform.config import load_config, validate_config
from pipelines.perform.note_shape import off_nodes
from pipelines.perform.rules import perform_part
from synth.strings import reference_forces

CFG = load_config()


def _brute_force(beta: float, nodes: list[int], width: float) -> float:
    """The contact point nearest ``beta`` in mode numbers (1 / beta) outside every zone."""
    grid = np.linspace(1.0 / beta - 1.0, 1.0 / beta + 1.0, 200001)
    outside = np.ones(grid.size, bool)
    for n in nodes:
        outside &= np.abs(grid - n) >= width
    return 1.0 / grid[outside][np.argmin(np.abs(grid[outside] - 1.0 / beta))]


@settings(max_examples=200, deadline=None)
@given(st.floats(0.03, 0.4), st.lists(st.integers(2, 20), max_size=4, unique=True),
       st.floats(0.0, 0.45))
def test_off_nodes_is_the_nearest_contact_point_outside_the_zones(beta, nodes, width):
    got = float(off_nodes(np.array([beta]), nodes, width)[0])
    nearest = _brute_force(beta, nodes, width)  # (at a node itself either edge is nearest)
    assert abs(1.0 / got - 1.0 / beta) == pytest.approx(abs(1.0 / nearest - 1.0 / beta),
                                                        abs=2e-5)
    assert all(abs(1.0 / got - n) >= width - 1e-9 for n in nodes)
    if all(abs(1.0 / beta - n) >= width for n in nodes):
        assert got == beta  # outside every zone: bit for bit


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(0.03, 0.4), min_size=2, max_size=20))
def test_off_nodes_keeps_the_order_of_contact_points(betas):
    """A contact point nearer the bridge stays nearer (no crossing in a hairpin)."""
    b = np.sort(np.array(betas))
    assert np.all(np.diff(off_nodes(b, [5, 6, 7], 0.25)) >= 0.0)


def _played(config: dict) -> tuple[np.ndarray, np.ndarray]:
    """Beta and the force's ratio to its window's middle of a violin's moving rows.

    A one-octave scale on the G string whose notes step from pppp to p (levels 0.25 apart):
    the lanes between ppp (beta 0.18) and pp (0.155) pass through 1/6.
    """
    notes = scale_notes(dynamic="pp", octaves=1, tempo=90.0)
    notes["dynamic"] = np.linspace(0.5, 2.5, len(notes))
    a = perform_part(notes, config, rng=np.random.default_rng(0)).actions
    moving = a[(a["bow_force"] > 0) & (a["bow_velocity"].abs() > 0.02)]
    middle = window_middle(reference_forces("violin")[moving["string"].to_numpy()],
                           moving["bow_velocity"].to_numpy(), moving["beta"].to_numpy())
    return moving["beta"].to_numpy(), moving["bow_force"].to_numpy() / middle


def _near_a_node(beta: np.ndarray) -> np.ndarray:
    return np.any([np.abs(1.0 / beta - n) < 0.25 - 1e-9 for n in (5, 6, 7)], axis=0)


def test_the_rules_bow_no_row_at_a_low_node_and_keep_the_force_in_its_window():
    free = copy.deepcopy(CFG)
    free["bow"]["node_guard"] = []
    beta_free, ratio_free = _played(free)
    beta, ratio = _played(CFG)
    assert _near_a_node(beta_free).any()  # without the guard the hairpin crosses 1/6 ...
    assert not _near_a_node(beta).any()   # ... with it, no row is bowed near a node
    moved = beta != beta_free
    assert moved.any() and np.all(np.abs(beta[moved] / beta_free[moved] - 1.0) < 0.05)
    # the force follows the window's middle (F ~ beta^-1.5): same place in the window
    np.testing.assert_allclose(ratio, ratio_free, rtol=1e-9)


@pytest.mark.parametrize(("key", "value", "message"), [
    ("node_guard", [6, 1], r"bow.node_guard=\[6, 1\] must be a list of whole mode numbers"),
    ("node_guard", 6, r"bow.node_guard=6 must be a list"),
    ("node_guard", [6.0], r"bow.node_guard=\[6.0\] must be a list"),
    ("node_width", 0.5, r"bow.node_width=0.5 must be in \[0, 0.5\)"),
    ("node_width", -0.1, r"bow.node_width=-0.1 must be in"),
])
def test_bad_node_settings_are_refused_with_their_key(key, value, message):
    bad = copy.deepcopy(CFG)
    bad["bow"][key] = value
    with pytest.raises(ParameterError, match=message):
        validate_config(bad, "mine.toml")
