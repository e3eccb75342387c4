"""Acceptance: a two-octave scale under feedback control sounds right (issue 4, item 7)."""

import pytest
from _listening import MF_PAIRS

from pipelines.listening.evaluate import evaluate
from pipelines.methods.feedback import render_feedback, scale_notes
from pipelines.perform.config import load_config
from pipelines.perform.rules import perform_part
from synth import render_with_diagnostics
from synth.listening.classifier import load_pair

CFG = load_config()


@pytest.fixture(scope="module")
def scale():
    """G3..G5 major scale at mf, one note per second: every violin string."""
    return scale_notes(tonic=55, octaves=2)


@pytest.fixture(scope="module")
def feedback_share(mf_models_dir, scale):
    audio, actions, diagnostics, _ = render_feedback(scale, CFG, models_dir=mf_models_dir,
                                                     instrument="violin", seed=0)
    piece = evaluate(audio, actions, diagnostics=diagnostics)["piece"]
    assert piece["notes"] == len(scale)
    return piece["sustained_class3_share"]


def test_scale_under_feedback_is_class_3_on_nine_tenths_of_sustained_hops(feedback_share):
    assert feedback_share >= 0.9


@pytest.mark.parametrize("force", [0.1, 4.0])
def test_scale_under_feedback_beats_wrong_fixed_forces(feedback_share, scale, force):
    wrong = perform_part(scale, CFG, instrument="violin").actions.copy()
    wrong.loc[wrong["bow_force"] > 0, "bow_force"] = force
    audio, diagnostics = render_with_diagnostics(wrong, instrument="violin", seed=0)
    theirs = evaluate(audio, wrong, diagnostics=diagnostics)["piece"]["sustained_class3_share"]
    assert feedback_share > theirs + 0.5, (force, feedback_share, theirs)


def test_cv_accuracy_by_clip_of_every_mf_pair_reaches_the_target(mf_models_dir):
    accuracy = {s: load_pair(mf_models_dir, "violin", s, d).metadata["cv_accuracy"]
                for s, d in MF_PAIRS}
    assert min(accuracy.values()) >= 0.95, accuracy
