import numpy as np
import pytest
from _listening import d_string_notes

from data_schemas.actions import validate_actions
from pipelines.listening.evaluate import evaluate
from pipelines.methods.feedback import render_feedback, scale_notes
from pipelines.perform.config import load_config
from pipelines.perform.rules import perform_part
from synth import render_with_diagnostics

CFG = load_config()
# The rules' bow lanes as written (no loudness evening-out, which moves notes along them).
CFG["loudness"]["enabled"] = False


@pytest.fixture(scope="module")
def feedback(models_dir):
    return render_feedback(d_string_notes(), CFG, models_dir=models_dir, instrument="violin",
                           seed=0)


def test_feedback_render_records_what_it_played(feedback):
    audio, actions, diagnostics, perf = feedback
    validate_actions(actions)
    assert audio.dtype == np.float32 and np.isfinite(audio).all()
    bowed = actions[actions["bow_force"] > 0]
    assert set(bowed["string"]) == {1}
    # The force is the controller's: it varies from hop to hop (jitter, feedback).
    assert bowed["bow_force"].diff().abs().median() > 0
    # Velocity and beta are the rules' bow lane (mf: 0.33 m/s, beta 0.10), within jitter.
    assert np.isclose(bowed["beta"].median(), 0.10)
    assert abs(bowed["bow_velocity"].abs().max() - 0.33) < 0.03
    assert set(diagnostics["string"]) == {1}


def test_feedback_is_deterministic(models_dir, feedback):
    again = render_feedback(d_string_notes(), CFG, models_dir=models_dir,
                            instrument="violin", seed=0)
    np.testing.assert_array_equal(again[0], feedback[0])


def test_feedback_beats_wrong_fixed_forces(feedback):
    audio, actions, diagnostics, _ = feedback
    ours = evaluate(audio, actions, diagnostics=diagnostics)["piece"]["sustained_class3_share"]
    perf = perform_part(d_string_notes(), CFG, instrument="violin")
    for force in (0.08, 5.0):
        wrong = perf.actions.copy()
        wrong.loc[wrong["bow_force"] > 0, "bow_force"] = force
        au, dg = render_with_diagnostics(wrong, instrument="violin", seed=0)
        theirs = evaluate(au, wrong, diagnostics=dg)["piece"]["sustained_class3_share"]
        assert ours > theirs + 0.2, (force, ours, theirs)


def test_feedback_refuses_a_part_without_models_of_its_instrument(models_dir):
    from synth.listening.classifier import ModelError

    cello = scale_notes(tonic=48, octaves=1, instrument="cello")
    with pytest.raises(ModelError, match="feedback needs cello models for this cello part"):
        render_feedback(cello, CFG, models_dir=models_dir, seed=0)


def test_feedback_loads_the_models_of_the_parts_instrument(models_dir, monkeypatch):
    import synth.listening.classifier as classifier

    asked = []
    real = classifier.load_models

    def spy(directory, instrument, *args):
        asked.append(instrument)
        return real(directory, "violin", *args)  # the fixture holds violin models only

    monkeypatch.setattr(classifier, "load_models", spy)
    viola = scale_notes(tonic=55, octaves=1, instrument="viola")  # G3 A3 B3: the G string
    render_feedback(viola[viola["midi_pitch"] < 60], CFG, models_dir=models_dir, seed=0,
                    diagnostics=False)
    assert asked == ["viola"]


def test_feedback_starts_each_note_at_the_rules_force(feedback):
    _, actions, _, perf = feedback
    rules = perf.actions[perf.actions["bow_force"] > 0]
    played = actions[actions["bow_force"] > 0]
    # The first hop of the first stroke plays the rules' force (within the 1 % jitter).
    t0 = played["time"].iloc[0]
    planned = np.interp(t0, rules["time"], rules["bow_force"])
    assert abs(played["bow_force"].iloc[0] / planned - 1.0) < 0.05


def test_feedback_rehearses_like_the_rules(models_dir):
    """With ``[loudness] rehearsals``, feedback keeps the take whose notes came nearest
    their loudness goals: never further than its first take (the render without
    rehearsal), and the actions and diagnostics returned are the kept take's."""
    from pipelines.methods.feedback import hop_plan
    from pipelines.methods.rehearsal import note_errors, try_score

    loud = load_config()
    once = load_config()
    once["loudness"]["rehearsals"] = 0
    notes = d_string_notes()
    first = render_feedback(notes, once, models_dir=models_dir, instrument="violin", seed=0)
    kept = render_feedback(notes, loud, models_dir=models_dir, instrument="violin", seed=0)

    def miss(render):
        audio, _, _, perf = render
        return float(try_score(note_errors(audio, 44100, perf)[None, :])[0])

    assert np.isfinite(miss(first)) and miss(kept) <= miss(first)
    audio, actions, diagnostics, perf = kept
    # The actions follow the kept take's plan: its bow lanes' velocity, within the jitter.
    plan, _ = hop_plan(perf, loud, "violin")
    bowed = actions[actions["bow_force"] > 0]
    hop = np.rint(bowed["time"].to_numpy() * 44100 / 256).astype(int) - 1
    planned = np.abs(plan.velocity[hop, 1])
    moving = planned > 0.05
    played = bowed["bow_velocity"].abs().to_numpy()[moving]
    assert np.median(np.abs(played / planned[moving] - 1.0)) < 0.02
    # The take kept is not the first (rehearsal moved the levels), nor are its diagnostics.
    assert not np.allclose(perf.events["dynamic"], first[3].events["dynamic"])
    assert len(diagnostics) != len(first[2]) or not diagnostics.equals(first[2])
