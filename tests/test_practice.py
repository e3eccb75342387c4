"""Practice on music: the support-vector refit, stroke factors, the replayed listener, the CLI."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import pipelines.cli.main as cli
from data_schemas.errors import ParameterError
from pipelines.listening.practice import (
    AS_PLANNED,
    direction_labels,
    heard_features,
    stroke_factors,
)
from pipelines.listening.practice_refit import MIN_STROKES, practised_factor
from synth.listening.classifier import fit_pair
from synth.listening.controller import HopPlan
from synth.listening.features import (
    FEATURE_NAMES,
    HOP,
    WINDOW,
    StreamingFeatures,
    yin_window_for,
)
from synth.listening.refit import refit_pair, support_set

N_FEATURES = len(FEATURE_NAMES)


def _toy_model(seed: int = 0):
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(240, N_FEATURES))
    y = np.where(X[:, 0] + 0.3 * X[:, 1] > 0.4, 4, np.where(X[:, 0] < -0.4, 2, 3))
    return fit_pair(X, y, instrument="violin", string=1, dynamic="mf", folds=2), X, y


def test_support_vectors_come_back_in_feature_units():
    model, X, y = _toy_model()
    sv, labels = support_set(model)
    # Every support vector is one of the training hops, with that hop's class.
    for row, label in zip(sv, labels, strict=True):
        i = int(np.argmin(np.abs(X - row).sum(axis=1)))
        assert np.allclose(X[i], row, atol=1e-9) and y[i] == label


def test_refit_on_its_own_support_vectors_keeps_the_decisions():
    model, _, _ = _toy_model()
    refit = refit_pair(model, np.zeros((0, N_FEATURES)), [])
    probe = np.random.default_rng(1).normal(size=(2000, N_FEATURES)) * 1.5
    # The SVM optimum depends only on the support vectors (the solver's tolerance aside).
    assert np.mean(model.predict(probe) == refit.predict(probe)) >= 0.995


def test_refit_learns_what_practice_heard():
    model, _, _ = _toy_model()
    rng = np.random.default_rng(2)
    heard = rng.normal(size=(300, N_FEATURES)) * 0.3
    heard[:, 0] += 2.5  # the basic training calls this region class 4
    assert np.mean(model.predict(heard) == 4) > 0.9
    model.metadata.update(K=1.02, initial_forces=[0.5, 0.6, 0.7])
    refit = refit_pair(model, heard, np.full(300, 3))
    probe = rng.normal(size=(200, N_FEATURES)) * 0.3
    probe[:, 0] += 2.5
    assert np.mean(refit.predict(probe) == 3) > 0.9
    far = rng.normal(size=(200, N_FEATURES)) * 0.3
    far[:, 0] -= 2.0  # class 2, far from the practice hops: unchanged
    assert np.mean(refit.predict(far) == model.predict(far)) > 0.95
    assert refit.metadata["refit"]["hops_added"] == 300
    assert refit.metadata["K"] == 1.02 and refit.metadata["initial_forces"] == [0.5, 0.6, 0.7]


@pytest.mark.parametrize(("features", "labels", "weight", "match"), [
    (np.zeros((3, N_FEATURES - 1)), [3, 3, 3], 1.0, "hops x"),
    (np.zeros((3, N_FEATURES)), [3, 3], 1.0, "3 feature rows but 2 labels"),
    (np.zeros((2, N_FEATURES)), [0, 3], 1.0, "classes 1..5"),
    (np.full((1, N_FEATURES), np.nan), [3], 1.0, "finite"),
    (np.zeros((1, N_FEATURES)), [3], 0.0, "weight"),
])
def test_refit_rejects_bad_hops(features, labels, weight, match):
    model, _, _ = _toy_model()
    with pytest.raises(ParameterError, match=match):
        refit_pair(model, features, labels, weight=weight)


def _plan(n: int, starts: list[int], bowed_to: int | None = None, f0: float = 293.66):
    shape = (n, 4)
    plan = HopPlan(np.zeros(shape, bool), np.zeros(shape), np.full(shape, 0.1),
                   np.zeros(shape), np.full(shape, f0), np.full(shape, 0.3),
                   np.full(shape, "mf", object), np.zeros(shape, bool),
                   np.zeros(shape, bool))
    plan.bowed[:bowed_to or n, 1] = True
    plan.note_start[starts, 1] = True
    return plan


@settings(max_examples=40, deadline=None)
@given(starts=st.lists(st.integers(0, 199), min_size=1, max_size=30, unique=True),
       spread=st.floats(1.05, 4.0), seed=st.integers(0, 2**16))
def test_stroke_factors_hold_over_each_stroke(starts, spread, seed):
    plan = _plan(200, sorted(starts))
    f = stroke_factors(plan, np.random.default_rng(seed), spread)
    again = stroke_factors(plan, np.random.default_rng(seed), spread)
    assert np.array_equal(f, again)
    assert np.all(f[:, [0, 2, 3]] == 1.0)
    assert np.all((f >= 1.0 / spread - 1e-12) & (f <= spread + 1e-12))
    bounds = sorted(starts) + [200]
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        assert np.all(f[a:b, 1] == f[a, 1])


def test_about_a_third_of_strokes_as_planned():
    plan = _plan(3000, list(range(0, 3000, 3)))
    f = stroke_factors(plan, np.random.default_rng(0), 2.0)[::3, 1]
    assert abs(np.mean(f == 1.0) - AS_PLANNED) < 0.05
    with pytest.raises(ParameterError, match="spread"):
        stroke_factors(plan, np.random.default_rng(0), 1.0)


def test_heard_features_forget_before_each_stroke():
    sr, n = 44100, 80
    t = np.arange(n * HOP) / sr
    tone = (0.1 * np.sin(2 * np.pi * 293.66 * t)).astype(np.float32)
    noisy = tone.copy()
    noisy[:40 * HOP] = np.random.default_rng(0).normal(0, 0.1, 40 * HOP)
    plan = _plan(n, [0, 40], bowed_to=70)
    a, b = heard_features(plan, tone, sr), heard_features(plan, noisy, sr)
    full = WINDOW // HOP  # hops until the listener has heard a whole window
    assert np.all(np.isnan(a[:, [0, 2, 3]])) and np.all(np.isnan(a[70:, 1]))
    assert np.all(np.isnan(a[40:40 + full - 1, 1]))  # just reset: not a window yet
    assert np.array_equal(a[40 + full:70, 1], b[40 + full:70, 1])
    # The same as a listener that heard only the second stroke.
    lis = StreamingFeatures(sr, yin_window=yin_window_for(293.66, sr))
    for k in range(40, 70):
        x = lis.push(tone[k * HOP:(k + 1) * HOP], 293.66)
        if lis.ready:
            assert np.array_equal(x, a[k, 1])


def _variants(shares: dict[float, list[int]], strokes: int = 1) -> pd.DataFrame:
    """Hops of ``strokes`` strokes played at each factor with the given teacher labels."""
    rows = []
    for v, (factor, labels) in enumerate(shares.items()):
        for stroke in range(strokes):
            rows += [{"part": "p", "seed": 0, "string": 2, "stroke": stroke, "variant": v,
                      "factor": factor, "teacher_label": c} for c in labels]
    return pd.DataFrame(rows)


def test_direction_points_to_the_stroke_best_variant():
    hops = _variants({1.0: [2, 2, 3, 3], 0.6: [3, 3, 3, 4], 1.7: [4, 4, 4, 3]})
    labels = direction_labels(hops)
    teacher = hops["teacher_label"].to_numpy()
    assert np.all(labels[teacher == 3] == 3)  # heard as good: hold
    factor = hops["factor"].to_numpy()
    assert np.all(labels[(teacher != 3) & (factor == 1.0)] == 4)  # the best is lighter
    assert np.all(labels[(teacher != 3) & (factor == 1.7)] == 4)
    assert np.all(labels[(teacher != 3) & (factor == 0.6)] == 3)  # the best: force no cure


def test_direction_ties_go_to_the_planned_force():
    hops = _variants({1.0: [3, 2], 1.5: [2, 3], 0.7: [4, 3]})
    labels = direction_labels(hops)
    faults = hops["teacher_label"].to_numpy() != 3
    assert labels[faults & (hops["factor"] == 1.5).to_numpy()].tolist() == [4]
    assert labels[faults & (hops["factor"] == 0.7).to_numpy()].tolist() == [2]
    assert labels[faults & (hops["factor"] == 1.0).to_numpy()].tolist() == [3]


def test_practised_factor_finds_the_better_force_and_needs_evidence():
    better = {1.0: [2, 2, 3, 3], 1.4: [3, 3, 3, 3], 0.7: [2, 2, 2, 3]}
    factor, gain = practised_factor(_variants(better, strokes=MIN_STROKES))
    assert factor == pytest.approx(1.4) and gain > 0.1
    assert practised_factor(_variants(better, strokes=MIN_STROKES - 1)) == (1.0, 0.0)
    same = {1.0: [3, 3, 2], 1.4: [3, 3, 2], 0.7: [3, 3, 2]}
    assert practised_factor(_variants(same, strokes=MIN_STROKES))[0] == 1.0


def test_practised_factor_keeps_each_performer_strokes_apart():
    # The same part, seed and stroke numbers from two performers, their variants' factors
    # swapped: every stroke of both sounded best at 1.5.
    rules = _variants({1.0: [2], 1.5: [3]}, strokes=MIN_STROKES).assign(performer="rules")
    sampled = _variants({1.5: [3], 1.0: [2]}, strokes=MIN_STROKES).assign(performer="sampling")
    factor, gain = practised_factor(pd.concat([rules, sampled], ignore_index=True))
    assert factor == 1.5 and gain > 0.3


def _d_string_score(path):
    from music21 import dynamics, note, stream, tempo

    part = stream.Part()
    part.partName = "Violin"
    part.append(tempo.MetronomeMark(number=90))
    part.append(dynamics.Dynamic("mf"))
    for p in ("D4", "E4", "F#4", "G4"):
        part.append(note.Note(p, quarterLength=1))
    score = stream.Score()
    score.insert(0, part)
    score.write("musicxml", fp=str(path))
    return path


def test_practice_cli_writes_practised_pairs(models_dir, tmp_path, capsys):
    score = _d_string_score(tmp_path / "d.musicxml")
    out = tmp_path / "practised"
    code = cli.main(["practice", "--models", str(models_dir), "-o", str(out), "--score",
                     str(score), "--end-measure", "1", "--seeds", "2", "--quiet"])
    text, err = capsys.readouterr()
    assert code == 0, err
    assert "violin-1-mf:" in text and "on unheard seeds" in text and "best factor" in text
    meta = json.loads((out / "violin-1-mf.json").read_text())
    practice = meta["practice"]
    assert practice["hops_added"] > 50 and practice["seeds"] == [0, 1]
    assert set(practice["class_counts"]) <= {"1", "2", "3", "4", "5"}
    assert meta["complete"] and meta["refit"]["hops_added"] == practice["hops_added"]
    assert practice["variants"] == 4 and 0.5 <= meta["practice_force_factor"] <= 2.0
    code = cli.main(["practice", "--models", str(models_dir), "-o", str(models_dir),
                     "--score", str(score), "--quiet"])
    assert code != 0 and "must differ" in capsys.readouterr().err


@pytest.mark.parametrize("practised", [False, True])
def test_a_corrected_stroke_starts_at_the_practised_factor(practised):
    from synth.engines import get_engine
    from synth.listening.controller import ControllerSettings, play_plan

    model, _, _ = _toy_model()
    model.metadata["practice_force_factor"] = 1.3
    plan = _plan(40, [0])
    plan.velocity[:, 1] = 0.3
    planned = np.where(plan.bowed, 0.8, 0.0)
    rules = ControllerSettings(jitter=0.0, trim=1.5, sure=1.01, practised_start=practised)
    log = play_plan(plan, {(1, "mf"): model}, get_engine("modal", "violin"),
                    rng=np.random.default_rng(0), settings=rules, planned_force=planned)
    assert np.allclose(log.force[:, 1], 0.8 * (1.3 if practised else 1.0))


@pytest.mark.parametrize(("extra", "message"), [
    (["--start-measure", "3", "--end-measure", "1"], "--end-measure 1 is before --start-measure 3"),
    (["--variants", "1"], "--variants 1 must be >= 2"),
    (["--spread", "1.0"], "--spread 1.0 must be > 1"),
])
def test_practice_cli_one_line_errors(tmp_path, capsys, extra, message):
    code = cli.main(["practice", "--models", str(tmp_path / "m"), "-o", str(tmp_path / "o"),
                     "--quiet", *extra])
    assert code != 0 and message in capsys.readouterr().err


def test_practice_needs_models_and_a_part_of_the_instrument(models_dir, tmp_path, capsys):
    from music21 import instrument, note, stream

    violin = _d_string_score(tmp_path / "d.musicxml")
    code = cli.main(["practice", "--instrument", "cello", "--models", str(models_dir), "-o",
                     str(tmp_path / "o"), "--score", str(violin), "--quiet"])
    assert code != 0 and "no trained cello models" in capsys.readouterr().err
    part = stream.Part([instrument.Violoncello(), note.Note("C3", quarterLength=4)])
    cello = tmp_path / "c.musicxml"
    stream.Score([part]).write("musicxml", fp=str(cello))
    code = cli.main(["practice", "--models", str(models_dir), "-o", str(tmp_path / "o"),
                     "--score", str(cello), "--end-measure", "1", "--quiet"])
    assert code != 0 and "no violin part in ['c.musicxml']" in capsys.readouterr().err


def _sampled_performance(tiny_db, tmp_path):
    from pipelines.methods.sampling import open_database, sample_part
    from pipelines.perform.config import load_config
    from pipelines.score import read_score

    notes = read_score(_d_string_score(tmp_path / "d.musicxml"))
    perf, _, _ = sample_part(notes, open_database(tiny_db / "db"), load_config(),
                             instrument="violin", rng=np.random.default_rng(0))
    return notes, perf


def test_sampled_plan_holds_the_sampled_force_and_each_stroke_peak_speed(tiny_db, tmp_path):
    from pipelines.methods.sampled_loop import sampled_plan

    _, perf = _sampled_performance(tiny_db, tmp_path)
    plan, _, force = sampled_plan(perf, "violin")
    bowed = perf.actions[~perf.actions["pluck"]]
    assert set(bowed["string"]) == {1}
    frames, f = bowed["time"].tolist(), bowed["bow_force"].tolist()
    checked = 0
    for k in range(0, plan.n_hops, 7):
        t = (k + 1) * HOP / 44100
        after = next((j for j, x in enumerate(frames) if x > t), None)
        if after is None or after == 0 or frames[after - 1] == frames[after]:
            continue
        a, b = after - 1, after  # the frames around the hop's end: straight line between
        w = (t - frames[a]) / (frames[b] - frames[a])
        assert force[k, 1] == pytest.approx((1 - w) * f[a] + w * f[b], abs=1e-12)
        checked += 1
    assert checked > 40
    assert force[:, 1].min() >= bowed["bow_force"].min() - 1e-12
    assert force[:, 1].max() <= bowed["bow_force"].max() + 1e-12
    assert np.all(force[:, [0, 2, 3]] == 0.0)
    starts = np.flatnonzero(plan.note_start[:, 1]).tolist() + [plan.n_hops]
    for a, b in zip(starts[:-1], starts[1:], strict=True):
        peak = max(abs(plan.velocity[k, 1]) for k in range(a, b))
        assert np.all(plan.target_speed[a:b, 1] == peak)


def test_practice_plays_the_sampled_bowing(tiny_db, models_dir, tmp_path):
    from pipelines.listening.practice import _planned, practice_part
    from pipelines.methods.sampling import open_database
    from pipelines.perform.config import load_config
    from synth.listening.classifier import load_models

    notes, perf = _sampled_performance(tiny_db, tmp_path)
    db = open_database(tiny_db / "db")
    _, plan, _, sampled = _planned(notes, load_config(), instrument="violin", seed=0,
                                   sample_rate=44100, database=db)
    _, _, _, ruled = _planned(notes, load_config(), instrument="violin", seed=0,
                              sample_rate=44100)
    again = _planned(notes, load_config(), instrument="violin", seed=0, sample_rate=44100,
                     database=db)[0]
    pd.testing.assert_frame_equal(perf.actions, again.actions)  # the sampled bowing
    bowed = plan.bowed[:, 1]
    assert np.abs(np.log(sampled[bowed, 1] / ruled[: plan.n_hops][bowed, 1])).max() > 0.1
    hops = practice_part(notes, load_config(), load_models(models_dir, "violin"),
                         instrument="violin", seed=0, variants=2, database=db)
    assert len(hops) > 50 and set(hops["variant"]) == {0, 1}
    assert set(hops["label"]) <= {2, 3, 4} and set(hops["teacher_label"]) <= {1, 2, 3, 4, 5}
    assert np.all(hops["label"][hops["teacher_label"] == 3] == 3)


def test_practice_cli_on_sampled_bowing(tiny_db, models_dir, tmp_path, capsys):
    score = _d_string_score(tmp_path / "d.musicxml")
    out = tmp_path / "practised"
    base = ["practice", "--models", str(models_dir), "-o", str(out), "--score", str(score),
            "--end-measure", "1", "--seeds", "1", "--variants", "2", "--quiet"]
    code = cli.main([*base, "--performer", "sampling"])
    assert code != 0 and "--performer sampling needs --db DIR" in capsys.readouterr().err
    code = cli.main([*base, "--performer", "both", "--db", str(tiny_db / "db")])
    text, err = capsys.readouterr()
    assert code == 0, err
    practice = json.loads((out / "violin-1-mf.json").read_text())["practice"]
    assert practice["performers"] == ["rules", "sampling"] and practice["hops_added"] > 100
