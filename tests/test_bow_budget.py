"""The bow-travel budget shared by the rules, the simulated performer and gesture sampling."""

from __future__ import annotations

import numpy as np
import pytest

from data_schemas.bow import BowBudget
from data_schemas.errors import ParameterError


def test_travel_is_distance_over_bow_length():
    budget = BowBudget(bow_length=0.65, margin=0.04)
    assert budget.travel(np.array([0.0, 0.325, -0.65])).tolist() == [0.0, 0.5, -1.0]
    assert budget.room == pytest.approx(0.92)


@pytest.mark.parametrize("seed", range(5))
def test_fit_keeps_a_run_inside_the_margins(seed):
    rng = np.random.default_rng(seed)
    budget = BowBudget(bow_length=0.65, margin=0.05)
    travel = np.cumsum(rng.normal(0, 0.2, 50))  # wanders far beyond the hair
    fit = budget.fit(travel)
    span = travel.max() - travel.min()
    assert fit.scale == pytest.approx(min(1.0, 0.9 / span))
    np.testing.assert_allclose(fit.travel, travel * fit.scale)
    lo, hi = fit.start_window
    for start in np.linspace(lo, max(lo, hi), 5):
        pos = start + fit.travel
        assert pos.min() >= 0.05 - 1e-12 and pos.max() <= 0.95 + 1e-12


def test_short_run_is_not_scaled():
    budget = BowBudget(bow_length=0.65, margin=0.04)
    fit = budget.fit(np.array([0.0, 0.3, 0.1]))
    assert fit.scale == 1.0
    assert fit.start_window == pytest.approx((0.04, 0.66))


def test_home_ahead_and_bad_parameters():
    budget = BowBudget(bow_length=0.62, margin=0.1)
    assert (budget.home(1), budget.home(-1)) == (0.1, 0.9)
    assert budget.ahead(0.3, 1) == pytest.approx(0.6)
    assert budget.ahead(0.3, -1) == pytest.approx(0.2)
    assert BowBudget(0.65).margin == 0.04  # the facts' bow_margin
    with pytest.raises(ParameterError):
        BowBudget(0.65, margin=0.5)
    with pytest.raises(ParameterError):
        BowBudget(0.0)
