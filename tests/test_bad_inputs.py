"""Every bad input is one line on stderr naming the file, and exit code 2 (no traceback).

Grouped by the reader that must catch the problem. Each test crafts the bad file in
``tmp_path`` and drives the real ``arco`` command (or the reader function).
"""

from __future__ import annotations

import mido
import pytest

from pipelines.cli.main import main


def _arco_fails(capsys, *argv: str) -> str:
    """Run ``arco argv``; assert exit 2 with a single stderr line; return that line."""
    capsys.readouterr()
    code = main([str(a) for a in argv])
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert "Traceback" not in err
    assert len(err.splitlines()) == 1, err
    return err


# --- pipelines/score/midi.py -------------------------------------------------------------


def _midi(path, *, ticks_per_beat: int = 480, tempo: int = 500000):
    mid = mido.MidiFile(ticks_per_beat=ticks_per_beat)
    track = mido.MidiTrack()
    track.append(mido.MetaMessage("set_tempo", tempo=tempo, time=0))
    track.append(mido.Message("note_on", note=60, velocity=64, time=0))
    track.append(mido.Message("note_off", note=60, velocity=0, time=480))
    mid.tracks.append(track)
    mid.save(path)
    return path


def test_midi_ticks_per_beat_zero(tmp_path, capsys):
    path = _midi(tmp_path / "tpb0.mid", ticks_per_beat=0)
    err = _arco_fails(capsys, "notes", path)
    assert str(path) in err and "ticks per beat" in err


def test_midi_tempo_zero_names_track_and_tick(tmp_path, capsys):
    path = _midi(tmp_path / "tempo0.mid", tempo=0)
    err = _arco_fails(capsys, "notes", path)
    assert str(path) in err and "track 0" in err and "tempo" in err


# --- pipelines/score/musicxml.py ---------------------------------------------------------

_MUSICXML = """<?xml version="1.0" encoding="UTF-8"?>
<score-partwise version="3.1">
  <part-list><score-part id="P1"><part-name>Violin</part-name></score-part></part-list>
  <part id="P1">
    <measure number="1">
      <attributes><divisions>1</divisions></attributes>
      <note><pitch><step>A</step><octave>4</octave></pitch><duration>4</duration></note>
    </measure>
    <measure number="2">
      <direction><direction-type><metronome><beat-unit>quarter</beat-unit>
        <per-minute>{per_minute}</per-minute></metronome></direction-type></direction>
      <note><pitch><step>A</step><octave>4</octave></pitch><duration>4</duration></note>
    </measure>
  </part>
</score-partwise>
"""


@pytest.mark.parametrize("per_minute", ["0", "-60"])
def test_musicxml_metronome_not_positive(tmp_path, capsys, per_minute):
    path = tmp_path / "tempo.musicxml"
    path.write_text(_MUSICXML.format(per_minute=per_minute))
    err = _arco_fails(capsys, "notes", path)
    assert str(path) in err and "measure 2" in err and "metronome" in err


def test_musicxml_good_metronome_still_reads(tmp_path, capsys):
    path = tmp_path / "tempo.musicxml"
    path.write_text(_MUSICXML.format(per_minute="30"))
    assert main(["notes", str(path)]) == 0
    # the first mark's tempo also applies before it: 8 beats at 30 qpm
    assert "16.0 s" in capsys.readouterr().out
