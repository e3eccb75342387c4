"""The probability-weighted control law against a synthetic plant with a known optimal force.

The plant (independent of the controller): a force ``F`` sounds as the class
``mu = 3 + log2(F / F_opt)`` (clipped to 1..5), heard with a delay of ``LAG`` hops (the
analysis window), and the classifier's probabilities are a Gaussian around ``mu``.
"""

from collections import deque

import numpy as np
import pytest

from synth.listening.controller import ControllerSettings, ForceController, correction
from synth.listening.probabilities import vote_probabilities

F_OPT = 0.8  # N
LAG = 3  # hops between playing a force and hearing it


class PlantPredictor:
    """Probabilities of classes 1..5 from the 'feature' (the force that was heard)."""

    def probabilities(self, features):
        mu = float(np.clip(3.0 + np.log2(features[0] / F_OPT), 1.0, 5.0))
        p = np.exp(-0.5 * ((np.arange(1, 6) - mu) / 0.5) ** 2)
        p /= p.sum()
        return p, int(np.argmax(p)) + 1


class PlantModel:
    dynamic = "mf"
    metadata: dict = {}
    K = 1.05

    def fast(self):
        return PlantPredictor()


def play(start, settings, hops, K=None, predictor=None):
    """The controller's force, hop by hop, on the plant (or ``predictor``)."""
    ctl = ForceController(PlantModel(), np.random.default_rng(0), settings, K=K)
    if predictor is not None:
        ctl.predict = predictor
    ctl.start_note(0.0, start)
    heard = deque([start] * LAG, maxlen=LAG)
    forces = []
    for _ in range(hops):
        ctl.step(np.array([heard[0]]), 0.3, 0.3)
        heard.append(ctl.force)
        forces.append(ctl.force)
    return np.array(forces)


def run(start, settings, hops=60, K=None):
    return np.abs(np.log2(play(start, settings, hops, K) / F_OPT))


SETTINGS = ControllerSettings(jitter=0.0, grace_hops=0, range_margin=0.0)


@pytest.mark.parametrize("start", [2.0 * F_OPT, 0.5 * F_OPT, 3.0 * F_OPT, F_OPT / 3.0])
def test_law_corrects_a_2x_error_within_10_hops_and_stays(start):
    error = run(start, SETTINGS)
    # within a quarter of an octave of the optimum by hop 10, and no overshoot after
    assert error[9] < 0.25 if abs(np.log2(start / F_OPT)) <= 1.0 else error[14] < 0.25
    assert error[15:].max() < 0.3


def test_law_leaves_a_good_force_alone():
    error = run(F_OPT * 1.05, SETTINGS)
    np.testing.assert_allclose(error, np.log2(1.05))


def test_trained_k_alone_is_too_slow():
    # The trained factors (1.005-1.05) leave a 2x error mostly uncorrected after 10 hops.
    slow = run(2.0 * F_OPT, ControllerSettings(jitter=0.0, grace_hops=0, range_margin=0.0,
                                               average=8), K=1.02)
    assert slow[9] > 0.6


def test_correction_follows_the_expected_class():
    too_little = np.array([0.1, 0.7, 0.2, 0.0, 0.0])
    too_much = too_little[::-1].copy()
    assert correction(too_little, 1.2, 0.5) > 1.0 > correction(too_much, 1.2, 0.5)
    assert np.isclose(correction(too_little, 1.2, 0.5) * correction(too_much, 1.2, 0.5), 1.0)


@pytest.mark.parametrize("n_class", [2, 3, 5])
def test_probabilities_sum_to_one_and_order_like_the_decisions(n_class):
    rng = np.random.default_rng(n_class)
    n_pairs = n_class * (n_class - 1) // 2
    pairs = [(i, j) for i in range(n_class) for j in range(i + 1, n_class)]
    for _ in range(50):
        d = rng.normal(scale=2.0, size=n_pairs)
        p = vote_probabilities(d, n_class)
        assert np.isclose(p.sum(), 1.0) and (p > 0).all()
        # a decision moved in favour of its pair's first class raises that class's share
        k = int(rng.integers(n_pairs))
        moved = d.copy()
        moved[k] += 1.0
        i, j = pairs[k]
        q = vote_probabilities(moved, n_class)
        assert q[i] > p[i] and q[j] < p[j]
    # two classes: the probability of the first rises with the decision value
    values = np.linspace(-3, 3, 13)
    assert np.all(np.diff([vote_probabilities(np.array([v]), 2)[0] for v in values]) > 0)


class OptimumPredictor(PlantPredictor):
    """The plant of the module doc around another optimum (a factor on a planned force)."""

    def __init__(self, optimum):
        self.optimum = optimum

    def probabilities(self, features):
        return super().probabilities(np.array([features[0] * F_OPT / self.optimum]))


def run_factor(optimum, settings, hops=80):
    """The correcting factor, hop by hop, on a plant whose best factor is ``optimum``."""
    return play(1.0, settings, hops, predictor=OptimumPredictor(optimum))


@pytest.mark.parametrize("optimum", [2.0, 3.0, 0.5, 0.3])
def test_trim_up_bounds_only_the_raise(optimum):
    both = ControllerSettings(jitter=0.0, grace_hops=0, range_margin=0.0, trim=1.5)
    lighten = ControllerSettings(jitter=0.0, grace_hops=0, range_margin=0.0, trim=1.5,
                                 trim_up=1.0)
    free, down = run_factor(optimum, both), run_factor(optimum, lighten)
    # the symmetric trim reaches the optimum's side (class 3 holds half the probability
    # within about half an octave of it) or the trim's bound
    reachable = min(max(optimum, 1 / 1.5), 1.5)
    assert abs(np.log2(free[-1] / reachable)) < 0.5
    if optimum > 1.0:  # more force wanted: never above the plan with trim_up = 1
        assert down.max() == 1.0 and free[-1] > 1.2
    else:  # less force wanted: the same correction as the symmetric trim
        np.testing.assert_array_equal(down, free)
        assert down.min() >= 1 / 1.5 - 1e-12


def test_trim_up_below_the_plan_is_refused():
    from data_schemas.errors import ParameterError

    with pytest.raises(ParameterError, match="trim_up=0.5 must be 0"):
        ControllerSettings(trim=1.5, trim_up=0.5)


def test_initial_forces_monotone_in_dynamic():
    from synth.listening.initial_forces import monotone_in_dynamic

    # the cello C string as trained: p 5.1-7.0 N, f 1.4-1.8 N
    trained = {"p": [5.1, 6.0, 7.0], "mp": [3.0, 3.2, 3.5], "mf": [2.0, 2.5, 2.6],
               "f": [1.4, 1.6, 1.8]}
    fixed = monotone_in_dynamic(trained, ("p", "mp", "mf", "f"))
    table = np.array([fixed[d] for d in ("p", "mp", "mf", "f")])
    assert (np.diff(table, axis=0) >= -1e-12).all()
    # the fit keeps each finger's mean force (least squares with equal weights)
    np.testing.assert_allclose(table.mean(axis=0),
                               np.array(list(trained.values())).mean(axis=0))
    ordered = {"p": [0.5, 0.6, 0.7], "f": [1.0, 1.1, 1.2]}
    assert monotone_in_dynamic(ordered, ("p", "mp", "mf", "f")) == ordered


def test_unsure_probabilities_leave_the_force_alone():
    # classes 2 and 5 heard at once: neither side holds 85 %
    mixed = np.array([0.0, 0.45, 0.1, 0.0, 0.45])
    assert correction(mixed, 1.2, 0.5, sure=0.85) == 1.0
    assert correction(mixed, 1.2, 0.5) != 1.0
    assert correction(np.array([0.0, 0.9, 0.1, 0.0, 0.0]), 1.2, 0.5, sure=0.85) > 1.0


def test_trim_bounds_the_correction_factor():
    # the plant says "too much" for ever (optimum far below): the factor stops at 1 / trim
    settings = ControllerSettings(jitter=0.0, grace_hops=0, range_margin=0.0, trim=1.5)
    ctl = ForceController(PlantModel(), np.random.default_rng(0), settings)
    ctl.start_note(0.0, 1.0)
    for _ in range(100):
        ctl.step(np.array([100.0 * F_OPT]), 0.3, 0.3)
    assert np.isclose(ctl.force, 1.0 / 1.5)


def test_no_law_right_after_a_finger_change():
    settings = ControllerSettings(jitter=0.0, grace_hops=0, range_margin=0.0, change_hops=8)
    ctl = ForceController(PlantModel(), np.random.default_rng(0), settings)
    ctl.start_note(0.0, 2.0 * F_OPT)
    ctl.finger_changed()
    forces = []
    for _ in range(12):
        ctl.step(np.array([2.0 * F_OPT]), 0.3, 0.3)
        forces.append(ctl.force)
    assert forces[:8] == [2.0 * F_OPT] * 8 and forces[8] < 2.0 * F_OPT


class TooLittlePredictor:
    """Always surely 'too little' (class 2), whatever it hears."""

    def probabilities(self, features):
        return np.array([0.0, 1.0, 0.0, 0.0, 0.0]), 2


class TooLittleModel(PlantModel):
    def fast(self):
        return TooLittlePredictor()


def _gated_forces(aperiodicity: float, gate: float, hops: int = 20) -> np.ndarray:
    from synth.listening.feature_spec import COL_APERIODICITY, FEATURE_NAMES

    settings = ControllerSettings(jitter=0.0, grace_hops=0, range_margin=0.0,
                                  periodic_gate=gate)
    ctl = ForceController(TooLittleModel(), np.random.default_rng(0), settings)
    ctl.start_note(0.0, 1.0)
    window = np.zeros(len(FEATURE_NAMES))
    window[COL_APERIODICITY] = aperiodicity
    forces = []
    for _ in range(hops):
        ctl.step(window, 0.3, 0.3)
        forces.append(ctl.force)
    return np.array(forces)


@pytest.mark.parametrize("aperiodicity", [0.0, 0.01, 0.099])
def test_periodic_gate_leaves_a_periodic_sound_alone(aperiodicity):
    # the classifier insists on "too little", but the window is periodic: force held at 1 N
    np.testing.assert_array_equal(_gated_forces(aperiodicity, 0.1), np.ones(20))


@pytest.mark.parametrize("aperiodicity", [0.1, 0.3, 0.9])
def test_periodic_gate_lets_the_law_act_on_an_aperiodic_sound(aperiodicity):
    step = ControllerSettings().step
    # from the first hop on, every hop raises the force by the law's full step
    np.testing.assert_allclose(_gated_forces(aperiodicity, 0.1),
                               step ** np.arange(1, 21), rtol=1e-12)


def test_periodic_gate_off_by_default():
    np.testing.assert_allclose(_gated_forces(0.0, 0.0)[-1], ControllerSettings().step ** 20)


class ContentPredictor:
    """A classifier that hears every window as good (class 3, full confidence)."""

    def probabilities(self, features):
        return np.array([0.0, 0.0, 1.0, 0.0, 0.0]), 3


def played_forces(settings, hops, start=1.0):
    """The controller's own force and the force it plays, hop by hop, while content."""
    ctl = ForceController(PlantModel(), np.random.default_rng(7), settings)
    ctl.predict = ContentPredictor()
    ctl.start_note(0.0, start)
    own, played = [], []
    for _ in range(hops):
        ctl.step(np.array([start]), 0.3, 0.3)
        own.append(ctl.force)
        played.append(ctl.played)
    return np.array(own), np.array(played)


def test_jitter_wobbles_the_played_force_without_drifting_it():
    # 2,000 hops (11.6 s) of a content controller with 1 % jitter: the played force stays
    # a 1 % wobble around the controller's own, which stays where it started. Carried
    # from hop to hop, the jitter would be a random walk: sigma 0.01 * sqrt(2000) = 45 %.
    settings = ControllerSettings(jitter=0.01, grace_hops=0, range_margin=0.0)
    own, played = played_forces(settings, 2000)
    np.testing.assert_array_equal(own, 1.0)
    wobble = np.log(played)
    assert 0.008 < wobble.std() < 0.012
    assert np.abs(wobble).max() < 0.05
    assert abs(np.corrcoef(wobble[:-1], wobble[1:])[0, 1]) < 0.1  # independent hops
    # the second half wanders no further than the first
    assert abs(wobble[1000:].mean() - wobble[:1000].mean()) < 0.002


def test_held_factor_plays_the_plan_exactly():
    # A trim of 1 (practice's open loop) holds the played factor at 1: no force jitter.
    settings = ControllerSettings(jitter=0.01, grace_hops=0, range_margin=0.0, trim=1.0)
    own, played = played_forces(settings, 200)
    np.testing.assert_array_equal(played, 1.0)
