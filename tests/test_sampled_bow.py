"""Sampled runs planned stroke by stroke (gesture_db.bow_plan, pipelines.methods.sampled_bow)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from data_schemas.bow import BowBudget
from data_schemas.errors import ParameterError
from gesture_db.assemble import assemble_actions
from gesture_db.bow_plan import DEADBAND, plan_run, stroke_index
from gesture_db.search_config import load_search_config
from pipelines.methods.sampled_bow import speed_limiter, stroke_planner
from pipelines.perform.config import load_config

BOW = 0.65


def _strokes_by_hand(v: np.ndarray) -> list[int]:
    """Stroke of each frame, walking the frames one by one."""
    first = next((np.sign(x) for x in v if abs(x) >= DEADBAND), 1.0)
    stroke, current, out = 0, first, []
    for x in v:
        if abs(x) >= DEADBAND and np.sign(x) != current:
            stroke, current = stroke + 1, np.sign(x)
        out.append(stroke)
    return out


@settings(max_examples=60, deadline=None)
@given(st.lists(st.sampled_from([-0.3, -0.01, -5e-4, 0.0, 4e-4, 0.02, 0.5]), min_size=1,
                max_size=40))
def test_strokes_are_the_runs_of_one_sign(values):
    v = np.array(values)
    stroke, direction = stroke_index(v)
    assert stroke.tolist() == _strokes_by_hand(v)
    assert direction.size == stroke[-1] + 1
    for k in range(direction.size):  # each stroke's direction is the sign of its movement
        moving = v[(stroke == k) & (np.abs(v) >= DEADBAND)]
        assert moving.size == 0 or set(np.sign(moving)) == {direction[k]}


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(0.1, 2.0), min_size=1, max_size=6), st.floats(0.05, 0.9))
def test_positions_integrate_the_planned_velocity(scales, start):
    """Positions are the start plus the trapezoid integral of each frame's scaled speed."""
    n = len(scales)
    t = np.linspace(0.0, 0.4 * n, 40 * n + 1)
    v = 0.3 * np.sin(np.pi * t / 0.4)  # one stroke per 0.4 s, alternating
    budget = BowBudget(BOW, 0.03)

    def planner(travel, duration, direction, b, prefer):
        assert travel.size == n and np.allclose(duration, 0.4, atol=0.011)
        return start, np.array(scales)

    pos, scale = plan_run(t, v, budget, planner, prefer=0.5)
    want = [start]
    for i in range(1, t.size):
        want.append(want[-1] + 0.5 * (scale[i] * v[i] + scale[i - 1] * v[i - 1])
                    * (t[i] - t[i - 1]) / BOW)
    np.testing.assert_allclose(pos, np.clip(want, 0.0, 1.0), atol=1e-12)
    assert scale[0] == scales[0] and scale[-1] == scales[-1]


def _drifting_run():
    """Long down-bows answered by short up-bows: 1.0 s down, 0.25 s up, five times."""
    durations = [1.0, 0.25] * 5
    onset = np.r_[0.0, np.cumsum(durations)[:-1]]
    n = len(durations)
    targets = pd.DataFrame({
        "onset": onset, "duration": durations, "string": 2, "finger_ratio": 0.0,
        "bow_direction": ["down", "up"] * 5,
        "run_position": ["init"] + ["mid"] * (n - 2) + ["end"]})
    choices = pd.DataFrame({"sample_group": "g", "note_id": [str(i) for i in range(n)],
                            "mirrored": [False, True] * 5})

    def contours(group, note_id):
        t = np.linspace(0.0, 0.5, 121)
        ramp = np.minimum(1.0, np.minimum(t, 0.5 - t) / 0.03)
        return t, np.c_[0.3 * ramp, np.full(t.size, 0.8), np.full(t.size, 0.1)]

    return targets, choices, contours


def test_a_drifting_run_slows_its_long_strokes_not_the_whole_run():
    """One scale for the run slows every stroke; the planner keeps the bow inside the
    margins, slows the long down-bows less than that and lets the short up-bows recover."""
    targets, choices, contours = _drifting_run()
    planner = stroke_planner(load_config(), {"render": {"plan_strokes": 1}})
    whole = assemble_actions(targets, choices, contours, bow_length=BOW)
    planned = assemble_actions(targets, choices, contours, bow_length=BOW, planner=planner)
    for a in (whole, planned):
        pos = a.loc[a["bow_force"] > 0, "bow_position"].to_numpy()
        assert pos.min() >= 0.03 - 1e-6 and pos.max() <= 0.97 + 1e-6

    def peak(a, sign):
        v = a["bow_velocity"].to_numpy()
        return np.abs(v[np.sign(v) == sign]).max()
    assert peak(whole, 1) == pytest.approx(peak(whole, -1) * 1.0, rel=1e-6)  # one scale
    # one scale: 0.94 of the hair over a drift of 5 x (0.46 - 0.115) -> 0.54 x 0.3 m/s;
    # the up-bows at 1.5x leave the down-bows about 0.7x
    assert peak(whole, 1) < 0.16
    assert peak(planned, 1) > 1.3 * peak(whole, 1)  # the long strokes keep more speed
    assert peak(planned, -1) > peak(planned, 1)  # the short up-bows recover bow
    assert peak(planned, -1) <= 0.3 * load_config()["bow"]["max_speed_scale"] + 1e-9


def test_without_a_planner_the_setting_off_gives_none():
    assert stroke_planner(load_config(), {"render": {"plan_strokes": 0}}) is None


LIMITED = {"render": {"max_acceleration": 5.0, "limit_acceleration": ["violin", "viola"]}}


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-1.0, 1.0), min_size=2, max_size=60), st.floats(0.5, 20.0))
def test_the_speed_limit_never_speeds_up_turns_or_accelerates_too_fast(values, most):
    v = np.array(values)
    t = np.arange(v.size) / 240.0
    limit = speed_limiter({"render": {"max_acceleration": most,
                                      "limit_acceleration": ["viola"]}}, "viola")
    out = limit(t, v)
    assert np.all(np.abs(out) <= np.abs(v) + 1e-12)
    assert np.all((np.sign(out) == np.sign(v)) | (out == 0))
    assert np.all(np.abs(np.diff(np.abs(out))) <= most / 240.0 + 1e-12)


def test_the_speed_limit_is_off_at_zero_and_for_instruments_not_listed():
    assert speed_limiter(LIMITED, "cello") is None
    off = {"render": {"max_acceleration": 0.0, "limit_acceleration": ["violin"]}}
    assert speed_limiter(off, "violin") is None
    assert speed_limiter(LIMITED, "violin") is not None


def test_an_assembled_run_turns_the_bow_within_the_limit():
    """The drifting run's samples turn the bow at 10 m/s^2; limited to 5 before the bow
    is planned, every frame on the string changes speed at most 5 m/s^2 times the
    planner's largest speed-up (1.5), and the planned bow stays on the hair."""
    targets, choices, contours = _drifting_run()
    planner = stroke_planner(load_config(), {"render": {"plan_strokes": 1}})
    free = assemble_actions(targets, choices, contours, bow_length=BOW, planner=planner)
    a = assemble_actions(targets, choices, contours, bow_length=BOW, planner=planner,
                         speed_limit=speed_limiter(LIMITED, "violin"))
    most = 5.0 * load_config()["bow"]["max_speed_scale"] + 1e-6
    for acts, fastest in ((free, most), (a, most)):
        on = acts[acts["bow_force"] > 0]
        rate = np.abs(np.diff(np.abs(on["bow_velocity"].to_numpy()))) / np.diff(
            on["time"].to_numpy())
        assert (rate.max() > fastest) == (acts is free)
    pos = a.loc[a["bow_force"] > 0, "bow_position"].to_numpy()
    assert pos.min() >= 0.03 - 1e-6 and pos.max() <= 0.97 + 1e-6


def test_a_bad_speed_limit_setting_is_a_clear_error():
    with pytest.raises(ParameterError, match="render.limit_acceleration"):
        load_search_config(overrides={"render": {"limit_acceleration": ["banjo"]}})
    with pytest.raises(ParameterError, match="render.max_acceleration"):
        load_search_config(overrides={"render": {"max_acceleration": -1.0}})
