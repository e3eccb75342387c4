"""The ensemble: pan law, the room's RT60, loudness, stems, determinism, players' timing."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
import scipy.io.wavfile
import scipy.signal
import soundfile as sf

import pipelines.cli.main as cli
from pipelines.ensemble.config import load_ensemble
from pipelines.ensemble.mixdown import mixdown
from pipelines.ensemble.wav_stream import audio_writer
from pipelines.perform.timing import downbeats, player_deviation
from synth.lufs import LoudnessMeter, integrated_loudness, k_weighting
from synth.pan import Panner, pan_gains
from synth.room import BlockConvolver, room_response, schroeder_rt60

RATE = 44100


def _tone(seconds: float, freq: float, amp: float, rate: int = RATE) -> np.ndarray:
    t = np.arange(int(seconds * rate)) / rate
    return (amp * np.sin(2 * np.pi * freq * t) * np.minimum(1.0, 20 * t)).astype(np.float32)


def _sources(folder, signals, rate=RATE):
    paths = []
    for k, x in enumerate(signals):
        paths.append(folder / f"src{k}.wav")
        scipy.io.wavfile.write(paths[-1], rate, x)
    return paths


def test_pan_law_keeps_power_and_places_left_left():
    positions = np.linspace(-1, 1, 41)
    power = [sum(g * g for g in pan_gains(p)) for p in positions]
    assert np.allclose(power, 1.0, atol=1e-12)
    left, right = pan_gains(-0.7)
    assert left > right and pan_gains(0.7) == pytest.approx((right, left))
    # The interaural delay moves energy in time, not in level.
    x = np.random.default_rng(0).standard_normal(5000)
    p = Panner(-0.7, RATE)
    y = np.vstack([p.process(x[:1234]), p.process(x[1234:]), p.flush()])
    assert (y ** 2).sum() == pytest.approx((x ** 2).sum())
    assert np.argmax(np.correlate(y[:, 1], x, "full")) - (x.size - 1) == p.latency > 0


@pytest.mark.parametrize("rt60", [0.8, 1.8, 2.6])
def test_room_rt60_by_schroeder_within_ten_percent(rt60):
    ir = room_response(RATE, rt60=rt60, seed=4)
    measured = []
    for centre in (500.0, 1000.0):
        sos = scipy.signal.butter(4, (centre / 2 ** 0.5, centre * 2 ** 0.5), "bandpass",
                                  fs=RATE, output="sos")
        measured += [schroeder_rt60(scipy.signal.sosfilt(sos, ir[:, ch]), RATE)
                     for ch in (0, 1)]
    assert abs(np.mean(measured) / rt60 - 1) < 0.10, measured
    # Decorrelated ears, and the treble dies sooner than the bass (air absorption).
    assert abs(np.corrcoef(ir.T)[0, 1]) < 0.2
    rts = []
    for band in ((177.0, 354.0), (2830.0, 5660.0)):
        sos = scipy.signal.butter(4, band, "bandpass", fs=RATE, output="sos")
        rts.append(schroeder_rt60(scipy.signal.sosfilt(sos, ir[:, 0]), RATE))
    assert rts[0] > rts[1]


def test_schroeder_reads_a_known_decay():
    """Independent truth: noise whose energy falls 60 dB in exactly 1.5 s."""
    t = np.arange(3 * 8000) / 8000
    ir = np.random.default_rng(1).standard_normal(t.size) * 10 ** (-3 * t / 1.5)
    assert schroeder_rt60(ir, 8000) == pytest.approx(1.5, rel=0.03)


def test_room_is_seeded():
    a, b = room_response(RATE, seed=1), room_response(RATE, seed=1)
    assert np.array_equal(a, b) and not np.array_equal(a, room_response(RATE, seed=2))


def test_block_convolution_equals_full_convolution():
    rng = np.random.default_rng(2)
    x, h = rng.standard_normal(20000), rng.standard_normal((3000, 2))
    conv, out, start = BlockConvolver(h), [], 0
    for n in (1, 700, 5000, 3, 14296):
        out.append(conv.process(x[start:start + n]))
        start += n
    y = np.vstack(out + [conv.flush()])
    full = np.stack([scipy.signal.fftconvolve(x, h[:, c]) for c in (0, 1)], axis=1)
    assert y.shape == full.shape and np.allclose(y, full, atol=1e-9)


def test_k_weighting_and_reference_tone():
    """BS.1770-4: its 48 kHz coefficients; a 0 dBFS 997 Hz sine in one channel is -3.01."""
    sos = k_weighting(48000)
    assert np.allclose(sos[0, :3], [1.53512485958697, -2.69169618940638, 1.19839281085285])
    assert np.allclose(sos[1, 4:], [-1.99004745483398, 0.99007225036621])
    for rate in (44100, 48000):
        t = np.arange(10 * rate) / rate
        x = np.stack([np.sin(2 * np.pi * 997 * t), np.zeros_like(t)], axis=1)
        assert integrated_loudness(x, rate) == pytest.approx(-3.01, abs=0.02)
    # Gating: 10 s of a tone then 10 s of silence reads as the tone alone (ungated: -3 dB;
    # the three 400 ms blocks across the edge pass the gate and lower it by 0.07 dB).
    tone = 0.1 * np.sin(2 * np.pi * 997 * np.arange(10 * RATE) / RATE)
    both = np.concatenate([tone, np.zeros_like(tone)])
    assert integrated_loudness(both, RATE) == pytest.approx(integrated_loudness(tone, RATE),
                                                            abs=0.1)
    meter = LoudnessMeter(RATE, 1)
    meter.add(np.zeros((RATE, 1)))
    assert meter.integrated() == -math.inf


def test_streamed_wav_is_scipys_bytes(tmp_path):
    x = np.random.default_rng(3).standard_normal((1001, 2)).astype(np.float32)
    with audio_writer(tmp_path / "a.wav", RATE, 2) as out:
        for start in range(0, 1001, 300):
            out.write(x[start:start + 300])
    scipy.io.wavfile.write(tmp_path / "b.wav", RATE, x)
    assert (tmp_path / "a.wav").read_bytes() == (tmp_path / "b.wav").read_bytes()


def test_dry_mix_is_the_sum_of_panned_stems_at_the_target_loudness(tmp_path):
    signals = [_tone(3.0, 440, 0.05), _tone(2.0, 220, 0.2), _tone(2.5, 110, 0.1)]
    sources = _sources(tmp_path, signals)
    settings = load_ensemble()
    settings["room"]["kind"] = "none"
    stems = [tmp_path / f"stem{k}.wav" for k in range(3)]
    report = mixdown(sources, tmp_path / "mix.wav", pans=[-0.7, 0.0, 0.7], ensemble=settings,
                     stems=stems)
    mix, rate = sf.read(tmp_path / "mix.wav")
    total = sum(sf.read(s)[0] for s in stems)
    assert rate == RATE and mix.shape == total.shape and mix.shape[1] == 2
    assert np.allclose(mix, total, atol=1e-6)
    assert integrated_loudness(mix, RATE) == pytest.approx(-18.0, abs=0.5)
    assert report.loudness == pytest.approx(-18.0, abs=0.01) and not report.limited
    left = sf.read(stems[0])[0]
    assert (left[:, 0] ** 2).sum() > 4 * (left[:, 1] ** 2).sum()
    gain = 10 ** (report.gain_db / 20)
    assert np.allclose(left[:, 0], gain * pan_gains(-0.7)[0] * np.pad(
        signals[0], (0, len(left) - len(signals[0]))), atol=1e-6)


def test_hall_mix_stays_under_the_ceiling_and_is_deterministic(tmp_path):
    # A loud click over quiet music: reaching -12 LUFS would clip, so the gain is limited.
    spiky = _tone(3.0, 440, 0.02)
    spiky[RATE] = 0.9
    sources = _sources(tmp_path, [spiky, _tone(3.0, 330, 0.02)])
    settings = load_ensemble()
    settings["master"]["loudness"] = -12.0
    for name in ("a.wav", "b.wav"):
        report = mixdown(sources, tmp_path / name, pans=[-0.5, 0.5], ensemble=settings)
    mix = sf.read(tmp_path / "a.wav")[0]
    assert report.limited and np.abs(mix).max() <= 10 ** (-1 / 20)
    assert integrated_loudness(mix, RATE) < -12.5
    assert mix.shape[0] > 3 * RATE + 2 * RATE  # the hall's tail
    assert (tmp_path / "a.wav").read_bytes() == (tmp_path / "b.wav").read_bytes()
    settings["master"]["loudness"] = -40.0
    report = mixdown(sources, tmp_path / "c.wav", pans=[-0.5, 0.5], ensemble=settings)
    assert not report.limited
    assert integrated_loudness(sf.read(tmp_path / "c.wav")[0], RATE) == pytest.approx(
        -40.0, abs=0.5)


def test_timing_deviation_is_zero_at_downbeats_and_bounded():
    knots = np.arange(0.0, 40.0, 2.0)
    t = np.linspace(0, 40, 40001)
    devs = [player_deviation(knots, seed=5, part_index=k, sigma=0.004, limit=0.012)(t)
            for k in range(4)]
    for dev in devs:
        assert np.abs(dev).max() <= 0.012 and np.abs(dev).max() > 0.001
        for knot in knots:
            assert player_deviation(knots, seed=5, part_index=0, sigma=0.004,
                                    limit=0.012)(np.array([knot]))[0] == 0.0
        assert np.all(np.diff(t + dev) > 0)  # time never runs backwards
        assert np.abs(np.diff(dev)).max() < 1e-4  # smooth: no jumps
    assert not np.allclose(devs[0], devs[1])
    again = player_deviation(knots, seed=5, part_index=0, sigma=0.004, limit=0.012)(t)
    assert np.array_equal(again, devs[0])


def test_downbeats_from_measure_changes():
    notes = pd.DataFrame({"onset": [0.0, 0.0, 1.0, 1.5, 3.0, 3.0, 5.0],
                          "measure": [1, 1, 1, 2, 2, 3, 1]})
    # A repeated number (a new movement) is a new bar; a measure starting late starts late.
    assert downbeats(notes).tolist() == [0.0, 1.5, 3.0, 5.0]


def test_quartet_players_together_at_downbeats(tmp_path):
    from pipelines.methods.rules import render
    from pipelines.perform.config import load_config

    rows = []
    for part in range(4):
        for i in range(16):  # four bars of four quarter notes at 60 bpm
            rows.append({"part_index": part, "part_name": f"p{part}", "part_id": f"P{part}",
                         "instrument": "cello" if part == 3 else "violin",
                         "measure": 1 + i // 4, "onset": float(i), "duration": 1.0,
                         "onset_beats": float(i), "duration_beats": 1.0,
                         "midi_pitch": 48 if part == 3 else 67})
    from pipelines.methods.feedback import scale_notes

    template = scale_notes(tonic=62, octaves=1)
    notes = pd.DataFrame([{**template.iloc[0].to_dict(), **r} for r in rows])
    res = render(notes, load_config(), parts=[0, 1, 2, 3], seed=3, audio=False)
    onsets = np.array([p.performance.events["t0"].to_numpy() for p in res.parts])
    downbeat = np.arange(16) % 4 == 0
    assert np.ptp(onsets[:, downbeat], axis=0).max() < 1e-9
    spread = np.ptp(onsets[:, ~downbeat], axis=0)
    assert 0.0005 < spread.max() <= 2 * 0.012
    solo = render(notes, load_config(), parts=[1], seed=3, audio=False)
    assert np.allclose(solo.parts[0].performance.events["t0"], np.arange(16.0))


def _duo(tmp_path):
    from music21 import note, stream

    score = stream.Score()
    for name, pitches in (("Violin", ["A4", "B4", "C5"]), ("Violoncello", ["C3", "D3", "E3"])):
        part = stream.Part()
        part.partName = name
        for p in pitches:
            part.append(note.Note(p, quarterLength=1))
        score.insert(0, part)
    path = tmp_path / "duo.musicxml"
    score.write("musicxml", fp=str(path))
    return path


def test_cli_all_parts_writes_stereo_master_and_stems(tmp_path, capsys):
    path = _duo(tmp_path)
    for name in ("a", "b"):
        code = cli.main(["render", str(path), "--method", "rules", "--all-parts", "--room",
                         "none", "--loudness", "-20", "-o", str(tmp_path / f"{name}.wav")])
        err = capsys.readouterr().err
        assert code == 0, err
    assert "LUFS" in err and "a-0-violin.wav" not in err and "b-1-cello.wav" in err
    mix, rate = sf.read(tmp_path / "a.wav")
    stems = [sf.read(tmp_path / f"a-{k}-{n}.wav")[0] for k, n in ((0, "violin"), (1, "cello"))]
    assert mix.shape[1] == 2 and np.allclose(mix, stems[0] + stems[1], atol=1e-6)
    assert integrated_loudness(mix, rate) == pytest.approx(-20.0, abs=0.5)
    assert np.abs(mix).max() <= 10 ** (-1 / 20)
    violin = stems[0]
    assert (violin[:, 0] ** 2).sum() > (violin[:, 1] ** 2).sum()  # violin I on the left
    for f in ("a.wav", "a-0-violin.wav", "a-1-cello.wav"):
        assert (tmp_path / f).read_bytes() == (tmp_path / f.replace("a", "b", 1)).read_bytes()
    assert not list(tmp_path.glob(".*"))  # no temporary files left


@pytest.mark.parametrize(("argv", "message"), [
    (("--all-parts", "--pan=-0.5,x"), "--pan"),
    (("--all-parts", "--pan=-2,0"), "pans"),
    (("--all-parts", "--rt60", "0"), "rt60"),
    (("--all-parts", "--loudness", "nan"), "loudness"),
    (("--room", "none"), "--all-parts"),
    (("--all-parts", "--mix-config", "missing.toml"), "missing.toml"),
])
def test_cli_bad_ensemble_options(tmp_path, capsys, argv, message):
    path = _duo(tmp_path)
    code = cli.main(["render", str(path), "--method", "rules", *argv,
                     "-o", str(tmp_path / "x.wav")])
    err = capsys.readouterr().err
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "x.wav").exists()
