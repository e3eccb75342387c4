"""The search's dynamic cost: uncapped, so a soft note is not sampled from a loud stroke."""

from types import SimpleNamespace

import numpy as np
import pandas as pd
from hypothesis import given
from hypothesis import strategies as st

from gesture_db.search import _target_costs, dynamic_costs
from gesture_db.search_config import load_search_config

levels = st.floats(0.0, 9.0)


@given(levels, levels, levels, st.floats(0.5, 5.0))
def test_dynamic_cost_is_a_distance_in_levels(a, b, c, span):
    ab, ba = dynamic_costs(a, b, span), dynamic_costs(b, a, span)
    assert ab == ba >= 0.0
    assert (ab == 0.0) == (a == b)
    assert ab <= dynamic_costs(a, c, span) + dynamic_costs(c, b, span) + 1e-12
    np.testing.assert_allclose(ab * span, abs(a - b), rtol=1e-12, atol=1e-12)


def test_a_pianissimo_note_prefers_a_soft_sample_to_a_longer_loud_one():
    # A 2.6 s pppp note; the database holds a 0.3 s pp sample and a 0.6 s ff sample, alike
    # otherwise. The ff sample is closer in duration by a factor of two (a cost of 1), and
    # seven levels away from the note instead of two.
    config = load_search_config()
    targets = pd.DataFrame({"duration": [2.6], "effective_string_length": [0.5],
                            "dynamic": [0.0], "string": [1.0]})
    group = SimpleNamespace(duration=np.array([0.3, 0.6]), string_length=np.array([0.5, 0.5]),
                            dynamic=np.array([2.0, 7.0]), string=np.array([1.0, 1.0]),
                            whiten=np.eye(2), whitened=np.zeros((2, 2)), quality=None)
    cost, _ = _target_costs(targets, np.zeros((1, 2)), group, config)
    w = config["weights"]
    span = config["costs"]["dynamic_span"]
    expected = w["basic"] * (w["duration"] * np.abs(np.log2(2.6 / np.array([0.3, 0.6])))
                             + w["dynamic"] * np.array([2.0, 7.0]) / span)
    np.testing.assert_allclose(cost[0], expected, rtol=1e-12)
    assert cost[0, 0] < cost[0, 1]
