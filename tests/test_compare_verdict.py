"""The comparison's intervals, separations, verdict and why, against independent truths."""

from __future__ import annotations

import itertools

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pipelines.reports.intervals import (
    COLUMNS,
    Interval,
    better,
    bootstrap,
    contenders,
    figures_of,
    note_arrays,
    winner,
)
from pipelines.reports.verdict import (
    note_contexts,
    note_failures,
    verdict_sentence,
    why,
    why_sentence,
)


def _note(share, hops, attack, c3, c5, pitch=1.0, level=0.0):
    return {"sustained_hops": hops, "helmholtz_share": share, "reached_helmholtz": share > 0,
            "attack_ms": attack, "pitch_error_cents_median": pitch,
            "level_error_db_median": level,
            "class_histogram": {"1": 0, "2": 0, "3": c3, "4": hops - c3 - c5, "5": c5},
            "sustained_class_histogram": {"1": 0, "2": 0, "3": c3, "4": hops - c3 - c5,
                                          "5": c5}}


notes_strategy = st.lists(st.builds(
    lambda share, hops, attack, f3, f5: _note(share, hops, attack, int(hops * f3),
                                             int(hops * (1 - f3) * f5)),
    st.floats(0.0, 1.0), st.integers(1, 60), st.floats(0.0, 300.0), st.floats(0.0, 1.0),
    st.floats(0.0, 1.0)), min_size=1, max_size=12)


@settings(max_examples=40, deadline=None)
@given(notes_strategy)
def test_figures_match_the_yardsticks_piece_figures(notes):
    from pipelines.listening.evaluate import piece_figures

    ours = figures_of(note_arrays(notes))
    theirs = piece_figures(notes)
    for key in ("helmholtz_share", "attack_ms_p90", "attack_ms_median",
                "sustained_class3_share", "reached_helmholtz_share",
                "pitch_error_cents_median", "level_error_db_median"):
        assert ours[key] == pytest.approx(theirs[key], nan_ok=True), key
    total = sum(sum(n["sustained_class_histogram"].values()) for n in notes)
    c5 = sum(n["sustained_class_histogram"]["5"] for n in notes)
    assert ours["sustained_class5_share"] == pytest.approx(c5 / total)


@settings(max_examples=25, deadline=None)
@given(st.lists(notes_strategy, min_size=1, max_size=3))
def test_bootstrap_intervals_stay_within_what_any_resample_can_give(per_seed_notes):
    arrays = [note_arrays(n) for n in per_seed_notes]
    ivs = bootstrap(arrays, n_boot=60)
    pooled = [n for seed in per_seed_notes for n in seed]
    shares = [n["helmholtz_share"] for n in pooled]
    attacks = [n["attack_ms"] for n in pooled]
    hs, at = ivs["helmholtz_share"], ivs["attack_ms_p90"]
    assert min(shares) - 1e-12 <= hs.low <= hs.high <= max(shares) + 1e-12
    assert min(attacks) - 1e-9 <= at.low <= at.high <= max(attacks) + 1e-9
    per_seed = [figures_of(a)["helmholtz_share"] for a in arrays]
    assert hs.mean == pytest.approx(np.mean(per_seed))
    assert bootstrap(arrays, n_boot=60) == ivs  # seeded: the same intervals again


def test_bootstrap_matches_the_exact_bootstrap_distribution_of_a_tiny_case():
    """One seed, four notes: enumerate all 4^4 resamples and compare the quantiles."""
    values = np.array([0.2, 0.5, 0.9, 1.0])
    hops = np.array([10.0, 20.0, 30.0, 40.0])
    base = {k: np.zeros(4) for k in COLUMNS}
    base.update(helmholtz_share=values, sustained_hops=hops, attack_ms=values * 100,
                sus_total=hops, reached_helmholtz=np.ones(4))
    exact = []
    for idx in itertools.product(range(4), repeat=4):
        i = np.array(idx)
        exact.append(np.sum(values[i] * hops[i]) / np.sum(hops[i]))
    lo, hi = np.percentile(exact, [2.5, 97.5])
    got = bootstrap([base], n_boot=4000)["helmholtz_share"]
    # Monte-Carlo percentiles of 4000 draws lie near the exact ones (within 1.5 % of the
    # exact distribution's mass on either side).
    assert np.percentile(exact, 1.0) <= got.low <= np.percentile(exact, 4.0)
    assert np.percentile(exact, 96.0) <= got.high <= np.percentile(exact, 99.0)
    assert lo < hi


def test_identical_seeds_and_notes_give_a_point_interval():
    one = note_arrays([_note(0.8, 10, 40.0, 9, 0)] * 5)
    iv = bootstrap([one, one, one], n_boot=100)["helmholtz_share"]
    assert iv == Interval(pytest.approx(0.8), pytest.approx(0.8), pytest.approx(0.8))


interval_strategy = st.tuples(st.floats(-5, 5), st.floats(0, 3), st.floats(0, 3)).map(
    lambda t: Interval(t[0], t[0] - t[1], t[0] + t[2]))


def _brute_winner(ivs, larger):
    """The method whose interval lies entirely on the better side of every other one."""
    def key(iv):
        if larger is None:
            lo, hi = ((0.0 if iv.low <= 0 <= iv.high else min(abs(iv.low), abs(iv.high))),
                      max(abs(iv.low), abs(iv.high)))
            return -hi, -lo
        return (iv.low, iv.high) if larger else (-iv.high, -iv.low)

    found = [m for m, iv in ivs.items()
             if all(key(iv)[0] > key(o)[1] for n, o in ivs.items() if n != m)]
    return found[0] if len(ivs) > 1 and found else None


@settings(max_examples=300, deadline=None)
@given(st.dictionaries(st.sampled_from("abcd"), interval_strategy, min_size=1, max_size=4),
       st.sampled_from([True, False, None]))
def test_winner_agrees_with_brute_force_separation(ivs, larger):
    w = winner(ivs, larger)
    assert w == _brute_winner(ivs, larger)
    if w is not None:
        assert contenders(ivs, larger) == [w]
        assert all(better(ivs[w], o, larger) and not better(o, ivs[w], larger)
                   for m, o in ivs.items() if m != w)


def test_overlapping_intervals_separate_nobody():
    a, b = Interval(0.8, 0.7, 0.9), Interval(0.75, 0.65, 0.85)
    assert not better(a, b, True) and not better(b, a, True)
    assert winner({"a": a, "b": b}, True) is None
    # Errors compared on magnitude: -0.5 [-0.6, -0.4] beats 2 [1.5, 2.5].
    assert winner({"a": Interval(-0.5, -0.6, -0.4), "b": Interval(2.0, 1.5, 2.5)}, None) == "a"


def _summary(**per):
    return {"helmholtz_share": per.get("hs", {}), "attack_ms_p90": per.get("at", {}),
            "sustained_class3_share": per.get("c3", {})}


def test_verdict_names_a_winner_and_the_figures_that_do_not_separate():
    s = _summary(hs={"rules": Interval(0.9, 0.88, 0.92), "feedback": Interval(0.6, 0.5, 0.7),
                     "sampling": Interval(0.7, 0.65, 0.75)},
                 at={"rules": Interval(50, 45, 55), "feedback": Interval(90, 80, 100),
                     "sampling": Interval(80, 70, 95)},
                 c3={"rules": Interval(0.7, 0.6, 0.8), "feedback": Interval(0.4, 0.3, 0.5),
                     "sampling": Interval(0.72, 0.65, 0.8)})
    assert verdict_sentence(s, n_excerpts=4, n_seeds=5) == (
        "On 4 excerpts x 5 seeds, rules beats feedback and sampling on Helmholtz share and "
        "attack p90; rules and sampling beat feedback on class-3 share.")


def test_a_tied_group_beats_the_rest_only_when_each_member_separates_from_each():
    low = Interval(0.91, 0.88, 0.94)
    group = _summary(hs={"rules": low, "feedback": low,
                         "sampling": Interval(0.96, 0.95, 0.98),
                         "open": Interval(0.97, 0.96, 0.98)})
    assert verdict_sentence(group, n_excerpts=2, n_seeds=5) == (
        "On 2 excerpts x 5 seeds, sampling and open beat rules and feedback on Helmholtz "
        "share.")
    # feedback ties with the best and with rules; rules is apart from the best only, and
    # the sentence names it behind the one it separates from
    chain = _summary(at={"rules": Interval(124, 110, 141), "feedback": Interval(118, 100, 140),
                         "sampling": Interval(98, 89, 120), "open": Interval(95, 86, 109)})
    assert verdict_sentence(chain, n_excerpts=2, n_seeds=5) == (
        "On 2 excerpts x 5 seeds, feedback, sampling and open do not separate on attack p90 "
        "(rules behind open).")


def test_a_method_left_out_of_a_tie_is_named_behind_those_it_trails():
    """The held-out run of the thirty-fourth session. Helmholtz share: rules, sampling and
    open do not separate; feedback (high 0.948) is separated from rules (low 0.953) and
    open (0.949), not from sampling (0.946). Class 3: all three separate from feedback."""
    s = _summary(hs={"rules": Interval(0.961, 0.953, 0.967),
                     "feedback": Interval(0.943, 0.937, 0.948),
                     "sampling": Interval(0.952, 0.946, 0.957),
                     "open": Interval(0.956, 0.949, 0.961)},
                 c3={"rules": Interval(0.919, 0.910, 0.927),
                     "feedback": Interval(0.886, 0.874, 0.894),
                     "sampling": Interval(0.904, 0.896, 0.913),
                     "open": Interval(0.905, 0.895, 0.914)})
    assert verdict_sentence(s, n_excerpts=6, n_seeds=5) == (
        "On 6 excerpts x 5 seeds, rules, sampling and open beat feedback on class-3 share; "
        "rules, sampling and open do not separate on Helmholtz share (feedback behind rules "
        "and open).")


def test_verdict_without_any_separation_and_with_ties():
    same = Interval(0.8, 0.7, 0.9)
    s = _summary(hs={"a": same, "b": same}, at={"a": Interval(50, 40, 60),
                                                 "b": Interval(50, 40, 60)})
    assert verdict_sentence(s, n_excerpts=1, n_seeds=2) == (
        "On 1 excerpt x 2 seeds, a and b do not separate on Helmholtz share and attack p90.")
    assert verdict_sentence(_summary(hs={"a": same}), n_excerpts=2, n_seeds=1).endswith(
        "no figure could be compared (fewer than two methods measured).")


def test_a_method_without_figures_is_left_out_of_the_verdict():
    s = _summary(hs={"a": Interval(0.9, 0.85, 0.95), "b": Interval(0.5, 0.4, 0.6),
                     "c": Interval(float("nan"), float("nan"), float("nan"))})
    assert verdict_sentence(s, n_excerpts=2, n_seeds=3) == (
        "On 2 excerpts x 3 seeds, a beats b on Helmholtz share.")


def test_note_contexts_and_failures_classify_each_note():
    events = pd.DataFrame({"t0": [0.0, 0.5, 0.6, 1.2, 2.0],
                           "played_end": [0.45, 0.58, 1.1, 1.9, 2.5],
                           "string": [2, 2, 1, 1, 1], "dynamic": [5.0, 5.0, 7.0, 7.2, 7.2],
                           "n_strings": [1, 1, 2, 1, 1],
                           "run_position": ["init", "mid", "mid", "end", "iso"],
                           "bow_join": ["", "bow change", "legato", "bow restart", ""]})
    notes = [{"start": t} for t in (0.0, 0.51, 0.6, 0.61, 1.2, 2.0)]
    assert note_contexts(notes, events) == [
        ["attack"], ["bow change", "short note"],
        ["legato", "string crossing", "double stop", "dynamic change"],
        ["legato", "string crossing", "double stop", "dynamic change"], ["bow restart"],
        ["attack"]]
    # events without the bowing column (an older table): no bow tags, "other"
    assert note_contexts(notes[4:5], events.drop(columns="bow_join")) == [["other"]]
    ok = _note(0.95, 20, 30.0, 20, 0)
    assert note_failures(ok) == []
    assert note_failures(_note(0.5, 20, float("nan"), 2, 10)) == ["slow attack", "unsteady",
                                                                   "class 5"]


def test_why_counts_failing_notes_and_lists_the_worst_first():
    def tagged(n, ctx, measure):
        return {**n, "failures": note_failures(n), "contexts": ctx, "excerpt": "x",
                "seed": 0, "part": "Violin I", "measure": measure, "pitch": "A4"}

    notes = [tagged(_note(0.95, 20, 30.0, 20, 0), ["attack"], 1),
             tagged(_note(0.95, 20, 80.0, 20, 0), ["attack"], 2),
             tagged(_note(0.2, 20, float("nan"), 0, 20), ["string crossing", "short note"], 3)]
    w = why(notes)
    assert w["notes"] == 3 and w["failing"] == 2
    assert w["by_failure"] == {"slow attack": 2, "unsteady": 1, "class 5": 1}
    assert w["by_context"]["attack"] == 1 and w["by_context"]["string crossing"] == 1
    assert w["notes_by_context"]["attack"] == 2 and w["notes_by_context"]["short note"] == 1
    assert "attack 1 of 2" in why_sentence("rules", w)
    assert [n["measure"] for n in w["worst"]] == [3, 2]


def _job(method, seed, excerpt, share, error=None):
    hist = {"1": 0, "2": 0, "3": 9, "4": 1, "5": 0}
    note = {**_note(share, 10, 30.0, 9, 0), "sustained_class_histogram": hist,
            "failures": [], "contexts": ["attack"], "excerpt": excerpt, "seed": seed}
    figures = ({"error": error} if error else
               {"render_seconds": 1.0, "real_time_factor": 2.0, "audio_seconds": 2.0})
    return {"excerpt": excerpt, "method": method, "seed": seed, "media": None,
            "figures": figures, "notes": [] if error else [note] * 4}


def test_an_excerpt_one_method_cannot_play_is_left_out_for_every_method():
    from pipelines.reports.summary import summarise

    done = [_job("a", s, e, 1.0) for s in (0, 1) for e in ("x", "y")]
    done += [_job("b", s, "x", 0.5) for s in (0, 1)]
    done += [_job("b", s, "y", 0.5, error="no bowed notes") for s in (0, 1)]
    done += [_job("c", s, e, 0.5, error="no models") for s in (0, 1) for e in ("x", "y")]
    r = summarise(done, excerpts=[{"name": "x"}, {"name": "y"}], methods=["a", "b", "c"],
                  seeds=[0, 1])
    assert r["failed"] == {"c": "no models"} and r["left_out"] == {"y": "b: no bowed notes"}
    assert r["verdict"].startswith("On 1 excerpt x 2 seeds, a beats b on Helmholtz share")
    assert r["verdict"].endswith("(y left out, b: no bowed notes; c not compared: no models).")
    assert r["why"]["a"]["notes"] == 8  # only excerpt x's notes, 4 per seed
    assert list(r["excerpts"]["y"]["summary"]) == ["a"]


def test_bow_joins_tell_a_new_stroke_from_a_stop_and_from_legato():
    from pipelines.perform.events import Event, events_table

    def ev(t0, direction, cont=False, stop=False, pizz=False):
        return Event(rows=[0], t0=t0, end=t0 + 0.2, strings=[2], semitones=[0.0],
                     dynamic=5.0, label="A4", played_end=t0 + 0.2, direction=direction,
                     cont=cont, stop=stop, pizz=pizz)

    events = [ev(0.0, 1), ev(0.2, -1), ev(0.4, -1, cont=True, stop=True),
              ev(0.6, -1, cont=True), ev(0.8, -1, cont=True), ev(1.0, 1, cont=True),
              ev(1.2, 0, pizz=True), ev(1.4, 1)]
    table = events_table(events, pd.DataFrame({"measure": [1]}))
    # the third note follows a legato note (not stopped); the fourth follows a stopped one
    assert table["bow_join"].tolist() == ["", "bow change", "legato", "bow restart", "legato",
                                          "bow change", "", ""]


def test_per_instrument_tables_pool_each_instruments_notes(tmp_path):
    from pipelines.reports.html import write_report
    from pipelines.reports.summary import summarise

    def job(method, seed, violin_share, cello_share):
        j = _job(method, seed, "x", 1.0)
        j["notes"] = ([{**n, "helmholtz_share": violin_share, "instrument": "violin"}
                       for n in j["notes"][:2]]
                      + [{**n, "helmholtz_share": cello_share, "instrument": "cello"}
                         for n in j["notes"][2:]])
        return j

    done = [job("a", s, 1.0, 0.5) for s in (0, 1)] + [job("b", s, 0.4, 0.9) for s in (0, 1)]
    r = summarise(done, excerpts=[{"name": "x"}], methods=["a", "b"], seeds=[0, 1])
    assert list(r["instruments"]) == ["violin", "cello"]
    violin, cello = r["instruments"]["violin"], r["instruments"]["cello"]
    assert violin["summary"]["a"]["helmholtz_share"]["mean"] == pytest.approx(1.0)
    assert violin["summary"]["b"]["helmholtz_share"]["mean"] == pytest.approx(0.4)
    assert cello["summary"]["b"]["helmholtz_share"]["mean"] == pytest.approx(0.9)
    assert violin["winners"]["helmholtz_share"] == "a"
    assert cello["winners"]["helmholtz_share"] == "b"
    assert cello["verdict"].startswith("On the cello parts of 1 excerpt x 2 seeds, b beats a "
                                       "on Helmholtz share")
    # pooled over both instruments (equal hops): 0.75 against 0.65, intervals apart
    assert r["summary"]["a"]["helmholtz_share"]["mean"] == pytest.approx(0.75)
    write_report(r, tmp_path)
    page = (tmp_path / "index.html").read_text()
    assert "<h2>violin parts</h2>" in page and "<h2>cello parts</h2>" in page
