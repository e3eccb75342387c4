"""``arco demo`` writes its audio, plots and report."""

import numpy as np
import soundfile as sf

from pipelines.cli.main import main


def test_demo_writes_audio_plots_and_report(tmp_path):
    assert main(["demo", "-o", str(tmp_path), "--skip-learning"]) == 0
    for name in ("scales.wav", "mozart-k421-rules.wav"):
        audio, rate = sf.read(tmp_path / name)
        assert rate == 44100 and np.isfinite(audio).all() and np.abs(audio).max() > 0.01
    assert (tmp_path / "scales_cello.png").stat().st_size > 10_000
    assert (tmp_path / "mozart-k421-rules.png").stat().st_size > 10_000
    report = (tmp_path / "report.md").read_text()
    cents = [float(line.split("|")[3]) for line in report.splitlines()
             if line.startswith("| violin |")]
    assert len(cents) == 20 and max(abs(c) for c in cents) < 25


def test_demo_says_when_the_held_out_protocol_cannot_run(tmp_path, monkeypatch, capsys):
    import pipelines.shared_data as shared
    from pipelines.cli.commands.demo import heldout_story


    monkeypatch.setattr(shared, "candidates", lambda: [tmp_path / "none"])
    lines = heldout_story(tmp_path, workers=1)
    assert lines[0] == "## The held-out protocol (quick run)"
    assert any(line.startswith("Not run: shared data not found") for line in lines)
    assert "held-out protocol skipped" in capsys.readouterr().out
