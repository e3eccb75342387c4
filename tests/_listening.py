"""Shared settings of the listening tests: the full training's clips, tiny K and force searches.

The trained-model fixtures built with them are in ``conftest.py``.

The clips (settle, record, band clips, force grid) are those of the full training, so the
classifiers' cross-validated accuracy is the one the full training reports for these pairs;
only the K and initial-force searches are cut down.
"""

from synth.listening.training import TrainingSettings

TINY = TrainingSettings(settle=0.7, record=0.3, band_clips=2, k_candidates=(1.005, 1.02),
                        k_repeats=1, k_note=0.5, f_candidates=4, f_rounds=1, f_repeats=1,
                        f_note=0.5)

PAIR = (1, "mf")
MF_PAIRS = [(s, "mf") for s in range(4)]


def d_string_notes():
    """D4 E4 F#4 G4 at mf, one second each: all on the D string."""
    from pipelines.methods.feedback import scale_notes

    notes = scale_notes(tonic=62, octaves=1)
    return notes[notes["midi_pitch"] < 69].reset_index(drop=True)
