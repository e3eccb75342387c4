"""Shared settings of the listening tests: the full training's clips, tiny K and force searches.

The clips (settle, record, band clips, force grid) are those of the full training, so the
classifiers' cross-validated accuracy is the one the full training reports for these pairs;
only the K and initial-force searches are cut down.
"""

from synth.listening.training import TrainingSettings

TINY = TrainingSettings(settle=0.7, record=0.3, band_clips=2, k_candidates=(1.005, 1.02),
                        k_repeats=1, k_note=0.5, f_candidates=4, f_rounds=1, f_repeats=1,
                        f_note=0.5)

import pytest  # noqa: E402

PAIR = (1, "mf")
MF_PAIRS = [(s, "mf") for s in range(4)]


@pytest.fixture(scope="session")
def models_dir(tmp_path_factory):
    """Violin D-string mf pair trained with TINY grids (reused: training resumes)."""
    from pipelines.listening.train import train_instrument

    out = tmp_path_factory.getbasetemp() / "listening-models"
    train_instrument("violin", out, pairs=[PAIR], settings=TINY, workers=1, progress=False)
    return out


@pytest.fixture(scope="session")
def mf_models_dir(models_dir):
    """All four violin mf pairs (TINY grids, two workers), beside the D-string pair."""
    from pipelines.listening.train import train_instrument

    train_instrument("violin", models_dir, pairs=MF_PAIRS, settings=TINY, workers=2,
                     progress=False)
    return models_dir


def d_string_notes():
    """D4 E4 F#4 G4 at mf, one second each: all on the D string."""
    from pipelines.methods.feedback import scale_notes

    notes = scale_notes(tonic=62, octaves=1)
    return notes[notes["midi_pitch"] < 69].reset_index(drop=True)
