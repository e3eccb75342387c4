"""Gesture sampling: stretch, join, reproduction of a take, rendering a score, clear errors."""

import json
import shutil

import numpy as np
import pandas as pd
import pytest

from data_schemas.errors import ArcoError, SchemaError
from gesture_db.join import Piece, join_run
from gesture_db.stretch import edge_length, stretch, warp


def _targets(annotation: pd.DataFrame) -> pd.DataFrame:
    fr = annotation["finger_ratio"].to_numpy(np.float64)
    t = pd.DataFrame(dict(
        onset=annotation["true_onset"], duration=annotation["true_offset"]
        - annotation["true_onset"], midi_pitch=annotation["midi_pitch"],
        string=annotation["string"], finger_ratio=fr, effective_string_length=0.325 * (1 - fr),
        dynamic=annotation["dynamic"], technique=annotation["technique"],
        bow_direction=annotation["bow_direction"], slur_position=annotation["slur_position"],
        run_position=annotation["run_position"]))
    t["group"] = (t["technique"] + "-" + t["bow_direction"] + "-" + t["slur_position"] + "-"
                  + t["run_position"])
    return t


# --------------------------------------------------------------------------- stretch


@pytest.mark.parametrize("factor", [0.45, 0.8, 1.7, 3.0])
def test_stretch_keeps_attack_and_release(factor):
    fs = 1000.0
    Ds = 0.5
    ts = np.arange(0, Ds + 1e-9, 1 / fs)
    # attack, wobbly sustain, release
    y = np.minimum(ts / 0.04, 1) * np.minimum((Ds - ts) / 0.05, 1) * (1 + 0.2 * np.sin(30 * ts))
    Dt = factor * Ds
    e = edge_length(Dt, Ds)
    tt = np.arange(0, Dt + 1e-9, 1 / fs)
    out = stretch(ts, y, Dt, tt)
    head = tt <= e
    tail = tt >= Dt - e
    np.testing.assert_allclose(out[head], np.interp(tt[head], ts, y), atol=1e-12)
    np.testing.assert_allclose(out[tail], np.interp(Ds - (Dt - tt[tail]), ts, y), atol=1e-12)
    u = warp(tt, Dt, Ds)
    assert u[0] == 0 and u[-1] == pytest.approx(Ds) and np.all(np.diff(u) >= 0)
    assert out.max() <= y.max() + 1e-12 and out.min() >= y.min() - 1e-12


# --------------------------------------------------------------------------- join


def _const_piece(t0, t1, start, end, direction):
    def signal(t):
        u = np.clip((np.asarray(t) - t0) / (t1 - t0), 0, 1)[:, None]
        return np.asarray(start)[None, :] * (1 - u) + np.asarray(end)[None, :] * u

    return Piece(t0, t1, signal, direction)


@pytest.mark.parametrize("bow_change", [True, False])
def test_joined_signals_are_continuous(bow_change):
    d2 = -1 if bow_change else 1
    a = _const_piece(0.0, 0.4, [0.3, 0.8, 0.10], [0.12, 0.9, 0.11], 1)
    b = _const_piece(0.4, 0.8, [0.2 * d2, 0.5, 0.07], [0.3 * d2, 0.55, 0.07], d2)
    fs = 10000.0
    t = np.arange(0, 0.8 + 1e-12, 1 / fs)
    out = join_run([a, b], t)
    naive = np.where((t < 0.4)[:, None], a.signal(t), b.signal(t))
    jump_naive = np.abs(np.diff(naive, axis=0)).max(axis=0)
    jump = np.abs(np.diff(out, axis=0)).max(axis=0)
    # force and beta: no step; the largest frame-to-frame change is a small share of the gap
    assert np.all(jump[1:] < 0.01 * jump_naive[1:])
    assert jump[0] < 0.002 * 0.3 * fs / 100 + 1e-3  # velocity changes by < 3 mm/s per 0.1 ms
    if bow_change:
        k = np.searchsorted(t, 0.4)
        assert out[k, 0] == pytest.approx(0.0, abs=1e-12)
        assert np.all(out[:k, 0] >= 0) and np.all(out[k + 1:, 0] <= 0)
    # away from the junction each sample is untouched
    far = (np.abs(t - 0.4) > 0.031)
    np.testing.assert_allclose(out[far], naive[far], atol=1e-12)


# --------------------------------------------------------------------------- reproduction


def test_assembling_a_take_from_its_own_database_reproduces_it(tiny_db):
    from data_schemas.annotation import read_annotation
    from data_schemas.recording import read_recording
    from gesture_db.assemble import ContourSource, assemble_actions
    from gesture_db.predict import load_predictors
    from gesture_db.search import SearchIndex, search
    from gesture_db.store import GestureDB

    db = GestureDB(tiny_db / "db")
    take = sorted((tiny_db / "rec").glob("*take000.annotation.parquet"))[0]
    ann = read_annotation(take)
    rec = read_recording(str(take).replace(".annotation", ""))
    targets = _targets(ann)
    result = search(targets, SearchIndex.from_db(db), predictors=load_predictors(db))
    actions = assemble_actions(targets, result.choices, ContourSource(db))
    assert actions["bow_position"].between(0, 1).all()
    t = rec["time"].to_numpy()
    inside = np.zeros(t.size, bool)
    for a, b in zip(targets["onset"], targets["onset"] + targets["duration"], strict=True):
        inside |= (t >= a + 0.01) & (t < b - 0.01)
    played = actions.groupby("time").max()
    for column, worst in (("bow_velocity", 0.2), ("bow_force", 0.3), ("beta", 0.3)):
        x = rec[column].to_numpy()[inside]
        y = np.interp(t[inside], played.index.to_numpy(), played[column].to_numpy())
        nrmse = np.sqrt(np.mean((x - y) ** 2)) / np.std(x)
        assert nrmse < worst, (column, nrmse)


# --------------------------------------------------------------------------- pipelines


@pytest.fixture(scope="module")
def scale():
    from pipelines.methods.feedback import scale_notes

    return scale_notes(tonic=62, octaves=1, tempo=120.0)


def test_render_sampling_open_loop(tiny_db, scale):
    from pipelines.methods.sampling import open_database, render_sampling

    sdb = open_database(tiny_db / "db")
    result = render_sampling(scale, db=sdb, feedback=False, progress=False, diagnostics=True)
    part = result.parts[0]
    assert len(part.targets) == len(scale)
    assert part.performance.actions["bow_position"].between(0, 1).all()
    assert result.audio.size > 4 * 44100 and np.abs(result.audio).max() > 0
    assert part.diagnostics is not None and len(part.diagnostics)
    again = render_sampling(scale, db=sdb, feedback=False, progress=False, audio=False)
    pd.testing.assert_frame_equal(again.parts[0].performance.actions,
                                  part.performance.actions)
    # the stem was brought to its marked loudness: measured again, nothing is left to move
    from pipelines.methods.stem_balance import part_gain_db
    from pipelines.perform.config import load_config

    assert np.isfinite(part.extras["gain_db"])
    left = part_gain_db(part.audio, 44100, part.performance.events, load_config())
    assert abs(left) < 0.05


def test_sampled_strokes_bite_as_the_rules_and_say_so(tiny_db, scale, tmp_path):
    """With ``[render] bite`` listing the violin, each sampled note that starts a stroke
    plays the sampled force times the rules' bite from its onset; the choices record which
    notes bit. Without it, the forces are the same samples' as they were chosen."""
    from pipelines.methods.sampling import open_database, render_sampling
    from pipelines.perform.config import load_config
    from pipelines.perform.note_shape import bite

    off = tmp_path / "off.toml"
    off.write_text("[render]\nbite = []\n")
    bit = render_sampling(scale, db=open_database(tiny_db / "db"), feedback=False,
                          progress=False, audio=False).parts[0]
    plain = render_sampling(scale, db=open_database(tiny_db / "db", search_config=off),
                            feedback=False, progress=False, audio=False).parts[0]
    assert bit.choices["bite"].all() and not plain.choices["bite"].any()  # detache scale
    a, b = bit.performance.actions, plain.performance.actions
    pd.testing.assert_frame_equal(a.drop(columns="bow_force"), b.drop(columns="bow_force"))
    t, force = b["time"].to_numpy(), b["bow_force"].to_numpy()
    onset = bit.targets["onset"].to_numpy()
    end = onset + bit.targets["duration"].to_numpy()
    note = np.searchsorted(onset, t, side="right") - 1
    inside = (note >= 0) & (t < end[np.maximum(note, 0)]) & (force > 0) & ~b["pluck"]
    want = force.copy()
    want[inside] *= bite(t[inside], onset[note[inside]], load_config())
    np.testing.assert_allclose(a["bow_force"].to_numpy(), want, rtol=1e-6)
    assert (a["bow_force"].to_numpy()[inside] > force[inside]).mean() > 0.2


def test_short_dotted_notes_are_sampled_on_the_string_unless_asked(tiny_db, tmp_path):
    """Dotted notes played shorter than ``[render] spiccato_below`` are sampled from
    spiccato strokes (their force falls to 0 between bounces); at the shipped 0 they are
    sampled from staccato strokes, whose force stays on the string from each onset."""
    from pipelines.methods.feedback import scale_notes
    from pipelines.methods.sampling import open_database, render_sampling

    notes = scale_notes(tonic=62, octaves=1, tempo=240.0)  # 0.25 s notes, played ~0.18 s
    notes["staccato"] = True
    bounce = tmp_path / "bounce.toml"
    bounce.write_text("[render]\nspiccato_below = 0.2\n")
    parts = {name: render_sampling(notes, db=open_database(tiny_db / "db", search_config=cfg),
                                   feedback=False, progress=False, audio=False).parts[0]
             for name, cfg in (("shipped", None), ("bounce", bounce))}
    played = {k: p.targets["technique"].tolist() for k, p in parts.items()}
    assert set(played["shipped"]) == {"staccato"} and set(played["bounce"]) == {"spiccato"}
    for name, p in parts.items():
        assert p.choices["group"].str.startswith(played[name][0]).all()
        a = p.performance.actions
        t, force = a["time"].to_numpy(), a["bow_force"].to_numpy()
        at_onset = force[np.searchsorted(t, p.targets["onset"].to_numpy() + 0.01)]
        # staccato: the bow is on the string 10 ms into every note; spiccato: in the air
        if name == "shipped":
            assert (at_onset > 0.05).all()
        else:
            assert (at_onset < 0.05).mean() > 0.5


def test_missing_database_is_a_clear_error(tmp_path, scale):
    from pipelines.methods.sampling import render_sampling

    with pytest.raises(SchemaError, match="no gesture database"):
        render_sampling(scale, db=tmp_path / "nowhere", audio=False)


def test_database_of_another_schema_version_is_a_clear_error(tiny_db, tmp_path, scale):
    from pipelines.methods.sampling import render_sampling

    old = tmp_path / "old"
    shutil.copytree(tiny_db / "db", old)
    manifest = json.loads((old / "manifest.json").read_text())
    manifest["schema_version"] = "0.3"
    (old / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(SchemaError, match="schema version 0.3"):
        render_sampling(scale, db=old, audio=False)


def test_score_whose_groups_are_all_empty_is_a_clear_error(tiny_db):
    from data_schemas.annotation import read_annotation
    from gesture_db.search import EmptyGroupsError, SearchIndex, search
    from gesture_db.store import GestureDB

    index = SearchIndex.from_db(GestureDB(tiny_db / "db"))
    legato = SearchIndex({g: i for g, i in index.groups.items() if g.startswith("legato")},
                         source="legato-only")
    ann = read_annotation(sorted((tiny_db / "rec").glob("*.annotation.parquet"))[0])
    spiccato = _targets(ann[ann["technique"] == "spiccato"].reset_index(drop=True))
    assert len(spiccato)
    with pytest.raises(EmptyGroupsError, match="no compatible samples for note group") as err:
        search(spiccato, legato)
    assert isinstance(err.value, ArcoError) and "spiccato" in str(err.value)


# --------------------------------------------------------------------------- compare CLI


def test_arco_compare_writes_the_report(tiny_db, tmp_path, capsys):
    from importlib import resources

    from pipelines.cli.main import main

    score = str(resources.files("pipelines").joinpath("data/mozart-k421.mxl"))
    out = tmp_path / "report"
    assert main(["compare", score, "--methods", "rules,sampling-open", "--db",
                 str(tiny_db / "db"), "-o", str(out), "--start-measure", "1",
                 "--end-measure", "2", "--seeds", "2", "--quiet"]) == 0
    verdict, *per_instrument = capsys.readouterr().out.strip().splitlines()
    results = json.loads((out / "results.json").read_text())
    assert next(iter(results)) == "verdict" and results["verdict"] == verdict
    assert list(results["instruments"]) == ["violin"]  # the score's first part
    assert per_instrument == [results["instruments"]["violin"]["verdict"]]
    assert per_instrument[0].startswith("On the violin parts of 1 excerpt x 2 seeds, ")
    assert verdict.startswith("On 1 excerpt x 2 seeds, ")
    assert set(results["runs"]) == {"rules", "sampling-open"}
    for seed in ("0", "1"):
        piece = results["runs"]["sampling-open"]["mozart-k421"][seed]
        assert piece["notes"] > 0 and piece["render_seconds"] > 0 and "helmholtz_share" in piece
    iv = results["summary"]["rules"]["helmholtz_share"]
    assert iv["low"] <= iv["high"] and 0.0 <= iv["low"] and iv["high"] <= 1.0
    assert set(results["why"]) == {"rules", "sampling-open"}
    assert (out / "results.csv").read_text().count("\n") == 5  # header + 2 methods x 2 seeds
    page = (out / "index.html").read_text()
    assert "<audio" in page and verdict.split(",")[0] in page and "intervals.png" in page
    assert (out / "audio" / "mozart-k421-sampling-open.wav").exists()
    assert (out / "intervals.png").stat().st_size > 10_000


@pytest.mark.parametrize("args, message", [
    (["--methods", "sampling-open", "--db", "NOWHERE"], "no gesture database"),
    (["--methods", "sampling-open"], "need --db"),
    (["--methods", "feedback"], "need --models"),
    (["--methods", "bogus"], "unknown"),
])
def test_arco_compare_errors_are_one_line(tmp_path, capsys, args, message):
    from importlib import resources

    from pipelines.cli.main import main

    score = str(resources.files("pipelines").joinpath("data/mozart-k421.mxl"))
    args = [a.replace("NOWHERE", str(tmp_path / "nowhere")) for a in args]
    assert main(["compare", score, *args, "-o", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and message in err and err.startswith("arco compare: error:")


def test_the_loop_keeps_sampled_forces_in_the_playable_band(tiny_db, mf_models_dir, scale,
                                                            monkeypatch):
    """With a band, every hop's force stays within the loop range given to the controller,
    and that range is pipelines.methods.playable.loop_range of the sampled force."""
    import synth.listening.controller as controller
    from pipelines.methods.playable import loop_range
    from pipelines.methods.sampling import open_database, render_sampling
    from synth.strings import reference_forces

    seen = {}
    real = controller.play_plan

    def spy(plan, *args, **kwargs):
        log = real(plan, *args, **kwargs)
        seen.update(plan=plan, planned=kwargs["planned_force"], range=kwargs["force_range"],
                    log=log)
        return log

    monkeypatch.setattr(controller, "play_plan", spy)
    sdb = open_database(tiny_db / "db")
    render_sampling(scale, db=sdb, models=mf_models_dir, feedback=True, progress=False)
    lo, hi = seen["range"]
    plan = seen["plan"]
    want = loop_range(seen["planned"], plan.velocity, plan.beta,
                      reference_forces("violin"), 1.5)
    np.testing.assert_allclose(lo, want[0])
    np.testing.assert_allclose(hi, want[1])
    force = seen["log"].force
    bowed = force > 0
    assert np.all(force[bowed] >= lo[bowed] * (1 - 1e-12))
    assert np.all(force[bowed] <= hi[bowed] * (1 + 1e-12))
