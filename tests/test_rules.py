"""One assertion (or a few) per performance rule, on a music21-written notation score."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from _notation_score import write_score

from data_schemas.actions import validate_actions
from data_schemas.instruments import finger_ratio, instrument_facts
from pipelines.perform.config import dynamic_table, load_config
from pipelines.perform.rules import perform_part
from pipelines.score import read_score

CFG = load_config()
# The notation rules are tested exact: no intonation, no vibrato (tests/test_expression.py).
CFG["vibrato"]["enabled"] = False
CFG["intonation"].update(sigma=0.0, semitone_step=0.0, by_ear=False)
# ... and the lanes as written (the loudness evening-out moves them: tests/test_loudness.py).
CFG["loudness"]["enabled"] = False
# ... and without the bite at each stroke's start (tests/test_bite.py).
CFG["articulations"]["bite_force"] = 1.0
L = CFG["instruments"]["violin"]["bow_length"]
FERMATA_SHIFT = 2.0 * (CFG["articulations"]["fermata_stretch"] - 1.0)


@pytest.fixture(scope="module")
def notes(tmp_path_factory):
    return read_score(write_score(tmp_path_factory.mktemp("score")))


@pytest.fixture(scope="module")
def perf(notes):
    return perform_part(notes, CFG, skill=3)


def at(beat: float) -> float:
    """Performance time of a score beat (60 qpm; the fermata at beat 32 adds time)."""
    return beat + (FERMATA_SHIFT if beat >= 34 else 0.0)


def event(perf, beat: float) -> pd.Series:
    ev = perf.events
    k = int(np.argmin(np.abs(ev["t0"] - at(beat))))
    assert abs(ev["t0"].iloc[k] - at(beat)) < 0.08
    return ev.iloc[k]


def window(perf, a: float, b: float, string: int | None = None) -> pd.DataFrame:
    a_ = perf.actions
    m = (a_["time"] >= a) & (a_["time"] <= b)
    if string is not None:
        m &= a_["string"] == string
    return a_[m]


def force_at(perf, t: float) -> float:
    """Bow force of the first bowed row at or after time ``t`` (a note's own attack)."""
    w = bowed(perf, t + 1e-4, t + 0.006)
    return float(w["bow_force"].iloc[0])


def attack_force(perf, t: float) -> float:
    """Largest bow force at exactly time ``t`` (a note's first frame)."""
    return float(bowed(perf, t - 1e-6, t + 1e-6)["bow_force"].max())


def bowed(perf, a: float, b: float) -> pd.DataFrame:
    w = window(perf, a, b)
    return w[(w["bow_force"] > 0) & ~w["pluck"]]


def plays(perf, pitch: int, a: float, b: float) -> bool:
    """Whether some string is bowed or plucked at MIDI ``pitch`` by a frame in [a, b] s."""
    w = window(perf, a, b)
    w = w[(w["bow_force"] > 0) | w["pluck"]]
    opens = np.asarray(instrument_facts("violin").open_strings)[w["string"].to_numpy(int)]
    return bool(np.any((pitch >= opens) & np.isclose(
        w["finger_ratio"].to_numpy(), [finger_ratio(k) for k in np.maximum(pitch - opens, 0)],
        atol=1e-5)))


def test_every_note_starts_at_its_score_onset(notes, perf):
    """Each note (tie continuations aside) sounds from its score onset: at once, after the
    appoggiaturas before it (acciaccaturas start a grace_duration each before it), or after
    the lower notes of a rolled chord (the notes table says which; the performance's own
    event times are not used)."""
    validate_actions(perf.actions)
    art = CFG["articulations"]
    late = []
    for _, n in notes[~notes["tie_stop"]].iterrows():
        t = at(n["onset"])
        graces = notes["grace"] & (notes["onset"] == n["onset"])
        # appoggiaturas are played on the beat, acciaccaturas (slashed) just before it
        on_beat = graces & (notes["grace_type"] == "appoggiatura")
        delay = art["grace_duration"] * int(on_beat.sum()) if not n["grace"] else 0.0
        if n["grace"] and n["grace_type"] == "acciaccatura":
            t -= art["grace_duration"] * int(graces.sum())
        if n["chord_size"] > 2:  # rolled: two strings at once, then one more per roll_time
            delay += art["roll_time"] * max(0, n["chord_index"] - 1)
        starts = plays(perf, n["midi_pitch"], t - 1e-6, t + delay + 1e-3)
        holds = n["technique"] == "pizz" or plays(perf, n["midi_pitch"], t + delay,
                                                   t + delay + 0.01)
        if not (starts and holds):
            late.append((n["measure"], n["onset"], n["midi_pitch"]))
    assert late == []


def test_dynamics_set_beta_and_velocity(perf):
    mf = bowed(perf, 0.1, 0.9)
    f = bowed(perf, 23.1, 23.9)
    def table(key, level):
        return float(dynamic_table(CFG, key, [level])[0])

    assert mf["beta"].to_numpy() == pytest.approx(table("beta", 5.0))
    assert f["beta"].to_numpy() == pytest.approx(table("beta", 6.0))
    assert table("beta", 6.0) < table("beta", 5.0)
    assert mf["bow_velocity"].abs().max() == pytest.approx(table("velocity", 5.0), abs=1e-6)
    assert f["bow_velocity"].abs().max() == pytest.approx(table("velocity", 6.0), abs=1e-6)


def _table_newtons(instrument: str, string: int, level: int) -> float:
    """The rules' newton table read straight from the configuration."""
    name = instrument_facts(instrument).string_names[string]
    return CFG["bow_force"][instrument][name][level]


def test_force_comes_from_the_newton_table(perf):
    mid = bowed(perf, 0.45, 0.55)
    strings = mid["string"].to_numpy(int)
    assert mid["bow_force"].to_numpy() == pytest.approx(
        [_table_newtons("violin", s, 5) for s in strings])


def test_detached_notes_stop_and_reverse(perf):
    assert event(perf, 0)["direction"] == 1
    assert event(perf, 1)["direction"] == -1
    a4 = window(perf, 0.0, 1.0, string=2)
    assert a4["bow_velocity"].iloc[-1] == pytest.approx(0.0, abs=1e-9)


def test_staccato_shortens_to_70_percent(perf):
    ev = event(perf, 1)
    assert ev["played_end"] - ev["t0"] == pytest.approx(0.7)
    after = window(perf, 1.71, 1.99)
    assert np.all(after["bow_velocity"] == 0)
    assert bowed(perf, 1.5, 1.6)["bow_velocity"].abs().min() > 0.1


def test_portato_shortens_to_90_percent(perf):
    ev = event(perf, 2)
    assert ev["played_end"] - ev["t0"] == pytest.approx(0.9)


def test_accent_multiplies_force(perf):
    assert attack_force(perf, 3.0) / force_at(perf, 3.5) == pytest.approx(2.5)


def test_slur_keeps_bow_direction(perf):
    w = bowed(perf, 4.05, 7.9)
    signs = np.sign(w["bow_velocity"].to_numpy())
    assert np.all(signs == signs[0])
    for boundary in (5.0, 6.0, 7.0):
        near = bowed(perf, boundary - 0.01, boundary + 0.01)
        assert near["bow_velocity"].abs().min() > 0.1


def test_tie_keeps_finger_force_and_velocity(perf):
    assert not np.any(np.abs(perf.events["t0"] - 12.0) < 1e-6)
    w = bowed(perf, 10.2, 13.8)
    assert w["string"].nunique() == 1 and w["finger_ratio"].nunique() == 1
    assert np.all(np.sign(w["bow_velocity"]) == np.sign(w["bow_velocity"].iloc[0]))
    assert w["bow_velocity"].abs().min() > 0


def test_breath_mark_shortens_and_lightens(perf):
    ev = event(perf, 14)
    assert ev["played_end"] - ev["t0"] == pytest.approx(0.6)
    w = bowed(perf, 14.0, 14.6)
    assert w["bow_force"].iloc[-1] == pytest.approx(0.3 * force_at(perf, 14.3), rel=0.02)


def test_last_note_on_a_string_is_lightened(perf):
    ev = event(perf, 48)
    w = bowed(perf, ev["t0"], ev["played_end"])
    mid = w[np.isclose(w["time"], ev["t0"] + 2.0)]["bow_force"].iloc[0]
    assert w["bow_force"].iloc[-1] == pytest.approx(0.5 * mid, rel=0.02)


def test_crescendo_interpolates_dynamics(notes, perf):
    dyn = notes.loc[notes["measure"] == 5, "dynamic"].to_numpy()
    assert np.all(np.diff(dyn) > 0) and dyn[0] == 3.0
    betas = [bowed(perf, b + 0.01, b + 0.02)["beta"].iloc[0] for b in (16, 17, 18, 19)]
    assert np.all(np.diff(betas) < 0)


def test_pizz_plucks_and_arco_bows_again(perf):
    plucks = window(perf, 19.99, 21.5)
    plucks = plucks[plucks["pluck"]]
    assert plucks["time"].round(3).tolist() == [20.0, 21.0]
    assert set(plucks["string"]) == {1}
    assert (plucks["bow_force"] > 0).all()  # the pluck's strength (1 N at mf)
    assert bowed(perf, 20.001, 21.99).empty
    assert not bowed(perf, 22.0, 22.9).empty


def test_up_and_down_bow_marks_set_direction(perf):
    assert event(perf, 22)["direction"] == -1
    assert event(perf, 23)["direction"] == 1
    assert bowed(perf, 22.2, 22.8)["bow_velocity"].max() < 0


def test_bow_region_words_place_the_bow(perf):
    tip = bowed(perf, 24.05, 25.95)["bow_position"]
    frog = bowed(perf, 26.05, 27.95)["bow_position"]
    assert tip.median() > 0.75 and frog.median() < 0.3


def test_tremolo_changes_bow_fast(perf):
    v = bowed(perf, 28.0, 32.0)["bow_velocity"].to_numpy()
    changes = np.count_nonzero(np.diff(np.sign(v[v != 0])) != 0)
    assert changes >= 40


def test_fermata_lengthens_and_everything_after_waits(perf):
    ev = event(perf, 32)
    assert ev["end"] - ev["t0"] == pytest.approx(2.0 * CFG["articulations"]["fermata_stretch"])
    assert event(perf, 36)["t0"] == pytest.approx(36.0 + FERMATA_SHIFT)


def test_double_stop_bows_two_adjacent_strings(perf):
    w = bowed(perf, at(36.5), at(36.5) + 0.01)
    assert sorted(w["string"].unique()) == [1, 2]


def test_impossible_chord_is_rolled_with_a_warning(perf):
    t0 = at(38)
    low = bowed(perf, t0, t0 + 1.9)
    g = low[low["string"] == 0]
    assert g["time"].max() < t0 + 0.1
    top = low[low["string"].isin([1, 2]) & (low["time"] > t0 + 0.001)]
    assert top["time"].min() >= t0 + 0.05
    assert any("rolled" in w for w in perf.warnings)


def test_string_indication_forces_the_string(perf):
    w = bowed(perf, at(40) + 0.1, at(40) + 0.5)
    assert set(w["string"]) == {0}
    assert w["finger_ratio"].to_numpy() == pytest.approx(1 - 2 ** (-14 / 12), abs=1e-6)
    assert set(bowed(perf, at(41) + 0.1, at(41) + 0.3)["string"]) == {2}


def test_staccatissimo_tenuto_strong_accent(perf):
    e = event(perf, 41)
    assert e["played_end"] - e["t0"] == pytest.approx(0.5)
    t = event(perf, 42)
    assert force_at(perf, t["played_end"] - 0.005) == pytest.approx(force_at(perf, t["t0"] + 0.5))
    s = event(perf, 43)
    assert attack_force(perf, s["t0"]) / force_at(perf, s["t0"] + 0.5) == pytest.approx(3.0)


def test_acciaccatura_is_played_before_the_beat(perf):
    """The notation score's grace note is slashed (music21's default): it takes its time
    from what precedes it and the main note keeps its onset, slurred from the grace."""
    ev = perf.events
    g = CFG["articulations"]["grace_duration"]
    grace = ev[(ev["label"] == "B4") & (np.abs(ev["t0"] - (at(44) - g)) < 1e-6)]
    main = event(perf, 44)
    assert len(grace) == 1
    assert main["t0"] == pytest.approx(at(44))
    assert main["direction"] == grace["direction"].iloc[0]


def test_sul_ponticello_moves_towards_the_bridge(perf):
    w = bowed(perf, at(46) + 0.1, at(46) + 0.5)
    assert w["beta"].to_numpy() == pytest.approx(float(dynamic_table(CFG, "beta", [6.0])[0]) * 0.5)


def _accelerations(perf) -> tuple[np.ndarray, np.ndarray]:
    """|dv/dt| (m/s^2) between bowed rows of each string, and the time of each."""
    out, when = [], []
    for _, rows in perf.actions.groupby("string"):
        t = rows["time"].to_numpy()
        v = rows["bow_velocity"].to_numpy()
        f = rows["bow_force"].to_numpy()
        dt = np.diff(t)
        both = (f[1:] > 0) & (f[:-1] > 0) & (dt > 0)
        out.append(np.abs(np.diff(v))[both] / dt[both])
        when.append(t[1:][both])
    return np.concatenate(out), np.concatenate(when)


def test_max_bow_acceleration_is_respected(perf):
    """Strokes long enough to reach their speed at 5 m/s^2 keep to it; none exceeds the
    short strokes' limit."""
    accel, when = _accelerations(perf)
    assert accel.max() <= CFG["bow"]["short_stroke_acceleration"] + 1e-6
    ev = perf.events
    long = ev[(ev["played_end"] - ev["t0"]) >= 0.5]
    inside = np.zeros(when.shape, bool)
    for t0, t1 in zip(long["t0"], long["played_end"], strict=True):
        inside |= (when > t0) & (when <= t1)
    assert inside.sum() > 50
    assert accel[inside].max() <= CFG["bow"]["max_acceleration"] + 1e-6


def test_short_detache_strokes_reach_their_speed(notes):
    """Eight detached sixteenths at 120 qpm (0.125 s): each stroke reaches the dynamic's
    lane velocity (at 5 m/s^2 a 0.125 s stroke would peak at 0.31 m/s at most, below f's
    0.40 m/s), faster than max_acceleration but within short_stroke_acceleration."""
    row = notes[notes["measure"] == 13].iloc[:1]
    run = pd.concat([row] * 8, ignore_index=True)
    run["onset"] = run["onset_beats"] = 48.0 + 0.125 * np.arange(8)
    run["duration"] = run["duration_beats"] = 0.125
    run["dynamic"] = 6.0
    perf = perform_part(run, CFG)
    lane = float(dynamic_table(CFG, "velocity", [6.0])[0])
    v = perf.actions["bow_velocity"].to_numpy()
    ev = perf.events
    for t0, t1 in zip(ev["t0"], ev["played_end"], strict=True):
        m = (perf.actions["time"] >= t0) & (perf.actions["time"] <= t1)
        assert np.abs(v[m.to_numpy()]).max() == pytest.approx(lane, rel=1e-6)
    accel, _ = _accelerations(perf)
    assert CFG["bow"]["max_acceleration"] < accel.max() <= CFG["bow"]["short_stroke_acceleration"]


def test_bow_position_follows_velocity_and_stays_on_the_bow(perf):
    a = perf.actions
    assert a["bow_position"].between(0, 1).all()
    for _, rows in a.groupby("string"):
        t, v, p = (rows[c].to_numpy() for c in ("time", "bow_velocity", "bow_position"))
        f = rows["bow_force"].to_numpy()
        dt = np.diff(t)
        ok = (f[1:] > 0) & (f[:-1] > 0) & (dt > 0) & (dt < 0.02)
        predicted = (v[1:] + v[:-1]) / 2 * dt / L
        assert np.abs(np.diff(p) - predicted)[ok].max() < 1e-4


def test_long_loud_note_slows_the_bow_to_fit(notes):
    long = notes[notes["measure"] == 13].copy()
    long["duration"] = 8.0
    long["dynamic"] = 7.0
    perf = perform_part(long, CFG)
    a = perf.actions
    assert a["bow_velocity"].abs().max() < 0.5 * 0.65 / 8.0 * 4
    assert a["bow_position"].max() - a["bow_position"].min() > 0.8
    assert a["bow_position"].between(0, 1).all()
    assert any("slowed" in w for w in perf.warnings)


def test_skill_levels_jitter_reproducibly(notes):
    def run(skill, seed):
        return perform_part(notes, CFG, skill=skill, rng=np.random.default_rng(seed))

    exact = run(3, 1)
    pd.testing.assert_frame_equal(exact.actions, run(3, 2).actions)
    a, b, c = run(0, 1), run(0, 1), run(0, 2)
    pd.testing.assert_frame_equal(a.actions, b.actions)
    assert not a.actions.equals(c.actions)
    jitter = a.events["t0"].to_numpy()[:12] - exact.events["t0"].to_numpy()[:12]
    assert 0 < np.abs(jitter).max() < 0.05
    open_a = a.actions[(a.actions["time"] < 0.9) & (a.actions["bow_force"] > 0)]
    assert np.all(open_a["finger_ratio"] == 0)  # the open A gets no pitch error
    stopped = a.actions[(a.actions["time"] > 1.1) & (a.actions["time"] < 1.6)]
    assert not np.allclose(stopped["finger_ratio"], 1 - 2 ** (-2 / 12), atol=1e-5)


def test_instrument_override_changes_force(notes, perf):
    viola = perform_part(notes, CFG, instrument="viola")
    ratio = force_at(viola, 0.5) / force_at(perf, 0.5)
    string_violin = int(bowed(perf, 0.5, 0.51)["string"].iloc[0])
    string_viola = int(bowed(viola, 0.5, 0.51)["string"].iloc[0])
    expected = (_table_newtons("viola", string_viola, 5)
                / _table_newtons("violin", string_violin, 5))
    assert ratio == pytest.approx(expected)
    assert ratio != pytest.approx(1.0)
