"""``arco notes`` and ``arco render --method rules`` end to end, and their one-line errors."""

from __future__ import annotations

import zipfile

import numpy as np
import pytest
from _notation_score import write_score

import pipelines.cli.main as cli
from data_schemas.actions import read_actions
from data_schemas.notes import read_notes


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
    # rehearsal would hear the louder notes and bow them softer: off in both
    plain, cfg = tmp_path / "plain.toml", tmp_path / "rules.toml"
    plain.write_text("[loudness]\nrehearsals = 0\n")
    from pipelines.perform.config import load_config

    rows = load_config()["bow_force"]["violin"]
    cfg.write_text("[loudness]\nrehearsals = 0\n[bow_force.violin]\n" + "".join(
        f"{name} = {[2.0 * f for f in row]}\n" for name, row in rows.items()))
    outs = []
    for extra in (("--config", plain), ("--config", cfg)):
        path = tmp_path / f"a{len(outs)}.parquet"
        code, _, err = run(capsys, "render", score, "--method", "rules", "--actions", path,
                           "--quiet", *extra)
        assert code == 0, err
        outs.append(read_actions(path)["bow_force"].max())
    assert outs[1] == pytest.approx(2.0 * outs[0])
    cfg.write_text("[instruments.violin]\nforce_scale = 2.0\n")
    code, _, err = run(capsys, "render", score, "--method", "rules", "--actions",
                       tmp_path / "x.parquet", "--config", cfg)
    assert code == 2 and "instruments.violin.force_scale" in err and "[bow_force." in err
    cfg.write_text("[bow]\nmax_acceleration = -1\n")
    code, _, err = run(capsys, "render", score, "--method", "rules", "--actions",
                       tmp_path / "x.parquet", "--config", cfg)
    assert code == 2 and "bow.max_acceleration" in err


@pytest.mark.parametrize("argv, message", [
    (("--method", "gestures"), "--method gestures: unknown method (choose from: rules,"),
    (("--method", "feedback"), "feedback: need --models DIR"),
    (("--method", "sampling", "--models", "."), "sampling: need --db DB"),
    (("--method", "sampling-open", "--db", "NOWHERE"), "no gesture database"),
    (("--method", "rules", "--models", "NOWHERE"), "--models NOWHERE: no such directory"),
    (("--method", "rules", "--part", "Cello"), "matches no parts"),
    (("--method", "rules", "--part", "3"), "out of range"),
    (("--method", "rules", "--skill", "5"), "--skill 5"),
    (("--method", "rules", "--start-measure", "40"), "no notes in measures"),
    (("--method", "rules", "--instrument", "cello", "--all-parts"), "single part"),
])
def test_render_errors_are_one_line(score, tmp_path, capsys, argv, message):
    argv = [str(tmp_path / "nowhere") if a == "NOWHERE" else a for a in argv]
    message = message.replace("NOWHERE", str(tmp_path / "nowhere"))
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
    # A stereo master in the hall (its tail longer than the music), peak under -1 dBFS.
    assert rate == 48000 and audio.shape[1] == 2 and audio.shape[0] > 48000 * 2.5
    assert 0.01 < np.abs(audio).max() <= 10 ** (-1 / 20) and np.isfinite(audio).all()
    for stem in ("duo-0-violin.wav", "duo-1-cello.wav"):
        assert soundfile.info(tmp_path / stem).channels == 2
    assert (tmp_path / "duo-0-violin.parquet").exists()
    assert (tmp_path / "duo-1-cello.parquet").exists()


class Silence:
    """An engine that plays nothing and remembers what it was built for."""

    built: list[tuple[str, int, int]] = []
    has_diagnostics = False
    n_strings = 4

    def __init__(self, instrument="violin", *, sample_rate=44100, seed=0, **options):
        self.name, self.sample_rate = instrument, sample_rate
        Silence.built.append((instrument, sample_rate, seed))

    def reset(self):
        pass

    def process(self, n_samples, controls=None, *, plucks=(), diagnostics=True):
        raise NotImplementedError

    def render(self, actions, *, tail=0.5, progress=False, diagnostics=False):
        n = int((float(actions["time"].max()) + tail) * self.sample_rate)
        return np.zeros(n, np.float32), None


@pytest.fixture
def silence():
    from synth.engines import register_engine, unregister_engine

    Silence.built.clear()
    register_engine("silence", Silence, "plays nothing (a test engine)")
    yield Silence
    unregister_engine("silence")


def test_engine_option_reaches_the_engine(score, tmp_path, capsys, silence):
    import soundfile

    code, _, err = run(capsys, "render", score, "--method", "rules", "--engine", "silence",
                       "--seed", "3", "--end-measure", "2", "-o", tmp_path / "s.wav", "--quiet")
    assert code == 0, err
    audio, _ = soundfile.read(tmp_path / "s.wav")
    assert audio.size > 0 and not audio.any()
    assert silence.built == [("violin", 44100, 3)]
    code, out, _ = run(capsys, "engines")
    assert code == 0 and out.splitlines()[0].startswith("modal ")
    assert any(line.split()[0] == "silence" for line in out.splitlines())


def test_synth_engine_option(tmp_path, capsys, silence):
    from data_schemas.actions import write_actions
    from pipelines.perform.scale import scale_actions

    write_actions(scale_actions("viola")[0], tmp_path / "a.parquet")
    code, _, err = run(capsys, "synth", tmp_path / "a.parquet", "--instrument", "viola",
                       "--engine", "silence", "--seed", "5", "-o", tmp_path / "a.wav")
    assert code == 0, err
    assert silence.built == [("viola", 44100, 5)]


def test_unknown_engine_is_a_usage_error(score, tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        cli.main(["render", str(score), "--engine", "nonesuch", "-o", str(tmp_path / "a.wav")])
    assert exc.value.code == 2 and "invalid choice: 'nonesuch'" in capsys.readouterr().err
