"""``arco notes`` and ``arco render --method rules`` end to end, and their one-line errors."""

from __future__ import annotations

import importlib.util
import zipfile

import numpy as np
import pytest
from _notation_score import write_score

import pipelines.cli.main as cli
from data_schemas.actions import read_actions
from data_schemas.notes import read_notes


@pytest.fixture(autouse=True)
def only_present_commands(monkeypatch):
    """Register the commands that exist (other sub-commands are written elsewhere)."""
    present = tuple(m for m in cli.COMMAND_MODULES if importlib.util.find_spec(m) is not None)
    monkeypatch.setattr(cli, "COMMAND_MODULES", present)


@pytest.fixture(scope="module")
def score(tmp_path_factory):
    return write_score(tmp_path_factory.mktemp("score"))


def run(capsys, *argv):
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_notes_summary_and_table(score, tmp_path, capsys):
    code, out, _ = run(capsys, "notes", score)
    assert code == 0 and "part 0 'Violin' (violin)" in out and "39 notes" in out
    code, _, _ = run(capsys, "notes", score, "-o", tmp_path / "n.parquet")
    assert code == 0 and len(read_notes(tmp_path / "n.parquet")) == 39


def test_render_actions_and_plot(score, tmp_path, capsys):
    code, _, err = run(capsys, "render", score, "--method", "rules", "--part", "Violin",
                       "--skill", "1", "--seed", "3", "--start-measure", "2",
                       "--end-measure", "5", "--actions", tmp_path / "a.parquet",
                       "--plot", tmp_path / "a.png", "--quiet")
    assert code == 0, err
    actions = read_actions(tmp_path / "a.parquet")
    assert actions["time"].min() == pytest.approx(0.0, abs=0.05)
    assert actions["time"].max() < 16.01
    assert (tmp_path / "a.png").read_bytes()[:4] == b"\x89PNG"


def test_config_override(score, tmp_path, capsys):
    cfg = tmp_path / "rules.toml"
    cfg.write_text("[instruments.violin]\nforce_scale = 2.0\n")
    outs = []
    for extra in ((), ("--config", cfg)):
        path = tmp_path / f"a{len(outs)}.parquet"
        code, _, err = run(capsys, "render", score, "--method", "rules", "--actions", path,
                           "--quiet", *extra)
        assert code == 0, err
        outs.append(read_actions(path)["bow_force"].max())
    assert outs[1] == pytest.approx(2 * outs[0])
    cfg.write_text("[bow]\nmax_acceleration = -1\n")
    code, _, err = run(capsys, "render", score, "--method", "rules", "--actions",
                       tmp_path / "x.parquet", "--config", cfg)
    assert code == 2 and "bow.max_acceleration" in err


@pytest.mark.parametrize("argv, message", [
    (("--method", "gestures"), "--method 'gestures' is not available"),
    (("--method", "rules", "--part", "Cello"), "matches no parts"),
    (("--method", "rules", "--part", "3"), "out of range"),
    (("--method", "rules", "--skill", "5"), "--skill 5"),
    (("--method", "rules", "--start-measure", "40"), "no notes in measures"),
    (("--method", "rules", "--instrument", "cello", "--all-parts"), "single part"),
])
def test_render_errors_are_one_line(score, tmp_path, capsys, argv, message):
    code, _, err = run(capsys, "render", score, *argv, "--actions", tmp_path / "a.parquet")
    assert code == 2
    assert message in err and len(err.strip().splitlines()) == 1


def _corrupt_mxl(path):
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("META-INF/container.xml", "<container><rootfiles><rootfile "
                   "full-path='score.xml'/></rootfiles></container>")
        z.writestr("score.xml", "<score-partwise><part-list>")
    return path


@pytest.mark.parametrize("name, content", [
    ("empty.musicxml", b""), ("broken.musicxml", b"<score-partwise><part"),
    ("garbage.mxl", b"PK\x03\x04 not a zip"), ("corrupt.mxl", None),
    ("noise.mid", b"MThd\x00\x00"), ("empty.mid", b""), ("score.pdf", b"%PDF-1.4"),
    ("missing.musicxml", False),
])
def test_bad_score_files_exit_2_naming_the_file(tmp_path, capsys, name, content):
    path = tmp_path / name
    if content is None:
        _corrupt_mxl(path)
    elif content is not False:
        path.write_bytes(content)
    for argv in (("notes", path), ("render", path, "--method", "rules", "--actions",
                                   tmp_path / "a.parquet")):
        code, _, err = run(capsys, *argv)
        assert code == 2, err
        assert str(path) in err and len(err.strip().splitlines()) == 1
        assert "Traceback" not in err


def test_render_audio_all_parts(tmp_path, capsys):
    pytest.importorskip("synth", reason="synthesizer not present")
    import soundfile
    from music21 import note, stream

    score = stream.Score()
    for name, pitches in (("Violin", ["A4", "B4"]), ("Violoncello", ["C3", "D3"])):
        part = stream.Part()
        part.partName = name
        for p in pitches:
            part.append(note.Note(p, quarterLength=1))
        score.insert(0, part)
    path = tmp_path / "duo.musicxml"
    score.write("musicxml", fp=str(path))
    code, _, err = run(capsys, "render", path, "--method", "rules", "--all-parts",
                       "-o", tmp_path / "duo.wav", "--actions", tmp_path / "duo.parquet",
                       "--sample-rate", "48000", "--quiet")
    assert code == 0, err
    audio, rate = soundfile.read(tmp_path / "duo.wav")
    assert rate == 48000 and audio.ndim == 1 and audio.size > 48000 * 0.9
    # The instrument level is kept (attenuated only if the mix would clip).
    assert 0.01 < np.abs(audio).max() <= 0.89 and np.isfinite(audio).all()
    assert (tmp_path / "duo-0-violin.parquet").exists()
    assert (tmp_path / "duo-1-cello.parquet").exists()
