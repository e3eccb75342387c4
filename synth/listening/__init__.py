"""The virtual violinist's ears: features, teacher, classifiers, training, feedback control."""

from synth.listening.classifier import (
    DYNAMICS,
    FINGERS,
    ModelError,
    PairModel,
    load_models,
    load_pair,
    save_pair,
)
from synth.listening.controller import ControllerSettings, HopPlan, play_plan
from synth.listening.features import FEATURE_NAMES, StreamingFeatures, batch_features

__all__ = ["DYNAMICS", "FEATURE_NAMES", "FINGERS", "ControllerSettings", "HopPlan",
           "ModelError", "PairModel", "StreamingFeatures", "batch_features", "load_models",
           "load_pair", "play_plan", "save_pair"]
