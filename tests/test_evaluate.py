import json

import numpy as np
import pytest
import soundfile

from data_schemas.actions import write_actions
from data_schemas.diagnostics import CONTACT_DIAGNOSTICS
from data_schemas.io import write_table
from pipelines.cli.main import main
from pipelines.listening.evaluate import evaluate, find_notes
from pipelines.perform.scale import scale_actions
from synth import render_with_diagnostics

PIECE_KEYS = {"notes", "helmholtz_share", "attack_ms_median", "attack_ms_p90",
              "pitch_error_cents_median", "level_error_db_median", "class_histogram"}


@pytest.fixture(scope="module")
def rendered():
    actions, _ = scale_actions("violin", note_duration=0.5)
    actions = actions[actions["string"] == 1].reset_index(drop=True)
    actions["time"] -= actions["time"].min()
    audio, diagnostics = render_with_diagnostics(actions, instrument="violin", seed=0)
    return audio, actions, diagnostics


def test_notes_are_found_in_the_actions(rendered):
    _, actions, _ = rendered
    notes = find_notes(actions)
    assert len(notes) == 5 and notes["semitones"].tolist() == [0, 2, 4, 5, 7]


def test_reference_scale_is_helmholtz_with_diagnostics_and_audio_only(rendered):
    audio, actions, diagnostics = rendered
    for diag, source in ((diagnostics, "instrument diagnostics"), (None, "audio-only estimates")):
        result = evaluate(audio, actions, diagnostics=diag)
        piece = result["piece"]
        assert result["measured_from"] == source
        assert PIECE_KEYS <= set(piece) and piece["notes"] == 5
        assert piece["helmholtz_share"] > 0.8
        assert abs(piece["pitch_error_cents_median"]) < 10
        assert all(n["reached_helmholtz"] for n in result["notes"])


def test_evaluate_cli_json(rendered, tmp_path, capsys):
    audio, actions, diagnostics = rendered
    wav, act, diag = tmp_path / "a.wav", tmp_path / "a.parquet", tmp_path / "d.parquet"
    soundfile.write(str(wav), audio, 44100, subtype="FLOAT")
    write_actions(actions, act)
    write_table(diagnostics, diag, CONTACT_DIAGNOSTICS)
    assert main(["evaluate", str(wav), "--actions", str(act), "--diagnostics", str(diag),
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert PIECE_KEYS <= set(out["piece"]) and isinstance(out["notes"], list)
    assert out["measured_from"] == "instrument diagnostics"
    assert set(out["piece"]["class_histogram"]) == {"1", "2", "3", "4", "5"}
    assert main(["evaluate", str(tmp_path / "missing.wav"), "--actions", str(act)]) == 2
    assert np.isfinite(out["piece"]["helmholtz_share"])


@pytest.mark.parametrize(("samples", "expected"), [
    (np.zeros(44100, np.float32), "silent"),
    (np.r_[np.zeros(10), np.nan, np.zeros(10)].astype(np.float32), "not finite from sample 10")])
def test_evaluate_refuses_silent_or_non_finite_audio_naming_the_file(tmp_path, capsys,
                                                                     samples, expected):
    wav = tmp_path / "bad.wav"
    soundfile.write(wav, samples, 44100, subtype="FLOAT")
    code = main(["evaluate", str(wav), "--actions", str(tmp_path / "missing.parquet")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1
    assert str(wav) in err[0] and expected in err[0]
